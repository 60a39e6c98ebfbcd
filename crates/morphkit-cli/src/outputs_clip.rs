//! The check of a compact clip as written (issue 56): how far from its frames a reader plays
//! it. The layout itself is the library's choice ([`morphkit::io::choose_layout`]), which the
//! output flags steer ([`crate::outputs_flags::OutputFlags::apply`]).
//!
//! **The rule.** `--per-frame-targets` keeps one target per frame. `--clip-tolerance T` asks
//! for a compact clip at `T` of the diagonal, whatever the length. Without either, a sequence
//! of more frames than `--max-targets` (default 200, what a WebGL2 viewer plays in one mesh)
//! is written compact at the default tolerance (1e-3 of the diagonal), since one target per
//! frame would be split into meshes shown in turn and cost `#V · 24` bytes a frame; a shorter
//! sequence keeps its frames exact. A compact clip that would need as many shapes as the
//! frames themselves, or more than `--max-targets`, falls back to one target per frame, and
//! says so.

use anyhow::Context;
use morphkit::clip::{self, ClipError};
use morphkit::io;
use morphkit::mesh::Point;
use morphkit::ShapeSet;
use serde_json::{json, Value};
use std::path::Path;

/// A clip to add to the user's asset compactly ([`add_compact_to_asset`]).
pub(crate) struct AssetClip<'a> {
    /// The clip's name and its keys' times (seconds).
    pub name: &'a str,
    pub times: &'a [f64],
    /// Per key: the frame as solved (the asset's vertices, in its units).
    pub positions: &'a [Vec<Point>],
    /// Per key: the weights of the asset's own targets (in the mesh's order).
    pub weights: &'a [Vec<f64>],
    /// Per key: the frame minus what those weights play (the linear blend).
    pub residuals: &'a [Vec<Point>],
    /// The base's bounding-box diagonal, the unit of the tolerance.
    pub diagonal: f64,
}

/// Adds `c` to `asset` as its own targets at the clip's weights plus the fewest corrective
/// targets ([`clip::residual_basis_on`] of the residuals) that bring every vertex of every
/// frame within `--clip-tolerance` of the diagonal (default [`clip::DEFAULT_TOLERANCE`]), as
/// many as `--max-targets` leaves room for ([`io::GltfAsset::add_compact_animation`]). The
/// correctives are stored as small as the asset's own data: quantized when the asset uses
/// `KHR_mesh_quantization` or `--quantize` is given, meshopt-compressed when the asset is or
/// `--meshopt` is given ([`io::CompactEncoding`]). Returns the `--report` summary; its error is measured on what a
/// viewer plays: the stored targets at the stored (f32) key weights.
pub(crate) fn add_compact_to_asset(
    asset: &mut io::GltfAsset,
    c: &AssetClip,
) -> anyhow::Result<Value> {
    let relative = crate::outputs::clip_flags()
        .0
        .unwrap_or(clip::DEFAULT_TOLERANCE);
    let mut encoding = asset.compact_encoding();
    encoding.quantize |= crate::outputs::quantize_flag();
    if crate::outputs::meshopt_flag() && encoding.meshopt.is_none() {
        encoding.meshopt = Some(io::MESHOPT_EXTENSION.to_string());
    }
    let have = asset.morphs().targets.len();
    let room = match asset.max_targets() {
        0 => usize::MAX,
        m => m.saturating_sub(have),
    };
    let tolerance = relative * c.diagonal;
    let grid = asset.corrective_grid(&encoding, tolerance);
    let basis =
        clip::residual_basis_on(c.residuals, tolerance, room, grid).map_err(|e| match e {
            ClipError::TooManyShapes { frame, error, .. } => anyhow::anyhow!(
                "{}: the compact clip '{}' needs more corrective targets than the {room} that \
             --max-targets leaves beside the asset's {have} (with {room}, frame {frame} is \
             {:.2e} of the diagonal off); raise --clip-tolerance, allow more targets \
             (--max-targets 0), or give --per-frame-targets",
                asset.path().display(),
                c.name,
                error / c.diagonal
            ),
            e => anyhow::anyhow!("{}: the compact clip: {e}", asset.path().display()),
        })?;
    asset.add_compact_animation(c.name, c.times, c.weights, &basis, &encoding)?;
    // What a viewer plays: the stored targets at the stored key weights.
    let anim = asset
        .weight_animation(Some(c.name))?
        .context("the compact clip was not added")?;
    let (mut worst, mut worst_frame) = (0.0f64, 0);
    for (k, (_, w)) in anim.keys.iter().enumerate() {
        let played = asset.morphs().evaluate(w);
        let e = morphkit::geom::max_distance(&played, &c.positions[k]);
        if e > worst {
            (worst, worst_frame) = (e, k);
        }
    }
    Ok(json!({
        "kind": "compact",
        "asset_targets": have,
        "corrective_targets": basis.shapes.len(),
        "quantized": encoding.quantize,
        "meshopt": encoding.meshopt,
        "tolerance": relative,
        "max_error": worst / c.diagonal,
        "worst_frame": worst_frame,
    }))
}

/// The largest distance, relative to frame 0's bounding-box diagonal, between each frame of
/// `frames` and what the glTF file at `path` plays at the key of the same index (read back as
/// a viewer decodes it: dequantized, the stored targets at the stored weights), and the frame
/// where it is reached.
pub(crate) fn played_error(path: &Path, frames: &ShapeSet) -> Result<(f64, usize), io::IoError> {
    let rig = io::read_gltf_morphs(path)?;
    let diagonal = frames.base().bbox_diagonal();
    let (mut worst, mut at) = (0.0f64, 0);
    for (k, (_, w)) in rig.weight_keys.iter().enumerate().take(frames.len()) {
        let e = morphkit::geom::max_distance(&rig.evaluate(w), frames.positions(k));
        if e > worst {
            (worst, at) = (e, k);
        }
    }
    Ok((worst / diagonal, at))
}

/// Whether `frames` frames go into the user's `asset` as a compact clip (the rule of
/// sequences, module documentation): asked for with `--clip-tolerance`, or due because one target
/// per frame would pass `--max-targets` beside the asset's own; never with
/// `--per-frame-targets`.
pub(crate) fn compacts_onto_asset(asset: &io::GltfAsset, frames: usize) -> bool {
    let (tolerance, per_frame) = crate::outputs::clip_flags();
    let room = match asset.max_targets() {
        0 => usize::MAX,
        m => m.saturating_sub(asset.morphs().targets.len()),
    };
    !per_frame && (tolerance.is_some() || frames > room)
}

/// Adds `positions` (frames of the asset's mesh) to `asset` as the compact clip `clip`: its own
/// targets at weight 0, and targets spanning the frames' displacements from its base.
pub(crate) fn add_frames_compactly(
    asset: &mut io::GltfAsset,
    clip: &str,
    times: &[f64],
    positions: &[Vec<morphkit::mesh::Point>],
) -> anyhow::Result<serde_json::Value> {
    let base = asset.morphs().base.positions.clone();
    let residuals: Vec<Vec<morphkit::mesh::Point>> = positions
        .iter()
        .map(|p| {
            p.iter()
                .zip(&base)
                .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                .collect()
        })
        .collect();
    let weights = vec![vec![0.0; asset.morphs().targets.len()]; positions.len()];
    let c = AssetClip {
        name: clip,
        times,
        positions,
        weights: &weights,
        residuals: &residuals,
        diagonal: asset.morphs().base.bbox_diagonal(),
    };
    add_compact_to_asset(asset, &c)
}
