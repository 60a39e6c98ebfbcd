//! Options of the physical blend, and what a solve reports.

use super::terms::HingeOptions;
use super::BlendError;
use super::{FixedVertices, SpringOptions};
use crate::mesh::Point;
pub use crate::sparse::Precision;

/// Options of the physical blend. Every field has a meaningful default.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendOptions {
    /// Which distance springs and how stiff (Ma et al. Sec. 3.1, 3.5).
    pub springs: SpringOptions,
    /// The signed-hinge bending term (weight 0 turns it off).
    pub hinges: HingeOptions,
    /// Boundary conditions. Default [`FixedVertices::Auto`].
    pub fixed: FixedVertices,
    /// Convergence: stop when $\max_k |\partial E / \partial x_k| \le$ `gradient_tolerance`
    /// $\cdot k_0 \cdot s$ over the free coordinates, with $s = 1$ for the $k = k_0/\bar r$
    /// rule (the gradient is then a force in units of $k_0$ times strain, independent of the
    /// mesh's scale) and $s$ = the mean base rest length for uniform stiffness. Default
    /// `1e-6`: residual forces of one part per million of strain on one spring.
    pub gradient_tolerance: f64,
    /// Newton iterations allowed per solve; a solve that has not converged by then is
    /// returned with `converged = false` and the vertices that failed. Default `300`.
    pub max_newton_iterations: usize,
    /// Newton iterations over which a solve's largest gradient entry must fall below half of
    /// its best before them, or the solve stops unconverged (issue 54: where no equilibrium
    /// lies near the start it crept for minutes). `0`: no such rule. Default `100`.
    pub stall_iterations: usize,
    /// Numeric factorizations (regularization retries included) one frame may use before it
    /// stops unconverged (issue 54; set-up solves such as the sampled start's samples and the
    /// interactive snapshots run to convergence). `0`: no limit. Default `300`. Both rules are counts over
    /// the iterates, never times, so a frame stays a function of its weights.
    pub max_factorizations: usize,
    /// Solves a frame by continuation along the ray from the rest shape (issue 54): `K > 1`
    /// solves at the weights `(j/K) w`, `j = 1 … K`, the first from the canonical start, each
    /// next one from the last equilibrium moved as the predictor moves, so that a frame keeps
    /// the branch its ray starts on where two equilibria are near (a fresh start can land in
    /// either). One-hot weights keep their shape's own numbers. `0` or `1`: one solve from the
    /// canonical start (the default). At most 64. About K times the work; docs/choices.md,
    /// "Continuity in the weights", has the measurements.
    pub continuation_steps: usize,
    /// Interpolated rest lengths are clamped below at this fraction of the spring's shortest
    /// length over the shapes (only extrapolated weights reach it; counted per frame), and
    /// stiffness $k_0/\bar r$ uses at least this fraction of its longest. Default `0.05`.
    pub min_rest_fraction: f64,
    /// Triangles stretched by more than this factor (largest singular value of their 2D
    /// deformation) between the base and any target are *kinematic*: no material stretches
    /// that far, so their vertices follow the linear blend as boundary conditions instead of
    /// being solved for (an opening mouth's inner lips and mouth interior, a slit that opens).
    /// `f64::INFINITY` turns this off. Default `10`: the tenfold stretch of an opening mouth's
    /// inner strip (ICT jawOpen stretches its mouth interior up to 30× and its lips 116×);
    /// the horse poses stretch at most 3 triangles past it (11×), and compress up to 30×,
    /// which never counts.
    pub kinematic_stretch: f64,
    /// The weight over which per-frame holds fade ([`holds`](super::holds)): a vertex that
    /// only targets of weight below it move is pulled towards the linear blend, exactly at
    /// weight 0 as in a rig without those targets; a kinematic vertex is held exactly once a
    /// target that over-stretches it reaches it, and free at weight 0. So a frame depends only
    /// on its nonzero weights, and stays continuous as a weight leaves 0. Default `0.05`.
    pub hold_ramp: f64,
    /// Stiffness of the *fold guard*, in the hinges' unit (mean structure stiffness times mean
    /// squared rest length): a one-sided penalty on triangles turned more than about 84° from
    /// their place in the predictor $P(w)$, where that place agrees with the linear blend
    /// (`terms::orientation`). Zero wherever no triangle turns over, so it changes no other
    /// equilibrium. `0` turns it off. Default `1`.
    pub fold_guard: f64,
    /// Components every vertex of which lies within this many mesh edges of the boundary, and
    /// at least twice as long as wide, are *thin bands* ([`thin_bands`](super::thin_bands)):
    /// strips and cards such as a face rig's eye-occlusion strips, tear films and eyelashes.
    /// They have no material across their width, buckle under the blended rest lengths and
    /// snap between frames, so they follow the predictor $P(w)$ as boundary conditions. `0`
    /// turns this off. Default `4` (a band up to about 9 edges across): the ICT head's strips
    /// and cards are 1–4 rings wide, its mouth socket 16, its face 89; the horse, the camel
    /// and the closed meshes have none.
    pub thin_band_rings: usize,
    /// Stiffness of the *predictor tether*, in units of the mean spring stiffness: every
    /// vertex whose coordinates are solved for is tied by a zero-length spring to its place in
    /// the predictor $P(w)$ ([`tether`](super::tether)). `0` turns it off. Default `1e-5`:
    /// far too weak to change a strained region, it lifts the soft modes of rest-length
    /// blending, parts that swing about a line of vertices at no cost in length, where the
    /// blended lengths have two equilibria and a sequence snaps between them. Only such parts
    /// move: over 36-step sequences, ICT mouthSmile_L's frames by at most 1e-4 of the
    /// diagonal, horse-05's freely turning lower legs by up to 2 % towards $P$ (0.2 % on
    /// average over the vertices). Measured on all twenty 36-step
    /// real sequences (docs/performance.md): largest step over the linear blend's 6.81 → 1.71
    /// (horse-04), 4.10 → 2.98 (ICT jawOpen), no fold; 3e-6 still joins them (at most 3.50),
    /// 1e-4 folds a triangle on two horse poses.
    pub tether: f64,
    /// Armijo sufficient-decrease constant of the [`LinearSolver::Direct`] line search.
    /// Default `1e-4`.
    pub armijo: f64,
    /// Where each solve starts. Default [`Predictor::RotationAware`].
    pub predictor: Predictor,
    /// Start each solve from the predictor corrected by every target's equilibria at three
    /// sample weights ([`sampled_start`](super::sampled_start)), computed once per target on
    /// the first solve that needs them. Default `true`: frames between the shapes then need
    /// about half the Newton iterations and factorizations, at the price of three extra solves
    /// per target used (so a single frame costs more; an animation or a slider costs less).
    pub sampled_start: bool,
    /// How Newton systems are solved. Default [`LinearSolver::TrustRegion`].
    pub linear_solver: LinearSolver,
    /// Fill-reducing ordering of the Hessian. Default [`FillOrdering::Cheapest`].
    pub ordering: FillOrdering,
    /// Preconditioner of the trust-region iteration's inner CG ([`LinearSolver::TrustRegion`]
    /// only). Default [`Preconditioner::Auto`].
    pub preconditioner: Preconditioner,
    /// Inner conjugate-gradient iterations per trust-region step before the preconditioner
    /// is refreshed (doubled while steps keep running out). Default `40`. A count, never a
    /// time, so that results do not depend on the machine's load.
    pub cg_iterations: usize,
    /// Arithmetic of the preconditioner's Cholesky factor. Default [`Precision::Single`]: the
    /// factor only preconditions the `f64` conjugate-gradient iteration on the exact Hessian
    /// and defines the trust-region norm, so an `f32` factor leaves the equilibrium to the
    /// gradient tolerance, while it halves the factor's memory and is about 1.5× faster per
    /// step (horse, measured). A single-precision factorization that fails even with the
    /// largest regularization is repeated in double precision.
    pub factor_precision: Precision,
    /// Refresh the preconditioner's factorization every this many trust-region iterations
    /// (`0`: only when the inner iteration stalls). Default `1`.
    pub refactor_every: usize,
    /// …unless the last inner solve converged inside the trust region within this many CG
    /// iterations: the factor then still fits the Hessian and is kept for the next step
    /// (`0` turns this off). Default `8`. Near the equilibrium the Hessian changes little, so
    /// the last Newton steps of a frame reuse the factor of the first: per step over 12-step
    /// sequences (`morphkit bench --suite springs`, one thread), tubes 2.2k/18.6k 73 → 37 ms and
    /// 917 → 563 ms, horse ↔ horse-05 1039 → 759 ms, ICT jawOpen 5055 → 4443 ms, armadillo
    /// 1403 → 1313 ms. A count, never a time, so results do not depend on the machine's load.
    pub keep_factor_cg: usize,
    /// Memory for [reference factors](super::reference), in bytes (`0` turns them off). A
    /// frame with one target's weight $0 < a < 1$ preconditions with the factor at the
    /// nearest of that target's equilibria at $a \in \{0, ¼, ½, ¾, 1\}$, turned by each
    /// vertex's rotation, instead of factorizing on its own, when that target passed a probe
    /// solve at $a = ⅜$. Targets get references in their order while five factors each (the
    /// base's shared) fit this budget; a count of bytes from the symbolic analysis, so which
    /// frames use them depends on the rig alone. Only with the trust region and the factor
    /// (not the aggregation cycle). Default 1 GiB.
    pub reference_factor_bytes: u64,
    /// Largest predicted memory of one solver, in bytes; a larger problem is refused before
    /// anything big is allocated, with the estimate in the error. Default 8 GiB.
    pub max_memory_bytes: u64,
}

