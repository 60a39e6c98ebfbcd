//! Physical blendshapes: rest-length interpolation of a mass–spring system solved to
//! equilibrium (Ma et al. 2012, Sec. 3.1–3.3 and 3.5; corrected Hessian from the project's
//! math notes §1), made robust on real rigs.
//!
//! Each blendshape target defines the rest lengths of one spring system over the shared
//! connectivity: *structure springs* on every edge (Sec. 3.1; the paper's *bending springs*
//! between vertices at graph distance exactly two are available with
//! [`SpringOptions::bending`], off by default). Blending interpolates the rest lengths,
//! $\bar r_q = \sum_s c_s r_q^s$ (Eq. 1, Sec. 3.3), and the blended shape is an equilibrium of
//!
//! $$E(x) = \sum_q \tfrac12 k_q (\lVert x_i - x_j \rVert - \bar r_q)^2 + E_{\text{hinge}}(x),
//! \qquad k_q = k_0 / \bar r_q \text{ (Sec. 3.5)},$$
//!
//! where $E_{\text{hinge}}$ ([`terms::HingeTerm`]) is a weak signed-dihedral term that the paper
//! does not have, and the blend's bending term: a distance spring across an edge sees only the
//! cosine of the fold there, so it cannot tell a fold up from a fold down, and thin regions of
//! real meshes (lips, eyelids, ears) mirror themselves and crumple. The hinge interpolates the
//! signed dihedral angle instead. With it, the 2-ring springs are two thirds of the springs
//! and a third of the factor's entries and add nothing the hinge does not do better: measured
//! over every frame of the 36-step sequences of the ten horse poses and ten ICT expressions,
//! leaving them out gives fewer creases (horse-05: 40 instead of 94 over the sequence, linear
//! 316), no fold anywhere, ICT jawOpen's gums move at most 4.1× the linear blend's step where
//! they snapped by 25×, and the sequences solve 1.5× faster (docs/choices.md).
//!
//! # The canonical equilibrium
//!
//! Rest-length blending makes $E$ non-convex, with many local minima, so "the equilibrium" is
//! only defined together with the procedure that finds it. morphkit defines the blend for
//! weights $w$ (affine coefficients $c(w)$, $\sum_s c_s = 1$) as
//!
//! > $x^*(w)$ = the minimiser reached by the deterministic trust-region Newton iteration of
//! > [`newton`](self) (fixed budgets, schedules and tolerances, no timing) started from the
//! > start $\tilde P(w) = P(w) + \sum_{s \ge 1} q_s(c_s)$. The predictor $P(w)$ is the Poisson
//! > interpolation of the shapes' deformation gradients with rotations blended in the log map
//! > ([`Predictor::RotationAware`], Xu et al. 2005; each shape's logs on one branch along the
//! > surface, so a part that turns by about π keeps one way round), placed rigidly on the
//! > fixed vertices or the linear blend $\sum_s c_s x^s$ ([`Predictor::Linear`] uses that
//! > blend directly), then each gauged component aligned rigidly to the linear blend. The
//! > *sampled correction* $q_s$ ([`sampled_start`], [`BlendOptions::sampled_start`])
//! > interpolates how far target $s$'s own equilibria at $a = ¼, ½, ¾$ lie from $P$ (solved
//! > once per rig, ½ from $P$, ¼ and ¾ from $P$ plus the ½ sample's correction); it is zero
//! > at $c_s \in \{0, 1\}$. The energy includes a weak [`tether`] of every solved vertex to
//! > $P(w)$ ([`BlendOptions::tether`]), which lifts the soft modes where the blended lengths
//! > have two equilibria, so that consecutive frames follow one branch instead of snapping.
//!
//! Consequences, each tested:
//! - **Endpoints are exact.** At one-hot weights $P = x^s$, where every term has zero energy and
//!   gradient: the solve takes zero iterations and returns shape $s$ (within round-off).
//! - **A frame is a function of its weights alone.** No solve starts from, or reuses numbers of,
//!   an earlier frame (the symbolic analysis and buffers are reused, never values; the sampled
//!   correction's samples and the [reference factors](reference) that precondition frames
//!   near them are computed the same way whichever frame first needs them), so frame
//!   order, scrubbing back and forth, threads ([`PhysicalBlend::solve_many`]) and machine load
//!   do not change a bit of the result (buffers are 64-byte aligned, METIS orderings are
//!   computed one at a time; the tests compare frames for equality). `--alpha a` equals the matching frame of `--frames`.
//! - **A frame depends only on its nonzero weights.** Adding a target at weight 0 changes no
//!   frame: which vertices are held (automatic fixed and kinematic ones), which hinges act and
//!   where thin bands are anchored are decided per frame from the weights, fading over
//!   [`BlendOptions::hold_ramp`] so that frames stay continuous as a weight leaves 0 (`holds`).
//! - **Kinematic sheets.** Triangles stretched more than [`BlendOptions::kinematic_stretch`]
//!   (default 10×) between the base and a target are no material: while that target is
//!   active their vertices follow the linear blend as boundary conditions.
//! - **Thin bands.** Connected components every vertex of which lies within
//!   [`BlendOptions::thin_band_rings`] (default 4) edges of the boundary, and at least twice
//!   as long as wide ([`thin_bands`]: eye strips, tear films, eyelash and hair cards), have no
//!   material across their width and
//!   crumple under blended rest lengths; they are held at the predictor $P(w)$, also chosen
//!   once per rig.
//! - **Failures are loud.** A solve that does not reach the tolerance returns
//!   `converged = false` with the vertices whose residual force is above it.
//!
//! The pieces, one module each:
//! - [`SpringSet`]: which springs exist ([`SpringOptions`]) and their rest lengths per target;
//! - [`Weights`]: two-shape α, convex weights, or artist "delta" weights;
//! - [`terms`]: the energy as a sum of [`terms::EnergyTerm`]s (springs, hinges; later internal
//!   springs, anchors, pulls, contacts) writing into one block sparsity pattern;
//! - [`Constraints`]: fixed, automatic and kinematic vertices and, where nothing is fixed, a
//!   minimal gauge that removes only the rigid motions;
//! - the solver, a one-way stack (each layer uses only those below it):
//!   1. data filled once or on first need, which solves nothing: `system` (the free-coordinate
//!      Newton system), [`sampled_start`] (each target's correction fields),
//!      [`reference`] (frozen factors near grid weights);
//!   2. `newton` (the iterations on a [`terms`] energy) and `rig` (the prepared rig: terms,
//!      constraints, symbolic analysis, memory check);
//!   3. `predictor` (the rig's $P(w)$ and the output alignment);
//!   4. `solve` (one frame: its start, its reference factor, its iteration; it also fills the
//!      lazily computed sampled starts and references, which are solves themselves);
//!   5. [`FrameSolver`] (one thread's view) and, on top, `blender`: [`PhysicalBlend`] /
//!      [`blend`], set up once, then single, parallel and prepared solves;
//! - [`metrics`]: edge-length, area, volume, fold and crease measures against
//!   [`linear_blend`];
//! - [`continuity`]: jumps between consecutive frames of a sequence ([`ContinuityCheck`]),
//!   where the energy has two equilibria and a part snaps from one to the other.

