//! Animation transfer between different meshes (Wang & Lee 2008; Sumner & Popović 2004).
//!
//! The pipeline:
//! 1. [`markers`]: marker pairs `[source_vertex, target_vertex]` (JSON, 0-based), validated.
//! 2. [`correspondence`]: both meshes warped by least-squares meshes ([`lsmesh`], with the
//!    mean-value Laplacian of [`laplacian`]) and compatible triangles found by centroid
//!    distance and normal direction; the result is a reusable [`Correspondence`] (JSON).
//! 3. [`gradients`]: per-triangle deformation gradients of every source frame relative to the
//!    source reference (fourth vertex along the scaled normal).
//! 4. [`solve`]: the prefactored deformation-transfer solve on the target's reference mesh,
//!    and [`animation`]: the frame-by-frame pipeline with the translation convention.

pub mod animation;
pub mod correspondence;
pub mod error;
pub mod fold_guard;
pub mod gradients;
pub mod kdtree;
pub mod laplacian;
pub mod lsmesh;
pub mod markers;
pub mod quality;
pub mod rig;
pub mod solve;
#[cfg(test)]
pub(crate) mod testmesh;

pub use animation::{
    transfer_animation, AnimationTransfer, GradientFrame, Placement, TransferOptions,
    TranslationMode,
};
pub use correspondence::{
    correspond, normal_agreement, Correspondence, CorrespondenceOptions, CorrespondenceResult,
    GradientCombine, MarkerResidual, RefineOptions, RefineStep, CONFIDENCE_FLOOR,
};
pub use error::{CorrespondenceError, MarkerError, Side, TransferError};
pub use fold_guard::{FoldGuard, GuardOutcome, GuardedFrame};
pub use gradients::{deformation_gradients, flipped_triangles, GradientOperator};
pub use laplacian::{mean_value_laplacian, LaplacianOptions, MeanValueLaplacian};
pub use lsmesh::{least_squares_mesh, LeastSquaresMesh, LsMeshOptions, OMEGA};
pub use markers::{Markers, MIN_MARKERS};
pub use quality::{
    correspondence_quality, cycle_consistency, fold_count, match_confidence, sharp_fold_edges,
    sharp_folds, CorrespondenceQuality, CycleConsistency, FoldCount, LOW_CONFIDENCE,
};
pub use rig::{transfer_rig, RigOptions, RigTransfer, TransferredShape};
pub use solve::{SolverOptions, TransferSolver, TriangleWeighting};