/// Refuses options outside their documented ranges.
pub(crate) fn check_options(o: &BlendOptions) -> Result<(), BlendError> {
    let bad = |name: &str, why: &str, v: f64| {
        Err(BlendError::InvalidOption(format!(
            "{name} must be {why}, got {v:e}"
        )))
    };
    let finite_pos = |v: f64| v.is_finite() && v > 0.0;
    if !finite_pos(o.gradient_tolerance) {
        return bad(
            "the gradient tolerance",
            "finite and positive",
            o.gradient_tolerance,
        );
    }
    if !finite_pos(o.springs.k0) {
        return bad("k0", "finite and positive", o.springs.k0);
    }
    if !(o.springs.bending_scale.is_finite() && o.springs.bending_scale >= 0.0) {
        return bad(
            "the bending scale",
            "finite and non-negative",
            o.springs.bending_scale,
        );
    }
    if !(o.hinges.weight.is_finite() && o.hinges.weight >= 0.0) {
        return bad(
            "the hinge weight",
            "finite and non-negative",
            o.hinges.weight,
        );
    }
    if !(o.tether.is_finite() && o.tether >= 0.0) {
        return bad("the tether", "finite and non-negative", o.tether);
    }
    if !(o.min_rest_fraction > 0.0 && o.min_rest_fraction < 1.0) {
        return bad("min_rest_fraction", "in (0, 1)", o.min_rest_fraction);
    }
    if o.continuation_steps > 64 {
        return bad(
            "the continuation steps",
            "at most 64",
            o.continuation_steps as f64,
        );
    }
    if !(o.fold_guard.is_finite() && o.fold_guard >= 0.0) {
        return bad("the fold guard", "finite and non-negative", o.fold_guard);
    }
    if !(o.hold_ramp.is_finite() && o.hold_ramp > 0.0 && o.hold_ramp <= 1.0) {
        return bad("the hold ramp", "in (0, 1]", o.hold_ramp);
    }
    if o.kinematic_stretch.is_nan() || o.kinematic_stretch <= 1.0 {
        return bad(
            "the kinematic stretch",
            "greater than 1 (or infinite)",
            o.kinematic_stretch,
        );
    }
    Ok(())
}

