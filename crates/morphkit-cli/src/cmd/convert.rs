//! `morphkit convert`: between OBJ, PLY, OFF, glTF/GLB, PC2 and USD (`.usda`), single meshes
//! or frame sequences.

use crate::outputs::{Kind, Outputs, Plan};
use crate::util::{check_fps, progress};
use anyhow::{bail, Context};
use morphkit::io::{self, Format, FramesOptions, GltfReadOptions};
use morphkit::{ShapeSet, TriMesh};
use std::path::{Path, PathBuf};

const EXAMPLES: &str = "\
Examples:
  morphkit convert bunny.obj.gz bunny.ply                 # one mesh, any two formats
  morphkit convert 'cat-run/*.obj.gz' cat-run.glb          # a sequence (glob, quoted) to a glTF animation
  morphkit convert cat-run/ --fps 30 cat-run.glb           # the OBJ files of a directory, in frame order
  morphkit convert a.obj b.obj c.obj anim.pc2              # several files to a point cache
  morphkit convert cat-run.glb frames/                     # an animation back to frames/frame_0000.obj, …
  morphkit convert anim.pc2 --reference rest.obj frames/   # PC2 needs the mesh for its connectivity
  morphkit convert face-rig.glb face-copy.gltf             # the whole asset: materials, textures, skins, nodes kept
  morphkit convert scene.glb --mesh Face face.usda         # choose the mesh when several have morph targets
  morphkit convert cat-run.glb --frame 12 pose12.obj       # one frame of an animation
  morphkit convert 'cat-run/*.obj.gz' cat-run.usda         # a USD Mesh with time-sampled points
  morphkit convert face-rig.glb face-rig.usda              # a rig (no animation): UsdSkel blend shapes
  morphkit convert long/ --max-targets 100 long.glb        # at most 100 morph targets per mesh

An output without extension (or an existing directory) receives numbered OBJ frames; an
existing directory that already holds frame_*.obj files needs --force. Frame k of a .glb/.gltf
or .usda animation is at k/fps seconds (default 24 fps), so N frames play as an (N − 1)/fps
second clip: 9 frames last 0.33 s, and viewers loop it. A .glb/.gltf animation of more than
--max-targets frames (default 200, what WebGL2 viewers such as three.js hold per mesh) is split
into meshes shown in turn, with a warning. A single-mesh output
(.obj, .ply, .off) of an animation needs --frame N. Outputs are written atomically and never
overwrite an input. A .glb/.gltf converted to .glb/.gltf is the same asset in one file: every
buffer merged, external images embedded, everything else (materials, textures, skins, other
meshes, node transforms, names, extras, animations) kept as it was.";

/// Arguments of `morphkit convert`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct ConvertArgs {
    /// Inputs (files, quoted glob patterns, or one directory of OBJ frames), then the output.
    #[arg(required = true, value_name = "IN... OUT")]
    pub paths: Vec<String>,
    /// Frames per second of a written .glb/.gltf or .usda animation (N frames last (N − 1)/fps
    /// seconds).
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Reference mesh giving the connectivity of a PC2 input.
    #[arg(long, value_name = "MESH")]
    pub reference: Option<PathBuf>,
    /// Write only this frame (0-based) of an animation input to a single-mesh output.
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,
    /// Replace the frame_*.obj files of an existing output directory.
    #[arg(long)]
    pub force: bool,
    /// The mesh of a .glb/.gltf input to read, by name or index (`--mesh 1`; an index where
    /// meshes share a name), when several have morph targets.
    #[arg(long, value_name = "NAME|INDEX")]
    pub mesh: Option<String>,
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
/// existing path) becomes its matching files sorted by name, frame numbers as numbers
/// ([`io::sort_frame_paths`]), a directory its OBJ frames
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
            io::sort_frame_paths(&mut matches);
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
        || matches!(Format::from_path(out), Some(Format::Pc2 | Format::Usda))
}

fn read_sequence(files: &[PathBuf]) -> anyhow::Result<ShapeSet> {
    let pb = progress(files.len() as u64, "reading");
    let set = io::read_shape_set_with(files, |_, _| pb.inc(1));
    pb.finish_and_clear();
    Ok(set?)
}

fn write_frames(
    mut outputs: Outputs,
    out: &Path,
    frames: &ShapeSet,
    opts: &FramesOptions,
) -> anyhow::Result<()> {
    let pb = progress(frames.len() as u64, "writing");
    let r = outputs.frames(out, frames, opts, |_| pb.inc(1));
    pb.finish_and_clear();
    r?;
    outputs.commit()?;
    eprintln!(
        "wrote {}: {} frames of {} vertices",
        out.display(),
        frames.len(),
        frames.num_vertices()
    );
    Ok(())
}

fn write_mesh(
    mut outputs: Outputs,
    out: &Path,
    mesh: &TriMesh,
    template: Option<&io::MeshTemplate>,
) -> anyhow::Result<()> {
    outputs.mesh_like(out, mesh, template)?;
    outputs.commit()?;
    eprintln!(
        "wrote {}: {} vertices, {} triangles",
        out.display(),
        mesh.num_vertices(),
        mesh.num_triangles()
    );
    Ok(())
}

/// Runs `morphkit convert`.
pub fn run(args: &ConvertArgs) -> anyhow::Result<()> {
    convert(args)?;
    // After the output is written: what a positions-and-faces output left out of a glTF.
    if let [input, out] = args.paths.as_slice() {
        crate::util::note_not_carried(Path::new(input), Path::new(out), args.mesh.as_deref());
    }
    Ok(())
}

