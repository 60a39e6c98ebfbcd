//! `morphkit synth`: assemble a new animation of a target from parts of several animations
//! (Wang & Lee 2008, Sec. 3.2), driven by a TOML recipe.

use crate::outputs::{Kind, Plan};
use crate::util::progress;
use anyhow::Context;
use morphkit::io::{self, Colors, FramesOptions};
use morphkit::synth::{selection_colors, RecipeFile};
use morphkit::ShapeSet;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  morphkit synth camel.toml --out camel.glb
  morphkit synth camel.toml --out camel-frames/ --report synth.json
  morphkit synth face.toml --out face.pc2 --selection face-regions.ply

A recipe (TOML, paths relative to it):
  target = \"camel-reference.obj.gz\"
  frames = 48
  [[layer]]
  source_reference = \"horse-reference.obj.gz\"
  source_frames = \"horse-gallop-*.obj.gz\"   # a glob, a list, a directory, a .glb or a .pc2
  source_scale = 0.59635                     # the gallop is stored 1.6768815x larger
  markers = \"markers-horse-camel.json\"       # or correspondence = \"corr.json\"
  scribble = \"legs.json\"                     # {\"triangles\": [...]} or {\"vertices\": [...]}, 0-based
  mode = \"blend\"                             # or \"compound\"
  offset = 0                                 # first output frame this layer drives
  speed = 1.0                                # source frames per output frame
  loop = true
Also: gamma, kappa, fps, rest, translation = \"follow\"|\"fixed\", follow_layer; per layer name,
blend_region = \"geodesic\" with blend_width (fraction of the target's diagonal); [[pose]]
tables with scribble, axis, angle (degrees) and layer.

OUT: a directory of numbered OBJ frames, a .glb/.gltf animation or a .pc2 cache. The refined
selection (each layer's colour, faded by its weight) is written as a coloured PLY next to OUT
(OUT's name + .selection.ply) or to --selection.";

/// Arguments of `morphkit synth`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct SynthArgs {
    /// The recipe (TOML).
    #[arg(value_name = "RECIPE")]
    pub recipe: PathBuf,
    /// Output: a directory of numbered OBJ frames, a .glb/.gltf or a .pc2.
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,
    /// Write a JSON report (layers, partitions, timings, flipped triangles).
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Where to write the refined selection (default: OUT + .selection.ply).
    #[arg(long, value_name = "PLY")]
    pub selection: Option<PathBuf>,
}

/// `OUT` with `.selection.ply` appended to its name (a trailing slash dropped).
fn selection_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map_or_else(|| "synth".to_string(), |n| n.to_string_lossy().into_owned());
    let stem = name
        .strip_suffix(".glb")
        .or_else(|| name.strip_suffix(".gltf"));
    let stem = stem.or_else(|| name.strip_suffix(".pc2")).unwrap_or(&name);
    out.with_file_name(format!("{stem}.selection.ply"))
}