/// Where every solve starts (the predictor P(w) of the canonical equilibrium).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Predictor {
    /// The linear blend of the shapes.
    Linear,
    /// Poisson interpolation of the shapes' deformation gradients, rotations blended in the
    /// log map (Xu et al. 2005): parts that turn are predicted turned, not cut along the
    /// chord. Falls back to the linear blend where the base cannot carry a Poisson solve.
    /// The default.
    #[default]
    RotationAware,
}

/// Fill-reducing ordering for the Hessian's Cholesky factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FillOrdering {
    /// faer's approximate minimum degree on the coordinate graph.
    Amd,
    /// METIS nested dissection on the vertex graph, expanded to coordinates.
    NestedDissection,
    /// Both, keeping the one whose factorization takes fewer multiply-adds (counted from the
    /// symbolic structure, so the choice is a function of the pattern alone), but never one
    /// whose factor has more entries than nested dissection's, with which the memory check
    /// ([`BlendOptions::max_memory_bytes`]) estimates. The default: neither wins everywhere.
    /// With the hinge pattern, AMD is cheaper on the horse (7.5e8 against 8.7e8 multiply-adds,
    /// 4.03 M against 4.24 M entries, and 25 % faster per step), nested dissection on the ICT
    /// head (2.1e9 against 2.3e9, 8.41 M against 8.79 M).
    #[default]
    Cheapest,
}

