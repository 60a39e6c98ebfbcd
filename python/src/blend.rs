//! `PhysicalBlend`: the library's stateful physical-blendshape solver (Ma et al. 2012), built
//! once per rig, then solved for many weight vectors with the GIL released.
//!
//! Thread safety: a solver's numeric workspace is mutable state. It lives in a [`Mutex`] that
//! is only ever waited for with the GIL released (inside `py.detach`), so calls from several
//! Python threads queue instead of failing, and no thread holds the GIL while it waits for
//! another's solve. What the properties read (`num_targets`, `summary`, the predictor) is set
//! at construction, and `last_stats` has its own small lock, so they answer at once while a
//! solve runs. `solve_many` solves in chunks and checks for signals between them, so that
//! Ctrl-C interrupts a long batch (see [`solve_in_chunks`]); the interactive preparation
//! checks between its solves ([`with_signal_checks`]).

use crate::args;
use crate::arrays::{to_array, to_array3};
use crate::blend_args::pulls as pulls_of;
pub use crate::blend_args::{fixed_vertices, shape_set, volume_options, weight_rows, weights};
use crate::dict::to_dict;
use crate::errors::{chain, new_err, IntoPyResult, Kind};
pub use crate::predictor::PyPredictor;
use crate::stop::with_signal_checks;
use crate::weld::{shape_weld, unweld_frame, unweld_stats, weld_fixed};
use morphkit::mesh::Weld;
use morphkit::springs::{
    AnchorPlacement, BlendError, BlendOptions, FrameStats, InteractiveCacheUse, InteriorMode,
    PhysicalBlend, SurfacePredictor, VolumetricBlend, Weights,
};
use numpy::{PyArray2, PyArray3};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

/// The physical blend of a base shape and its targets (Ma et al. 2012).
///
/// Built once (springs, hinges, boundary conditions, symbolic factorization); each
/// :meth:`solve` then returns the canonical equilibrium for a weight vector, a function of the
/// weights alone: the same weights give the same shape in any order and on any thread.
///
/// Thread-safe: one blend may be shared by several threads. Its solves (:meth:`solve`,
/// :meth:`solve_many`) run one at a time, with the GIL released: concurrent calls wait for
/// each other instead of failing, and each returns what it would have returned alone.
/// :attr:`num_targets`, :attr:`summary`, :attr:`last_stats`, :meth:`predict` and
/// :meth:`predictor` answer at once, also while a solve runs.
///
/// >>> blend = morphkit.PhysicalBlend(V0, [V1], F)
/// >>> half = blend.solve([0.5])
/// >>> blend.last_stats["converged"]
/// True
#[pyclass(name = "PhysicalBlend", module = "morphkit", frozen)]
pub struct PyPhysicalBlend {
    /// The solver; locked only with the GIL released (see the module doc).
    inner: Mutex<Solver>,
    /// The solver's predictor (it shares the immutable rig: no lock).
    predictor: SurfacePredictor,
    /// `summary`, as built (the rig does not change after construction).
    summary: serde_json::Value,
    targets: usize,
    vertices: usize,
    /// The weld the solver works on (`None`: nothing welded, the input's own layout).
    weld: Option<Arc<Weld>>,
    /// Statistics of the last solve that finished.
    last: Mutex<Option<FrameStats>>,
}

/// Locks `m`, also after a panic in a solve (a library bug, raised as Python's
/// `PanicException`): every solve starts from scratch, so the workspace stays usable, as it
/// did when a panic merely released the object's borrow.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Frames per chunk of [`solve_in_chunks`]: `threads` (one frame per thread), or one frame on
/// one thread.
///
/// One round of the threads per chunk keeps Ctrl-C within one frame's solve time; the cost is
/// a thread start and a numeric workspace per extra thread and chunk, which measured 0–15 % of
/// a batch on meshes of 50–1 800 vertices solved in 0.1–6 ms per frame (nothing with one
/// thread), and is lost in the solve time on larger meshes.
fn chunk_size(threads: usize) -> usize {
    threads.max(1)
}

