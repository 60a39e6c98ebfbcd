//! [`PhysicalBlend`]: set-up once (springs, hinges, constraints, the Hessian pattern, the
//! memory check and the symbolic analysis), then canonical solves, one weight vector at a time
//! or many in parallel.

use super::frame_solver::{report_lost, FrameSolver};
use super::interactive::InteractiveSpace;
use super::options::{BlendOptions, BlendResult, RigSummary};
use super::predictor::BlendPredictor;
use super::rig::{Built, Rig};
use super::sampled_start::StartSamples;
use super::solve::Sampler;
use super::terms::{EnergyTerm, PointTarget};
use super::workspace::Workspace;
use super::{BlendError, Constraints, Weights};
use crate::mesh::ShapeSet;
use crate::sparse::{AggregationPreconditioner, Cholesky};
use std::sync::Arc;

/// Physical blendshape solver: build once, then [`solve`](Self::solve) for as many weight
/// vectors as needed (a slider, an animation). Each solve is the canonical equilibrium of its
/// weights (see the [module docs](super)): it never depends on earlier solves.
pub struct PhysicalBlend {
    pub(super) rig: Arc<Rig>,
    pub(super) ws: Workspace,
    /// The interactive mode's space, once prepared.
    pub(super) interactive: Option<InteractiveSpace>,
}

impl std::fmt::Debug for PhysicalBlend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicalBlend")
            .field("summary", &self.rig.summary)
            .finish()
    }
}

impl PhysicalBlend {
    /// Builds springs, hinges, constraints, the Hessian pattern and its symbolic factorization.
    pub fn new(shapes: &ShapeSet, options: &BlendOptions) -> Result<Self, BlendError> {
        Self::with_terms(shapes, options, Vec::new())
    }

    /// Like [`new`](Self::new), with additional energy terms (internal springs, anchors, soft
    /// pulls…) added to the springs and hinges. Their couplings join the one pattern.
    pub fn with_terms(
        shapes: &ShapeSet,
        options: &BlendOptions,
        extra: Vec<Box<dyn EnergyTerm>>,
    ) -> Result<Self, BlendError> {
        match Rig::build(shapes, options, extra, false)? {
            Built::Rig(built) => {
                let (rig, ws) = *built;
                Ok(Self {
                    rig: Arc::new(rig),
                    ws,
                    interactive: None,
                })
            }
            Built::Estimate(_) => Err(BlendError::InvalidOption(
                "internal: an estimate where a blend was built".into(),
            )),
        }
    }

    /// Sizes of what was built.
    pub fn summary(&self) -> &RigSummary {
        &self.rig.summary
    }
    /// The energy terms, springs first.
    pub fn terms(&self) -> &[Box<dyn EnergyTerm>] {
        &self.rig.terms
    }
    /// The resolved constraints.
    pub fn constraints(&self) -> &Constraints {
        &self.rig.constraints
    }
    /// Number of free unknowns of the Newton system.
    pub fn num_free_dofs(&self) -> usize {
        self.rig.system.num_free()
    }
    /// Number of stored entries of the Cholesky factor (memory ≈ 8 bytes each).
    pub fn factor_nnz(&self) -> usize {
        self.rig.summary.factor_nnz
    }
    /// The shape set.
    pub fn shapes(&self) -> &ShapeSet {
        &self.rig.shapes
    }
    /// The absolute gradient tolerance of a converged solve.
    pub fn tolerance(&self) -> f64 {
        self.rig.tolerance
    }

    /// The predictor $P(w)$ that the solve for `weights` starts from, before the sampled
    /// correction (see [`BlendPredictor::predict`]).
    pub fn predict(&self, weights: &Weights) -> Result<Vec<crate::mesh::Point>, BlendError> {
        self.predictor().predict(weights)
    }

    /// A handle on the predictor that does not borrow the blend: a UI can show
    /// [`BlendPredictor::predict`] while a thread solves the equilibrium.
    pub fn predictor(&self) -> BlendPredictor {
        BlendPredictor {
            rig: Arc::clone(&self.rig),
        }
    }