/// The preconditioner (and trust-region norm) of [`LinearSolver::TrustRegion`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Preconditioner {
    /// A sparse Cholesky factor of the projected Hessian: near the equilibrium the inner CG
    /// converges in one or two iterations, at the price of the factor's fill.
    Cholesky,
    /// The two-level aggregation cycle of [`crate::sparse::AggregationPreconditioner`] on
    /// the projected Hessian (rigid modes of vertex aggregates as the coarse space): no fine
    /// factor at all, more CG iterations. For volumetric systems, whose factor fills with the
    /// body's cross-sections.
    Aggregation,
    /// [`Self::Aggregation`] when the Cholesky factor would cost more than
    /// [`AGGREGATION_FLOPS_PER_ENTRY`] multiply-adds per stored Hessian entry (a count from the
    /// symbolic analysis, never a timing), [`Self::Cholesky`] otherwise. The default. (Not
    /// when only the cycle would fit [`BlendOptions::max_memory_bytes`]: on bent surface
    /// sheets the cycle-preconditioned iteration does not converge; such blends are refused.)
    #[default]
    Auto,
}

/// The fill threshold of [`Preconditioner::Auto`]: factor multiply-adds per stored
/// lower-triangle entry of the Hessian above which the aggregation cycle is used.
pub const AGGREGATION_FLOPS_PER_ENTRY: f64 = 1.0e4;

impl BlendOptions {
    /// Whether the inner CG is preconditioned by the aggregation cycle rather than the
    /// factor, for a factorization of `factor_flops` multiply-adds of a Hessian with
    /// `hessian_nnz` stored entries (see [`Preconditioner`]). Only the trust-region iteration
    /// has an inner CG.
    /// Whether the aggregation cycle may precondition (so that the factor's memory does not
    /// decide a refusal before the scalar analysis).
    pub(crate) fn may_aggregate(&self) -> bool {
        self.preconditioner != Preconditioner::Cholesky
            && self.linear_solver == LinearSolver::TrustRegion
    }

    pub(crate) fn uses_aggregation(&self, factor_flops: f64, hessian_nnz: usize) -> bool {
        let wanted = match self.preconditioner {
            Preconditioner::Aggregation => true,
            Preconditioner::Cholesky => false,
            Preconditioner::Auto => {
                factor_flops > AGGREGATION_FLOPS_PER_ENTRY * hessian_nnz.max(1) as f64
            }
        };
        wanted && self.linear_solver == LinearSolver::TrustRegion && hessian_nnz > 0
    }
}

/// How each Newton system is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Projected Newton with an Armijo line search and a fresh numeric factorization per step.
    Direct,
    /// Trust-region Newton–CG (Steihaug–Toint) on the exact Hessian, preconditioned by a
    /// Cholesky factorization of the projected Hessian that is refreshed only when the inner
    /// iteration stalls. The default.
    #[default]
    TrustRegion,
}

impl Default for BlendOptions {
    fn default() -> Self {
        Self {
            springs: SpringOptions::default(),
            hinges: HingeOptions::default(),
            fixed: FixedVertices::Auto,
            gradient_tolerance: 1e-6,
            max_newton_iterations: 300,
            stall_iterations: 100,
            max_factorizations: 300,
            continuation_steps: 0,
            min_rest_fraction: 0.05,
            kinematic_stretch: 10.0,
            hold_ramp: 0.05,
            fold_guard: 1.0,
            thin_band_rings: 4,
            tether: 1e-5,
            armijo: 1e-4,
            predictor: Predictor::RotationAware,
            sampled_start: true,
            linear_solver: LinearSolver::TrustRegion,
            ordering: FillOrdering::Cheapest,
            preconditioner: Preconditioner::Auto,
            cg_iterations: 40,
            factor_precision: Precision::Single,
            refactor_every: 1,
            keep_factor_cg: 8,
            reference_factor_bytes: 1 << 30,
            max_memory_bytes: 8 << 30,
        }
    }
}