/// Solves `items` chunk by chunk through `solve` (called with the GIL released; one result
/// per item of its chunk, in order), checking for signals (Ctrl-C) before each chunk, so that
/// `KeyboardInterrupt` comes after at most one chunk, not at the end of the batch. Frames do
/// not depend on each other (nor on the thread count), so the results are those of one call
/// over all items, bit for bit. A failed frame `k` is a `BlendError` `"frame k: …"` (frames
/// after its chunk are not solved).
pub(crate) fn solve_in_chunks<T: Sync, R: Send>(
    py: Python<'_>,
    items: &[T],
    threads: usize,
    mut solve: impl FnMut(&[T]) -> Vec<Result<R, String>> + Send,
) -> PyResult<Vec<R>> {
    let mut out = Vec::with_capacity(items.len());
    for (c, chunk) in items.chunks(chunk_size(threads)).enumerate() {
        py.check_signals()?;
        let start = c * chunk_size(threads);
        let results = py.detach(|| solve(chunk));
        for (k, r) in results.into_iter().enumerate() {
            out.push(r.map_err(|e| new_err(Kind::Blend, format!("frame {}: {e}", start + k)))?);
        }
    }
    Ok(out)
}

/// The surface-only blend, or the blend with internal springs and an anchor (Sec. 3.1, 3.4).
enum Solver {
    Surface(Box<PhysicalBlend>),
    Volume(Box<VolumetricBlend>),
}

