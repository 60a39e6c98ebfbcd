//! Output planning shared by every subcommand: check every output location before any work,
//! then write all outputs or none.
//!
//! A command lists its inputs and its outputs (each with the flag that named it and what it
//! must hold) in a [`Plan`]. [`Plan::check`] fails, before anything is read or solved, when
//! - an output is an input, or a directory holding one (compared after canonicalization);
//! - two outputs are the same file, or one is a `frame_*.obj` file inside another's frame
//!   directory;
//! - an output's extension names no format it can hold (`transfer --out t.ply`);
//! - an output's directory does not exist or cannot be written (`--report /proc/x.json`);
//! - a frame directory already holds `frame_*.obj` files, which the write would replace or
//!   delete, and `--force` was not given.
//!
//! The [`Outputs`] it returns stage every write to a temporary file next to its destination
//! ([`morphkit::io::Staging`]); [`Outputs::commit`] moves them all into place once every one
//! has been written. A failed write (or an error before the commit) leaves every destination
//! as it was.

use anyhow::bail;
use morphkit::io::{self, Format, FramesOptions, GltfMorphs, GltfOptions, Staging};
use morphkit::{ShapeSet, TriMesh};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Options of every written animation, accepted by every subcommand (`global` clap arguments).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct OutputFlags {
    /// Most morph targets per mesh in a .glb/.gltf animation (default 200, what WebGL2 viewers
    /// such as three.js play). A longer animation is split into meshes of at most N targets,
    /// shown in turn by node scale; 0 never splits (a warning says when viewers will not play
    /// it).
    #[arg(long, global = true, value_name = "N")]
    pub max_targets: Option<usize>,
    /// Leave vertex normals and normal deltas out of .glb/.gltf output (smaller, shades flat).
    #[arg(long, global = true)]
    pub no_normals: bool,
}

/// What every output of this run is stamped with: the flags, the subcommand and the command
/// line.
#[derive(Clone, Debug, Default)]
struct Context {
    flags: OutputFlags,
    subcommand: String,
    command: String,
}

static CONTEXT: OnceLock<Context> = OnceLock::new();

/// Records the output flags, the subcommand name and the command line (call once, from main).
pub fn set_context(flags: OutputFlags, subcommand: &str) {
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let _ = CONTEXT.set(Context {
        flags,
        subcommand: subcommand.to_string(),
        command,
    });
}

fn context() -> Context {
    CONTEXT.get().cloned().unwrap_or_default()
}

/// The stem of a path without mesh extensions (`horse-07.obj.gz` → `horse-07`).
fn stem(p: &Path) -> String {
    let name = p
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    io::shape_name(&name).to_string()
}

/// The name of what the inputs hold: the longest prefix shared by at least two input stems
/// (without trailing digits and separators: `horse-gallop-01` … `horse-gallop-48` give
/// `horse-gallop`), else the first input's stem, else `morphkit`.
pub fn sequence_name(inputs: &[PathBuf]) -> String {
    let stems: Vec<String> = inputs
        .iter()
        .map(|p| stem(p))
        .filter(|s| !s.is_empty())
        .collect();
    let trim = |s: &str| {
        s.trim_end_matches(|c: char| c.is_ascii_digit() || matches!(c, '-' | '_' | '.' | ' '))
            .to_string()
    };
    let mut best = String::new();
    for (i, a) in stems.iter().enumerate() {
        for b in &stems[i + 1..] {
            let n = a
                .char_indices()
                .zip(b.chars())
                .take_while(|((_, x), y)| x == y)
                .last()
                .map_or(0, |((k, x), _)| k + x.len_utf8());
            let p = trim(&a[..n]);
            if p.len() > best.len() {
                best = p;
            }
        }
    }
    if best.is_empty() {
        best = stems.first().map_or_else(String::new, |s| trim(s));
    }
    if best.is_empty() {
        "morphkit".into()
    } else {
        best
    }
}

