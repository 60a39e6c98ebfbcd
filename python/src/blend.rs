//! `PhysicalBlend`: the library's stateful physical-blendshape solver (Ma et al. 2012), built
//! once per rig, then solved for many weight vectors with the GIL released.

use crate::args::{self, Elements};
use crate::arrays::{self, to_array, to_array3};
use crate::dict::to_dict;
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::mesh::ShapeSet;
use morphkit::springs::{
    AnchorOptions, AnchorPlacement, BlendOptions, FixedVertices, FrameStats, InteriorMode,
    InteriorOptions, PhysicalBlend, PointTarget, SurfacePredictor, VolumetricBlend, Weights,
};
use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;

/// The physical blend of a base shape and its targets (Ma et al. 2012).
///
/// Built once (springs, hinges, boundary conditions, symbolic factorization); each
/// :meth:`solve` then returns the canonical equilibrium for a weight vector, a function of the
/// weights alone: the same weights give the same shape in any order and on any thread.
///
/// >>> blend = morphkit.PhysicalBlend(V0, [V1], F)
/// >>> half = blend.solve([0.5])
/// >>> blend.last_stats["converged"]
/// True
#[pyclass(name = "PhysicalBlend", module = "morphkit")]
pub struct PyPhysicalBlend {
    inner: Solver,
    targets: usize,
    vertices: usize,
    last: Option<FrameStats>,
}

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
pub(crate) fn volume_options(
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

/// The surface-only blend, or the blend with internal springs and an anchor (Sec. 3.1, 3.4).
enum Solver {
    Surface(Box<PhysicalBlend>),
    Volume(Box<VolumetricBlend>),
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

fn pulls(obj: Option<&Bound<'_, PyAny>>, vertices: usize) -> PyResult<Vec<PointTarget>> {
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

#[pymethods]
impl PyPhysicalBlend {
    /// `base` `(n, 3)`, `targets` `(k, n, 3)` or a list of `(n, 3)`, `F` `(m, 3)` shared by all.
    ///
    /// `fixed`: `"auto"` (default: vertices that move in no shape), `"none"`, or vertex ids
    /// (interpolated linearly). `hinge_weight` (default 0.01, 0 turns the bending term off),
    /// `tether` (default 1e-5: every solved vertex tied weakly to the predictor, so that parts
    /// that can swing either way do not snap between frames; 0 turns it off),
    /// `kinematic_stretch` (default 10), `thin_band_rings` (an integer ≥ 0, default 4: long
    /// parts within 4 edges of the boundary follow the predictor; 0 turns it off),
    /// `gradient_tolerance` (default 1e-6), `max_newton_iterations` (an integer ≥ 0, default
    /// 300), `sampled_start` (default True: frames start
    /// from the predictor corrected by each target's equilibria at ¼, ½, ¾, solved once per
    /// target on first need; False saves those three solves when only a frame or two is
    /// wanted): see the library's `BlendOptions`.
    /// `interior="lattice"` adds internal springs on a lattice inside each closed component
    /// (Sec. 3.1; `"lattice,2"` doubles its density, `"tetgen[,density]"` runs an external
    /// tetgen); `anchor="auto"` (or `"x,y,z[,size]"`) adds the rigid interior anchor
    /// (Sec. 3.4), which then holds the body instead of fixed vertices: the strings of
    /// `morphkit blend --interior/--anchor`. `summary["interior"]` reports what was built.
    #[new]
    #[pyo3(signature = (base, targets, faces, *, fixed=None, hinge_weight=None,
        tether=None, kinematic_stretch=None, thin_band_rings=None, gradient_tolerance=None,
        max_newton_iterations=None, sampled_start=true, interior=None, anchor=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        base: &Bound<'_, PyAny>,
        targets: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        fixed: Option<&Bound<'_, PyAny>>,
        hinge_weight: Option<f64>,
        tether: Option<f64>,
        kinematic_stretch: Option<f64>,
        thin_band_rings: Option<&Bound<'_, PyAny>>,
        gradient_tolerance: Option<f64>,
        max_newton_iterations: Option<&Bound<'_, PyAny>>,
        sampled_start: bool,
        interior: Option<&str>,
        anchor: Option<&str>,
    ) -> PyResult<Self> {
        let thin_band_rings = args::opt_count("thin_band_rings", thin_band_rings, Kind::Blend, 0)?;
        let max_newton_iterations = args::opt_count(
            "max_newton_iterations",
            max_newton_iterations,
            Kind::Blend,
            0,
        )?;
        let shapes = shape_set(base, targets, faces)?;

        let (n, k) = (shapes.num_vertices(), shapes.len() - 1);
        let mut opts = BlendOptions {
            fixed: fixed_vertices(fixed, n)?,
            sampled_start,
            ..BlendOptions::default()
        };
        if let Some(w) = hinge_weight {
            opts.hinges.weight = w;
        }
        if let Some(t) = tether {
            opts.tether = t;
        }
        if let Some(s) = kinematic_stretch {
            opts.kinematic_stretch = s;
        }
        if let Some(r) = thin_band_rings {
            opts.thin_band_rings = r;
        }
        if let Some(t) = gradient_tolerance {
            opts.gradient_tolerance = t;
        }
        if let Some(m) = max_newton_iterations {
            opts.max_newton_iterations = m;
        }
        let (io, ao) = volume_options(interior, anchor)?;
        let inner = if io.mode == InteriorMode::None && ao.placement == AnchorPlacement::None {
            Solver::Surface(Box::new(
                py.detach(|| PhysicalBlend::new(&shapes, &opts))
                    .py(Kind::Blend)?,
            ))
        } else {
            Solver::Volume(Box::new(
                py.detach(|| VolumetricBlend::new(&shapes, &opts, &io, &ao))
                    .py(Kind::Blend)?,
            ))
        };
        Ok(Self {
            inner,
            targets: k,
            vertices: n,
            last: None,
        })
    }

    /// The equilibrium for `weights` as a new `(n, 3)` array.
    ///
    /// `weights`: one per target in the delta form `base + Σ wᵢ (targetᵢ − base)` (a plain
    /// number when there is one target), or with `convex=True` one per shape (base first)
    /// summing to 1. `pulls`: `{vertex: (x, y, z)}` hard pulls (Ma et al. Sec. 4; the vertex's
    /// part must be held by fixed vertices). Statistics of the solve are in
    /// :attr:`last_stats`. The GIL is released while solving.
    #[pyo3(signature = (weights, *, convex=false, pulls=None))]
    fn solve<'py>(
        &mut self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
        pulls: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = self::weights(weights, convex, self.targets)?;
        let targets = self::pulls(pulls, self.vertices)?;
        let (positions, stats) = match &mut self.inner {
            Solver::Surface(b) => {
                let r = py
                    .detach(|| b.solve_with(&w, &targets, None))
                    .py(Kind::Blend)?;
                (r.positions, r.stats)
            }
            Solver::Volume(b) => {
                let r = py.detach(|| b.solve_with(&w, &targets)).py(Kind::Blend)?;
                (r.positions, r.stats)
            }
        };
        let out = to_array(py, &positions);
        self.last = Some(stats);
        Ok(out)
    }

    /// Solves every weight vector of `weights` (a sequence, each as in :meth:`solve`) on up to
    /// `threads` threads (an integer ≥ 1) and returns a `(len(weights), n, 3)` array, in input
    /// order, equal to solving them one by one. :attr:`last_stats` is the last frame's.
    #[pyo3(signature = (weights, *, convex=false, threads=None),
        text_signature = "($self, weights, *, convex=False, threads=1)")]
    fn solve_many<'py>(
        &mut self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
        threads: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let threads = args::opt_count("threads", threads, Kind::Blend, 1)?.unwrap_or(1);
        let rows = weight_rows(weights, convex, self.targets)?;
        let results: Vec<Result<(Vec<_>, FrameStats), _>> = match &mut self.inner {
            Solver::Surface(b) => py
                .detach(|| b.solve_many(&rows, threads))
                .into_iter()
                .map(|r| r.map(|r| (r.positions, r.stats)))
                .collect(),
            Solver::Volume(b) => py
                .detach(|| b.solve_many(&rows, threads))
                .into_iter()
                .map(|r| r.map(|r| (r.positions, r.stats)))
                .collect(),
        };
        let mut frames = Vec::with_capacity(results.len());
        let mut last = None;
        for (i, r) in results.into_iter().enumerate() {
            let (positions, stats) = r.map_err(|e| {
                new_err(
                    Kind::Blend,
                    format!("frame {i}: {}", crate::errors::chain(&e)),
                )
            })?;
            frames.push(positions);
            last = Some(stats);
        }
        self.last = last;
        Ok(to_array3(py, &frames, self.vertices))
    }

    /// The predictor the solve for `weights` starts from, before the sampled correction (see
    /// :class:`Predictor`), as a new `(n, 3)` array: a preview in milliseconds, not the
    /// equilibrium.
    #[pyo3(signature = (weights, *, convex=false))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.predictor()?.predict(py, weights, convex)
    }

    /// A :class:`Predictor` of this blend that can be used while :meth:`solve` runs on
    /// another thread. With `interior` or `anchor` it predicts the volumetric solve's start
    /// (the interior carried along), on the input surface in world coordinates.
    fn predictor(&self) -> PyResult<PyPredictor> {
        let p = match &self.inner {
            Solver::Surface(b) => SurfacePredictor::from(b.predictor()),
            Solver::Volume(v) => v.predictor(),
        };
        Ok(PyPredictor::new(p, self.targets))
    }

    /// Statistics of the last solve as a dict (Newton iterations, factorizations, gradient
    /// norm and tolerance, energy, `converged`, clamped springs, unconverged vertices,
    /// seconds), or `None` before the first.
    #[getter]
    fn last_stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.last.as_ref().map(|s| to_dict(py, s)).transpose()
    }

    /// What the solver was built with (vertices, springs, hinges, fixed and kinematic
    /// vertices, free unknowns, factor size, predicted bytes) as a dict.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match &self.inner {
            Solver::Surface(b) => to_dict(py, b.summary()),
            Solver::Volume(b) => {
                let d = to_dict(py, b.physical().summary())?;
                d.set_item("interior", to_dict(py, b.report())?)?;
                Ok(d)
            }
        }
    }

    /// Number of targets (shapes other than the base).
    #[getter]
    fn num_targets(&self) -> usize {
        self.targets
    }

    fn __repr__(&self) -> String {
        format!(
            "PhysicalBlend(vertices={}, targets={})",
            self.vertices, self.targets
        )
    }
}

