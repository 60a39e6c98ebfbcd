//! How a .glb/.gltf animation of a frame sequence is laid out (issue 56): one morph target per
//! frame, or a compact clip ([`morphkit::io::compact_frames`]: a few shapes at per-frame
//! weights, within `--clip-tolerance` of every frame).
//!
//! **The rule.** `--per-frame-targets` keeps one target per frame. `--clip-tolerance T` asks
//! for a compact clip at `T` of the diagonal, whatever the length. Without either, a sequence
//! of more frames than `--max-targets` (default 200, what a WebGL2 viewer plays in one mesh)
//! is written compact at the default tolerance (1e-3 of the diagonal), since one target per
//! frame would be split into meshes shown in turn and cost `#V · 24` bytes a frame; a shorter
//! sequence keeps its frames exact. A compact clip that would need as many shapes as the
//! frames themselves, or more than `--max-targets`, falls back to one target per frame, and
//! says so.

use crate::outputs_flags::context;
use morphkit::clip::{ClipError, DEFAULT_TOLERANCE};
use morphkit::io::{self, CompactFrames, FramesOptions};
use morphkit::ShapeSet;
use std::path::Path;

/// The layout [`choose`] picked.
pub(crate) enum Layout {
    /// One morph target per frame; the reason when a compact clip was asked for or due and
    /// could not be made.
    PerFrame(Option<String>),
    /// A compact clip, and its tolerance as a fraction of the diagonal.
    Compact(Box<CompactFrames>, f64),
}

/// Chooses the layout of `frames` written to `path` with `opts` (after the output flags are
/// applied): see the module documentation.
pub(crate) fn choose(path: &Path, frames: &ShapeSet, opts: &FramesOptions) -> Layout {
    let flags = context().flags;
    let max = opts.gltf.max_targets;
    let relative = match (flags.per_frame_targets, flags.clip_tolerance) {
        (true, _) => return Layout::PerFrame(None),
        (false, Some(t)) => t,
        (false, None) if max != 0 && frames.len().saturating_sub(1) > max => DEFAULT_TOLERANCE,
        (false, None) => return Layout::PerFrame(None),
    };
    let diagonal = frames.base().bbox_diagonal();
    if !(diagonal > 0.0 && diagonal.is_finite()) || frames.len() < 3 {
        return Layout::PerFrame(None);
    }
    // Fewer shapes than the frames' own targets, and within what one mesh may hold.
    let mut most = frames.len() - 2;
    if max != 0 {
        most = most.min(max);
    }
    // Quantized, the writer rounds each shape again (2.7e-5 of the diagonal a coordinate at
    // most): a quarter of the tolerance is left for it, and the played error is measured.
    let share = if opts.gltf.quantize { 0.75 } else { 1.0 };
    let tolerance = relative * diagonal * share;
    match io::compact_frames(frames, opts.fps, tolerance, most) {
        Ok(c) if c.morphs.targets.is_empty() => Layout::PerFrame(None),
        Ok(c) => Layout::Compact(Box::new(c), relative),
        Err(ClipError::TooManyShapes { error, .. }) => Layout::PerFrame(Some(format!(
            "note: {}: a compact clip within {relative:.1e} of the diagonal would need more than \
             {most} morph targets (with {most}, a frame stays {:.2e} off); written with one \
             target per frame (raise --clip-tolerance for a compact clip)",
            path.display(),
            error / diagonal
        ))),
        Err(e) => Layout::PerFrame(Some(format!(
            "note: {}: no compact clip ({e}); written with one target per frame",
            path.display()
        ))),
    }
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
