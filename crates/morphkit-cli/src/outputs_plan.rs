//! The first phase of writing outputs: every output location is checked, before any work,
//! by a [`Plan`] (see the parent module's docs); its check returns the [`Outputs`] writer.

use super::Outputs;
use anyhow::bail;
use morphkit::io::{self, Format, Staging};
use std::path::{Path, PathBuf};

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
        Ok(Outputs {
            staging,
            notes: Vec::new(),
            clips: Vec::new(),
        })
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
