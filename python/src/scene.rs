//! Physical blends in a scene (Ma et al. 2012, Sec. 4): rigid obstacles with keyframed motion
//! and keyframed pulls, through the library's `scene::SceneBlend`.

use crate::args::{self, Elements};
use crate::arrays::{to_array, to_array3};
use crate::blend::{lock, solve_in_chunks};
use crate::dict::to_dict;
use crate::errors::{chain, new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use std::sync::{Arc, Mutex};

use morphkit::mesh::{Point, Weld};
use morphkit::scene::{
    CollisionOptions, Obstacle, Primitive, Pull, PullKey, PullKind, RigidKey, Rotation, SceneBlend,
    SceneFrame,
};
use morphkit::springs::{BlendOptions, SurfacePredictor, Weights};
use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A rigid obstacle: a primitive or a closed mesh, with an optional keyframed rigid motion
/// `keys = [(frame, (tx, ty, tz)), …]` or `[(frame, (tx, ty, tz), (w, x, y, z)), …]` (frames
/// strictly increasing; poses interpolated between keys, held outside).
///
/// >>> ball = morphkit.Obstacle.sphere(0.3, keys=[(0, (1, 0, 0)), (10, (1, 0.5, 0))])
#[pyclass(name = "Obstacle", module = "morphkit", frozen)]
pub struct PyObstacle {
    inner: Obstacle,
}

type Key = (f64, [f64; 3], Option<[f64; 4]>);

/// `(frame, translation)` or `(frame, translation, (w, x, y, z))`.
fn key_of(obj: &Bound<'_, PyAny>) -> PyResult<Key> {
    if let Ok((f, t)) = obj.extract::<(f64, [f64; 3])>() {
        return Ok((f, t, None));
    }
    obj.extract::<(f64, [f64; 3], [f64; 4])>()
        .map(|(f, t, q)| (f, t, Some(q)))
        .map_err(|_| {
            new_err(
                Kind::Blend,
                "keys: each key is (frame, (tx, ty, tz)) or (frame, (tx, ty, tz), (w, x, y, z))",
            )
        })
}

fn keyed(o: Obstacle, keys: Option<Vec<Bound<'_, PyAny>>>) -> PyResult<PyObstacle> {
    let inner = match keys {
        None => o,
        Some(keys) => {
            let keys = keys
                .iter()
                .map(key_of)
                .collect::<PyResult<Vec<Key>>>()?
                .into_iter()
                .map(|(frame, translation, q)| {
                    let [w, x, y, z] = q.unwrap_or([1.0, 0.0, 0.0, 0.0]);
                    RigidKey {
                        frame,
                        translation,
                        rotation: Rotation::from_xyzw(x, y, z, w).normalize(),
                    }
                })
                .collect();
            o.with_keys(keys).py(Kind::Blend)?
        }
    };
    Ok(PyObstacle { inner })
}

#[pymethods]
impl PyObstacle {
    /// A sphere of `radius` centred at the origin of its pose.
    #[staticmethod]
    #[pyo3(signature = (radius, *, name="sphere", keys=None))]
    fn sphere(radius: f64, name: &str, keys: Option<Vec<Bound<'_, PyAny>>>) -> PyResult<Self> {
        let o = Obstacle::primitive(name, &Primitive::Sphere { radius }, 1.0).py(Kind::Blend)?;
        keyed(o, keys)
    }

    /// An axis-aligned box of `size` (x, y, z) centred at the origin of its pose.
    #[staticmethod]
    #[pyo3(signature = (size, *, name="box", keys=None))]
    fn r#box(size: [f64; 3], name: &str, keys: Option<Vec<Bound<'_, PyAny>>>) -> PyResult<Self> {
        let o = Obstacle::primitive(name, &Primitive::Box { size }, 1.0).py(Kind::Blend)?;
        keyed(o, keys)
    }

    /// A cylinder of `radius` and `height` along its pose's y axis, centred at its origin.
    #[staticmethod]
    #[pyo3(signature = (radius, height, *, name="cylinder", keys=None))]
    fn cylinder(
        radius: f64,
        height: f64,
        name: &str,
        keys: Option<Vec<Bound<'_, PyAny>>>,
    ) -> PyResult<Self> {
        let o = Obstacle::primitive(name, &Primitive::Cylinder { radius, height }, 1.0)
            .py(Kind::Blend)?;
        keyed(o, keys)
    }

    /// A closed, consistently oriented triangle mesh `(V, F)` (an open mesh has no inside and
    /// is refused).
    #[staticmethod]
    #[pyo3(signature = (v, f, *, name="mesh", keys=None))]
    fn mesh(
        v: &Bound<'_, PyAny>,
        f: &Bound<'_, PyAny>,
        name: &str,
        keys: Option<Vec<Bound<'_, PyAny>>>,
    ) -> PyResult<Self> {
        let m = from_arrays("obstacle", v, f)?;
        let o = Obstacle::from_mesh(name, &m).py(Kind::Blend)?;
        keyed(o, keys)
    }

    /// The obstacle's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_string()
    }

    fn __repr__(&self) -> String {
        format!("Obstacle({:?})", self.inner.name())
    }
}

