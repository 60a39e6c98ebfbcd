//! Quality measures on any `V, F`: the library's blend metrics (edge-length and area strain,
//! enclosed volume) and fold metrics, measured against a rest shape.

use crate::arrays;
use crate::dict::to_dict;
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::mesh::{ShapeSet, Topology};
use morphkit::springs::{blend_metrics, fold_metrics, Weights};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Measures a deformed shape `V` `(n, 3)` against its rest shape `V_rest` over the
/// connectivity `F`, and returns a dict:
///
/// - `edge_length_rms`, `edge_length_max`: RMS and max over edges of `(ℓ − ℓ_rest) / ℓ_rest`;
/// - `area_rms`: RMS over triangles of `A / A_rest − 1`;
/// - `volume`, `volume_ratio`: enclosed volume and `V / V_rest` (closed meshes; else `None`);
/// - `folds`: triangles whose normal turned more than 120° from the rest normal;
/// - `creases`: interior edges whose dihedral angle is more than 30° off the rest angle.
///
/// >>> morphkit.metrics(V_rest, V, F)["edge_length_rms"]
#[pyfunction]
pub fn metrics<'py>(
    py: Python<'py>,
    v_rest: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let rest = from_arrays("rest", v_rest, f)?;
    let x = arrays::points("V", v)?;
    if x.len() != rest.num_vertices() {
        return Err(new_err(
            Kind::Mesh,
            format!(
                "V: has {} vertices, V_rest has {}",
                x.len(),
                rest.num_vertices()
            ),
        ));
    }
    let topo = Topology::new(rest.num_vertices(), &rest.triangles);
    let positions = rest.positions.clone();
    let shapes = ShapeSet::new(rest, vec![("rest".into(), positions)]).py(Kind::Mesh)?;
    let w = Weights::Delta(Vec::new());
    let (m, fm) = py
        .detach(|| {
            let m = blend_metrics(&shapes, &topo, &w, &x)?;
            let fm = fold_metrics(&shapes, &topo, &w, &x)?;
            Ok::<_, morphkit::springs::BlendError>((m, fm))
        })
        .py(Kind::Blend)?;
    let d = to_dict(py, &m)?.cast_into::<PyDict>()?;
    d.set_item("folds", fm.folds)?;
    d.set_item("creases", fm.creases)?;
    Ok(d)
}

/// Finds where a sequence jumps: pairs of consecutive frames between which some vertex moved
/// more than `bound` × the linear blend's largest step between the same weights (a part that
/// snapped from one equilibrium of the spring energy to another; see the README, "Jumps
/// between frames"). `frames` and `linear` are `(k, n, 3)` arrays (or sequences of `(n, 3)`
/// arrays): the physical frames and the linear blends of the same weights, in sequence order.
/// Linear steps below 1e-6 × the bounding-box diagonal of `linear[0]` count as that floor.
/// Returns a dict: `bound`, `worst_ratio`, `worst_frames` (`[k - 1, k]` or `None`) and
/// `jumps`, a list of dicts with `frames`, `ratio`, `vertex` (the one that moved most) and
/// `vertices` (every vertex above the bound).
///
/// >>> morphkit.continuity(frames, linear)["jumps"]
#[pyfunction]
#[pyo3(signature = (frames, linear, bound = morphkit::springs::JUMP_BOUND))]
pub fn continuity<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    linear: &Bound<'py, PyAny>,
    bound: f64,
) -> PyResult<Bound<'py, PyAny>> {
    if !(bound.is_finite() && bound > 0.0) {
        return Err(new_err(
            Kind::Blend,
            format!("bound: must be a finite positive number, got {bound}"),
        ));
    }
    let x = arrays::frames("frames", frames, None)?;
    let n = x.first().map(Vec::len);
    let lin = arrays::frames("linear", linear, n)?;
    if x.len() != lin.len() {
        return Err(new_err(
            Kind::Mesh,
            format!("frames: has {} frames, linear has {}", x.len(), lin.len()),
        ));
    }
    let diagonal = lin
        .first()
        .map_or(0.0, |l| morphkit::mesh::bbox_diagonal(l));
    let c = py
        .detach(|| morphkit::springs::sequence_continuity(&x, &lin, bound, diagonal))
        .py(Kind::Mesh)?;
    to_dict(py, &c)
}