/// Solver statistics of one solve.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Newton (outer) iterations.
    pub newton_iterations: usize,
    /// Rejected steps (trust-region shrinks or line-search halvings).
    pub rejected_steps: usize,
    /// Numeric factorizations (including regularization retries).
    pub factorizations: usize,
    /// Inner conjugate-gradient iterations.
    pub cg_iterations: usize,
    /// Final $\max_k |\partial E/\partial x_k|$ over free coordinates.
    pub gradient_norm: f64,
    /// The tolerance it was compared with (absolute).
    pub gradient_tolerance: f64,
    /// Final energy.
    pub energy: f64,
    /// Whether the gradient reached the tolerance.
    pub converged: bool,
    /// Springs (and hinges) whose interpolated rest parameter was clamped.
    pub clamped_springs: usize,
    /// When not converged: vertices whose residual force exceeds the tolerance, largest
    /// first (at most 10 000).
    pub unconverged_vertices: Vec<u32>,
    /// Whether the inner iterations started on a shared
    /// [reference factor](super::reference) (and, with no factorizations, ended on it).
    pub reference_factor: bool,
    /// The interactive mode's estimate of its distance from the equilibrium, as a fraction
    /// of the base's bounding-box diagonal (the largest vertex move of one more
    /// preconditioned step); `None` for full solves.
    pub error_estimate: Option<f64>,
    /// Wall time in seconds (reported only; no decision depends on it).
    pub seconds: f64,
}

/// A blended shape and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendResult {
    /// Vertex positions, `#V`.
    pub positions: Vec<Point>,
    /// Solver statistics.
    pub stats: FrameStats,
}

/// What a [`PhysicalBlend`](super::PhysicalBlend) was built with.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RigSummary {
    /// Vertices.
    pub vertices: usize,
    /// Distance springs.
    pub springs: usize,
    /// Signed hinges.
    pub hinges: usize,
    /// Vertices held by boundary conditions (user-given or automatic).
    pub fixed_vertices: usize,
    /// Stored (lower-triangle) entries of the Newton matrix.
    pub hessian_entries: usize,
    /// Aggregates of the [`Preconditioner::Aggregation`] cycle (`0`: the Cholesky factor
    /// preconditions, and [`Self::factor_nnz`] / [`Self::factor_flops`] are its size).
    pub aggregates: usize,
    /// Multiply-adds of one factorization of the aggregation cycle's coarse matrix.
    pub coarse_flops: f64,
    /// Vertices of over-stretched (kinematic) triangles that follow the linear blend.
    pub kinematic_vertices: usize,
    /// Vertices of thin bands that follow the predictor
    /// ([`BlendOptions::thin_band_rings`]).
    pub band_vertices: usize,
    /// Connected components with no place in the world of their own, aligned rigidly to
    /// the linear blend after each solve: those held only by the rigid gauge, and those held
    /// only by kinematic vertices.
    pub gauged_components: usize,
    /// Free unknowns of the Newton system.
    pub free_dofs: usize,
    /// Stored entries of the Cholesky factor.
    pub factor_nnz: usize,
    /// Multiply-adds of one numeric factorization (from the symbolic structure).
    pub factor_flops: f64,
    /// The fill-reducing ordering used: [`FillOrdering::Amd`] or
    /// [`FillOrdering::NestedDissection`] (never `Cheapest`, which picks one of them).
    pub ordering: FillOrdering,
    /// Predicted bytes of the blend with one solver workspace (the memory check): the
    /// system, the preconditioner actually used and the reference factors' share.
    pub predicted_bytes: u64,
    /// Predicted bytes of each further workspace (a thread solving frames in parallel);
    /// threads get one only while the total stays within
    /// [`BlendOptions::max_memory_bytes`].
    pub workspace_bytes: u64,
    /// Targets whose frames may precondition with
    /// [reference factors](BlendOptions::reference_factor_bytes) (the first this many).
    pub reference_targets: usize,
}
