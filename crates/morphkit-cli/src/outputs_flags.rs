//! The output flags every subcommand accepts (`--max-targets`, `--quantize`, `--meshopt`,
//! `--sparse-targets`, `--no-normals`) and the run's context every output is stamped with
//! (the flags, the subcommand, the command line): set once by `main`, read by the writers in
//! [`crate::outputs`], and checked against asset edits, which keep the asset's own encoding.

use morphkit::io::{self, GltfOptions};
use std::path::Path;
use std::sync::OnceLock;

/// Options of every written animation, accepted by every subcommand (`global` clap arguments).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct OutputFlags {
    /// Most morph targets per mesh in a .glb/.gltf animation (default 200, what WebGL2 viewers
    /// such as three.js play). A longer animation is split into meshes of at most N targets,
    /// shown in turn by node scale; 0 never splits (a warning says when viewers will not play
    /// it). In a user's asset (`blend --rig`, `rig --target X.glb`) a mesh is never split: more
    /// targets than N is an error, and 0 allows any number.
    #[arg(long, global = true, value_name = "N")]
    pub max_targets: Option<usize>,
    /// Leave vertex normals and normal deltas out of .glb/.gltf output (smaller, shades flat).
    #[arg(long, global = true)]
    pub no_normals: bool,
    /// Quantize .glb/.gltf output (KHR_mesh_quantization, which viewers must support):
    /// positions and morph deltas as 16-bit integers scaled by the node (within 2.7e-5 of the
    /// bounding-box diagonal), normals and normal deltas as 8-bit integers. About half the size.
    /// With `blend --rig X --out Y.glb`: the compact clip's corrective targets as 16-bit
    /// (the asset's own data stays as it is).
    #[arg(long, global = true)]
    pub quantize: bool,
    /// Compress .glb/.gltf output with EXT_meshopt_compression (which viewers must support:
    /// three.js with GLTFLoader.setMeshoptDecoder, Blender 3.4+, Babylon.js): vertex data,
    /// morph deltas and animation keys, losslessly; with --quantize as gltfpack -c writes.
    /// With `blend --rig X --out Y.glb` (and transfer or synth onto an asset): the compact
    /// clip's new data (the asset's own data stays as it is; an asset compressed already keeps
    /// its compression without the flag).
    #[arg(long, global = true)]
    pub meshopt: bool,
    /// Store each morph target of .glb/.gltf output as a sparse accessor listing only the
    /// vertices that move (when that is smaller): for shapes that move part of the mesh.
    #[arg(long, global = true)]
    pub sparse_targets: bool,
    /// A compact clip's largest vertex error in any frame, as a fraction of the base's
    /// bounding-box diagonal (default 1e-3, `morphkit::clip::DEFAULT_TOLERANCE`). A compact
    /// clip plays a few shapes at per-frame weights instead of one morph target per frame:
    /// what `blend --rig X --out Y.glb` adds to the asset (the asset's own targets at the
    /// clip's weights plus corrective targets), and how a .glb/.gltf animation of more frames
    /// than --max-targets is written (given, also a shorter one).
    #[arg(long, global = true, value_name = "FRACTION", value_parser = positive_fraction, conflicts_with = "per_frame_targets")]
    pub clip_tolerance: Option<f64>,
    /// One morph target per frame (each frame exact as f32) instead of a compact clip: in a
    /// rig's asset (`blend --rig`) and in a .glb/.gltf animation of any length (a long one is
    /// then split into meshes of at most --max-targets targets, shown in turn).
    #[arg(long, global = true)]
    pub per_frame_targets: bool,
}

/// A `--clip-tolerance`: a finite positive number.
fn positive_fraction(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!(
            "--clip-tolerance must be a finite positive fraction of the diagonal, not {s}"
        )),
    }
}

impl OutputFlags {
    /// `opts` with these flags applied.
    pub(crate) fn apply(&self, opts: &mut GltfOptions) {
        if let Some(n) = self.max_targets {
            opts.max_targets = n;
        }
        if self.no_normals {
            opts.normals = false;
        }
        opts.quantize |= self.quantize;
        opts.meshopt |= self.meshopt;
        opts.sparse_targets |= self.sparse_targets;
        if self.per_frame_targets {
            opts.layout = io::FrameLayout::PerFrame;
        } else if let Some(t) = self.clip_tolerance {
            opts.layout = io::FrameLayout::Compact(t);
        }
    }
}

/// What every output of this run is stamped with: the flags, the subcommand and the command
/// line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Context {
    pub(crate) flags: OutputFlags,
    pub(crate) subcommand: String,
    pub(crate) command: String,
}

static CONTEXT: OnceLock<Context> = OnceLock::new();

