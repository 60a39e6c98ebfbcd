//! glTF 2.0 (`.gltf` JSON and `.glb` binary) meshes with morph targets and morph-weight
//! animations.
//!
//! Reading ([`read_gltf_morphs`], or [`read_gltf_morphs_with`] to choose a mesh by name with
//! [`GltfReadOptions::mesh`]) takes **the mesh with morph targets**: when several meshes have
//! morph targets the caller must choose one (the error lists their names); when none has, the
//! first mesh. Its triangle primitives, indexed or not (consecutive vertex triples), are merged
//! into one [`TriMesh`] (indices offset by the vertices of the primitives before). Node
//! transforms are not applied: positions are in the mesh's own space (a quantized file keeps
//! its dequantization on the node, so its positions are then in integer units; morphkit's own
//! quantized files are the exception, their `mesh.extras.morphkitDequantization` is applied).
//! The morph
//! targets' `POSITION` displacements become absolute target positions, names come from
//! `mesh.extras.targetNames`, and the first animation channel that drives the `weights` of a
//! node using that mesh gives the weight keys (`STEP`, `LINEAR`, or the values of
//! `CUBICSPLINE` keys). Accessors are decoded by morphkit (every component type, `normalized`,
//! `byteStride`, sparse accessors, accessors without a buffer view), so files written by
//! exporters' tools are read: `KHR_mesh_quantization` (gltfpack's default),
//! `EXT_meshopt_compression` / `KHR_meshopt_compression` (`gltfpack -c`, `gltf-transform
//! meshopt`), sparse storage (`gltf-transform sparse`). Required extensions that change only
//! materials, textures, lights or instancing are ignored; any other required extension (for
//! example `KHR_draco_mesh_compression`) is an error naming it. A long animation that
//! [`write_gltf_with`] split into several meshes (their `extras.morphkitTargets`) is read back
//! as one rig: every target once, the windows' keys merged in time order. See
//! `docs/gltf-input.md`.
//!
//! Writing ([`write_gltf_with`], or [`write_gltf_morphs`] with the default [`GltfOptions`])
//! produces one buffer (the GLB `BIN` chunk, or a base64 data URI in a `.gltf`, so the output
//! is always one file) and this layout (glTF 2.0 §3.7 meshes, §3.11 animations):
//!
//! - **Geometry, shared.** One `f32` `POSITION` accessor (with `min`/`max`), one unit `NORMAL`
//!   accessor (area-weighted vertex normals; [`GltfOptions::normals`]), `u32` indices, and per
//!   morph target one `POSITION` displacement accessor (with `min`/`max`) and one `NORMAL`
//!   delta accessor (target normal − base normal, §3.7.2.2). Every accessor has its own
//!   4-byte-aligned buffer view with the proper `target`.
//! - **Material.** One default PBR metallic-roughness material (§3.9.2: light grey, metallic 0,
//!   roughness 0.6), `doubleSided` when the mesh is open (has boundary edges), so the inside of
//!   an open surface is not culled.
//! - **Weights animation, stored sparsely.** Keys are `LINEAR` on the node's `weights` path.
//!   The output accessor (keys × targets floats) is a **sparse accessor without a buffer view**
//!   (§3.6.2.3: it starts all zero and lists only the nonzero weights with `u32` indices), so a
//!   frame sequence, where each key has one nonzero weight, costs 8 bytes per key instead of
//!   4 × targets. Dense output is kept when it is smaller.
//! - **Long animations are split** ([`GltfOptions::max_targets`], default
//!   [`SAFE_MORPH_TARGETS`]). Viewers hold all morph targets of a mesh at once (three.js packs
//!   them into one texture array and one uniform array, limited by the GPU: WebGL2 guarantees 256
//!   layers and 256 vertex uniform vectors), so a mesh with thousands of targets silently stays
//!   at its base. When an animation needs more targets than the limit, the keys are cut into
//!   consecutive windows needing at most `max_targets` targets each (neighbouring windows share
//!   their boundary key). Each window is one mesh and one node: the meshes share the base
//!   accessors, and a target used by two windows shares its accessor, so nothing is stored twice.
//!   Each node has its own `weights` channel over its window, and a `STEP` `scale` channel
//!   (§3.11.2) shows it (scale 1) during its window and hides it (scale 0) otherwise; every node
//!   but the first starts hidden. Such meshes carry `extras.morphkitTargets` (the original index
//!   of each of their targets), from which [`read_gltf_morphs`] puts the rig back together.
//! - **Or compact** ([`compact_frames`], [`write_compact_frames_with`]; the CLI's default for a
//!   sequence longer than `--max-targets`): a few shapes spanning the frames' displacements and
//!   one weight per shape and key, within a tolerance of every frame, in one mesh.
//! - **Smaller, on request** ([`GltfOptions::quantize`], [`GltfOptions::sparse_targets`]; the
//!   CLI's `--quantize` and `--sparse-targets`). Quantized: `KHR_mesh_quantization` (used and
//!   required), positions and position deltas normalized `i16` with the dequantizing offset and
//!   uniform scale as every node's `translation` and `scale` (a split window is shown at that
//!   scale, hidden at 0) and as `mesh.extras.morphkitDequantization`, which the reader applies;
//!   normals and normal deltas normalized `i8`. Positions read back within `√3 / 65534`
//!   (2.7e-5) of the bounding-box diagonal; a target whose deltas do not fit keeps `f32` for
//!   them ([`GltfSummary`] counts them). Sparse: each target's delta accessors list only the
//!   vertices that move, when that is smaller. Details in `write_vertices.rs`. Measured on the
//!   2 100-frame cragl tube (`morphkit blend --base cylinder-rest.obj --target
//!   cylinder-bend-4.obj --frames 2100 --linear --out tube2100`, then `morphkit convert tube2100
//!   [FLAGS] tube2100.glb`): 22.2 MB by default, 16.0 MB sparse, 12.6 MB quantized (305 of 2 099
//!   targets keep `f32` normal deltas: the tube bends by more than 90°), 7.8 MB both.
//! - **Names and extras.** Node, mesh, material and clip are named after
//!   [`GltfOptions::name`] and [`GltfOptions::clip_name`]; `mesh.extras.targetNames` holds the
//!   target names; [`GltfOptions::extras`] becomes `scenes[0].extras` (the command, the sources,
//!   the blend weights per frame), where Blender shows it as custom properties.
//!
//! **Editing a user's asset** ([`GltfAsset`]): the writer above makes a fresh file with only the
//! rig in it. To give users their own asset back (materials, textures, skins, other meshes and
//! nodes, names, extras, transforms), read it whole with [`GltfAsset::read`], edit its chosen
//! mesh ([`GltfAsset::set_base`], [`GltfAsset::add_targets`], [`GltfAsset::add_frame_animation`])
//! and [`GltfAsset::write`] it: everything not edited is carried, all buffers are merged into
//! one and external images embedded. See `docs/gltf-assets.md`.

