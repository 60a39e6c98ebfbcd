//! The arguments of the blend constructors and solves as Python gives them: fixed vertices,
//! the rig's arrays, volume options, weight vectors and pulls, checked with messages that name
//! the argument and element.

use crate::args::{self, Elements};
use crate::arrays;
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::mesh::ShapeSet;
use morphkit::springs::{AnchorOptions, FixedVertices, InteriorOptions, PointTarget, Weights};
use pyo3::prelude::*;

/// `fixed` as given to the constructors: `None` or `"auto"`, `"none"`, or vertex ids of a
/// mesh of `vertices` vertices.
pub fn fixed_vertices(obj: Option<&Bound<'_, PyAny>>, vertices: usize) -> PyResult<FixedVertices> {
    let Some(obj) = obj else {
        return Ok(FixedVertices::Auto);
    };
    if let Ok(s) = obj.extract::<String>() {
        return match s.as_str() {
            "auto" => Ok(FixedVertices::Auto),
            "none" => Ok(FixedVertices::None),
            other => Err(new_err(
                Kind::Blend,
                format!("fixed: expected \"auto\", \"none\" or vertex ids, got {other:?}"),
            )),
        };
    }
    let ids = args::indices("fixed", obj, Kind::Blend, Elements::vertices(vertices))?;
    Ok(FixedVertices::Ids(ids))
}

/// The rig of a blend: `base` `(n, 3)` and `targets` `(k, n, 3)` over `faces`, at least one
/// target; shape 0 is the base.
pub fn shape_set(
    base: &Bound<'_, PyAny>,
    targets: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
) -> PyResult<ShapeSet> {
    let mesh = from_arrays("base", base, faces)?;
    let n = mesh.num_vertices();
    let targets = arrays::frames("targets", targets, Some(n))?;
    if targets.is_empty() {
        return Err(new_err(
            Kind::Blend,
            "targets: at least one target is needed",
        ));
    }
    let mut named = vec![("base".to_string(), mesh.positions.clone())];
    named.extend(
        targets
            .into_iter()
            .enumerate()
            .map(|(i, p)| (format!("target_{i}"), p)),
    );
    ShapeSet::new(mesh, named).py(Kind::Mesh)
}

/// `interior` and `anchor` as given to the constructors (`None`: none), parsed as the CLI's
/// `--interior` and `--anchor`.
pub fn volume_options(
    interior: Option<&str>,
    anchor: Option<&str>,
) -> PyResult<(InteriorOptions, AnchorOptions)> {
    let io = match interior {
        None => InteriorOptions::default(),
        Some(s) => {
            InteriorOptions::parse(s).map_err(|e| new_err(Kind::Blend, format!("interior: {e}")))?
        }
    };
    let ao = match anchor {
        None | Some("none") => AnchorOptions::default(),
        Some(s) => {
            AnchorOptions::parse(s).map_err(|e| new_err(Kind::Blend, format!("anchor: {e}")))?
        }
    };
    Ok((io, ao))
}

/// A sequence of weight vectors, each as [`weights`] reads it.
pub fn weight_rows(obj: &Bound<'_, PyAny>, convex: bool, targets: usize) -> PyResult<Vec<Weights>> {
    obj.try_iter()
        .map_err(|_| {
            new_err(
                Kind::Blend,
                "weights: expected a sequence of weight vectors",
            )
        })?
        .map(|row| weights(&row?, convex, targets))
        .collect()
}

pub fn weights(obj: &Bound<'_, PyAny>, convex: bool, targets: usize) -> PyResult<Weights> {
    let w: Vec<f64> = match obj.extract::<f64>() {
        Ok(a) if !convex && targets == 1 => vec![a],
        Ok(_) => {
            return Err(new_err(
                Kind::Blend,
                format!(
                    "weights: a single number needs exactly one target (delta form); \
                     this blend has {targets}; pass a sequence"
                ),
            ))
        }
        Err(_) => obj.extract().map_err(|_| {
            new_err(
                Kind::Blend,
                "weights: expected a number or a sequence of numbers",
            )
        })?,
    };
    Ok(if convex {
        Weights::Convex(w)
    } else {
        Weights::Delta(w)
    })
}

pub(crate) fn pulls(obj: Option<&Bound<'_, PyAny>>, vertices: usize) -> PyResult<Vec<PointTarget>> {
    let Some(obj) = obj else {
        return Ok(Vec::new());
    };
    let items: Vec<(String, Bound<'_, PyAny>, [f64; 3])> =
        if let Ok(d) = obj.cast::<pyo3::types::PyDict>() {
            d.iter()
                .map(|(k, v)| Ok(("pulls vertex".to_string(), k, v.extract()?)))
                .collect::<PyResult<_>>()
        } else {
            obj.extract::<Vec<(Bound<'_, PyAny>, [f64; 3])>>()
                .map(|items| {
                    items
                        .into_iter()
                        .enumerate()
                        .map(|(i, (k, v))| (format!("pulls[{i}][0]"), k, v))
                        .collect()
                })
        }
        .map_err(|_| {
            new_err(
                Kind::Blend,
                "pulls: expected {vertex: (x, y, z)} or a sequence of (vertex, (x, y, z))",
            )
        })?;
    items
        .into_iter()
        .map(|(label, v, p)| {
            let vertex = args::index(&label, &v, Kind::Blend, Elements::vertices(vertices))?;
            if p.iter().any(|x| !x.is_finite()) {
                return Err(new_err(
                    Kind::Blend,
                    format!("pulls: vertex {vertex} has a non-finite position {p:?}"),
                ));
            }
            Ok(PointTarget {
                vertex,
                position: p,
                stiffness: PointTarget::HARD_STIFFNESS,
            })
        })
        .collect()
}
