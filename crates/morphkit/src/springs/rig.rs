//! The prepared rig ([`Rig`]): everything a [`PhysicalBlend`](super::PhysicalBlend) builds
//! once and every solve reads — springs and hinges, constraints, the free system and its
//! symbolic analysis, the predictor's rotation data, and the lazily filled sampled-start
//! fields and reference factors. It is the bottom of the solver's stack:
//!
//! `rig` → `predictor`, `newton` → `solve` (one frame) → `frame_solver` → `blender`
//! (`PhysicalBlend`).
//!
//! Nothing here solves; the fields computed on first need (sampled starts, references) are
//! filled by the solve layer above through [`super::sampled_start::SampleSolver`].

use super::constraints::{stretched_by_target, thin_bands, Components, Constraints};
use super::holds::FrameHolds;
use super::options::{check_options, BlendOptions, LinearSolver, RigSummary};
use super::reference::References;
use super::rotation_predictor::RotationPredictor;
use super::sampled_start::StartSamples;
use super::system::{
    expand_vertex_order, predicted_bytes, vertex_nested_dissection, FreeSystem, SystemBytes,
};
use super::terms::{BlockHessian, BlockPattern, EnergyTerm, HingeTerm, PointTarget, SpringTerm};
use super::workspace::Workspace;
use super::{BlendError, FillOrdering, MemoryEstimate, Predictor, SpringSet, StiffnessRule};
use crate::mesh::{validate, ShapeSet, Topology};
use crate::sparse::{AggregationLevels, AggregationPreconditioner, Cholesky, Ordering};
use std::sync::Arc;

/// Everything that does not change between solves (shared by all threads).
pub(super) struct Rig {
    pub(super) shapes: ShapeSet,
    pub(super) terms: Vec<Box<dyn EnergyTerm>>,
    pub(super) constraints: Constraints,
    pub(super) system: FreeSystem,
    pub(super) options: BlendOptions,
    pub(super) tolerance: f64,
    /// Mean structure-spring stiffness on the base (the unit of point-target stiffness).
    pub(super) mean_stiffness: f64,
    /// The fold guard's absolute stiffness (0: off).
    pub(super) guard_weight: f64,
    /// The rotation-aware predictor, when asked for and possible.
    pub(super) rotation: Option<RotationPredictor>,
    /// Per vertex: held at the linear blend by a boundary condition (not the bands).
    pub(super) is_fixed: Vec<bool>,
    /// What each frame holds besides, from its weights.
    pub(super) holds: FrameHolds,
    /// Each target's correction fields of the sampled start.
    pub(super) samples: StartSamples,
    /// The aggregation cycle's pattern, when it preconditions instead of the factor.
    pub(super) aggregation: Option<Arc<AggregationLevels>>,
    /// Reference factors of frames near a grid weight of one target.
    pub(super) references: References,
    pub(super) summary: RigSummary,
}

/// What [`Rig::build`] made: the rig and a first numeric workspace, or only its memory
/// estimate.
pub(super) enum Built {
    Rig(Box<(Rig, Workspace)>),
    Estimate(u64),
}

impl Rig {
    /// Builds springs, hinges, constraints, the Hessian pattern and its symbolic
    /// factorization (or, with `estimate_only`, stops at the memory estimate).
    pub(super) fn build(
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
            super::memory::check_early(shapes, o, Rig::estimate_bytes)?;
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
        )
        .fading(o.hold_ramp);
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
        let stretched_by = stretched_by_target(shapes, o.kinematic_stretch);
        let mut kinematic: Vec<u32> = stretched_by.iter().flatten().copied().collect();
        kinematic.sort_unstable();
        kinematic.dedup();
        let bands = thin_bands(&topology, &components, o.thin_band_rings);
        let mut constraints = Constraints::new(shapes, &components, &o.fixed, &kinematic, &bands)?;
        summary.fixed_vertices =
            constraints.fixed.len() - constraints.kinematic.len() - constraints.bands.len();
        summary.kinematic_vertices = constraints.kinematic.len();
        let released = constraints.release_kinematic();
        let holds = FrameHolds::new(
            shapes,
            &constraints,
            &released,
            &stretched_by,
            o.fixed == super::FixedVertices::Auto,
            o.hold_ramp,
        );
        summary.band_vertices = constraints.bands.len();
        summary.gauged_components = constraints.gauges.len() + constraints.aligned.len();
        let vertex_order = match o.ordering {
            FillOrdering::NestedDissection | FillOrdering::Cheapest => {
                Some(vertex_nested_dissection(&block_pattern)?)
            }
            FillOrdering::Amd => None,
        };
        // Before the scalar system: the factor's fill decides only where no aggregation cycle
        // may replace it; the path actually used is decided (and checked) after the analysis.
        let samples_bytes = StartSamples::bytes(n, shapes.len() - 1, o.sampled_start);
        summary.predicted_bytes = predicted_bytes(
            &block_pattern,
            vertex_order.as_deref(),
            o.factor_precision,
            o.may_aggregate(),
        )? + samples_bytes;
        if summary.predicted_bytes > o.max_memory_bytes && !estimate_only {
            return Err(BlendError::TooLarge {
                vertices: n,
                predicted_bytes: summary.predicted_bytes,
                limit_bytes: o.max_memory_bytes,
                basis: MemoryEstimate::Symbolic,
            });
        }
        let system = FreeSystem::new(block_pattern.clone(), &constraints.fixed_dof)?;
        let rotation = match o.predictor {
            Predictor::RotationAware => RotationPredictor::new(shapes, &topology, &components),
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
        let (aggregation, chol) = choose_preconditioner(
            &system,
            chol,
            o,
            SystemBytes::new(n as u64, block_pattern.num_pairs() as u64),
            samples_bytes,
            &mut summary,
        )?;
        if let (Some(chol), LinearSolver::TrustRegion) = (&chol, o.linear_solver) {
            // References get what the limit leaves, and are counted.
            let left = o.max_memory_bytes.saturating_sub(summary.predicted_bytes);
            let budget = o.reference_factor_bytes.min(left);
            summary.reference_targets = References::targets(chol, shapes.len() - 1, budget);
            if summary.reference_targets > 0 {
                summary.predicted_bytes +=
                    (4 * summary.reference_targets as u64 + 1) * chol.factor_bytes();
            }
        }
        if estimate_only {
            // The path the blend would take, with its preconditioner's own memory (the
            // aggregation levels and the coarse factor are a seventh of a sheet's total).
            return Ok(Built::Estimate(summary.predicted_bytes));
        }
        // Numeric buffers only now, past the estimate (the early check estimates a part of
        // the mesh through this function and must not allocate its factor).
        let chol = chol.map(Cholesky::with_numeric).transpose()?;
        let cycle = match &aggregation {
            Some(levels) => Some(AggregationPreconditioner::new(levels.clone())?),
            None => None,
        };
        let ws = Workspace::new(chol, cycle, BlockHessian::zeros(block_pattern), nnz);
        Ok(Built::Rig(Box::new((
            Rig {
                shapes: shapes.clone(),
                terms,
                constraints,
                system,
                options: o.clone(),
                tolerance,
                mean_stiffness,
                guard_weight: if o.springs.structure {
                    o.fold_guard * mean_stiffness * mean_square_length
                } else {
                    0.0
                },
                rotation,
                is_fixed,
                holds,
                samples: StartSamples::new(shapes.len() - 1),
                references: References::new(summary.reference_targets),
                aggregation,
                summary,
            },
            ws,
        ))))
    }

