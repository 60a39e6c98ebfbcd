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

use morphkit::io;
use morphkit::ShapeSet;
use std::path::Path;

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