mod accessor;
mod anim;
mod asset;
mod asset_anim;
mod asset_edit;
mod asset_pack;
mod asset_write;
mod budget;
mod buffers;
mod choose;
mod compact_frames;
mod extensions;
mod meshopt_pack;
mod normals;
mod precheck;
mod read;
mod read_chunks;
mod split;
mod write;
mod write_scene;
mod write_vertices;

pub use asset::{GltfAsset, GltfAssetOptions, GltfWeightAnimation};
pub use asset_pack::CompactEncoding;
pub use compact_frames::{
    choose_layout, compact_frames, write_compact_frames_with, CompactFrames, FrameLayout, Layout,
};
pub use meshopt_pack::EXT as MESHOPT_EXTENSION;
pub use read::{
    parse_gltf_morphs, parse_gltf_morphs_with, read_gltf_morphs, read_gltf_morphs_with,
    GltfReadOptions,
};
pub use write::{write_gltf_morphs, write_gltf_with, GltfSummary};
pub use write_scene::{write_gltf_scene, write_gltf_scene_with, GltfRigidMesh};

use crate::mesh::{Point, TriMesh};

/// The most morph targets one mesh gets by default ([`GltfOptions::max_targets`]): WebGL2
/// guarantees 256 texture-array layers and 256 vertex uniform vectors, and three.js needs one
/// layer and one uniform per target plus its other uniforms.
pub const SAFE_MORPH_TARGETS: usize = 200;