/// `s` as a JSON value (what `summary` returns, as a dict).
fn json<T: serde::Serialize>(s: &T) -> PyResult<serde_json::Value> {
    serde_json::to_value(s).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

fn not_surface() -> BlendError {
    BlendError::InvalidOption(
        "the interactive mode is for surface blends (not with interior or anchor)".into(),
    )
}

impl PyPhysicalBlend {
    fn solve_interactive<'py>(
        &self,
        py: Python<'py>,
        w: &Weights,
        refine: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let weld = self.weld.as_deref();
        let positions = with_signal_checks(py, |stop| {
            let mut solver = lock(&self.inner);
            let Solver::Surface(b) = &mut *solver else {
                return Err(not_surface());
            };
            // A first interactive solve prepares the space (on one thread): Ctrl-C stops it.
            b.prepare_interactive_until(1, stop)?;
            let r = b.solve_interactive(w, refine)?;
            *lock(&self.last) = Some(unweld_stats(weld, r.stats));
            Ok(unweld_frame(weld, r.positions, w, self.targets + 1))
        })?;
        Ok(to_array(py, &positions))
    }
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
    /// wanted), `continuation_steps` (an integer 0–64, default 0: a frame is solved along its
    /// weights' ray from the rest shape in that many steps, keeping the branch the ray starts
    /// on where a fresh start can land in either of two equilibria, at about that many times
    /// the work): see the library's `BlendOptions`.
    /// `interior="lattice"` adds internal springs on a lattice inside each closed component
    /// (Sec. 3.1; `"lattice,2"` doubles its density, `"tetgen[,density]"` runs an external
    /// tetgen); `anchor="auto"` (or `"x,y,z[,size]"`) adds the rigid interior anchor
    /// (Sec. 3.4), which then holds the body instead of fixed vertices: the strings of
    /// `morphkit blend --interior/--anchor`. `summary["interior"]` reports what was built.
    /// `weld` (default True): vertices split at seams and hard edges (coincident in every
    /// shape within 1e-6 of the base's diagonal) are one vertex for the solve, so seams never
    /// open; results, `fixed` and `pulls` ids and `last_stats` stay in the caller's layout;
    /// :attr:`welded_vertices` and `summary["welded_vertices"]` say how many were welded. A
    /// mesh with nothing to weld solves exactly as with `weld=False`.
    #[new]
    #[pyo3(signature = (base, targets, faces, *, fixed=None, hinge_weight=None,
        tether=None, kinematic_stretch=None, thin_band_rings=None, gradient_tolerance=None,
        max_newton_iterations=None, sampled_start=true, continuation_steps=None, interior=None,
        anchor=None, weld=true))]
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
        continuation_steps: Option<&Bound<'_, PyAny>>,
        interior: Option<&str>,
        anchor: Option<&str>,
        weld: bool,
    ) -> PyResult<Self> {
        let thin_band_rings = args::opt_count("thin_band_rings", thin_band_rings, Kind::Blend, 0)?;
        let max_newton_iterations = args::opt_count(
            "max_newton_iterations",
            max_newton_iterations,
            Kind::Blend,
            0,
        )?;
        let continuation_steps =
            args::opt_count("continuation_steps", continuation_steps, Kind::Blend, 0)?;
        let input = shape_set(base, targets, faces)?;
        let (n, k) = (input.num_vertices(), input.len() - 1);
        let weld = shape_weld(&input, weld);
        let fixed = weld_fixed(weld.as_deref(), fixed_vertices(fixed, n)?);
        // Split seams and hard edges are one vertex for the solve; results go back in the
        // caller's layout.
        let welded;
        let shapes = match &weld {
            Some(w) => {
                welded = w.shapes(&input).py(Kind::Mesh)?;
                &welded
            }
            None => &input,
        };
        let mut opts = BlendOptions {
            fixed,
            sampled_start,
            continuation_steps: continuation_steps.unwrap_or(0),
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
        let (inner, predictor, summary) =
            if io.mode == InteriorMode::None && ao.placement == AnchorPlacement::None {
                let b = py
                    .detach(|| PhysicalBlend::new(shapes, &opts))
                    .py(Kind::Blend)?;
                let predictor = SurfacePredictor::from(b.predictor());
                let summary = json(b.summary())?;
                (Solver::Surface(Box::new(b)), predictor, summary)
            } else {
                let b = py
                    .detach(|| VolumetricBlend::new(shapes, &opts, &io, &ao))
                    .py(Kind::Blend)?;
                let mut summary = json(b.physical().summary())?;
                if let serde_json::Value::Object(m) = &mut summary {
                    m.insert("interior".into(), json(b.report())?);
                }
                let predictor = b.predictor();
                (Solver::Volume(Box::new(b)), predictor, summary)
            };
        let mut summary = summary;
        if let serde_json::Value::Object(m) = &mut summary {
            m.insert(
                "welded_vertices".into(),
                weld.as_ref().map_or(0, |w| w.merged()).into(),
            );
        }
        Ok(Self {
            inner: Mutex::new(inner),
            predictor,
            summary,
            targets: k,
            vertices: n,
            weld,
            last: Mutex::new(None),
        })
    }

    /// The equilibrium for `weights` as a new `(n, 3)` array.
    ///
    /// `weights`: one per target in the delta form `base + Σ wᵢ (targetᵢ − base)` (a plain
    /// number when there is one target), or with `convex=True` one per shape (base first)
    /// summing to 1. `pulls`: `{vertex: (x, y, z)}` hard pulls (Ma et al. Sec. 4; the vertex's
    /// part must be held by fixed vertices). Statistics of the solve are in
    /// :attr:`last_stats`. The GIL is released while solving; a solve running on another
    /// thread is waited for.
    ///
    /// `interactive=True`: the interactive mode (a slider being dragged): a small solve in the
    /// rig's prepared space of equilibria (see :meth:`prepare_interactive`; prepared on one
    /// thread at the first call if not yet), tens of milliseconds instead of the full solve's
    /// hundreds, within ``last_stats["error_estimate"]`` (a fraction of the base's diagonal)
    /// of the full solve; one-hot and zero weights give the full solve exactly. `refine`
    /// projected-Newton steps follow, each costing about one Newton iteration of the full
    /// solve and bringing the shape closer. Not with `pulls`, and not for volumetric blends.
    #[pyo3(signature = (weights, *, convex=false, pulls=None, interactive=false, refine=None),
        text_signature = "($self, weights, *, convex=False, pulls=None, interactive=False, refine=0)")]
    fn solve<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
        pulls: Option<&Bound<'py, PyAny>>,
        interactive: bool,
        refine: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = crate::blend_args::weights(weights, convex, self.targets)?;
        let refine = args::opt_count("refine", refine, Kind::Blend, 0)?.unwrap_or(0);
        if interactive {
            if pulls.is_some_and(|p| !p.is_none()) {
                return Err(new_err(
                    Kind::Blend,
                    "pulls are not part of the interactive mode: solve without interactive=True",
                ));
            }
            return self.solve_interactive(py, &w, refine);
        }
        let mut targets = pulls_of(pulls, self.vertices)?;
        let weld = self.weld.as_deref();
        if let Some(wd) = weld {
            for t in &mut targets {
                t.vertex = wd.to_welded()[t.vertex as usize];
            }
        }
        let positions = py
            .detach(|| {
                let mut solver = lock(&self.inner);
                let r = match &mut *solver {
                    Solver::Surface(b) => b
                        .solve_with(&w, &targets, None)
                        .map(|r| (r.positions, r.stats)),
                    Solver::Volume(b) => b.solve_with(&w, &targets).map(|r| (r.positions, r.stats)),
                };
                r.map(|(positions, stats)| {
                    *lock(&self.last) = Some(unweld_stats(weld, stats));
                    unweld_frame(weld, positions, &w, self.targets + 1)
                })
            })
            .py(Kind::Blend)?;
        Ok(to_array(py, &positions))
    }

    /// Prepares the interactive mode of :meth:`solve` once: canonical solves of every target
    /// at ¼, ½, ¾ and of every pair of targets at (½, ½) and (0.3, 0.3), then checks that give
    /// the error estimate, on up to `threads` threads (the result does not depend on them).
    /// With `cache` (a path), a preparation of this very rig saved there is read instead (a
    /// damaged file, or one of another rig or options, is replaced; a file that is not such a
    /// cache raises BlendError and is left as it is). Returns a dict: ``snapshots``,
    /// ``unconverged``, ``seconds`` (this call), ``loaded`` (from the cache), ``replaced`` (why
    /// a cache file there was not used, or None). Only for surface blends. Ctrl-C
    /// (`KeyboardInterrupt`) stops it between two solves: nothing is prepared, no cache
    /// written.
    #[pyo3(signature = (*, threads=None, cache=None),
        text_signature = "($self, *, threads=1, cache=None)")]
    fn prepare_interactive<'py>(
        &self,
        py: Python<'py>,
        threads: Option<&Bound<'py, PyAny>>,
        cache: Option<std::path::PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let threads = args::opt_count("threads", threads, Kind::Blend, 1)?.unwrap_or(1);
        let report = with_signal_checks(py, |stop| {
            let started = std::time::Instant::now();
            let mut solver = lock(&self.inner);
            let Solver::Surface(b) = &mut *solver else {
                return Err(not_surface());
            };
            let used = match &cache {
                Some(path) => b.prepare_interactive_cached_until(threads, path, stop)?,
                None => {
                    b.prepare_interactive_until(threads, stop)?;
                    InteractiveCacheUse {
                        loaded: false,
                        replaced: None,
                    }
                }
            };
            let space = b.interactive_space().expect("prepared above");
            Ok(serde_json::json!({
                "snapshots": space.len(),
                "unconverged": space.unconverged,
                "seconds": started.elapsed().as_secs_f64(),
                "loaded": used.loaded,
                "replaced": used.replaced,
            }))
        })?;
        to_dict(py, &report)
    }

    /// Bakes the physical blend into ordinary blendshapes (issue 56) and returns a
    /// :class:`BakedRig`: per target, its equilibria alone at `k / (inbetweens + 1)` (default
    /// 7: the eighths) as in-between shapes, and per pair of targets that interact (its
    /// correction beyond the two in-betweens at (s, s) moves a vertex more than
    /// `pair_tolerance` of the diagonal; at most `max_pairs`, largest first) a combination
    /// shape with an in-between per pair sample `s` (`pair_samples`, default ½ and 1), driven
    /// by `4 wi wj ((wi + wj) / sum w) ** damping` (default damping 0: the plain product). Solves on up to
    /// `threads` threads (the result does not depend on it); in the caller's (unwelded) layout.
    /// Where a target's interpolation between its in-betweens is farther than
    /// `inbetween_tolerance` of the diagonal from its equilibrium (default 1e-3; 0 keeps the
    /// regular grid), more in-betweens are added, halving segments, at most `max_refined` in all.
    #[pyo3(signature = (*, inbetweens=7, pair_tolerance=1e-4, max_pairs=120, damping=0.0,
        pair_samples=None, threads=None, inbetween_tolerance=1e-3, max_refined=64))]
    #[allow(clippy::too_many_arguments)]
    fn bake(
        &self,
        py: Python<'_>,
        inbetweens: usize,
        pair_tolerance: f64,
        max_pairs: usize,
        damping: f64,
        pair_samples: Option<Vec<f64>>,
        threads: Option<&Bound<'_, PyAny>>,
        inbetween_tolerance: f64,
        max_refined: usize,
    ) -> PyResult<crate::bake::PyBakedRig> {
        let threads = args::opt_count("threads", threads, Kind::Blend, 1)?.unwrap_or(1);
        let defaults = morphkit::bake::BakeOptions::default();
        let options = morphkit::bake::BakeOptions {
            inbetweens,
            pair_tolerance,
            max_pairs,
            damping,
            pair_samples: pair_samples.unwrap_or(defaults.pair_samples),
            inbetween_tolerance,
            max_refined,
        };
        let weld = self.weld.clone();
        let baked = py.detach(|| {
            let mut solver = lock(&self.inner);
            let Solver::Surface(b) = &mut *solver else {
                return Err(
                    "a bake is for surface blends (not with interior or anchor)".to_string()
                );
            };
            let rig = morphkit::bake::bake(b, &options, threads).map_err(|e| e.to_string())?;
            Ok(match weld {
                Some(w) => rig.unweld(&w, b.shapes()),
                None => rig,
            })
        });
        let inner = baked.map_err(|e| new_err(Kind::Blend, e))?;
        Ok(crate::bake::PyBakedRig { inner })
    }

    /// Solves every weight vector of `weights` (a sequence, each as in :meth:`solve`) on up to
    /// `threads` threads (an integer ≥ 1) and returns a `(len(weights), n, 3)` array, in input
    /// order, equal to solving them one by one. :attr:`last_stats` is the last frame's. The
    /// GIL is released; frames are solved `threads` at a time, and Ctrl-C
    /// (`KeyboardInterrupt`) is honoured between them.
    #[pyo3(signature = (weights, *, convex=false, threads=None),
        text_signature = "($self, weights, *, convex=False, threads=1)")]
    fn solve_many<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
        threads: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let threads = args::opt_count("threads", threads, Kind::Blend, 1)?.unwrap_or(1);
        let rows = weight_rows(weights, convex, self.targets)?;
        let frames = solve_in_chunks(py, &rows, threads, |chunk| {
            let mut solver = lock(&self.inner);
            let results: Vec<Result<_, String>> = match &mut *solver {
                Solver::Surface(b) => b
                    .solve_many(chunk, threads)
                    .into_iter()
                    .map(|r| r.map(|r| (r.positions, r.stats)).map_err(|e| chain(&e)))
                    .collect(),
                Solver::Volume(b) => b
                    .solve_many(chunk, threads)
                    .into_iter()
                    .map(|r| r.map(|r| (r.positions, r.stats)).map_err(|e| chain(&e)))
                    .collect(),
            };
            if let Some(Ok((_, stats))) = results.last() {
                if results.iter().all(Result::is_ok) {
                    *lock(&self.last) = Some(unweld_stats(self.weld.as_deref(), stats.clone()));
                }
            }
            results
        })?;
        let frames: Vec<_> = frames
            .into_iter()
            .zip(&rows)
            .map(|((p, _), w)| unweld_frame(self.weld.as_deref(), p, w, self.targets + 1))
            .collect();
        Ok(to_array3(py, &frames, self.vertices))
    }

    /// The predictor the solve for `weights` starts from, before the sampled correction (see
    /// :class:`Predictor`), as a new `(n, 3)` array: a preview in milliseconds, not the
    /// equilibrium. It does not wait for a solve running on another thread.
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
        Ok(PyPredictor::new(self.predictor.clone(), self.targets).welded(self.weld.clone()))
    }

    /// How many of the input's vertices were welded into others for the solve: vertices split
    /// at seams and hard edges (coincident in every shape, within 1e-6 of the base's diagonal)
    /// are one vertex, and results come back in the input's layout; 0 with `weld=False`.
    #[getter]
    fn welded_vertices(&self) -> usize {
        self.weld.as_ref().map_or(0, |w| w.merged())
    }

    /// Statistics of the last solve as a dict (Newton iterations, factorizations, gradient
    /// norm and tolerance, energy, `converged`, clamped springs, unconverged vertices,
    /// seconds), or `None` before the first. Readable while a solve runs (it then shows the
    /// last solve that finished).
    #[getter]
    fn last_stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let last = lock(&self.last).clone();
        last.as_ref().map(|s| to_dict(py, s)).transpose()
    }

    /// What the solver was built with (vertices, springs, hinges, fixed and kinematic
    /// vertices, free unknowns, factor size, predicted bytes) as a dict.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, &self.summary)
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