/// Runs `morphkit synth`.
pub fn run(args: &SynthArgs) -> anyhow::Result<()> {
    let rf = RecipeFile::read(&args.recipe)?;
    let t0 = Instant::now();
    let built = rf.build()?;
    let build_s = t0.elapsed().as_secs_f64();
    let s = &built.synthesizer;
    // Split seams and hard edges are one vertex for the solve (mesh::weld); frames come back
    // in the target's own layout.
    super::weld_util::announce(&built.weld, "the target");
    let selection = args
        .selection
        .clone()
        .unwrap_or_else(|| selection_path(&args.out));
    if io::Format::from_path(&selection) != Some(io::Format::Ply) {
        anyhow::bail!(
            "--selection {}: the selection colours are written as .ply",
            selection.display()
        );
    }
    // Every output is checked before the frames are synthesised (the recipe's inputs are known
    // once it is built), and all are written or none.
    let mut outputs = Plan::new(&built.inputs)
        .output("--out", &args.out, Kind::Animation)
        .output("--selection", &selection, Kind::Mesh)
        .output_opt("--report", args.report.as_ref(), Kind::Json)
        .check()?;
    crate::outputs::check_frames_of_target(
        &args.out,
        &built.target_path,
        built.target.num_vertices(),
        s.num_frames(),
        "synth",
        built.fps,
    )?;
    let mut layers = Vec::new();
    for k in 0..s.num_layers() {
        let info = s.layer_info(k);
        let between = info
            .weights
            .values
            .iter()
            .filter(|&&w| w > 0.0 && w < 1.0)
            .count();
        eprintln!(
            "{}: {} of {} stiff partitions selected ({} triangles), {} blended, weights {:.3} s",
            built.layer_names[k],
            info.selection.partitions.iter().filter(|&&x| x).count(),
            info.partitions.num_stiff(),
            info.selection.num_triangles(),
            between,
            info.weights_seconds
        );
        layers.push(json!({
            "name": built.layer_names[k],
            "stiff_partitions": info.partitions.num_stiff(),
            "partitions": info.partitions.num_partitions(),
            "selected_partitions": info.selection.partitions.iter().filter(|&&x| x).count(),
            "selected_triangles": info.selection.num_triangles(),
            "blended_triangles": between,
            "weights_s": info.weights_seconds,
        }));
    }
    eprintln!(
        "factorized the {}-vertex target once in {:.3} s",
        built.target.num_vertices(),
        s.factor_seconds()
    );
    let pb = progress(s.num_frames() as u64, "synth");
    let mut out = Vec::with_capacity(s.num_frames());
    let (mut blend_t, mut solve_t, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    let mut flips = Vec::with_capacity(s.num_frames());
    for f in 0..s.num_frames() {
        let fr = built
            .frame(f)
            .with_context(|| format!("output frame {f}"))?;
        blend_t += fr.blend_seconds;
        solve_t += fr.solve_seconds;
        worst = worst.max(fr.blend_seconds + fr.solve_seconds);
        flips.push(built.flipped_triangles(&fr).len());
        out.push((format!("frame_{f:04}"), fr.positions));
        pb.inc(1);
    }
    pb.finish_and_clear();
    let n = s.num_frames() as f64;
    eprintln!(
        "synthesised {} frames: {:.2} ms per frame blending gradients, {:.2} ms per frame solving",
        s.num_frames(),
        1e3 * blend_t / n,
        1e3 * solve_t / n
    );
    let worst_flips = flips.iter().copied().max().unwrap_or(0);
    if worst_flips > 0 {
        eprintln!(
            "note: up to {worst_flips} of {} target triangles face against their synthesised orientation in a frame",
            built.target.num_triangles()
        );
    }
    let set = ShapeSet::new(built.target.clone(), out)?;
    // The target comes back as the artist's own file (an OBJ's records, a glTF asset's clip).
    outputs.frames_of_target(
        &args.out,
        &set,
        &FramesOptions {
            fps: built.fps,
            inputs: built.inputs.clone(),
            ..FramesOptions::default()
        },
        &built.target_path,
        "synth",
    )?;
    let weights: Vec<&[f64]> = (0..s.num_layers())
        .map(|k| s.layer_info(k).weights.values.as_slice())
        .collect();
    let colors = selection_colors(&weights, built.target.num_triangles());
    outputs.colored_ply(&selection, &built.target, &Colors::PerFace(colors))?;
    if let Some(r) = &args.report {
        outputs.json(
            r,
            &json!({
                "recipe": args.recipe,
                "out": args.out,
                "selection": selection,
                "frames": s.num_frames(),
                "target_vertices": built.target.num_vertices(),
                "target_triangles": built.target.num_triangles(),
                "follow_layer": s.follow_layer(),
                "clip": outputs.clips().last(),
                "welded_vertices": {
                    "target": built.weld.merged(),
                    "sources": built.source_welded_vertices,
                },
                "layers": layers,
                "timings": {
                    "build_s": build_s,
                    "read_s": built.read_seconds,
                    "correspondence_s": built.correspondence_seconds,
                    "factorization_s": s.factor_seconds(),
                    "blend_per_frame_s": blend_t / n,
                    "solve_per_frame_s": solve_t / n,
                    "frame_max_s": worst,
                },
                "flipped_triangles_per_frame": flips,
            }),
        )?;
    }
    outputs.commit()?;
    eprintln!("wrote {}", args.out.display());
    eprintln!("wrote {}", selection.display());
    if let Some(r) = &args.report {
        eprintln!("wrote {}", r.display());
    }
    Ok(())
}