/// `opts` with what the run knows filled in where it still has the default: glTF and USD
/// names (the inputs' [`sequence_name`]; the clip is `NAME-SUBCOMMAND`, or `NAME` for
/// `convert`), the output flags, and extras / custom layer data with the command line, the
/// subcommand, the source files, the frame rate and the frame count (merged into extras the
/// command set, such as blend weights per frame).
pub fn frames_options(opts: &FramesOptions, frames: usize) -> FramesOptions {
    let ctx = context();
    let mut o = opts.clone();
    let name = sequence_name(&o.inputs);
    let defaults = GltfOptions::default();
    if o.gltf.name == defaults.name {
        o.gltf.name = name.clone();
        if o.gltf.clip_name.is_none() && !ctx.subcommand.is_empty() && ctx.subcommand != "convert" {
            o.gltf.clip_name = Some(format!("{name}-{}", ctx.subcommand));
        }
    }
    if o.usd.name == io::UsdOptions::default().name {
        o.usd.name = name;
    }
    if let Some(n) = ctx.flags.max_targets {
        o.gltf.max_targets = n;
    }
    if ctx.flags.no_normals {
        o.gltf.normals = false;
    }
    let mut extras = match o.gltf.extras.take() {
        Some(serde_json::Value::Object(m)) => m,
        Some(other) => {
            let mut m = serde_json::Map::new();
            m.insert("data".into(), other);
            m
        }
        None => serde_json::Map::new(),
    };
    if !ctx.command.is_empty() {
        extras.insert("command".into(), json!(ctx.command));
        extras.insert("subcommand".into(), json!(ctx.subcommand));
    }
    extras.insert(
        "sources".into(),
        json!(o
            .inputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()),
    );
    extras.insert("fps".into(), json!(o.fps));
    extras.insert("frames".into(), json!(frames));
    let extras = json!({ "morphkit": extras });
    o.gltf.extras = Some(extras.clone());
    if o.usd.custom_data.is_none() {
        o.usd.custom_data = Some(extras);
    }
    o
}

/// What an output holds, which decides the extensions it accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// One mesh: `.obj`, `.obj.gz`, `.ply`, `.off`, `.gltf`, `.glb` or `.usda`.
    Mesh,
    /// An animation: a frame directory (an existing directory or a path without extension),
    /// `.glb`, `.gltf`, `.pc2` or `.usda`.
    Animation,
    /// Either, as the extension says (a single-frame blend).
    MeshOrAnimation,
    /// A JSON document (a report, a correspondence); any file name.
    Json,
}

const MESH_EXTS: &str = ".obj, .obj.gz, .ply, .off, .gltf, .glb or .usda";
const ANIM_EXTS: &str = "a directory (a path without extension), .glb, .gltf, .pc2 or .usda";

/// One planned output.
#[derive(Clone, Debug)]
struct Planned {
    flag: String,
    path: PathBuf,
    kind: Kind,
    /// Written only by some runs: removed at the commit when this run did not write it.
    sometimes: bool,
}

/// The inputs and outputs of one command, checked together; see the module docs.
#[derive(Debug, Default)]
pub struct Plan {
    inputs: Vec<PathBuf>,
    outputs: Vec<Planned>,
    force: bool,
}

/// True when `out` names a frame directory: an existing directory, or a path without extension.
pub fn is_frame_dir(out: &Path) -> bool {
    out.is_dir() || (!out.exists() && out.extension().is_none())
}

