//! glTF 2.0 (`.gltf` JSON and `.glb` binary) meshes with morph targets and morph-weight
//! animations.
//!
//! Reading ([`read_gltf_morphs`]) uses the `gltf` crate and takes the **first mesh** of the
//! file: its triangle primitives are merged into one [`TriMesh`] (indices offset by the
//! vertices of the primitives before), node transforms are ignored (positions are the mesh's
//! own), the morph targets' `POSITION` displacements become absolute target positions, names
//! come from `mesh.extras.targetNames`, and the first animation channel that drives the
//! `weights` of a node using that mesh gives the weight keys.
//!
//! Writing ([`write_gltf_morphs`]) produces one buffer (the GLB `BIN` chunk, or a base64 data
//! URI in a `.gltf`, so the output is always one file), one mesh with one triangle primitive —
//! `f32` `POSITION` with `min`/`max`, `u32` indices, one `f32` `POSITION` displacement accessor
//! (with `min`/`max`) per morph target — `mesh.weights` all zero, `mesh.extras.targetNames`,
//! one node and one scene, and, when there are weight keys, one animation with a `LINEAR`
//! sampler on the node's `weights` path (what Blender and three.js play). Every accessor has its
//! own buffer view, 4-byte aligned, with the proper `target` for vertex data and indices.

mod buffers;
mod precheck;
mod read;
mod write;
mod write_scene;

pub use read::{parse_gltf_morphs, read_gltf_morphs};
pub use write::write_gltf_morphs;
pub use write_scene::{write_gltf_scene, GltfRigidMesh};

use crate::mesh::{Point, TriMesh};

/// A mesh with morph targets and an optional morph-weight animation, as stored in glTF.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct GltfMorphs {
    /// The base mesh (the primitives' `POSITION`s and indices).
    pub base: TriMesh,
    /// One name per morph target (`target_0`, … when the file gives none).
    pub target_names: Vec<String>,
    /// Absolute positions of each morph target: base + displacement, `#targets × #V`.
    pub targets: Vec<Vec<Point>>,
    /// Animation keys `(time in seconds, one weight per target)`, in time order; empty when the
    /// file has no morph-weight animation.
    pub weight_keys: Vec<(f64, Vec<f64>)>,
}

impl GltfMorphs {
    /// Positions at the given weights: base + Σ wᵢ (targetᵢ − base).
    pub fn evaluate(&self, weights: &[f64]) -> Vec<Point> {
        let mut p = self.base.positions.clone();
        for (t, &w) in self.targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            for ((q, a), b) in p.iter_mut().zip(t).zip(&self.base.positions) {
                for k in 0..3 {
                    q[k] += w * (a[k] - b[k]);
                }
            }
        }
        p
    }
}