fn convert(args: &ConvertArgs) -> anyhow::Result<()> {
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
    check_fps(args.fps)?;
    crate::outputs::check_clip_flags(&out)?;
    crate::util::announce_reading(&inputs);
    let frames_out = is_frames_output(&out);
    let out_fmt = Format::from_path(&out);
    let out_gltf = matches!(out_fmt, Some(Format::Glb | Format::Gltf));
    let sequence = inputs.len() > 1 || single_dir;
    if sequence && !frames_out && !out_gltf && args.frame.is_none() {
        bail!(
            "{}: a sequence converts to an animation: give a directory, .glb, .gltf, .pc2 or .usda output, or --frame N for one frame",
            out.display()
        );
    }
    if frames_out && args.frame.is_some() {
        bail!(
            "--frame picks one frame for a single-mesh output; {} receives a whole animation",
            out.display()
        );
    }
    let kind = if frames_out {
        Kind::Animation
    } else {
        Kind::Mesh
    };
    let outputs = Plan::new(&protected)
        .force(args.force)
        .output("OUT", &out, kind)
        .check()?;
    let opts = FramesOptions {
        fps: args.fps,
        inputs: protected.clone(),
        ..FramesOptions::default()
    };
    if sequence && args.mesh.is_some() {
        bail!("--mesh chooses the mesh of one .glb/.gltf input, not of a sequence");
    }
    if sequence {
        let frames = read_sequence(&inputs)?;
        return match args.frame {
            Some(k) => write_mesh(outputs, &out, &pick(&frames, k, ins.join(" "))?, None),
            None => write_frames(outputs, &out, &frames, &opts),
        };
    }
    let input = &inputs[0];
    let in_fmt = Format::from_path(input);
    let in_gltf = matches!(in_fmt, Some(Format::Glb | Format::Gltf));
    let in_anim = in_gltf || matches!(in_fmt, Some(Format::Pc2 | Format::Usda));
    if args.mesh.is_some() && !in_gltf {
        bail!(
            "--mesh chooses a mesh of a .glb/.gltf input; {} is not one",
            input.display()
        );
    }
    let gltf_opts = GltfReadOptions {
        mesh: args.mesh.clone(),
    };
    // A glTF input's frames, from the chosen mesh.
    let read_animation = |input: &Path| -> anyhow::Result<ShapeSet> {
        Ok(if in_gltf {
            io::gltf_to_frames(input, &io::read_gltf_morphs_with(input, &gltf_opts)?)?
        } else {
            io::read_animation(input, args.reference.as_deref())?
        })
    };
    if in_gltf && out_fmt == Some(Format::Usda) {
        let rig = io::read_gltf_morphs_with(input, &gltf_opts)?;
        if rig.weight_keys.is_empty() && !rig.targets.is_empty() {
            // A rig without an animation: UsdSkel blend shapes with the target names.
            let mut outputs = outputs;
            outputs.usd_blendshapes(&out, &rig, &protected)?;
            outputs.commit()?;
            eprintln!(
                "wrote {}: {} vertices, {} blend shapes",
                out.display(),
                rig.base.num_vertices(),
                rig.targets.len()
            );
            return Ok(());
        }
    }
    if frames_out {
        let frames = read_animation(input)?;
        return write_frames(outputs, &out, &frames, &opts);
    }
    if in_gltf && out_gltf && args.frame.is_none() {
        // The user's asset, carried whole (io::GltfAsset).
        let asset = io::GltfAsset::read(input, &gltf_opts)?;
        let rig = asset.morphs();
        morphkit::mesh::validate(&rig.base)
            .map_err(|e| anyhow::anyhow!("{}: {e}", input.display()))?;
        let mut outputs = outputs;
        outputs.gltf_asset(&out, &asset, &protected, rig.weight_keys.len())?;
        outputs.commit()?;
        let doc = asset.document();
        let count = |k: &str| doc[k].as_array().map_or(0, Vec::len);
        eprintln!(
            "wrote {}: the asset whole ({} meshes, {} nodes, {} materials, {} animations); mesh {}: {} vertices, {} morph targets",
            out.display(),
            count("meshes"),
            count("nodes"),
            count("materials"),
            count("animations"),
            asset.mesh_name().map_or_else(|| asset.mesh_index().to_string(), |n| format!("'{n}'")),
            rig.base.num_vertices(),
            rig.targets.len(),
        );
        return Ok(());
    }
    if in_anim && out_gltf && args.frame.is_none() {
        let frames = read_animation(input)?;
        return write_frames(outputs, &out, &frames, &opts);
    }
    if in_anim || args.frame.is_some() {
        let frames = read_animation(input)?;
        let k = match args.frame {
            Some(k) => k,
            None if frames.len() == 1 => 0,
            None => bail!(
                "{}: holds {} frames ({} … {}), but {} holds one mesh; give --frame N (0 to {}) \
                 for one of them, or a directory, .glb, .gltf, .pc2 or .usda output for all",
                input.display(),
                frames.len(),
                frames.name(0),
                frames.name(frames.len() - 1),
                out.display(),
                frames.len() - 1
            ),
        };
        return write_mesh(
            outputs,
            &out,
            &pick(&frames, k, input.display().to_string())?,
            None,
        );
    }
    let mesh = io::read_mesh(input)?;
    // OBJ to OBJ and PLY to PLY keep the artist's records (io::MeshTemplate).
    let template = crate::util::template(input, mesh.num_vertices())?;
    write_mesh(outputs, &out, &mesh, template.as_ref())
}

/// Frame `k` of `frames` as a mesh; the error names `what` and the valid range.
fn pick(frames: &ShapeSet, k: usize, what: String) -> anyhow::Result<TriMesh> {
    if k >= frames.len() {
        bail!(
            "--frame {k}: {what} has {} frame{} (0 to {})",
            frames.len(),
            if frames.len() == 1 { "" } else { "s" },
            frames.len() - 1
        );
    }
    Ok(frames.mesh(k))
}