/// The predictor P(w) of a physical blend, on its own: the rotation-aware interpolation of the
/// shapes that every solve starts from (exact at each shape's one-hot weights; fixed vertices
/// at their linear blend; no pulls, no obstacles). It costs one prefactored solve, so a UI can
/// show it while a slider moves and replace it by the equilibrium when that is ready. It
/// shares the blend's set-up and may be called from any thread, also while the blend solves.
///
/// >>> preview = blend.predictor()
/// >>> X = preview.predict([0.5])
#[pyclass(name = "Predictor", module = "morphkit", frozen)]
pub struct PyPredictor {
    inner: SurfacePredictor,
    targets: usize,
}

impl PyPredictor {
    pub fn new(inner: SurfacePredictor, targets: usize) -> Self {
        Self { inner, targets }
    }
}

#[pymethods]
impl PyPredictor {
    /// The predicted shape for `weights` (as in :meth:`PhysicalBlend.solve`) as a new `(n, 3)`
    /// array. The GIL is released.
    #[pyo3(signature = (weights, *, convex=false))]
    pub fn predict<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = self::weights(weights, convex, self.targets)?;
        let inner = &self.inner;
        let p = py.detach(|| inner.predict(&w)).py(Kind::Blend)?;
        Ok(to_array(py, &p))
    }

    fn __repr__(&self) -> String {
        format!("Predictor(targets={})", self.targets)
    }
}