/// Records the output flags, the subcommand name and the command line (call once, from main).
/// Arguments that are not UTF-8 (a file name in another encoding) are recorded lossily, with
/// U+FFFD for what is not UTF-8: the record is for people, the files are opened by their bytes.
pub fn set_context(flags: OutputFlags, subcommand: &str) {
    let command = std::env::args_os()
        .map(|a| a.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(" ");
    let _ = CONTEXT.set(Context {
        flags,
        subcommand: subcommand.to_string(),
        command,
    });
}

pub(crate) fn context() -> Context {
    CONTEXT.get().cloned().unwrap_or_default()
}

/// The most morph targets an edited asset's mesh may have: `--max-targets`, else
/// [`io::SAFE_MORPH_TARGETS`]; 0 allows any number.
pub fn asset_max_targets() -> usize {
    context()
        .flags
        .max_targets
        .unwrap_or(io::SAFE_MORPH_TARGETS)
}

/// Refuses the output flags that an edit of a user's asset written to `out` does not apply:
/// the edit keeps the asset's own accessors as they are and stores its new targets as `f32`
/// (with normal deltas where the asset has normals; [`io::GltfAsset`]), so `--quantize`,
/// `--sparse-targets` and `--no-normals` would be ignored.
pub fn check_asset_flags(out: &Path) -> anyhow::Result<()> {
    refuse_asset_flags(out, false)
}

/// [`check_asset_flags`] for an edit that adds a compact clip: `--quantize` and `--meshopt`
/// apply to its new data ([`io::CompactEncoding`]), the others are refused.
pub fn check_compact_asset_flags(out: &Path) -> anyhow::Result<()> {
    refuse_asset_flags(out, true)
}

/// `--clip-tolerance` and `--per-frame-targets`: `(tolerance if given, per-frame)`.
pub fn clip_flags() -> (Option<f64>, bool) {
    let f = context().flags;
    (f.clip_tolerance, f.per_frame_targets)
}

/// Refuses `--clip-tolerance` and `--per-frame-targets` for an output `out` they do nothing
/// to: anything but a .glb/.gltf animation.
pub fn check_clip_flags(out: &Path) -> anyhow::Result<()> {
    let f = context().flags;
    let gltf = matches!(
        io::Format::from_path(out),
        Some(io::Format::Glb | io::Format::Gltf)
    );
    for (flag, given) in [
        ("--clip-tolerance", f.clip_tolerance.is_some()),
        ("--per-frame-targets", f.per_frame_targets),
    ] {
        crate::util::only_with(
            flag,
            given,
            "a .glb/.gltf output",
            gltf,
            &format!(
                "it shapes the morph targets of a glTF animation; {} is not one",
                out.display()
            ),
        )?;
    }
    Ok(())
}

/// Whether `--quantize` was given.
pub fn quantize_flag() -> bool {
    context().flags.quantize
}

/// Whether `--meshopt` was given.
pub fn meshopt_flag() -> bool {
    context().flags.meshopt
}

pub(crate) fn refuse_asset_flags(out: &Path, quantize_applies: bool) -> anyhow::Result<()> {
    let f = context().flags;
    let given = given(&[
        (f.quantize && !quantize_applies, "--quantize"),
        (f.meshopt && !quantize_applies, "--meshopt"),
        (f.sparse_targets, "--sparse-targets"),
        (f.no_normals, "--no-normals"),
    ]);
    if !given.is_empty() {
        anyhow::bail!(
            "{}: {} not applied to an edit of the user's asset, which keeps its own accessors and \
             encoding as they are (they apply to animations written whole); leave {} out",
            out.display(),
            given.join(", "),
            if given.len() == 1 { "it" } else { "them" }
        );
    }
    Ok(())
}

/// Notes on stderr that `--quantize`, `--meshopt` and `--sparse-targets`, when given, do
/// nothing to `path`, an output in another format than glTF (OBJ, PLY, OFF, PC2, USD), which
/// is written as it would be without them.
pub(crate) fn note_gltf_only_flags(path: &Path) {
    if matches!(
        io::Format::from_path(path),
        Some(io::Format::Glb | io::Format::Gltf)
    ) {
        return;
    }
    let f = context().flags;
    let given = given(&[
        (f.quantize, "--quantize"),
        (f.meshopt, "--meshopt"),
        (f.sparse_targets, "--sparse-targets"),
    ]);
    if !given.is_empty() {
        eprintln!(
            "note: {}: {} shape .glb/.gltf output only; this output is written without {}",
            path.display(),
            given.join(", "),
            if given.len() == 1 { "it" } else { "them" }
        );
    }
}

/// The names of the flags given, of `(given, name)` pairs.
fn given(flags: &[(bool, &'static str)]) -> Vec<&'static str> {
    flags
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, name)| *name)
        .collect()
}
