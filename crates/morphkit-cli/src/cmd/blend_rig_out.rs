//! The `--rig` mode of `morphkit blend` when `--out` is a .glb/.gltf: the output is the rig's
//! own asset (materials, skins, other meshes and animations kept) with clips added. The
//! pipeline is [`run`]: inputs (an [`Input`] and the [`Rig`] read by `blend_rig.rs`) → the
//! surface solve ([`super::blend_solve`]), every frame kept → [`write()`], the output step.
//!
//! [`write()`] receives everything a clip may be made from, in a [`RigFrames`]: the rig (asset,
//! per-frame weights and times, clip name), the solved frames, the shapes and the arguments.
//! Each kind of clip is a function of its own: [`add_compact_clip`] (the default: the asset's
//! own targets at the clip's weights plus corrective targets spanning each frame's residual
//! against the linear blend, [`RigFrames::linear`]; issue 56) and [`add_physical_clip`]
//! (`--per-frame-targets`: one morph target per frame).
//!
//! A mode at the top of `blend`'s one-way stack (see [`super::blend`]); the rig's reader sits
//! low in it (`blend_rig.rs`), since the common input step calls it. A `--rig` run whose
//! `--out` is not the asset is the plain mode ([`super::blend_frames`]).

use super::blend_args::BlendArgs;
use super::blend_inputs::Input;
use super::blend_rig::Rig;
use super::blend_solve::{finish, Surface};
use crate::outputs::Outputs;
use morphkit::mesh::{Point, ShapeSet};
use morphkit::springs::linear_blend;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::time::Instant;

/// What the output step of `--rig` receives: the rig and its solved frames. Frames are in
/// the input's layout (`n` points each, the asset mesh's vertex order), one per weight
/// vector of `rig.weights`, played at `rig.times`.
pub(super) struct RigFrames<'a> {
    /// The asset, the per-frame delta weights and times, and the clip's name.
    pub rig: Rig,
    /// Per frame: the solved positions (the physical equilibrium, or the linear blend with
    /// `--linear`).
    pub positions: Vec<Vec<Point>>,
    /// Shape 0 the asset mesh's base, then its morph targets (in the file's order).
    pub shapes: &'a ShapeSet,
    /// The arguments (`--out`, and any flag a clip reads).
    pub args: &'a BlendArgs,
}

impl RigFrames<'_> {
    /// Frame `k`'s linear blend, `base + Σ wᵢ (targetᵢ − base)` (`n` points): the very numbers
    /// the solve measured frame `k` against, recomputed (a pass over the targets, far cheaper
    /// than a solve) rather than kept, so that the frames held until the write stay at one
    /// copy, as the `--max-memory` estimate counts them. `positions[k] − linear(k)` is the
    /// physical correction of frame `k`.
    pub fn linear(&self, k: usize) -> anyhow::Result<Vec<Point>> {
        Ok(linear_blend(self.shapes, &self.rig.weights[k])?)
    }
}

/// Runs the rig mode: solves `input`'s frames (the rig's weights) and writes the asset with
/// the physical clip to `--out`.
pub(super) fn run(
    a: &BlendArgs,
    rig: Rig,
    input: Input,
    mut outputs: Outputs,
) -> anyhow::Result<()> {
    let mut surface = Surface::setup(a, &input)?;
    let mut positions = Vec::with_capacity(input.weights.len());
    let solved = surface.solve(a, &input, |_, p| {
        positions.push(p);
        Ok(())
    })?;
    let regions = solved.warn(&mut outputs, a, &input)?;
    let t_write = Instant::now();
    let frames = RigFrames {
        rig,
        positions,
        shapes: &input.shapes,
        args: a,
    };
    let clip = write(&mut outputs, frames, &input.inputs)?;
    let write_seconds = t_write.elapsed().as_secs_f64();
    let timing = (write_seconds, Some(clip));
    surface.report(&mut outputs, a, &input, (&solved, &regions), timing)?;
    finish(outputs, a, &input)
}

/// The output step of `--rig`: adds the clip to the rig's asset and stages it at `--out`
/// (`inputs`: the input files, named in the asset's metadata). Returns what the clip came to,
/// for `--report`.
pub(super) fn write(
    outputs: &mut Outputs,
    mut frames: RigFrames,
    inputs: &[PathBuf],
) -> anyhow::Result<Value> {
    let summary = if crate::outputs::clip_flags().1 {
        add_physical_clip(&mut frames)?
    } else {
        add_compact_clip(&mut frames)?
    };
    let rig = &frames.rig;
    let compact = !crate::outputs::clip_flags().1;
    let n = frames.positions.len();
    outputs.gltf_asset_with(&frames.args.out, &rig.asset, inputs, n, compact)?;
    let how = match summary["corrective_targets"].as_u64() {
        Some(k) => format!(
            "the asset's {} targets at the clip's weights and {k} corrective targets, within {:.2e} of the diagonal",
            summary["asset_targets"], summary["max_error"].as_f64().unwrap_or(f64::NAN)
        ),
        None => "one morph target each".to_string(),
    };
    eprintln!(
        "added the animation '{}' ({} frames: {how}) to the asset of {}",
        rig.clip,
        frames.positions.len(),
        rig.asset.path().display()
    );
    Ok(summary)
}

/// Adds the physical animation `rig.clip` to the asset: one new morph target per frame (its
/// positions minus the base), keyed at the frame's time
/// ([`morphkit::io::GltfAsset::add_frame_animation`]).
fn add_physical_clip(frames: &mut RigFrames) -> anyhow::Result<Value> {
    let rig = &mut frames.rig;
    rig.asset
        .add_frame_animation(&rig.clip, &rig.times, &frames.positions)?;
    Ok(json!({ "kind": "per_frame_targets", "targets_added": frames.positions.len() }))
}

/// Adds the physical animation `rig.clip` compactly: the asset's own targets at the clip's
/// weights, plus corrective targets spanning the frames' residuals against the linear blend
/// ([`crate::outputs::clip::add_compact_to_asset`]).
fn add_compact_clip(frames: &mut RigFrames) -> anyhow::Result<Value> {
    let n_targets = frames.shapes.len() - 1;
    let mut residuals = Vec::with_capacity(frames.positions.len());
    let mut weights = Vec::with_capacity(frames.positions.len());
    for (k, p) in frames.positions.iter().enumerate() {
        let linear = frames.linear(k)?;
        residuals.push(
            p.iter()
                .zip(&linear)
                .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                .collect::<Vec<Point>>(),
        );
        let c = frames.rig.weights[k].coefficients(frames.shapes.len())?;
        weights.push(c[1..=n_targets].to_vec());
    }
    let clip = crate::outputs::clip::AssetClip {
        name: &frames.rig.clip,
        times: &frames.rig.times,
        positions: &frames.positions,
        weights: &weights,
        residuals: &residuals,
        diagonal: frames.shapes.base().bbox_diagonal(),
    };
    crate::outputs::clip::add_compact_to_asset(&mut frames.rig.asset, &clip)
}