/// A physical blend with obstacles and keyframed pulls, built once; :meth:`solve` is one frame
/// (Ma et al. Sec. 4: after each equilibrium, surface vertices inside an obstacle are moved to
/// its surface, held there, and the blend is solved again, until nothing penetrates by more
/// than `tolerance` × the diagonal or `max_rounds` (an integer ≥ 0) re-solves were made).
///
/// `pulls = [(vertex, [(frame, (x, y, z)), …]), …]` are hard pulls (the vertex's part must be
/// held by fixed vertices). `interior` and `anchor` as in :class:`PhysicalBlend`: interior
/// vertices are never contacts, and with an anchor obstacles and pulls are mapped into its
/// frame. Other arguments as :class:`PhysicalBlend`.
///
/// Thread-safe as :class:`PhysicalBlend`: solves run one at a time with the GIL released
/// (concurrent calls wait for each other), :attr:`last_stats` and :meth:`predictor` answer at
/// once while a solve runs.
#[pyclass(name = "SceneBlend", module = "morphkit", frozen)]
pub struct PySceneBlend {
    /// The solver; locked only with the GIL released (see `blend.rs`).
    inner: Mutex<SceneBlend>,
    /// Its predictor without obstacles and pulls (no lock).
    predictor: SurfacePredictor,
    targets: usize,
    /// The weld the solver works on (`None`: nothing welded; see `PhysicalBlend`).
    weld: Option<Arc<Weld>>,
    /// The last finished frame, without its positions (what `last_stats` reports).
    last: Mutex<Option<SceneFrame>>,
}

/// `r` kept for `last_stats` (positions dropped, vertex ids in input numbering) and its
/// positions in the input's layout.
fn keep(last: &Mutex<Option<SceneFrame>>, weld: Option<&Weld>, mut r: SceneFrame) -> Vec<Point> {
    let positions = std::mem::take(&mut r.positions);
    r.extra = Vec::new();
    if let Some(w) = weld {
        for c in &mut r.contacts {
            c.vertex = w.representative()[c.vertex as usize];
        }
    }
    r.solver = crate::weld::unweld_stats(weld, r.solver);
    *lock(last) = Some(r);
    crate::weld::unweld(weld, positions)
}

