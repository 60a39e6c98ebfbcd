//! Example-driven animation synthesis (Wang & Lee 2008, Sec. 3.1.1, 3.2–3.2.4, 4): a new
//! animation of a target mesh assembled from parts of several animations, "like playing a
//! jigsaw puzzle".
//!
//! The pipeline, one concept per module:
//! 1. [`flexibility`] (Eq. 1): how much each triangle bends against its neighbours over a
//!    source animation; carried to the target through the correspondence.
//! 2. [`partitions`] (Sec. 3.2.1): stiff and flexible partitions by threshold γ.
//! 3. [`scribble`] (Sec. 3.2.1): a scribble refined by intelligent scribbling.
//! 4. [`weights`] (Eq. 5): smooth blend weights over the triangle adjacency; or
//!    [`geodesic`] (Sec. 4): weights by heat-method geodesic distance for non-articulated meshes.
//! 5. [`gradient_blend`] (Sec. 3.2.2): polar-decomposed blending, modes blend and compound.
//! 6. [`pose`] (Sec. 3.2.4): rotating a selected partition of the target's reference pose.
//! 7. [`synthesizer`] (Sec. 3.2.3): the stateful, prefactored frame-by-frame synthesis, fed
//!    by a [`recipe`] (TOML).
//!
//! Every solve of positions goes through [`crate::transfer::TransferSolver`], factored once
//! per target.

pub mod colors;
pub mod error;
pub mod flexibility;
pub mod geodesic;
pub mod gradient_blend;
mod layer;
pub mod partitions;
pub mod pose;
pub mod recipe;
pub mod recipe_build;
pub mod recipe_weld;
pub mod scribble;
pub mod synthesizer;
pub mod weights;

pub use colors::{flexibility_colors, selection_colors};
pub use error::SynthError;
pub use flexibility::{flexibility, Flexibility, FlexibilityAccumulator};
pub use geodesic::{geodesic_distance, geodesic_weights, HeatGeodesics, HeatOptions};
pub use gradient_blend::{apply_layer, blend_gradient, blend_gradients, polar, BlendMode};
pub use partitions::{partitions, Partitions, GAMMA};
pub use pose::{axis_angle, edit_pose, rotation_gradients, PoseEdit, PoseEditor};
pub use recipe::{Recipe, RecipeError, RecipeFile};
pub use recipe_build::BuiltRecipe;
pub use scribble::{refine_scribble, Scribble, Selection};
pub use synthesizer::{
    synthesize, BlendRegion, LayerInfo, LayerSpec, PoseSpec, SynthFrame, SynthOptions, Synthesizer,
    Timing,
};
pub use weights::{blend_weights, BlendWeights, WeightSolver, KAPPA};