    /// The memory estimate of a blend of `shapes` (bytes) on the path it would take (the
    /// factor or the aggregation cycle, with its levels), whatever the limit: the symbolic
    /// analysis and the aggregation levels are built, the solver's buffers are not, and the
    /// early checks are skipped.
    pub(super) fn estimate_bytes(
        shapes: &ShapeSet,
        options: &BlendOptions,
    ) -> Result<u64, BlendError> {
        let unlimited = BlendOptions {
            max_memory_bytes: u64::MAX,
            ..options.clone()
        };
        match Self::build(shapes, &unlimited, Vec::new(), true)? {
            Built::Estimate(b) => Ok(b),
            Built::Rig(_) => Err(BlendError::InvalidOption(
                "internal: a blend where an estimate was asked for".into(),
            )),
        }
    }

    pub(super) fn check_targets(&self, targets: &[PointTarget]) -> Result<(), BlendError> {
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

    /// The coefficients of sample `a` of target `s`: $(1-a)\,e_0 + a\,e_s$.
    pub(super) fn sample_coefficients(&self, s: usize, a: f64) -> Vec<f64> {
        let mut c = vec![0.0; self.shapes.len()];
        c[0] = 1.0 - a;
        c[s] = a;
        c
    }
}

/// The preconditioner of a blend (see [`super::Preconditioner`]) and its memory: the
/// aggregation levels when the cycle preconditions (the fine factor's symbolic analysis, which
/// only decided the choice, is then dropped), or the factor's symbolic analysis (its numeric
/// buffers come after the estimate). Sets `summary`'s predicted bytes for the path
/// chosen (with one workspace, and per further workspace) and its aggregation counts; fails
/// with [`BlendError::TooLarge`] when that path is over the limit.
fn choose_preconditioner(
    system: &FreeSystem,
    chol: Cholesky,
    o: &BlendOptions,
    sys: SystemBytes,
    samples_bytes: u64,
    summary: &mut RigSummary,
) -> Result<(Option<Arc<AggregationLevels>>, Option<Cholesky>), BlendError> {
    let nnz = system.pattern.nnz();
    let base = sys.shared + samples_bytes;
    let factor_ws = sys.workspace + chol.numeric_bytes();
    let wanted = o.uses_aggregation(chol.factor_flops(), nnz);
    let over = |b: u64| b > o.max_memory_bytes;
    let mut chosen = (None, base + factor_ws, factor_ws);
    // The cycle is not taken merely because the factor is over the limit: on a bent surface
    // sheet (8.1k vertices, every vertex free) the cycle-preconditioned Newton iteration did
    // not converge in 300 iterations (255 rejected steps), so such a blend is refused instead.
    if wanted {
        let levels = Arc::new(system.aggregation_levels()?);
        let (shared, cycle) = levels.bytes();
        summary.aggregates = levels.num_aggregates();
        summary.coarse_flops = levels.coarse_flops();
        let workspace = sys.workspace - sys.factor_only + cycle;
        chosen = (Some(levels), base + shared + workspace, workspace);
    }
    let (aggregation, predicted, workspace) = chosen;
    summary.predicted_bytes = predicted;
    summary.workspace_bytes = workspace;
    if over(predicted) {
        return Err(BlendError::TooLarge {
            vertices: summary.vertices,
            predicted_bytes: predicted,
            limit_bytes: o.max_memory_bytes,
            basis: MemoryEstimate::Symbolic,
        });
    }
    // The factor without numeric buffers yet (see `Rig::build`).
    let chol = aggregation.is_none().then_some(chol);
    Ok((aggregation, chol))
}
