//! The inputs of `morphkit blend` beyond the meshes: fixed vertices (in the welded numbering),
//! the weights of every frame, and the memory an animation's frames will take.

use super::blend_args::{BlendArgs, MAX_FRAMES};
use crate::outputs::is_frame_dir;
use crate::util::read_json;
use crate::weights::{self, Origin};
use anyhow::{bail, Context};
use morphkit::io;
use morphkit::mesh::Weld;
use morphkit::springs::{FixedVertices, Weights};
use std::path::Path;

pub(super) fn read_fixed(spec: &str) -> anyhow::Result<FixedVertices> {
    Ok(match spec {
        "auto" => FixedVertices::Auto,
        "none" => FixedVertices::None,
        file => {
            let v = read_json(Path::new(file), "fixed-vertex file (or use auto / none)")?;
            let ids = v.get("fixed").unwrap_or(&v);
            let ids: Vec<u32> = serde_json::from_value(ids.clone())
                .with_context(|| format!("{file}: expected {{\"fixed\": [vertex ids]}} or an array of non-negative integers"))?;
            FixedVertices::Ids(ids)
        }
    })
}

/// The fixed vertices of the input in the welded numbering ([`Weld`]): ids are checked
/// against the input's vertex count first, so a message names the input's id.
pub(super) fn welded_fixed(
    fixed: FixedVertices,
    weld: &Weld,
    file: &Path,
) -> anyhow::Result<FixedVertices> {
    let FixedVertices::Ids(ids) = fixed else {
        return Ok(fixed);
    };
    let n = weld.num_input();
    if let Some(&v) = ids.iter().find(|&&v| v as usize >= n) {
        bail!(
            "{}: fixed vertex {v} is out of range: the mesh has {n} vertices",
            file.display()
        );
    }
    Ok(FixedVertices::Ids(weld.welded_ids(&ids)))
}

/// The weight vectors of every frame.
pub(super) fn frame_weights(a: &BlendArgs, n_shapes: usize) -> anyhow::Result<Vec<Weights>> {
    let wrap = |w: Vec<f64>| {
        if a.convex {
            Weights::Convex(w)
        } else {
            Weights::Delta(w)
        }
    };
    if let Some(alpha) = a.alpha {
        let w = Weights::Alpha(alpha);
        weights::check(&w, n_shapes, Origin::Flag("--alpha"))?;
        return Ok(vec![w]);
    }
    if let Some(w) = &a.weights {
        let w = wrap(w.clone());
        weights::check(&w, n_shapes, Origin::Flag("--weights"))?;
        return Ok(vec![w]);
    }
    if let Some(n) = a.frames {
        if n_shapes != 2 {
            bail!("--frames needs exactly one --target (got {}); use --weights-file for several targets", n_shapes - 1);
        }
        if !(2..=MAX_FRAMES).contains(&n) {
            bail!("--frames must be between 2 (α = 0 and 1) and {MAX_FRAMES}, got {n}");
        }
        return Ok((0..n)
            .map(|k| Weights::Alpha(k as f64 / (n - 1) as f64))
            .collect());
    }
    if let Some(f) = &a.weights_file {
        let rows = io::read_weights(f)?;
        if rows.len() > MAX_FRAMES {
            bail!(
                "{}: {} rows are more than the {MAX_FRAMES} frames one run writes; split the file and run once per part",
                f.display(),
                rows.len()
            );
        }
        let mut out = Vec::with_capacity(rows.len());
        for (frame, row) in rows.iter().enumerate() {
            let w = wrap(row.values.clone());
            let origin = Origin::File {
                path: f,
                row,
                frame,
            };
            weights::check(&w, n_shapes, origin)?;
            out.push(w);
        }
        return Ok(out);
    }
    bail!("give one of --alpha, --weights, --frames or --weights-file")
}

/// Bytes one frame's vertex holds while an animation to `out` is made: the solved positions
/// (`f64` × 3, all frames are kept until the write) and what the writer builds in memory
/// before the file (a .glb/.gltf buffer: `f32` positions and normals; a .usda text layer:
/// about 40 characters a point). A frame directory or .pc2 is streamed
/// ([`io::FrameStream`]) and holds [`FRAME_CHUNK`](super::blend_args::FRAME_CHUNK) frames at most: nothing per frame.
fn bytes_per_frame_vertex(out: &Path) -> u64 {
    let dir = is_frame_dir(out);
    if io::FrameStream::supports(out, dir) {
        return 0;
    }
    24 + match io::Format::from_path(out) {
        Some(io::Format::Glb | io::Format::Gltf) => 24,
        Some(io::Format::Usda) => 40,
        _ => 0,
    }
}

/// Refuses, before any solve, an animation whose frames would not fit in `max_gib` GiB
/// (frames × vertices × [`bytes_per_frame_vertex`]), naming the estimate.
pub(super) fn check_frames_memory(
    out: &Path,
    frames: usize,
    vertices: usize,
    max_gib: f64,
) -> anyhow::Result<()> {
    let per = bytes_per_frame_vertex(out);
    let bytes = (frames as u64)
        .saturating_mul(vertices as u64)
        .saturating_mul(per);
    let gib = bytes as f64 / (1u64 << 30) as f64;
    if gib > max_gib {
        bail!(
            "{}: {frames} frames of {vertices} vertices would hold about {gib:.1} GiB in memory ({per} bytes per vertex and frame), over the limit of {max_gib} GiB (--max-memory); write fewer frames per run (split the weights file), or raise --max-memory",
            out.display()
        );
    }
    Ok(())
}

/// Refuses the flags that act only with another one given without it (see
/// [`crate::util::only_with`]): `--mesh` and `--animation` without `--rig`, `--refine` and
/// `--interactive-cache` without `--interactive`.
pub(super) fn check_dependent_flags(a: &BlendArgs) -> anyhow::Result<()> {
    use crate::util::only_with;
    let rig = a.rig.is_some();
    only_with(
        "--mesh",
        a.mesh.is_some(),
        "--rig",
        rig,
        "it names the mesh of the asset",
    )?;
    let what = "it names the asset's weights animation";
    only_with("--animation", a.animation.is_some(), "--rig", rig, what)?;
    let what = "projected-Newton steps after each reduced solve";
    only_with(
        "--refine",
        a.refine > 0,
        "--interactive",
        a.interactive,
        what,
    )?;
    let what = "it keeps the interactive preparation";
    let cache = a.interactive_cache.is_some();
    only_with(
        "--interactive-cache",
        cache,
        "--interactive",
        a.interactive,
        what,
    )
}
