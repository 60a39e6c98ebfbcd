//! The side outputs of `morphkit blend` and its volumetric path: regions of unconverged or
//! jumping vertices beside the output, and weights as the report writes them.
//!
//! Shared by the surface frame solve (`blend_solve.rs`) and the volumetric mode (`volume.rs`),
//! and named by the common input step when it stages the outputs, so it sits near the bottom
//! of `blend`'s one-way stack (see [`super::blend`]) and imports no `blend` module.

use crate::outputs::Outputs;
use morphkit::io;
use morphkit::mesh::Weld;
use morphkit::springs::{Continuity, Weights};
use serde_json::json;
use std::path::{Path, PathBuf};

pub(super) fn weights_json(w: &Weights) -> serde_json::Value {
    match w {
        Weights::Alpha(a) => json!({ "alpha": a }),
        Weights::Convex(v) => json!({ "convex": v }),
        Weights::Delta(v) => json!({ "delta": v }),
    }
}

/// `OUT-WHAT.ply` beside `out` (`OUT` the file name up to its first dot).
fn region_path(out: &Path, what: &str) -> PathBuf {
    let stem = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "blend".into());
    let stem = stem.split('.').next().unwrap_or("blend").to_string();
    out.with_file_name(format!("{stem}-{what}.ply"))
}

/// `OUT-unconverged.ply` beside `out`.
pub(super) fn unconverged_path(out: &Path) -> PathBuf {
    region_path(out, "unconverged")
}

/// `OUT-jumps.ply` beside `out`: the vertices of jumps between frames.
pub(super) fn jumps_path(out: &Path) -> PathBuf {
    region_path(out, "jumps")
}

/// Writes `base` to `path` with the vertices flagged in `region` red, the others grey.
pub(super) fn write_region(
    outputs: &mut Outputs,
    path: &Path,
    base: &morphkit::mesh::TriMesh,
    region: &[bool],
) -> anyhow::Result<()> {
    let colors = region
        .iter()
        .map(|&f| if f { [220, 30, 30] } else { [200, 200, 200] })
        .collect();
    outputs.colored_ply(path, base, &io::Colors::PerVertex(colors))
}

/// Warns about the jumps of a sequence (a part that snapped from one equilibrium to another
/// between two frames, see `morphkit::springs::continuity`) and writes their vertices, red on
/// the base mesh, to [`jumps_path`]. Returns that path when anything jumped. The warning names
/// that file, so it is printed once the outputs are in place ([`Outputs::warn_after_commit`]).
pub(super) fn report_jumps(
    outputs: &mut Outputs,
    out: &Path,
    base: &morphkit::mesh::TriMesh,
    continuity: &Continuity,
    snaps: Option<&[[usize; 2]]>,
) -> anyhow::Result<Option<PathBuf>> {
    let Some(first) = continuity.jumps.first() else {
        return Ok(None);
    };
    let worst = continuity
        .jumps
        .iter()
        .max_by(|a, b| a.ratio.total_cmp(&b.ratio))
        .unwrap_or(first);
    let region = continuity.jump_vertices();
    let path = jumps_path(out);
    // Snaps (the frames' equilibrium ends: the physics snaps) and fast steps (a smooth motion
    // faster than the bound), where they were told apart (`morphkit::springs::snaps`).
    let two =
        "the spring energy has two equilibria there and the frames pass from one to the other";
    let why = match snaps {
        None => format!("{two}."),
        Some([]) => "none of them snaps: the equilibrium moves smoothly there, faster than the bound (halving a step keeps its ratio).".to_string(),
        Some(s) if s.len() == continuity.jumps.len() => {
            format!("{two} (each a snap: halving the step keeps the move in one half).")
        }
        Some(s) => format!(
            "{} of them snap ({two}; first at frames {}→{}), the others are fast steps (the equilibrium moves smoothly, faster than the bound).",
            s.len(),
            s[0][0],
            s[0][1]
        ),
    };
    outputs.warn_after_commit(format!(
        "warning: a part jumped between {} pair(s) of consecutive frames (first: frames {}→{}; worst: frames {}→{}, {} vertices moving up to {:.1}× the linear blend's step, bound {}); {why} {} vertices shown red in {}; try --hinge-weight 1 (see the README, \"Jumps between frames\")",
        continuity.jumps.len(),
        first.frames[0],
        first.frames[1],
        worst.frames[0],
        worst.frames[1],
        worst.vertices.len(),
        worst.ratio,
        continuity.bound,
        region.len(),
        path.display()
    ));
    let mut flagged = vec![false; base.positions.len()];
    for &v in &region {
        flagged[v as usize] = true;
    }
    write_region(outputs, &path, base, &flagged)?;
    Ok(Some(path))
}

/// Marks in `failed` (input layout) the input vertices of the welded vertices `welded`.
pub(super) fn mark_failed(failed: &mut [bool], weld: &Weld, welded: &[u32]) {
    for v in weld.input_vertices(welded) {
        failed[v as usize] = true;
    }
}
