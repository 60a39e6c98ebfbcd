//! `morphkit convert`: between OBJ, PLY, OFF, glTF/GLB and PC2, single meshes or frame
//! sequences.

use crate::util::progress;
use anyhow::{bail, Context};
use morphkit::io::{self, Format, FramesOptions};
use morphkit::ShapeSet;
use std::path::{Path, PathBuf};

const EXAMPLES: &str = "\
Examples:
  morphkit convert bunny.obj.gz bunny.ply                 # one mesh, any two formats
  morphkit convert 'cat-run/*.obj.gz' cat-run.glb          # a sequence (glob, quoted) to a glTF animation
  morphkit convert cat-run/ --fps 30 cat-run.glb           # the OBJ files of a directory, sorted by name
  morphkit convert a.obj b.obj c.obj anim.pc2              # several files to a point cache
  morphkit convert cat-run.glb frames/                     # an animation back to frames/frame_0000.obj, …
  morphkit convert anim.pc2 --reference rest.obj frames/   # PC2 needs the mesh for its connectivity
  morphkit convert face-rig.glb face-copy.gltf             # a morph-target rig keeps its targets and names

An output without extension (or an existing directory) receives numbered OBJ frames.
Outputs are written atomically and never overwrite an input.";

/// Arguments of `morphkit convert`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct ConvertArgs {
    /// Inputs (files, quoted glob patterns, or one directory of OBJ frames), then the output.
    #[arg(required = true, value_name = "IN... OUT")]
    pub paths: Vec<String>,
    /// Frames per second of a written glTF animation.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Reference mesh giving the connectivity of a PC2 input.
    #[arg(long, value_name = "MESH")]
    pub reference: Option<PathBuf>,
}

/// Input arguments after expansion (see [`expand`]).
pub(crate) struct Inputs {
    /// The files to read, in order: globs and directories replaced by their files.
    pub files: Vec<PathBuf>,
    /// Every path the output must not overwrite: the files and the directories they came from.
    pub protected: Vec<PathBuf>,
    /// True when the arguments were exactly one directory (a frame sequence).
    pub single_dir: bool,
}

/// Expands input arguments: a glob pattern (an argument with `*`, `?` or `[` that is not an
/// existing path) becomes its matching files sorted by name, a directory its OBJ frames
/// ([`io::obj_files`]), anything else stays as given.
pub(crate) fn expand(args: &[String]) -> anyhow::Result<Inputs> {
    let mut files = Vec::new();
    let mut protected = Vec::new();
    let mut dirs = 0;
    for a in args {
        let p = PathBuf::from(a);
        if !p.exists() && a.contains(['*', '?', '[']) {
            let mut matches: Vec<PathBuf> = glob::glob(a)
                .with_context(|| format!("invalid glob pattern '{a}'"))?
                .filter_map(Result::ok)
                .filter(|p| p.is_file())
                .collect();
            if matches.is_empty() {
                bail!("no files match '{a}'");
            }
            matches.sort();
            files.extend(matches);
        } else if p.is_dir() {
            dirs += 1;
            files.extend(io::obj_files(&p)?);
            protected.push(p);
        } else {
            files.push(p);
        }
    }
    protected.extend(files.iter().cloned());
    Ok(Inputs {
        files,
        protected,
        single_dir: args.len() == 1 && dirs == 1,
    })
}

/// True when the output receives an animation rather than one mesh.
fn is_frames_output(out: &Path) -> bool {
    out.is_dir()
        || (!out.exists() && out.extension().is_none())
        || Format::from_path(out) == Some(Format::Pc2)
}

fn read_sequence(files: &[PathBuf]) -> anyhow::Result<ShapeSet> {
    let pb = progress(files.len() as u64, "reading");
    let set = io::read_shape_set_with(files, |_, _| pb.inc(1));
    pb.finish_and_clear();
    Ok(set?)
}

fn write_frames(out: &Path, frames: &ShapeSet, opts: &FramesOptions) -> anyhow::Result<()> {
    let pb = progress(frames.len() as u64, "writing");
    let r = io::write_frames_with(out, frames, opts, |_| pb.inc(1));
    pb.finish_and_clear();
    r?;
    eprintln!(
        "wrote {}: {} frames of {} vertices",
        out.display(),
        frames.len(),
        frames.num_vertices()
    );
    Ok(())
}

/// Runs `morphkit convert`.
pub fn run(args: &ConvertArgs) -> anyhow::Result<()> {
    let (out, ins) = match args.paths.split_last() {
        Some((out, ins)) if !ins.is_empty() => (out, ins),
        _ => bail!("give at least one input and an output (morphkit convert IN... OUT)"),
    };
    let out = PathBuf::from(out);
    let Inputs {
        files: inputs,
        mut protected,
        single_dir,
    } = expand(ins)?;
    protected.extend(args.reference.iter().cloned());
    io::check_not_input(&out, &protected)?;
    let opts = FramesOptions {
        fps: args.fps,
        inputs: protected,
    };
    let frames_out = is_frames_output(&out);
    if inputs.len() > 1 || single_dir {
        if !frames_out && !matches!(Format::from_path(&out), Some(Format::Glb | Format::Gltf)) {
            bail!(
                "{}: a sequence converts to an animation: give a directory, .glb, .gltf or .pc2 output",
                out.display()
            );
        }
        let frames = read_sequence(&inputs)?;
        return write_frames(&out, &frames, &opts);
    }
    let input = &inputs[0];
    let in_fmt = Format::from_path(input);
    let out_fmt = Format::from_path(&out);
    match (in_fmt, frames_out) {
        (Some(Format::Pc2), false) if !matches!(out_fmt, Some(Format::Glb | Format::Gltf)) => {
            bail!(
                "{}: a PC2 animation converts to a directory, .glb, .gltf or .pc2",
                out.display()
            )
        }
        (Some(Format::Glb | Format::Gltf), false)
            if matches!(out_fmt, Some(Format::Glb | Format::Gltf)) =>
        {
            let rig = io::read_gltf_morphs(input)?;
            morphkit::mesh::validate(&rig.base)
                .map_err(|e| anyhow::anyhow!("{}: {e}", input.display()))?;
            io::write_gltf_morphs(&out, &rig)?;
            eprintln!(
                "wrote {}: {} vertices, {} morph targets, {} animation keys",
                out.display(),
                rig.base.num_vertices(),
                rig.targets.len(),
                rig.weight_keys.len()
            );
            Ok(())
        }
        (Some(Format::Pc2), _) | (Some(Format::Glb | Format::Gltf), true) => {
            let frames = io::read_animation(input, args.reference.as_deref())?;
            write_frames(&out, &frames, &opts)
        }
        (_, true) => {
            let frames = io::read_animation(input, None)?;
            write_frames(&out, &frames, &opts)
        }
        (_, false) => {
            let mesh = io::read_mesh(input)?;
            io::write_mesh(&out, &mesh)?;
            eprintln!(
                "wrote {}: {} vertices, {} triangles",
                out.display(),
                mesh.num_vertices(),
                mesh.num_triangles()
            );
            Ok(())
        }
    }
}