    /// The canonical equilibrium for `weights`.
    ///
    /// A solve that does not reach the tolerance within the iteration budget still returns the
    /// best state found, with `stats.converged == false` and the failing vertices in
    /// `stats.unconverged_vertices`; it never returns NaNs.
    pub fn solve(&mut self, weights: &Weights) -> Result<BlendResult, BlendError> {
        self.frame_solver().solve_with(weights, &[], None)
    }

    /// The equilibrium for `weights` with vertices pulled towards point targets (pulled
    /// vertices, contacts; Ma et al. Sec. 4), starting from `start` (world positions, `#V`)
    /// instead of the predictor when given: a collision round continues from the previous
    /// round of the same frame. Targets must lie on components held by fixed vertices (a
    /// gauged component has no world position to pull against); targets on fixed vertices
    /// have no effect.
    pub fn solve_with(
        &mut self,
        weights: &Weights,
        targets: &[PointTarget],
        start: Option<&[crate::mesh::Point]>,
    ) -> Result<BlendResult, BlendError> {
        self.frame_solver().solve_with(weights, targets, start)
    }

    /// Solves every weight vector, spread over up to `threads` threads (each with its own
    /// numeric workspace; the symbolic analysis is shared). Results come back in input order
    /// and equal those of [`solve`](Self::solve) bit for bit, whatever the thread count.
    pub fn solve_many(
        &mut self,
        weights: &[Weights],
        threads: usize,
    ) -> Vec<Result<BlendResult, BlendError>> {
        self.prepare(weights, threads);
        report_lost(self.map_frames(weights, threads, |s, w| s.solve_with(w, &[], None)))
    }

