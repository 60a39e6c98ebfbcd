//! The inputs of `morphkit blend`, read once for every mode but `--scene`: the meshes (a
//! base and targets, or `--rig`'s asset through [`super::blend_rig::read`]), the weights of
//! every frame, the fixed vertices (in the welded numbering), the weld of split vertices and
//! the solver's options, gathered in [`Input`] with the staged outputs; and the checks on
//! them that no mode may skip (a single-mesh output of one frame, the memory an animation's
//! frames will take).
//!
//! In `blend`'s one-way stack (see [`super::blend`]) this sits above the arguments
//! ([`super::blend_args`]), the side outputs' names ([`super::blend_outputs`]) and the rig's
//! reader, and below every mode: a mode receives an [`Input`] and never reads a file itself.

use super::blend_args::{blend_options, threads, BlendArgs, MAX_FRAMES};
use super::blend_outputs::{jumps_path, unconverged_path};
use super::blend_rig::Rig;
use crate::outputs::{is_frame_dir, Kind, Outputs, Plan};
use crate::util::{check_fps, check_positive, read_json};
use crate::weights::{self, Origin};
use anyhow::{bail, Context};
use morphkit::io;
use morphkit::mesh::{ShapeSet, Weld, WELD_TOLERANCE};
use morphkit::springs::{BlendOptions, FixedVertices, Weights};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What every mode of `morphkit blend` (but `--scene`) starts from, read and checked by
/// [`read`]. Shapes are in the input's layout (`n` vertices); the solver's numbering is the
/// weld's (`weld.num_welded()` vertices), and `options.fixed` is in it.
pub(super) struct Input {
    /// When the run started (the report's `total_seconds`).
    pub start: Instant,
    /// The input files: the base (or `--rig`'s asset), then the targets.
    pub inputs: Vec<PathBuf>,
    /// Shape 0 the base, then the targets; `n` vertices each.
    pub shapes: ShapeSet,
    /// The base's own file, for an output in its format (io::MeshTemplate), if it has one.
    pub template: Option<io::MeshTemplate>,
    /// Per frame: its weights, valid for `shapes`.
    pub weights: Vec<Weights>,
    /// Split seams and hard edges as one vertex for the solve (identity for `--linear`).
    pub weld: Weld,
    /// The solver's options, `fixed` in the welded numbering.
    pub options: BlendOptions,
    /// Threads solving frames in parallel.
    pub threads: usize,
    /// True when `--out` is one mesh (.obj/.ply/.off), which holds one frame.
    pub single_mesh: bool,
}

/// The input files named by the flags: `--rig`'s asset or `--base`, then the `--target`s.
pub(super) fn input_paths(a: &BlendArgs) -> anyhow::Result<Vec<PathBuf>> {
    let mut inputs = match (&a.rig, &a.base) {
        (Some(rig), _) => vec![rig.clone()],
        (None, Some(base)) => vec![base.clone()],
        _ => bail!("give --base and --target, --rig, or --scene"),
    };
    inputs.extend(a.targets.iter().cloned());
    Ok(inputs)
}

/// Refuses flags whose values no mode accepts, before any file is touched: flags given
/// without the one they act with, a non-positive `--k0` or `--tolerance`, a bad `--fps`.
pub(super) fn check_flags(a: &BlendArgs) -> anyhow::Result<()> {
    check_dependent_flags(a)?;
    check_positive("--k0", a.k0)?;
    check_positive("--tolerance", a.tolerance)?;
    check_fps(a.fps)?;
    Ok(())
}

/// Stages the outputs (refusing one that would overwrite an input), reads `inputs` (from
/// [`input_paths`]) and the weights, checks them, welds and builds the options: the common
/// first step of every mode. Returns the rig as well when `--rig` was given.
pub(super) fn read(
    a: &BlendArgs,
    inputs: Vec<PathBuf>,
    start: Instant,
) -> anyhow::Result<(Input, Option<Rig>, Outputs)> {
    let mut protected = inputs.clone();
    protected.extend(a.weights_file.iter().cloned());
    if !matches!(a.fixed.as_str(), "auto" | "none") {
        protected.push(PathBuf::from(&a.fixed));
    }
    let outputs = Plan::new(&protected)
        .force(a.force)
        .output("--out", &a.out, Kind::MeshOrAnimation)
        .output_opt("--report", a.report.as_ref(), Kind::Json)
        .output_opt(
            "--interactive-cache",
            a.interactive_cache.as_ref(),
            Kind::Json,
        )
        .output_sometimes("OUT-unconverged.ply", &unconverged_path(&a.out), Kind::Mesh)
        .output_sometimes("OUT-jumps.ply", &jumps_path(&a.out), Kind::Mesh)
        .check()?;
    crate::util::announce_reading(&inputs);
    let (rig, shapes) = match &a.rig {
        Some(r) => {
            let (rig, shapes) = super::blend_rig::read(a, r)?;
            (Some(rig), shapes)
        }
        None => (None, io::read_shape_set(&inputs)?),
    };
    crate::util::warn_carried(&inputs[0], shapes.base());
    // An OBJ or PLY base comes back as the artist's own file: texture coordinates, normals'
    // hard edges, materials, groups, colours and custom properties kept (io::MeshTemplate).
    let template = crate::util::template(&inputs[0], shapes.num_vertices())?;
    let weights = match &rig {
        Some(r) => r.weights.clone(),
        None => frame_weights(a, shapes.len())?,
    };
    for (k, w) in weights.iter().enumerate() {
        w.coefficients(shapes.len())
            .with_context(|| format!("frame {k}: invalid weights"))?;
    }
    let single_mesh =
        !is_frame_dir(&a.out) && io::Format::from_path(&a.out).is_some_and(|f| f.is_single_mesh());
    if single_mesh && weights.len() != 1 {
        bail!("{}: a single-mesh output holds one frame, but {} frames were asked for; use a directory, .glb or .pc2", a.out.display(), weights.len());
    }
    if !(a.max_memory.is_finite() && a.max_memory > 0.0) {
        bail!("--max-memory must be a finite positive number of GiB");
    }
    check_frames_memory(&a.out, weights.len(), shapes.num_vertices(), a.max_memory)?;
    // Split seams and hard edges are one vertex for the solve (mesh::weld); results go back in
    // the input's layout.
    let weld = (!a.linear).then(|| Weld::of_shapes(&shapes, WELD_TOLERANCE));
    let weld = weld.unwrap_or_else(|| Weld::identity(shapes.num_vertices()));
    if !weld.is_identity() {
        eprintln!(
            "welded {} split vertices (seams, hard edges) into the {} they share a position with in every shape; the result keeps the input's {} vertices",
            weld.merged(),
            weld.num_welded(),
            weld.num_input()
        );
    }
    let fixed = welded_fixed(read_fixed(&a.fixed)?, &weld, Path::new(&a.fixed))?;
    let options = blend_options(a, fixed, weights.len());
    let input = Input {
        start,
        inputs,
        shapes,
        template,
        weights,
        weld,
        options,
        threads: threads(a),
        single_mesh,
    };
    Ok((input, rig, outputs))
}

fn read_fixed(spec: &str) -> anyhow::Result<FixedVertices> {
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
fn welded_fixed(fixed: FixedVertices, weld: &Weld, file: &Path) -> anyhow::Result<FixedVertices> {
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
fn frame_weights(a: &BlendArgs, n_shapes: usize) -> anyhow::Result<Vec<Weights>> {
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
fn check_frames_memory(
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
fn check_dependent_flags(a: &BlendArgs) -> anyhow::Result<()> {
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
    )?;
    crate::outputs::check_clip_flags(&a.out)
}