/// True for a name that a morph target (and the file that holds it, as the CLI's
/// `rig --shapes-dir` writes one file per target) may have: not empty, not `.` or `..`, and
/// without `/`, `\` or NUL. [`GltfAsset::add_targets`] refuses other names; every client
/// (the CLI, the Python module) applies this one rule.
pub fn is_valid_target_name(name: &str) -> bool {
    !(name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\', '\0']))
}

/// How [`write_gltf_with`] writes a rig (see the [module documentation](self) for the layout).
#[derive(Clone, Debug, PartialEq)]
pub struct GltfOptions {
    /// Name of the node, mesh and material. Default `morphkit`.
    pub name: String,
    /// Name of the animation; `None` (default) uses [`GltfOptions::name`].
    pub clip_name: Option<String>,
    /// Write vertex normals for the base and normal deltas for the targets, so viewers shade
    /// smoothly. Default `true`; `false` saves 12 bytes per vertex and target.
    pub normals: bool,
    /// Write the default PBR material (double-sided when the mesh is open). Default `true`.
    pub material: bool,
    /// The most morph targets one mesh gets; an animation needing more is split into several
    /// meshes switched by node scale. `0` never splits. Default [`SAFE_MORPH_TARGETS`].
    pub max_targets: usize,
    /// JSON written as `scenes[0].extras`. Default `None`.
    pub extras: Option<serde_json::Value>,
    /// Quantize the geometry (`KHR_mesh_quantization`, listed as used and required): positions
    /// and position deltas as normalized `i16` with the dequantizing offset and uniform scale
    /// on the node, normals and normal deltas as normalized `i8`. Positions stay within
    /// `√3 / 65534` (2.7e-5) of the bounding-box diagonal (see the module documentation).
    /// Default `false`.
    pub quantize: bool,
    /// Store each target's `POSITION` and `NORMAL` deltas as sparse accessors listing only the
    /// vertices that move, when that is smaller than the dense accessor. Default `false`.
    pub sparse_targets: bool,
    /// How a frame sequence is laid out ([`crate::io::write_frames`]; [`write_gltf_with`]
    /// writes a rig as given): one target per frame, or a compact clip ([`choose_layout`]).
    /// Default [`FrameLayout::Auto`]: compact when the sequence is longer than `max_targets`.
    pub layout: FrameLayout,
    /// Compress the written buffer views with `EXT_meshopt_compression` (listed as used and
    /// required; three.js needs `GLTFLoader.setMeshoptDecoder`): vertex attributes, morph
    /// deltas and animation data, a morph-weight key at a time; index buffers and sparse
    /// accessors stay as they are (see `meshopt_pack.rs`). Lossless: the decoded bytes are the
    /// ones written without it. Default `false`.
    pub meshopt: bool,
}

impl Default for GltfOptions {
    fn default() -> Self {
        Self {
            name: "morphkit".into(),
            clip_name: None,
            normals: true,
            material: true,
            max_targets: SAFE_MORPH_TARGETS,
            extras: None,
            quantize: false,
            sparse_targets: false,
            layout: FrameLayout::Auto,
            meshopt: false,
        }
    }
}

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

#[cfg(test)]
mod asset_anim_tests;
#[cfg(test)]
mod asset_tests;
#[cfg(test)]
mod hardening_tests;
#[cfg(test)]
mod read_tests;
#[cfg(test)]
mod split_tests;