/// `(vertex, [(frame, (x, y, z)), …])` of a mesh of `vertices` vertices, the `i`th pull.
fn pull_of(
    i: usize,
    obj: &Bound<'_, PyAny>,
    vertices: usize,
    weld: Option<&Weld>,
) -> PyResult<Pull> {
    let (v, keys) = obj
        .extract::<(Bound<'_, PyAny>, Vec<(f64, [f64; 3])>)>()
        .map_err(|_| {
            new_err(
                Kind::Blend,
                format!("pulls[{i}]: expected (vertex, [(frame, (x, y, z)), …])"),
            )
        })?;
    let v = args::index(
        &format!("pulls[{i}][0]"),
        &v,
        Kind::Blend,
        Elements::vertices(vertices),
    )?;
    let keys = keys
        .into_iter()
        .map(|(frame, position)| PullKey { frame, position })
        .collect();
    let v = weld.map_or(v, |w| w.to_welded()[v as usize]);
    Pull::new(v, keys, PullKind::Hard).py(Kind::Blend)
}

#[pymethods]
impl PySceneBlend {
    #[new]
    #[pyo3(signature = (base, targets, faces, *, obstacles=Vec::new(), pulls=Vec::new(),
        fixed=None, hinge_weight=None, tolerance=1e-4, max_rounds=None, interior=None,
        anchor=None, weld=true),
        text_signature = "(base, targets, faces, *, obstacles=(), pulls=(), fixed=None, \
            hinge_weight=None, tolerance=1e-4, max_rounds=10, interior=None, anchor=None, \
            weld=True)")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        base: &Bound<'_, PyAny>,
        targets: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        obstacles: Vec<Bound<'_, PyObstacle>>,
        pulls: Vec<Bound<'_, PyAny>>,
        fixed: Option<&Bound<'_, PyAny>>,
        hinge_weight: Option<f64>,
        tolerance: f64,
        max_rounds: Option<&Bound<'_, PyAny>>,
        interior: Option<&str>,
        anchor: Option<&str>,
        weld: bool,
    ) -> PyResult<Self> {
        let max_rounds = args::opt_count("max_rounds", max_rounds, Kind::Blend, 0)?
            .unwrap_or(CollisionOptions::default().max_rounds);
        let (io, ao) = crate::blend::volume_options(interior, anchor)?;
        let input = crate::blend::shape_set(base, targets, faces)?;
        let (n, k) = (input.num_vertices(), input.len() - 1);
        // Split seams and hard edges are one vertex for the solve (as in PhysicalBlend).
        let weld = crate::weld::shape_weld(&input, weld);
        let welded;
        let shapes = match &weld {
            Some(w) => {
                welded = w.shapes(&input).py(Kind::Mesh)?;
                &welded
            }
            None => &input,
        };
        let mut opts = BlendOptions {
            fixed: crate::weld::weld_fixed(
                weld.as_deref(),
                crate::blend::fixed_vertices(fixed, n)?,
            ),
            ..BlendOptions::default()
        };
        if let Some(w) = hinge_weight {
            opts.hinges.weight = w;
        }
        let pulls = pulls
            .iter()
            .enumerate()
            .map(|(i, p)| pull_of(i, p, n, weld.as_deref()))
            .collect::<PyResult<Vec<_>>>()?;
        let obstacles = obstacles.iter().map(|o| o.get().inner.clone()).collect();
        let col = CollisionOptions {
            tolerance,
            max_rounds,
        };
        let inner = py
            .detach(|| SceneBlend::with_interior(shapes, &opts, &io, &ao, obstacles, pulls, &col))
            .py(Kind::Blend)?;
        Ok(Self {
            predictor: inner.surface_predictor(),
            inner: Mutex::new(inner),
            targets: k,
            weld,
            last: Mutex::new(None),
        })
    }

    /// The frame at frame number `frame` (it places obstacles and pulls) for `weights` (as in
    /// :meth:`PhysicalBlend.solve`): a new `(n, 3)` array. The GIL is released; a solve
    /// running on another thread is waited for.
    #[pyo3(signature = (weights, *, frame=0.0, convex=false))]
    fn solve<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        frame: f64,
        convex: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w: Weights = crate::blend::weights(weights, convex, self.targets)?;
        let positions = py
            .detach(|| {
                let mut solver = lock(&self.inner);
                let r = solver.solve(frame, &w)?;
                Ok::<_, morphkit::scene::SceneError>(keep(&self.last, self.weld.as_deref(), r))
            })
            .py(Kind::Blend)?;
        Ok(to_array(py, &positions))
    }

    /// Every weight vector of `weights` (a sequence, each as in :meth:`solve`) as frame
    /// `frames[k]` (default: frame number k), solved on up to `threads` threads (an integer
    /// ≥ 1); a `(len(weights), n, 3)` array in input order, equal to :meth:`solve` frame by
    /// frame. :attr:`last_stats` is the last frame's. The GIL is released; frames are solved
    /// `threads` at a time, and Ctrl-C (`KeyboardInterrupt`) is honoured between them.
    #[pyo3(signature = (weights, *, frames=None, convex=false, threads=None),
        text_signature = "($self, weights, *, frames=None, convex=False, threads=1)")]
    fn solve_many<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        frames: Option<Vec<f64>>,
        convex: bool,
        threads: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let threads = args::opt_count("threads", threads, Kind::Blend, 1)?.unwrap_or(1);
        let rows = crate::blend::weight_rows(weights, convex, self.targets)?;
        let numbers = frames.unwrap_or_else(|| (0..rows.len()).map(|k| k as f64).collect());
        if numbers.len() != rows.len() {
            return Err(new_err(
                Kind::Blend,
                format!(
                    "frames: {} frame numbers for {} weight vectors",
                    numbers.len(),
                    rows.len()
                ),
            ));
        }
        let items: Vec<(f64, Weights)> = numbers.into_iter().zip(rows).collect();
        let out = solve_in_chunks(py, &items, threads, |chunk| {
            let mut solver = lock(&self.inner);
            let results = solver.solve_many(chunk, threads);
            let ok = results.iter().all(Result::is_ok);
            let n = results.len();
            results
                .into_iter()
                .enumerate()
                .map(|(k, r)| match r {
                    // The chunk's last frame is kept for `last_stats` when all succeeded.
                    Ok(f) if ok && k + 1 == n => Ok(keep(&self.last, self.weld.as_deref(), f)),
                    Ok(f) => Ok(crate::weld::unweld(self.weld.as_deref(), f.positions)),
                    Err(e) => Err(chain(&e)),
                })
                .collect()
        })?;
        let n = out.first().map_or(0, Vec::len);
        Ok(to_array3(py, &out, n))
    }

    /// A :class:`Predictor` of the blend without obstacles and pulls (a preview that may
    /// penetrate the obstacles), usable while :meth:`solve` runs on another thread. With
    /// `interior` or `anchor` it predicts the volumetric solve's start, on the input surface
    /// in world coordinates.
    fn predictor(&self) -> PyResult<crate::blend::PyPredictor> {
        Ok(
            crate::blend::PyPredictor::new(self.predictor.clone(), self.targets)
                .welded(self.weld.clone()),
        )
    }

    /// The last frame's statistics: `solver` (as :attr:`PhysicalBlend.last_stats`),
    /// `collision` (contacts, rounds, max_penetration, tolerance, resolved, timings) and
    /// `contacts` (vertex, obstacle, position, depth), or `None` before the first solve.
    /// Readable while a solve runs (it then shows the last frame that finished).
    #[getter]
    fn last_stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(r) = lock(&self.last).clone() else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("solver", to_dict(py, &r.solver)?)?;
        d.set_item("collision", to_dict(py, &r.collision)?)?;
        d.set_item("contacts", to_dict(py, &r.contacts)?)?;
        Ok(Some(d))
    }
}
