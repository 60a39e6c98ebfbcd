//! [`PhysicalBlend`]: set-up once (springs, hinges, constraints, the Hessian pattern, the
//! memory check and the symbolic analysis), then canonical solves, one weight vector at a time
//! or many in parallel.

use super::frame_solver::{report_lost, FrameSolver};
use super::interactive::{
    decode, encode, fine_target, is_cache_head, snapshot_coefficients, InteractiveSpace, CHECKS,
};
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
                        .map(|k| (k, f(&mut solver, &items[k])))
                        .collect::<Vec<_>>()
                }));
            }
            let mut solver = FrameSolver {
                rig,
                ws: &mut self.ws,
            };
            for k in (0..items.len()).step_by(stride) {
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
        slots
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

impl PhysicalBlend {
    /// Prepares the [interactive mode](super::interactive): the canonical solves at the
    /// snapshot weights, spread over up to `threads` threads (the space, hence every
    /// interactive shape, does not depend on the thread count). Done once; later calls return
    /// the prepared space.
    pub fn prepare_interactive(&mut self, threads: usize) -> &InteractiveSpace {
        if self.interactive.is_none() {
            let started = std::time::Instant::now();
            let coefficients = snapshot_coefficients(self.rig.shapes.len());
            let solved = self.map_frames(&coefficients, threads, |f, c| f.rig.snapshot(f.ws, c));
            let targets = self.rig.shapes.len() - 1;
            let mut snapshots = Vec::with_capacity(solved.len());
            let mut unconverged = 0;
            // A target whose snapshot off the coarse weights did not converge has no check
            // for frames of several targets there: its estimate is unknown (infinite).
            let mut checked_many = vec![0.0; targets];
            for (s, c) in solved.into_iter().zip(&coefficients) {
                match s {
                    Some(Some(s)) => snapshots.push(s),
                    _ => {
                        unconverged += 1;
                        if let Some(t) = fine_target(c) {
                            checked_many[t - 1] = f64::INFINITY;
                        }
                    }
                }
            }
            let diagonal = crate::mesh::bbox_diagonal(self.rig.shapes.positions(0));
            let mut space = InteractiveSpace::new(
                snapshots,
                [vec![0.0; targets], checked_many],
                unconverged,
                diagonal,
                0.0,
            );
            // The error estimate's data: each combination left out, and with all of its
            // pair's snapshots (held apart); each target's snapshots off the coarse weights
            // against the coarse ones alone (frames of several targets); each target checked
            // between its snapshots (frames of one).
            let indices: Vec<usize> = (0..space.len()).collect();
            let errors = self.map_frames(&indices, threads, |f, &k| {
                let truth = &space.snapshots[k];
                let same: Vec<usize> = (0..space.len())
                    .filter(|&j| space.snapshots[j].active == truth.active)
                    .collect();
                if truth.active.len() == 1 {
                    if !truth.fine() {
                        return (0.0, 0.0);
                    }
                    let fine: Vec<usize> = same
                        .into_iter()
                        .filter(|&j| space.snapshots[j].fine())
                        .collect();
                    return (f.rig.interactive_error(f.ws, &space, truth, &fine), 0.0);
                }
                let left_out = f.rig.interactive_error(f.ws, &space, truth, &[k]);
                (
                    left_out,
                    f.rig.interactive_error(f.ws, &space, truth, &same),
                )
            });
            for (k, e) in errors.into_iter().enumerate() {
                let e = e.unwrap_or((f64::INFINITY, f64::INFINITY));
                let s = &mut space.snapshots[k];
                if s.active.len() == 1 {
                    let t = s.active[0] - 1;
                    space.checked_many[t] = space.checked_many[t].max(e.0);
                } else {
                    (s.left_out, s.apart) = e;
                }
            }
            let checks: Vec<(usize, f64)> = (1..=targets)
                .flat_map(|s| CHECKS.iter().map(move |&a| (s, a)))
                .collect();
            let n = self.rig.shapes.len();
            let errors = self.map_frames(&checks, threads, |f, &(s, a)| {
                let mut c = vec![0.0; n];
                c[0] = 1.0 - a;
                c[s] = a;
                match f.rig.snapshot(f.ws, &c) {
                    Some(truth) => f.rig.interactive_error(f.ws, &space, &truth, &[]),
                    None => f64::INFINITY,
                }
            });
            for (&(s, _), e) in checks.iter().zip(errors) {
                let e = e.unwrap_or(f64::INFINITY);
                space.checked[s - 1] = space.checked[s - 1].max(e);
            }
            space.prepare_seconds = started.elapsed().as_secs_f64();
            self.interactive = Some(space);
        }
        self.interactive.as_ref().expect("prepared above")
    }

    /// The prepared interactive space as bytes (see [`interactive`](super::interactive) for
    /// the layout), to be given to [`load_interactive`](Self::load_interactive) when the
    /// same rig is opened again; `None` before [`prepare_interactive`](Self::prepare_interactive).
    pub fn interactive_bytes(&self) -> Option<Vec<u8>> {
        let space = self.interactive.as_ref()?;
        let sizes = self.cache_sizes();
        Some(encode(
            space,
            &self.rig.samples,
            self.rig.cache_key(),
            sizes,
        ))
    }

    /// Takes a preparation saved by [`interactive_bytes`](Self::interactive_bytes): the same
    /// space, so the same interactive shapes bit for bit, without the preparation's solves.
    /// Refused with [`BlendError::InteractiveCache`] when the bytes are damaged, of another
    /// format version, or were made for another rig (other shapes, triangles, options or
    /// energy terms); the blend is then unchanged.
    pub fn load_interactive(&mut self, bytes: &[u8]) -> Result<&InteractiveSpace, BlendError> {
        let (space, fields, pairs) = decode(bytes, self.rig.cache_key(), self.cache_sizes())?;
        let mut pairs = pairs.into_iter();
        for t in 2..self.rig.shapes.len() {
            for s in 1..t {
                if let Some(Some(field)) = pairs.next() {
                    self.rig.samples.restore_pair(s, t, field);
                }
            }
        }
        for (s, three) in fields.into_iter().enumerate() {
            for (k, field) in three.into_iter().enumerate() {
                if let Some(field) = field {
                    self.rig.samples.restore(s + 1, k, field);
                }
            }
        }
        Ok(self.interactive.insert(space))
    }

    /// Shape, free-coordinate and vertex counts, as the interactive cache records them.
    fn cache_sizes(&self) -> [usize; 3] {
        let r = &self.rig;
        [r.shapes.len(), r.system.num_free(), r.shapes.num_vertices()]
    }

    /// [`prepare_interactive`](Self::prepare_interactive) through a cache file: where `path`
    /// holds a preparation of this very rig (same shapes, triangles, options and terms), it is
    /// read instead of solved; otherwise (no file, empty, damaged, another format version,
    /// another rig) the preparation runs and replaces it, written atomically, and
    /// [`InteractiveCacheUse::replaced`] says why, naming the file. Once prepared, the file is
    /// only written where there is none, never read.
    ///
    /// Fails when the file cannot be written, and, leaving it untouched, when it cannot be
    /// read or is not a morphkit interactive preparation of any version (it does not start
    /// with `MKINTER`): a path given by mistake is never overwritten.
    pub fn prepare_interactive_cached(
        &mut self,
        threads: usize,
        path: &std::path::Path,
    ) -> Result<InteractiveCacheUse, BlendError> {
        let unused = InteractiveCacheUse {
            loaded: false,
            replaced: None,
        };
        if self.interactive.is_some() {
            if !path.exists() {
                self.write_interactive(path)?;
            }
            return Ok(unused);
        }
        let replaced = match read_cache(path)? {
            Some(bytes) => match self.load_interactive(&bytes) {
                Ok(_) => {
                    return Ok(InteractiveCacheUse {
                        loaded: true,
                        ..unused
                    })
                }
                Err(e) => Some(format!("{}: {e}", path.display())),
            },
            None => None,
        };
        self.prepare_interactive(threads);
        self.write_interactive(path)?;
        Ok(InteractiveCacheUse { replaced, ..unused })
    }

    fn write_interactive(&self, path: &std::path::Path) -> Result<(), BlendError> {
        let bytes = self.interactive_bytes().expect("prepared");
        crate::io::write_atomic(path, &bytes).map_err(|e| BlendError::InteractiveCache {
            problem: format!("cannot write {}: {e}", path.display()),
        })
    }

    /// The interactive space, where prepared.
    pub fn interactive_space(&self) -> Option<&InteractiveSpace> {
        self.interactive.as_ref()
    }

    /// The interactive shape for `weights` (see [`interactive`](super::interactive)),
    /// preparing the space on one thread first where it is not prepared.
    /// `refine` projected-Newton steps with the frame's own factorization follow (each one
    /// costs about a full solve's Newton iteration and brings the shape closer).
    pub fn solve_interactive(
        &mut self,
        weights: &Weights,
        refine: usize,
    ) -> Result<BlendResult, BlendError> {
        let c = weights.coefficients(self.rig.shapes.len())?;
        self.prepare_interactive(1);
        let space = self.interactive.as_ref().expect("prepared above");
        self.rig.solve_interactive(&mut self.ws, space, &c, refine)
    }
}

/// The bytes of an interactive cache file (`None` where there is none), refusing a file that
/// cannot be read or is not a cache: only its first bytes are read to tell.
fn read_cache(path: &std::path::Path) -> Result<Option<Vec<u8>>, BlendError> {
    use std::io::Read;
    let fail = |problem: String| BlendError::InteractiveCache { problem };
    let cannot = |e: std::io::Error| {
        fail(format!(
            "cannot read {} to check that it is a cache: {e}; it was left as it is",
            path.display()
        ))
    };
    let mut file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(cannot(e)),
    };
    let mut head = Vec::new();
    (&mut file).take(8).read_to_end(&mut head).map_err(cannot)?;
    if !is_cache_head(&head) {
        let shown: Vec<String> = head.iter().map(|b| format!("{b:02x}")).collect();
        return Err(fail(format!(
            "{} is not a morphkit interactive preparation (it starts with {}, not MKINTER); \
             refusing to replace it: give the cache another path",
            path.display(),
            shown.join(" ")
        )));
    }
    let mut bytes = head;
    file.read_to_end(&mut bytes).map_err(cannot)?;
    Ok(Some(bytes))
}

/// How [`PhysicalBlend::prepare_interactive_cached`] used its file.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct InteractiveCacheUse {
    /// The preparation was read from the file (no solves).
    pub loaded: bool,
    /// Why a file that was there was not used (it was replaced), naming the file.
    pub replaced: Option<String>,
}