    /// `f(solver, item)` for every item, spread over up to `threads` threads, each with its
    /// own numeric workspace (the symbolic analysis is shared; fewer threads when memory for a
    /// workspace is short). Results come back in input order; `None` marks an item lost to a
    /// thread that panicked (a bug), so that the caller can report it instead of crashing.
    /// Each call solves from scratch, so the results do not depend on the thread count or on
    /// which thread ran which item.
    pub fn map_frames<T: Sync, R: Send>(
        &mut self,
        items: &[T],
        threads: usize,
        f: impl Fn(&mut FrameSolver<'_>, &T) -> R + Sync,
    ) -> Vec<Option<R>> {
        self.map_frames_until(items, threads, &|| false, f)
            .expect("never stopped")
    }

    /// [`map_frames`](Self::map_frames) that stops early: every thread calls `stop` before
    /// each item, and once a call returns `true` no thread starts another item (those running
    /// finish). `None` when it stopped, else what `map_frames` returns. `stop` is called from
    /// every thread; a hook that can only be asked from one thread (Python's signal check, on
    /// the calling thread) returns `false` on the others, which then stop at their next item.
    pub fn map_frames_until<T: Sync, R: Send>(
        &mut self,
        items: &[T],
        threads: usize,
        stop: &(dyn Fn() -> bool + Sync),
        f: impl Fn(&mut FrameSolver<'_>, &T) -> R + Sync,
    ) -> Option<Vec<Option<R>>> {
        use std::sync::atomic::{AtomicBool, Ordering};
        let stopped = AtomicBool::new(false);
        let halt = || {
            stopped.load(Ordering::Relaxed) || {
                let now = stop();
                if now {
                    stopped.store(true, Ordering::Relaxed);
                }
                now
            }
        };
        let halt = &halt;
        let threads = threads.clamp(1, items.len().max(1));
        let mut workspaces = Vec::with_capacity(threads - 1);
        let s = &self.rig.summary;
        for k in 1..threads {
            // A further workspace only while the blend's predicted memory stays in the limit.
            if s.predicted_bytes + k as u64 * s.workspace_bytes > self.rig.options.max_memory_bytes
            {
                break;
            }
            let aggregation = match &self.rig.aggregation {
                Some(levels) => match AggregationPreconditioner::new(levels.clone()) {
                    Ok(a) => Some(a),
                    Err(_) => break,
                },
                None => None,
            };
            match self
                .ws
                .chol
                .as_ref()
                .map(Cholesky::share_symbolic)
                .transpose()
            {
                Ok(chol) => workspaces.push(Workspace::new(
                    chol,
                    aggregation,
                    self.ws.blocks.clone(),
                    self.ws.exact.len(),
                )),
                Err(_) => break,
            }
        }
        let rig = &self.rig;
        let f = &f;
        let mut slots: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
        let stride = workspaces.len() + 1;
        std::thread::scope(|scope| {
            let mut handles = Vec::new();
            for (t, mut ws) in workspaces.into_iter().enumerate() {
                handles.push(scope.spawn(move || {
                    let mut solver = FrameSolver { rig, ws: &mut ws };
                    (t + 1..items.len())
                        .step_by(stride)
                        .take_while(|_| !halt())
                        .map(|k| (k, f(&mut solver, &items[k])))
                        .collect::<Vec<_>>()
                }));
            }
            let mut solver = FrameSolver {
                rig,
                ws: &mut self.ws,
            };
            for k in (0..items.len()).step_by(stride) {
                if halt() {
                    break;
                }
                slots[k] = Some(f(&mut solver, &items[k]));
            }
            for h in handles {
                if let Ok(done) = h.join() {
                    for (k, r) in done {
                        slots[k] = Some(r);
                    }
                }
            }
        });
        (!stopped.into_inner()).then_some(slots)
    }

    /// A solver over this blend's own workspace (what [`map_frames`](Self::map_frames) hands
    /// to each item on the calling thread).
    pub fn frame_solver(&mut self) -> FrameSolver<'_> {
        FrameSolver {
            rig: &self.rig,
            ws: &mut self.ws,
        }
    }
}

/// One-shot physical blend: builds a [`PhysicalBlend`] and solves once.
pub fn blend(
    shapes: &ShapeSet,
    weights: &Weights,
    options: &BlendOptions,
) -> Result<BlendResult, BlendError> {
    PhysicalBlend::new(shapes, options)?.solve(weights)
}

impl PhysicalBlend {
    /// Computes the [sampled start](super::sampled_start)'s fields that solves for `weights`
    /// will read, spread over up to `threads` threads (the ½ samples first, then the others,
    /// which start from them, then the pairs' fields). A solve computes what it lacks itself; this only lets the
    /// samples run in parallel instead of one after another inside the first frames. Invalid
    /// weights are skipped (their solves report them).
    pub fn prepare(&mut self, weights: &[Weights], threads: usize) {
        if !self.rig.options.sampled_start {
            return;
        }
        let n = self.rig.shapes.len();
        let samples = &self.rig.samples;
        let coefficients: Vec<Vec<f64>> = weights
            .iter()
            .filter_map(|w| w.coefficients(n).ok())
            .collect();
        let mut pairs: Vec<(usize, usize)> = coefficients
            .iter()
            .flat_map(|c| StartSamples::needed_pairs(c))
            .filter(|&(s, t)| samples.pair_computed(s, t).is_none())
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let mut missing: Vec<(usize, usize)> = coefficients
            .iter()
            .flat_map(|c| StartSamples::needed(c).collect::<Vec<_>>())
            .chain(pairs.iter().flat_map(|&(s, t)| [(s, 1), (t, 1)]))
            .filter(|&(s, k)| !samples.is_computed(s, k))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        let mut halves: Vec<(usize, usize)> = missing.iter().map(|&(s, _)| (s, 1)).collect();
        halves.dedup();
        let sides: Vec<(usize, usize)> = missing.into_iter().filter(|&(_, k)| k != 1).collect();
        let field = |f: &mut FrameSolver<'_>, &(s, k): &(usize, usize)| {
            let rig = f.rig;
            rig.samples.field(s, k, &mut Sampler { rig, ws: f.ws });
        };
        self.map_frames(&halves, threads, field);
        self.map_frames(&sides, threads, field);
        // The pairs last: each starts from its two targets' ½ fields.
        self.map_frames(&pairs, threads, |f, &(s, t)| {
            let rig = f.rig;
            rig.samples.pair(s, t, &mut Sampler { rig, ws: f.ws });
        });
    }

    /// Sample solves of the [sampled start](super::sampled_start) run so far (each target's
    /// fields are solved once per blend, on first need).
    pub fn start_samples_solved(&self) -> usize {
        self.rig.samples.solved()
    }
}
