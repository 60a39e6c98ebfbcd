//! Physical blendshapes: rest-length interpolation of a mass–spring system solved to
//! equilibrium (Ma et al. 2012, Sec. 3.1–3.3 and 3.5; corrected Hessian from the project's
//! math notes §1).
//!
//! Each blendshape target defines the rest lengths of one spring system over the shared
//! connectivity: *structure springs* on every edge and *bending springs* between vertices at
//! graph distance exactly two (Sec. 3.1). Blending interpolates the rest lengths,
//! $\bar r_q = \sum_i w_i r_q^i$ (Eq. 1, Sec. 3.3), and the blended shape is the equilibrium of
//!
//! $$E(x) = \sum_q \tfrac12 k_q (\lVert x_i - x_j \rVert - \bar r_q)^2, \qquad k_q = k_0 / \bar r_q
//! \text{ (Sec. 3.5)},$$
//!
//! found by projected Newton with a backtracking line search ([`PhysicalBlend`]).
//!
//! The pieces, one module each:
//! - [`SpringSet`]: which springs exist ([`SpringOptions`]) and their rest lengths per target;
//! - [`Weights`]: two-shape α, convex weights, or artist "delta" weights, resolved to one convex
//!   combination of rest lengths with clamping;
//! - [`energy`]: $E$, $\nabla E$ and the projected Hessian, per spring;
//! - [`Constraints`]: fixed vertices (user-given or `auto`) and, where nothing is fixed, a
//!   minimal gauge that removes only the rigid motions;
//! - [`PhysicalBlend`] / [`blend`]: the stateful solver and its one-shot wrapper;
//! - [`metrics`]: edge-length, area and volume measures used to compare with [`linear_blend`].

mod constraints;
pub mod energy;
pub mod metrics;
mod pcg;
mod solver;
mod spring_set;
mod steihaug;
pub mod weights;

pub use constraints::{Constraints, FixedVertices, Gauge};
pub use metrics::{blend_metrics, linear_blend, BlendMetrics};
pub use solver::{
    blend, BlendOptions, BlendResult, FillOrdering, FrameStats, LinearSolver, PhysicalBlend,
};
pub use spring_set::{Spring, SpringKind, SpringOptions, SpringSet, StiffnessRule};
pub use weights::{RestLengths, Weights};

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
    /// Options out of their valid range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Every spring was removed by the options.
    #[error("the spring options select no springs")]
    NoSprings,
    /// The linear system could not be solved.
    #[error("equilibrium solve failed: {0}")]
    Solve(#[from] crate::sparse::SolveError),
    /// The Newton iteration produced a non-finite state.
    #[error("the Newton iteration diverged (non-finite energy) at iteration {iteration}")]
    Diverged {
        /// Newton iteration at which it happened.
        iteration: usize,
    },
}
