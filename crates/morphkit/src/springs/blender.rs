//! [`PhysicalBlend`]: set-up once (springs, hinges, constraints, the Hessian pattern, the
//! memory check and the symbolic analysis), then canonical solves, one weight vector at a time
//! or many in parallel.

use super::constraints::{stretched_vertices, thin_bands, Components, Constraints};
use super::frame_solver::{report_lost, FrameSolver};
use super::newton::{projected_newton, reference_at, trust_region, Problem, Workspace};
use super::options::{
    check_options, BlendOptions, BlendResult, FrameStats, LinearSolver, RigSummary,
};
use super::predictor::BlendPredictor;
use super::reference::{Factor, References};
use super::rotation_predictor::RotationPredictor;
use super::sampled_start::{shifted, Sampler, StartSamples};
use super::system::{expand_vertex_order, predicted_bytes, vertex_nested_dissection, FreeSystem};
use super::terms::{
    BlockHessian, BlockPattern, EnergyTerm, Held, HingeTerm, PointTarget, PointTerm, SpringTerm,
    TermParameters,
};
use super::{
    predictor, BlendError, FillOrdering, MemoryEstimate, Predictor, SpringSet, StiffnessRule,
    Weights,
};
use crate::mesh::{validate, Point, ShapeSet, Topology};
use crate::sparse::{AggregationLevels, AggregationPreconditioner, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Physical blendshape solver: build once, then [`solve`](Self::solve) for as many weight
/// vectors as needed (a slider, an animation). Each solve is the canonical equilibrium of its
/// weights (see the [module docs](super)): it never depends on earlier solves.
pub struct PhysicalBlend {
    pub(super) rig: Arc<Rig>,
    pub(super) ws: Workspace,
}

/// Everything that does not change between solves (shared by all threads).
pub(super) struct Rig {
    pub(super) shapes: ShapeSet,
    terms: Vec<Box<dyn EnergyTerm>>,
    pub(super) constraints: Constraints,
    system: FreeSystem,
    pub(super) options: BlendOptions,
    tolerance: f64,
    /// Mean structure-spring stiffness on the base (the unit of point-target stiffness).
    mean_stiffness: f64,
    /// The rotation-aware predictor, when asked for and possible.
    pub(super) rotation: Option<RotationPredictor>,
    /// Per vertex: held at the linear blend by a boundary condition (not the bands).
    pub(super) is_fixed: Vec<bool>,
    /// Each target's correction fields of the sampled start.
    pub(super) samples: StartSamples,
    /// The aggregation cycle's pattern, when it preconditions instead of the factor.
    aggregation: Option<Arc<AggregationLevels>>,
    /// Reference factors of frames near a grid weight of one target.
    pub(super) references: References,
    summary: RigSummary,
}

impl std::fmt::Debug for PhysicalBlend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicalBlend")
            .field("summary", &self.rig.summary)
            .finish()
    }
}