/// The directory a file `path` is created in.
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Fails unless a file can be created in the existing directory `dir` (tried with a probe
/// file, removed at once: permission bits do not tell for root, read-only mounts or `/proc`).
fn check_writable_dir(flag: &str, out: &Path, dir: &Path) -> anyhow::Result<()> {
    if !dir.exists() {
        bail!(
            "{flag} {}: the directory {} does not exist",
            out.display(),
            dir.display()
        );
    }
    if !dir.is_dir() {
        bail!(
            "{flag} {}: {} is not a directory",
            out.display(),
            dir.display()
        );
    }
    let probe = dir.join(format!(".morphkit-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => bail!(
            "{flag} {}: cannot write in the directory {}: {e}",
            out.display(),
            dir.display()
        ),
    }
}

/// The nearest existing ancestor of `p` (`.` for a relative path with none).
fn existing_ancestor(p: &Path) -> PathBuf {
    let mut cur = p.to_path_buf();
    loop {
        if cur.exists() {
            return cur;
        }
        match cur.parent() {
            Some(d) if !d.as_os_str().is_empty() => cur = d.to_path_buf(),
            _ => return PathBuf::from("."),
        }
    }
}

impl Plan {
    /// A plan for a command reading `inputs` (files and directories that must not be written).
    pub fn new(inputs: &[PathBuf]) -> Self {
        Self {
            inputs: inputs.to_vec(),
            ..Self::default()
        }
    }

    /// Allows replacing the `frame_*.obj` files of an existing frame directory (`--force`).
    pub fn force(mut self, force: bool) -> Self {
        self.force = force;
        self
    }

    /// Adds an output named by `flag` (for messages: `--out`, `--report`, `OUT`).
    pub fn output(mut self, flag: &str, path: &Path, kind: Kind) -> Self {
        self.outputs.push(Planned {
            flag: flag.to_string(),
            path: path.to_path_buf(),
            kind,
            sometimes: false,
        });
        self
    }

    /// Adds an output that only some runs write (`OUT-unconverged.ply`): when this run does
    /// not, a file an earlier run left there is removed at the commit, since it would describe
    /// another result.
    pub fn output_sometimes(mut self, flag: &str, path: &Path, kind: Kind) -> Self {
        self = self.output(flag, path, kind);
        if let Some(o) = self.outputs.last_mut() {
            o.sometimes = true;
        }
        self
    }

    /// Adds an output when `path` is given.
    pub fn output_opt(self, flag: &str, path: Option<&PathBuf>, kind: Kind) -> Self {
        match path {
            Some(p) => self.output(flag, p, kind),
            None => self,
        }
    }

    /// Checks every output (see the module docs) and returns the writer for them.
    pub fn check(self) -> anyhow::Result<Outputs> {
        for o in &self.outputs {
            io::check_not_input(&o.path, &self.inputs)
                .map_err(|e| anyhow::anyhow!("{}: {e}", o.flag))?;
            self.check_format(o)?;
        }
        self.check_distinct()?;
        for o in &self.outputs {
            self.check_location(o)?;
        }
        let mut staging = Staging::new();
        for o in self.outputs.iter().filter(|o| o.sometimes) {
            staging.remove_unless_written(&o.path);
        }
        Ok(Outputs { staging })
    }

    fn check_format(&self, o: &Planned) -> anyhow::Result<()> {
        let p = o.path.display();
        let fmt = Format::from_path(&o.path);
        let frame_dir = is_frame_dir(&o.path);
        match o.kind {
            Kind::Mesh => {
                if o.path.is_dir() {
                    bail!(
                        "{} {p}: is a directory, expected a mesh file ({MESH_EXTS})",
                        o.flag
                    );
                }
                if !fmt.is_some_and(|f| f != Format::Pc2) {
                    bail!(
                        "{} {p}: unsupported format for a mesh; expected {MESH_EXTS}",
                        o.flag
                    );
                }
            }
            Kind::Animation => {
                if !frame_dir && !fmt.is_some_and(Format::is_animation) {
                    bail!(
                        "{} {p}: unsupported format for an animation; expected {ANIM_EXTS}{}",
                        o.flag,
                        if fmt.is_some_and(Format::is_single_mesh) {
                            " (this extension holds one mesh)"
                        } else {
                            ""
                        }
                    );
                }
            }
            Kind::MeshOrAnimation => {
                if !frame_dir && fmt.is_none() {
                    bail!(
                        "{} {p}: unsupported format; expected {ANIM_EXTS}, or {MESH_EXTS} for one frame",
                        o.flag
                    );
                }
            }
            Kind::Json => {
                if o.path.is_dir() {
                    bail!("{} {p}: is a directory, expected a file name", o.flag);
                }
            }
        }
        Ok(())
    }

    fn check_location(&self, o: &Planned) -> anyhow::Result<()> {
        let frame_dir = o.kind != Kind::Json && o.kind != Kind::Mesh && is_frame_dir(&o.path);
        if !frame_dir {
            return check_writable_dir(&o.flag, &o.path, &parent_dir(&o.path));
        }
        if o.path.exists() {
            check_writable_dir(&o.flag, &o.path, &o.path)?;
            check_writable_dir(&o.flag, &o.path, &parent_dir(&o.path))?;
            let old = io::frame_files(&o.path);
            if !old.is_empty() && !self.force {
                let name = |p: &PathBuf| {
                    p.file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
                };
                let range = if old.len() == 1 {
                    name(&old[0])
                } else {
                    format!("{} … {}", name(&old[0]), name(&old[old.len() - 1]))
                };
                bail!(
                    "{} {}: the directory already holds {} frame file{} ({range}), which this \
                     write would replace or delete; pass --force to replace them, or give an \
                     empty or new directory",
                    o.flag,
                    o.path.display(),
                    old.len(),
                    if old.len() == 1 { "" } else { "s" }
                );
            }
            Ok(())
        } else {
            let anc = existing_ancestor(&o.path);
            check_writable_dir(&o.flag, &o.path, &anc)
        }
    }

    fn check_distinct(&self) -> anyhow::Result<()> {
        let canon: Vec<PathBuf> = self
            .outputs
            .iter()
            .map(|o| io::canonical_path(&o.path))
            .collect();
        for (i, a) in self.outputs.iter().enumerate() {
            for (j, b) in self.outputs.iter().enumerate().skip(i + 1) {
                if canon[i] == canon[j] {
                    bail!(
                        "{} and {} are the same file {}; every output of one command needs its own path",
                        a.flag,
                        b.flag,
                        b.path.display()
                    );
                }
            }
            let a_dir = a.kind != Kind::Json && a.kind != Kind::Mesh && is_frame_dir(&a.path);
            for (j, b) in self.outputs.iter().enumerate() {
                let inside = canon[j].parent() == Some(canon[i].as_path())
                    && b.path
                        .file_name()
                        .is_some_and(|n| io::is_frame_file_name(&n.to_string_lossy()));
                if i != j && a_dir && inside {
                    bail!(
                        "{} {} is a frame file inside the frame directory of {} {}; give it another name or place",
                        b.flag,
                        b.path.display(),
                        a.flag,
                        a.path.display()
                    );
                }
            }
        }
        Ok(())
    }
}

/// Writers for the outputs of a checked [`Plan`]: everything is staged, and
/// [`Outputs::commit`] moves it all into place.
#[derive(Debug)]
pub struct Outputs {
    staging: Staging,
}

impl Outputs {
    /// Stages one mesh (format by extension).
    pub fn mesh(&mut self, path: &Path, mesh: &TriMesh) -> anyhow::Result<()> {
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_mesh(tmp, mesh))?)
    }

    /// Stages one mesh; an `.obj`/`.obj.gz` with a `template` (the input's own OBJ) is that
    /// file with the mesh's positions and recomputed normals, every other record kept.
    pub fn mesh_like(
        &mut self,
        path: &Path,
        mesh: &TriMesh,
        template: Option<&io::ObjTemplate>,
    ) -> anyhow::Result<()> {
        match (template, Format::from_path(path)) {
            (Some(t), Some(Format::Obj { gzip })) => {
                Ok(self
                    .staging
                    .write(path, false, |tmp| t.write(tmp, &mesh.positions, gzip))?)
            }
            _ => self.mesh(path, mesh),
        }
    }

    /// Stages a binary PLY with colours.
    pub fn colored_ply(
        &mut self,
        path: &Path,
        mesh: &TriMesh,
        colors: &io::Colors,
    ) -> anyhow::Result<()> {
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_ply_colored(tmp, mesh, colors))?)
    }

    /// Stages a glTF rig (target names kept) with the run's flags and extras, named `morphkit`;
    /// see [`Outputs::gltf_from`] to name it after the inputs.
    // Kept with its signature for the commands written against it (issue 9's `rig`).
    #[allow(dead_code)]
    pub fn gltf(&mut self, path: &Path, rig: &GltfMorphs) -> anyhow::Result<()> {
        self.gltf_from(path, rig, &[])
    }

    /// Stages a glTF rig (target names kept), with the run's names (after `inputs`), flags and
    /// extras ([`frames_options`]); warns on stderr about what viewers may not play.
    pub fn gltf_from(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        inputs: &[PathBuf],
    ) -> anyhow::Result<()> {
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            rig.weight_keys.len(),
        );
        self.gltf_with(path, rig, &opts.gltf)
    }

    fn gltf_with(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        opts: &GltfOptions,
    ) -> anyhow::Result<()> {
        let mut summary = io::GltfSummary::default();
        self.staging.write(path, false, |tmp| {
            summary = io::write_gltf_with(tmp, rig, opts)?;
            Ok(())
        })?;
        report_gltf(path, &summary, opts);
        Ok(())
    }

    /// Stages a rig as `UsdSkel` blend shapes named after its targets, with the run's names and
    /// custom layer data ([`frames_options`]).
    pub fn usd_blendshapes(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        inputs: &[PathBuf],
    ) -> anyhow::Result<()> {
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            0,
        );
        Ok(self.staging.write(path, false, |tmp| {
            io::write_usd_blendshapes(tmp, &rig.base, &rig.targets, &rig.target_names, &opts.usd)
        })?)
    }

    /// Stages an animation (a frame directory, `.glb`/`.gltf`, `.pc2` or `.usda`), calling
    /// `on_frame(i)` after each OBJ frame; names, flags and extras as [`frames_options`].
    pub fn frames(
        &mut self,
        path: &Path,
        frames: &ShapeSet,
        opts: &FramesOptions,
        on_frame: impl FnMut(usize),
    ) -> anyhow::Result<()> {
        let opts = frames_options(opts, frames.len());
        let dir = is_frame_dir(path);
        if !dir && matches!(Format::from_path(path), Some(Format::Glb | Format::Gltf)) {
            return self.gltf_with(path, &io::frames_to_gltf(frames, opts.fps), &opts.gltf);
        }
        Ok(self.staging.write(path, dir, |tmp| {
            io::write_frames_with(tmp, frames, &opts, on_frame)
        })?)
    }

    /// Stages an animation written frame by frame ([`io::FrameStream`]: a frame directory
    /// when `dir`, else `.pc2`) of `frames` frames of `base`'s connectivity; a directory's
    /// frames are written into `template` where there is one.
    pub fn stream(
        &mut self,
        path: &Path,
        dir: bool,
        base: &TriMesh,
        frames: usize,
        template: Option<io::ObjTemplate>,
    ) -> anyhow::Result<io::FrameStream> {
        let tmp = self.staging.stage(path, dir)?;
        Ok(io::FrameStream::create(&tmp, path, dir, base, frames)?.with_obj_template(template))
    }

    /// Stages an output that `write` produces at the temporary path it is given (a file, or a
    /// directory when `dir`): for writers without a method of their own.
    pub fn custom(
        &mut self,
        path: &Path,
        dir: bool,
        write: impl FnOnce(&Path) -> Result<(), io::IoError>,
    ) -> anyhow::Result<()> {
        Ok(self.staging.write(path, dir, write)?)
    }

    /// Stages a JSON document (pretty-printed).
    pub fn json(&mut self, path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(value)?;
        self.text(path, &text)
    }

    /// Stages a text file.
    pub fn text(&mut self, path: &Path, text: &str) -> anyhow::Result<()> {
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_atomic(tmp, text.as_bytes()))?)
    }

    /// Moves every staged output into place.
    pub fn commit(self) -> anyhow::Result<()> {
        Ok(self.staging.commit()?)
    }
}

/// Tells on stderr when a glTF animation was split or will not play everywhere.
pub fn report_gltf(path: &Path, summary: &io::GltfSummary, opts: &GltfOptions) {
    for w in &summary.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    if summary.meshes > 1 {
        eprintln!(
            "warning: {}: {} morph targets are more than the {} one mesh may hold in WebGL2 \
             viewers (--max-targets); written as {} meshes of at most {} targets, shown in turn by \
             node scale",
            path.display(),
            summary.targets,
            opts.max_targets,
            summary.meshes,
            opts.max_targets
        );
    }
}

#[cfg(test)]
#[path = "outputs_tests.rs"]
mod tests;
