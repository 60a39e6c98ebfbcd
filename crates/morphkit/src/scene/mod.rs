//! Physical interaction during the blend (Ma et al. 2012, Sec. 4, Figs. 2 and 5; math notes §1
//! "Physical interaction"): blendshapes that collide with rigid obstacles and vertices pulled
//! to keyframed positions.
//!
//! - [`Obstacle`]: a closed mesh or a primitive with a keyframed rigid motion;
//! - [`Pull`]: a vertex pulled to keyframed positions, hard or soft;
//! - `collide`: the Sec. 4 loop (detect, project to the surface, hold, solve again);
//! - [`SceneBlend`] / [`blend_scene`]: a prefactored
//!   [`PhysicalBlend`](crate::springs::PhysicalBlend) with obstacles and pulls;
//! - [`Scene`]: the TOML scene file of `morphkit blend --scene`, with errors naming the line
//!   and the key.
//!
//! Pulls and contacts are [`PointTarget`](crate::springs::PointTarget)s of
//! [`PhysicalBlend::solve_with`](crate::springs::PhysicalBlend::solve_with): hard ones are
//! boundary conditions held exactly, soft ones diagonal Hessian blocks, so either changes every
//! frame and every collision round without a new symbolic analysis. A scene can also carry the
//! internal springs and the anchor of [`VolumetricBlend`](crate::springs::VolumetricBlend)
//! ([`SceneBlend::with_interior`]): interior vertices are never contacts, and with an anchor
//! obstacles and pulls are mapped into the anchor's frame for the solve and back.

mod blend;
mod collide;
mod error;
mod file;
mod keys;
mod obstacle;
mod pulls;
// The loader of scene files; named like its module because it is what the module is about.
#[allow(clippy::module_inception)]
mod scene;
mod weights_file;

pub use blend::{blend_scene, SceneBlend, SceneFrame};
pub use collide::{CollisionOptions, CollisionStats, Contact};
pub use error::SceneError;
pub use obstacle::{Obstacle, ObstacleError, Placed, Primitive, RigidKey};
/// Rotations of obstacle keys: `parry3d-f64`'s unit quaternion (`glam::DQuat`).
pub use parry3d_f64::math::Rotation;
pub use pulls::{Pull, PullError, PullKey, PullKind};
pub use scene::Scene;