/// What [`PhysicalBlend::build`] made: the blend, or only its memory estimate.
enum Built {
    Blend(Box<PhysicalBlend>),
    Estimate(u64),
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
        match Self::build(shapes, options, extra, false)? {
            Built::Blend(b) => Ok(*b),
            Built::Estimate(_) => Err(BlendError::InvalidOption(
                "internal: an estimate where a blend was built".into(),
            )),
        }
    }

    /// The symbolic analysis's memory estimate of a blend of `shapes` (bytes), without the
    /// early checks and without building the solver ([`crate::springs`]' memory module).
    pub(crate) fn estimate_bytes(
        shapes: &ShapeSet,
        options: &BlendOptions,
    ) -> Result<u64, BlendError> {
        match Self::build(shapes, options, Vec::new(), true)? {
            Built::Estimate(b) => Ok(b),
            Built::Blend(_) => Err(BlendError::InvalidOption(
                "internal: a blend where an estimate was asked for".into(),
            )),
        }
    }

    fn build(
        shapes: &ShapeSet,
        options: &BlendOptions,
        extra: Vec<Box<dyn EnergyTerm>>,
        estimate_only: bool,
    ) -> Result<Built, BlendError> {
        let o = options;
        check_options(o)?;
        // Triangles that use a vertex twice carry no energy: the solve leaves them out.
        let proper;
        let shapes = if shapes
            .triangles()
            .iter()
            .any(|t| t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
        {
            proper = crate::mesh::Weld::identity(shapes.num_vertices()).shapes(shapes)?;
            &proper
        } else {
            shapes
        };
        if !estimate_only {
            super::memory::check_early(shapes, o)?;
        }
        for s in 0..shapes.len() {
            validate(&shapes.mesh(s))?;
        }
        super::spring_set::check_scale(shapes)?;
        let n = shapes.num_vertices();
        let topology = Topology::new(n, shapes.triangles());
        let springs = SpringSet::new(shapes, &topology, &o.springs);
        if springs.is_empty() {
            return Err(BlendError::NoSprings {
                cause: if o.springs.structure || o.springs.bending {
                    "every spring joins vertices that coincide in all shapes"
                } else {
                    "both structure and bending springs are turned off"
                },
            });
        }
        springs.check_degenerate(shapes)?;
        // μ of the hinges from the base's structure springs (weight-independent).
        let (mean_stiffness, mean_square_length) = springs.base_means(o.springs.stiffness);
        let tolerance = o.gradient_tolerance
            * o.springs.k0
            * match o.springs.stiffness {
                StiffnessRule::InverseRestLength => 1.0,
                StiffnessRule::Uniform => {
                    let r = springs.rest_lengths(0);
                    r.iter().sum::<f64>() / r.len() as f64
                }
            };
        let hinges = HingeTerm::new(
            shapes,
            &topology,
            &o.hinges,
            mean_stiffness,
            mean_square_length,
        );
        let mut summary = RigSummary {
            vertices: n,
            springs: springs.len(),
            hinges: hinges.len(),
            ..Default::default()
        };
        let mut terms: Vec<Box<dyn EnergyTerm>> =
            vec![Box::new(SpringTerm::new(springs, o.min_rest_fraction))];
        if !hinges.is_empty() {
            terms.push(Box::new(hinges));
        }
        terms.extend(extra);

        let mut pairs = Vec::new();
        for t in &terms {
            t.couplings(&mut pairs);
        }
        if let Some(&[a, b]) = pairs
            .iter()
            .find(|p| p[0] as usize >= n || p[1] as usize >= n)
        {
            return Err(BlendError::InvalidOption(format!(
                "an energy term couples vertices {a} and {b}, but the mesh has {n} vertices"
            )));
        }
        let block_pattern = Arc::new(BlockPattern::new(n, &pairs));
        for t in &mut terms {
            t.bind(&block_pattern);
        }
        let components = Components::from_pairs(n, pairs);
        let kinematic = stretched_vertices(shapes, o.kinematic_stretch);
        let bands = thin_bands(&topology, &components, o.thin_band_rings);
        let constraints = Constraints::new(shapes, &components, &o.fixed, &kinematic, &bands)?;
        summary.fixed_vertices =
            constraints.fixed.len() - constraints.kinematic.len() - constraints.bands.len();
        summary.kinematic_vertices = constraints.kinematic.len();
        summary.band_vertices = constraints.bands.len();
        summary.gauged_components = constraints.gauges.len() + constraints.aligned.len();
        let vertex_order = match o.ordering {
            FillOrdering::NestedDissection | FillOrdering::Cheapest => {
                Some(vertex_nested_dissection(&block_pattern)?)
            }
            FillOrdering::Amd => None,
        };
        summary.predicted_bytes =
            predicted_bytes(&block_pattern, vertex_order.as_deref(), o.factor_precision)?
                + StartSamples::bytes(n, shapes.len() - 1, o.sampled_start);
        if estimate_only {
            return Ok(Built::Estimate(summary.predicted_bytes));
        }
        if summary.predicted_bytes > o.max_memory_bytes {
            return Err(BlendError::TooLarge {
                vertices: n,
                predicted_bytes: summary.predicted_bytes,
                limit_bytes: o.max_memory_bytes,
                basis: MemoryEstimate::Symbolic,
            });
        }
        let system = FreeSystem::new(block_pattern.clone(), &constraints.fixed_dof)?;
        let rotation = match o.predictor {
            Predictor::RotationAware => RotationPredictor::new(shapes, &components),
            Predictor::Linear => None,
        };
        // Held at the linear blend (bands are held at the predictor, which places them).
        let mut is_fixed = vec![false; n];
        for &v in &constraints.fixed {
            is_fixed[v as usize] = true;
        }
        for &v in &constraints.bands {
            is_fixed[v as usize] = false;
        }
        let mut orderings = Vec::with_capacity(2);
        if let Some(order) = &vertex_order {
            orderings.push(Ordering::Custom(expand_vertex_order(
                order,
                &system.dof_index,
            )));
        }
        if vertex_order.is_none() || o.ordering == FillOrdering::Cheapest {
            orderings.push(Ordering::Amd);
        }
        let (chol, chosen) = system.analyze(&orderings, o.factor_precision)?;
        summary.ordering = match orderings[chosen] {
            Ordering::Amd => FillOrdering::Amd,
            _ => FillOrdering::NestedDissection,
        };
        summary.free_dofs = system.num_free();
        summary.factor_nnz = chol.factor_nnz();
        summary.factor_flops = chol.factor_flops();
        let nnz = system.pattern.nnz();
        summary.hessian_entries = nnz;
        let aggregation = if o.uses_aggregation(chol.factor_flops(), nnz) {
            let levels = Arc::new(system.aggregation_levels()?);
            summary.aggregates = levels.num_aggregates();
            summary.coarse_flops = levels.coarse_flops();
            Some(levels)
        } else {
            None
        };
        if aggregation.is_none() && o.linear_solver == LinearSolver::TrustRegion {
            summary.reference_targets =
                References::targets(&chol, shapes.len() - 1, o.reference_factor_bytes);
        }
        let mut ws = Workspace::new(chol, BlockHessian::zeros(block_pattern), nnz);
        if let Some(levels) = &aggregation {
            ws.aggregation = Some(AggregationPreconditioner::new(levels.clone())?);
        }
        Ok(Built::Blend(Box::new(Self {
            rig: Arc::new(Rig {
                shapes: shapes.clone(),
                terms,
                constraints,
                system,
                options: o.clone(),
                tolerance,
                mean_stiffness,
                rotation,
                is_fixed,
                samples: StartSamples::new(shapes.len() - 1),
                references: References::new(summary.reference_targets),
                aggregation,
                summary,
            }),
            ws,
        })))
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
        for _ in 1..threads {
            let aggregation = match &self.rig.aggregation {
                Some(levels) => match AggregationPreconditioner::new(levels.clone()) {
                    Ok(a) => Some(a),
                    Err(_) => break,
                },
                None => None,
            };
            match self.ws.chol.share_symbolic() {
                Ok(chol) => {
                    let mut ws = Workspace::new(chol, self.ws.blocks.clone(), self.ws.exact.len());
                    ws.aggregation = aggregation;
                    workspaces.push(ws);
                }
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

impl Rig {
    fn check_targets(&self, targets: &[PointTarget]) -> Result<(), BlendError> {
        let n = self.shapes.num_vertices();
        for t in targets {
            let v = t.vertex as usize;
            if v >= n {
                return Err(BlendError::TargetOutOfRange {
                    vertex: t.vertex,
                    num_vertices: n,
                });
            }
            if !(t.stiffness.is_finite() && t.stiffness > 0.0)
                || t.position.iter().any(|c| !c.is_finite())
            {
                return Err(BlendError::InvalidOption(format!(
                    "the target of vertex {v} needs a finite position and a finite positive stiffness"
                )));
            }
            let c = &self.constraints;
            let free = c.gauges.iter().map(|g| &g.vertices);
            if free
                .chain(c.aligned.iter().map(|a| &a.vertices))
                .any(|comp| comp.binary_search(&t.vertex).is_ok())
            {
                return Err(BlendError::TargetOnFreeComponent { vertex: t.vertex });
            }
        }
        Ok(())
    }

    pub(super) fn solve(
        &self,
        ws: &mut Workspace,
        c: &[f64],
        targets: &[PointTarget],
        from: Start<'_>,
        factor: Factor<'_>,
    ) -> Result<BlendResult, BlendError> {
        let start = Instant::now();
        self.check_targets(targets)?;
        let lin = predictor::linear(&self.shapes, c);
        // One Poisson solve per frame: a given start needs the prediction only for the bands.
        let rotated = match from {
            // The tether pulls towards P, so it needs the prediction whatever the start.
            Start::From(_) if self.constraints.bands.is_empty() && self.options.tether == 0.0 => {
                None
            }
            _ => self.rotation_prediction(c, &lin),
        };
        let corrected;
        let start_from = match from {
            Start::From(p) => Some(p),
            Start::Plain => None,
            Start::Canonical if !self.options.sampled_start => None,
            Start::Canonical => {
                let correction = self.samples.correction(c, &mut Sampler { rig: self, ws });
                corrected = correction
                    .map(|d| shifted(self.world_prediction(&lin, rotated.as_deref()), &d, 1.0));
                corrected.as_deref()
            }
        };
        if start_from.is_some_and(|p| p.len() != self.shapes.num_vertices()) {
            return Err(BlendError::InvalidOption(
                "the start positions must have one point per vertex".into(),
            ));
        }
        let n = self.shapes.num_vertices();
        let dof = &self.system.dof_index;
        let free = |v: usize| (0..3).all(|a| dof[3 * v + a] != u32::MAX);
        let held = Held::new(n, targets, free);
        let mut soft: Vec<PointTarget> = targets.iter().filter(|t| !t.is_hard()).copied().collect();
        // P(w) in solver coordinates: the tether's targets, and the start when none is given.
        let predicted = (self.options.tether > 0.0 || start_from.is_none())
            .then(|| self.start(&lin, rotated.as_deref(), None));
        if let Some(p) = predicted.as_deref().filter(|_| self.options.tether > 0.0) {
            soft.extend(super::tether::targets(p, free, self.options.tether));
        }
        let points = PointTerm {
            targets: &soft,
            scale: self.mean_stiffness,
        };
        let mut terms: Vec<&dyn EnergyTerm> = self.terms.iter().map(|t| t.as_ref()).collect();
        let mut params: Vec<TermParameters> = self.terms.iter().map(|t| t.prepare(c)).collect();
        if !soft.is_empty() {
            terms.push(&points);
            params.push(TermParameters::default());
        }
        let mut x = match (start_from, predicted) {
            (None, Some(p)) => p,
            _ => self.start(&lin, rotated.as_deref(), start_from),
        };
        let mut stats = FrameStats {
            gradient_tolerance: self.tolerance,
            clamped_springs: params.iter().map(|p| p.clamped).sum(),
            ..Default::default()
        };
        held.place(&mut x);
        let prob = Problem {
            terms: &terms,
            params: &params,
            system: &self.system,
            held: &held,
            options: &self.options,
            tolerance: self.tolerance,
        };
        let reference = match factor {
            _ if self.options.linear_solver != LinearSolver::TrustRegion => None,
            Factor::Reference => self.reference(ws, c, true),
            Factor::Probe => self.reference(ws, c, false),
            _ => None,
        };
        stats.reference_factor = reference.is_some();
        let g = match self.options.linear_solver {
            LinearSolver::TrustRegion => {
                let probe = matches!(factor, Factor::Probe);
                trust_region(&prob, ws, &mut x, &mut stats, reference.as_deref(), probe)?
            }
            LinearSolver::Direct => projected_newton(&prob, ws, &mut x, &mut stats)?,
        };
        if let Factor::Produce(out) = factor {
            if stats.converged {
                *out = reference_at(&prob, ws, &x)?;
            }
        }
        if !stats.converged {
            stats.unconverged_vertices = prob.failed_vertices(&g);
        }
        let positions = predictor::output(&self.constraints, &x, &lin);
        stats.seconds = start.elapsed().as_secs_f64();
        Ok(BlendResult { positions, stats })
    }
}

/// Where a solve starts.
#[derive(Clone, Copy)]
pub(super) enum Start<'a> {
    /// The canonical start: the predictor, with the sampled correction when asked for.
    Canonical,
    /// The predictor alone (the sampled start's own samples).
    Plain,
    /// Given world positions (`#V`).
    From(&'a [Point]),
}

/// One-shot physical blend: builds a [`PhysicalBlend`] and solves once.
pub fn blend(
    shapes: &ShapeSet,
    weights: &Weights,
    options: &BlendOptions,
) -> Result<BlendResult, BlendError> {
    PhysicalBlend::new(shapes, options)?.solve(weights)
}
