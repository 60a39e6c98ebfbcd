//! `morphkit blend --rig FILE.glb`: the base, the named morph targets and a weights animation
//! of a user's glTF asset drive the physical blend, and the output is that asset with the
//! physical animation added ([`morphkit::io::GltfAsset::add_frame_animation`]).
//!
//! The weights of frame `k` are key `k` of the file's weights animation (`--animation NAME`
//! picks one when several drive the mesh), played at the key's time; or row `k` of
//! `--weights-file`, whose CSV header row may name the targets (others weigh 0), at `k / fps`
//! seconds. The solve is `blend`'s own (welding included); only the reading (here) and the
//! writing (`blend_rig_out.rs`) differ.
//!
//! This file is the rig's *input* step and sits low in `blend`'s one-way stack (see
//! [`super::blend`]): the common reader [`super::blend_inputs::read`] calls it, so it imports
//! only the arguments ([`super::blend_args`]). The rig's output step, which needs the frame
//! solve, is a mode above it, in [`super::blend_rig_out`].

use super::blend_args::{BlendArgs, MAX_FRAMES};
use crate::weights::{self, Origin};
use anyhow::{bail, Context};
use morphkit::io::{self, Format, GltfAsset, GltfReadOptions};
use morphkit::mesh::ShapeSet;
use morphkit::springs::Weights;
use std::path::Path;

/// A rig read for `blend --rig`.
pub(super) struct Rig {
    /// The asset, carried to a .glb/.gltf output.
    pub asset: GltfAsset,
    /// Per frame: its delta weights, one per target.
    pub weights: Vec<Weights>,
    /// Per frame: its time in seconds.
    pub times: Vec<f64>,
    /// The name of the physical animation.
    pub clip: String,
}

/// True when `out` receives the asset (a .glb/.gltf file).
pub(super) fn carries(out: &Path) -> bool {
    matches!(Format::from_path(out), Some(Format::Glb | Format::Gltf))
}

/// Reads `--rig` with its weights, and its base and targets (named) as shapes (see the
/// [module documentation](self)); refuses, before any solve, an animation whose key times are
/// not strictly increasing, and what the output asset would refuse at the write
/// ([`GltfAsset::check_frame_animation`]: more targets than --max-targets, no node to play it).
pub(super) fn read(a: &BlendArgs, path: &Path) -> anyhow::Result<(Rig, ShapeSet)> {
    let opts = GltfReadOptions {
        mesh: a.mesh.clone(),
    };
    let mut asset = GltfAsset::read(path, &opts)?;
    let m = asset.morphs();
    if m.targets.is_empty() {
        bail!(
            "{}: the mesh has no morph targets to blend; give --base and --target instead",
            path.display()
        );
    }
    // Shape 0 is the base, then the targets.
    let named = std::iter::once(("base".to_string(), m.base.positions.clone()))
        .chain(m.target_names.iter().cloned().zip(m.targets.clone()))
        .collect();
    let shapes = ShapeSet::new(m.base.clone(), named)
        .with_context(|| format!("{}: the morph targets", path.display()))?;
    let n_shapes = shapes.len();
    let (weights, times, clip): (Vec<Weights>, Vec<f64>, String) = match &a.weights_file {
        Some(f) => {
            let rows = io::read_named_weights(f, &m.target_names)?;
            if rows.len() > MAX_FRAMES {
                bail!(
                    "{}: {} rows are more than the {MAX_FRAMES} frames one run writes",
                    f.display(),
                    rows.len()
                );
            }
            let mut w = Vec::with_capacity(rows.len());
            for (frame, row) in rows.iter().enumerate() {
                let x = Weights::Delta(row.values.clone());
                weights::check(
                    &x,
                    n_shapes,
                    Origin::File {
                        path: f,
                        row,
                        frame,
                    },
                )?;
                w.push(x);
            }
            let times = (0..w.len()).map(|k| k as f64 / a.fps).collect();
            let stem = f
                .file_stem()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            (w, times, format!("{stem}-physical"))
        }
        None => {
            let Some(anim) = asset.weight_animation(a.animation.as_deref())? else {
                bail!(
                    "{}: no animation drives the morph weights of the mesh; give --weights-file (a CSV whose header names the targets: {})",
                    path.display(),
                    m.target_names.join(", ")
                );
            };
            // Keys out of time order are refused here, naming the input animation, not after
            // every frame is solved where the physical animation is made from them.
            anim.check_times(path)?;
            let mut w = Vec::with_capacity(anim.keys.len());
            for (k, (_, keys)) in anim.keys.iter().enumerate() {
                let x = Weights::Delta(keys.clone());
                let at = format!("{} (animation key {k})", path.display());
                weights::check(&x, n_shapes, Origin::Flag(&at))?;
                w.push(x);
            }
            let times = anim.keys.iter().map(|k| k.0).collect();
            let name = anim.name.clone().unwrap_or_else(|| "animation".into());
            (w, times, format!("{name}-physical"))
        }
    };
    if carries(&a.out) {
        if crate::outputs::clip_flags().1 {
            crate::outputs::check_asset_flags(&a.out)?;
        } else {
            crate::outputs::check_compact_asset_flags(&a.out)?;
        }
        asset.set_max_targets(crate::outputs::asset_max_targets());
        if crate::outputs::clip_flags().1 {
            asset.check_frame_animation(&clip, &times, weights.len())?;
        } else {
            // The compact clip's correctives are counted once the residual is known.
            asset.check_clip_keys(&clip, &times, weights.len())?;
            asset.check_room(0)?;
            let (have, max) = (asset.morphs().targets.len(), asset.max_targets());
            if !a.linear && max != 0 && have >= max {
                bail!(
                    "{}: the mesh has {have} morph targets, and --max-targets {max} leaves no room \
                     for the compact clip's corrective targets; allow more (--max-targets 0) or \
                     give --per-frame-targets (which needs room too)",
                    path.display()
                );
            }
        }
    }
    let rig = Rig {
        asset,
        weights,
        times,
        clip,
    };
    Ok((rig, shapes))
}