mod blender;
mod constraints;
pub mod continuity;
mod direct;
mod frame;
mod frame_solver;
mod gauge;
mod guard_trust;
mod holds;
pub mod interactive;
pub mod interior;
mod memory;
pub mod metrics;
mod newton;
mod options;
mod predictor;
pub mod reference;
mod rig;
mod rotation_predictor;
pub mod sampled_start;
pub mod snaps;
mod solve;
mod spring_set;
mod steihaug;
mod system;
pub mod terms;
pub mod tether;
pub mod weights;
mod workspace;

pub use blender::{blend, PhysicalBlend};
pub use constraints::{
    stretched_vertices, thin_bands, AlignedComponent, Components, Constraints, FixedVertices, Gauge,
};
pub use continuity::{sequence_continuity, Continuity, ContinuityCheck, Jump, JUMP_BOUND};
pub(crate) use frame_solver::report_lost;
pub use frame_solver::FrameSolver;
pub use interactive::{InteractiveCacheUse, InteractiveSpace};
pub use interior::{
    AnchorOptions, AnchorPlacement, InteriorMode, InteriorOptions, SurfacePredictor,
    VolumetricBlend,
};
pub use memory::{SAMPLED_ABOVE, SAMPLE_VERTICES};
pub use metrics::{blend_metrics, fold_metrics, linear_blend, BlendMetrics, FoldMetrics};
pub use options::{
    BlendOptions, BlendResult, FillOrdering, FrameStats, LinearSolver, Precision, Preconditioner,
    Predictor, RigSummary, AGGREGATION_FLOPS_PER_ENTRY,
};
pub use predictor::BlendPredictor;
pub use spring_set::{Spring, SpringKind, SpringOptions, SpringSet, StiffnessRule, SCALE_RANGE};
pub use terms::{HingeOptions, PointTarget};
pub use weights::Weights;

/// What a memory prediction of [`BlendError::TooLarge`] rests on (see `springs::memory`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryEstimate {
    /// The symbolic analysis of the whole Hessian: the estimate the solver allocates by.
    Symbolic,
    /// A lower bound from the triangle count alone, before any connectivity is built.
    LowerBound,
    /// The symbolic analysis of a connected part of this many vertices, scaled to the mesh.
    Sampled {
        /// Vertices of the part.
        vertices: usize,
    },
}

impl MemoryEstimate {
    fn word(&self) -> &'static str {
        match self {
            Self::LowerBound => "at least",
            _ => "about",
        }
    }
    fn note(&self) -> String {
        match self {
            Self::Sampled { vertices } => format!(
                " (scaled from a connected part of {vertices} vertices, before the whole mesh was set up)"
            ),
            _ => String::new(),
        }
    }
}

/// Why a blend could not be computed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum BlendError {
    /// A weight is NaN or infinite.
    #[error("weight {index} is not finite ({value})")]
    NonFiniteWeight {
        /// Position of the weight.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A weight is larger in magnitude than [`weights::MAX_WEIGHT`].
    #[error("weight {index} is {value}; weights are limited to ±{max}")]
    WeightOutOfRange {
        /// Position of the weight.
        index: usize,
        /// Its value.
        value: f64,
        /// The bound.
        max: f64,
    },
    /// The number of weights does not fit the number of shapes.
    #[error("{kind} weights: {found} given, {expected} expected for {shapes} shapes")]
    WeightCount {
        /// Which kind of weights.
        kind: &'static str,
        /// How many were expected.
        expected: usize,
        /// How many were given.
        found: usize,
        /// Number of shapes in the set.
        shapes: usize,
    },
    /// Convex weights must be non-negative and sum to one.
    #[error("convex weights must be non-negative and sum to 1; they sum to {sum} (min {min})")]
    NotConvex {
        /// Their sum.
        sum: f64,
        /// Their smallest entry.
        min: f64,
    },
    /// A point target names a vertex that does not exist.
    #[error("point target on vertex {vertex}, but the mesh has {num_vertices} vertices")]
    TargetOutOfRange {
        /// The bad id.
        vertex: u32,
        /// Vertex count.
        num_vertices: usize,
    },
    /// A point target lies on a component that only the rigid gauge holds.
    #[error("point target on vertex {vertex}, whose component has no fixed vertices: fix at least 3 non-collinear vertices of it so that it has a place in the world to be pulled against")]
    TargetOnFreeComponent {
        /// The vertex.
        vertex: u32,
    },
    /// A fixed vertex id is out of range.
    #[error("fixed vertex {vertex} is out of range (the mesh has {num_vertices} vertices)")]
    FixedOutOfRange {
        /// The bad id.
        vertex: u32,
        /// Vertex count.
        num_vertices: usize,
    },
    /// A connected component has fixed vertices that do not pin down its rotations.
    #[error("component {component} (containing vertex {example_vertex}) has {fixed} fixed vertices that are collinear or too few: it can still rotate; fix at least 3 non-collinear vertices there, or none (then only its rigid motion is removed)")]
    UnderConstrained {
        /// Component label.
        component: usize,
        /// One vertex of the component.
        example_vertex: usize,
        /// Number of fixed vertices in it.
        fixed: usize,
    },
    /// The mesh or shape set is unusable.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// The shapes do not share one connectivity.
    #[error(transparent)]
    Shapes(#[from] crate::mesh::ShapeSetError),
    /// Options out of their valid range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// No spring is left.
    #[error("no springs to blend: {cause}")]
    NoSprings {
        /// Why.
        cause: &'static str,
    },
    /// A shape has no spring of positive length (all its vertices coincide).
    #[error("shape '{shape}' is degenerate: no edge has a positive length (do all its vertices coincide?)")]
    DegenerateShape {
        /// The shape's name.
        shape: String,
    },
    /// A shape's size is beyond what double precision can solve (squared lengths and their
    /// products would underflow to zero or overflow to infinity).
    #[error("shape '{shape}' has a size (largest bounding-box extent {extent:e}) outside the range the solver works in, {:e} to {:e}: its squared lengths would {}; rescale the meshes (the same factor for every shape, e.g. to centimetres or metres) and blend again", SCALE_RANGE.0, SCALE_RANGE.1, if *extent < SCALE_RANGE.0 { "underflow to zero" } else { "overflow to infinity" })]
    Scale {
        /// The shape's name (its file name when read from files).
        shape: String,
        /// Its largest bounding-box extent.
        extent: f64,
    },
    /// The solver would need more memory than allowed.
    #[error("the physical blend of {vertices} vertices would need {} {} of memory{}, over the limit of {}; raise the limit (--max-memory in the CLI), leave out bending springs if they are on, or blend a decimated mesh", basis.word(), gib(*predicted_bytes), basis.note(), gib(*limit_bytes))]
    TooLarge {
        /// Vertex count.
        vertices: usize,
        /// Predicted bytes of one solver.
        predicted_bytes: u64,
        /// The limit ([`BlendOptions::max_memory_bytes`]).
        limit_bytes: u64,
        /// What the prediction rests on.
        basis: MemoryEstimate,
    },
    /// The linear system could not be solved.
    #[error("equilibrium solve failed: {0}")]
    Solve(#[from] crate::sparse::SolveError),
    /// A saved interactive preparation cannot be used for this rig
    /// ([`PhysicalBlend::load_interactive`]).
    #[error("interactive preparation: {problem}")]
    InteractiveCache {
        /// What is wrong: truncated, another format version, or made for another rig.
        problem: String,
    },
    /// The Newton iteration produced a non-finite state.
    #[error("the Newton iteration diverged (non-finite energy) at iteration {iteration}")]
    Diverged {
        /// Newton iteration at which it happened.
        iteration: usize,
    },
    /// The caller's stop hook ended a long computation before its end (Ctrl-C in Python;
    /// [`PhysicalBlend::prepare_interactive_until`]): nothing of it was kept or written.
    #[error("{what} was stopped before its end; nothing of it was kept or written")]
    Stopped {
        /// What was stopped.
        what: String,
    },
}

fn gib(b: u64) -> String {
    format!("{:.2} GiB", b as f64 / (1u64 << 30) as f64)
}
