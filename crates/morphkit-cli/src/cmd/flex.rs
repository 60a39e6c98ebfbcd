//! `morphkit flex`: per-triangle flexibility of an animation (Wang & Lee 2008, Sec. 3.1.1,
//! Eq. 1), as face colours and numbers, on the source or, through a correspondence, the target.

use super::weld_util;
use crate::outputs::{Kind, Plan};
use crate::util::progress;
use anyhow::Context;
use morphkit::io::{self, Colors};
use morphkit::mesh::Topology;
use morphkit::synth::{flexibility_colors, FlexibilityAccumulator, Partitions, GAMMA};
use morphkit::transfer::{
    correspond, Correspondence, CorrespondenceOptions, GradientOperator, Markers,
};
use serde_json::json;
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  morphkit flex --reference horse-gallop-reference.obj.gz --frames 'horse-gallop-*.obj.gz' --out flex.ply
  morphkit flex --reference horse-reference.obj.gz --frames 'horse-0*.obj.gz' --out camel-flex.ply \\
      --target camel-reference.obj.gz --markers markers-horse-camel.json --json camel-flex.json

Colours: blue = stiff (0), white = the partition threshold gamma, red = flexible (2 gamma and
above). Red regions bend against their neighbours: place markers there. With --target the
values are carried to the target through the correspondence (the mean over matched source
triangles) and the target is written. --json writes the numbers, one per triangle.";

/// Arguments of `morphkit flex`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct FlexArgs {
    /// The reference pose the frames' gradients are measured from.
    #[arg(long, value_name = "MESH")]
    pub reference: PathBuf,
    /// Frames: OBJ files, a quoted glob, a directory, a .glb/.gltf or a .pc2.
    #[arg(long, required = true, num_args = 1.., value_name = "FRAMES")]
    pub frames: Vec<String>,
    /// Output PLY with face colours.
    #[arg(long, value_name = "PLY")]
    pub out: PathBuf,
    /// Also write the values as JSON.
    #[arg(long, value_name = "JSON")]
    pub json: Option<PathBuf>,
    /// Show the flexibility on this target mesh (needs --markers or --correspondence).
    #[arg(long, value_name = "MESH")]
    pub target: Option<PathBuf>,
    /// Marker pairs between the reference and --target.
    #[arg(
        long,
        value_name = "JSON",
        requires = "target",
        conflicts_with = "correspondence"
    )]
    pub markers: Option<PathBuf>,
    /// A correspondence from `morphkit correspond` between the reference and --target.
    #[arg(long, value_name = "JSON", requires = "target")]
    pub correspondence: Option<PathBuf>,
    /// Partition threshold γ (the paper's 0.1): white in the colour map.
    #[arg(long, default_value_t = GAMMA)]
    pub gamma: f64,
}

/// Runs `morphkit flex`.
pub fn run(args: &FlexArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.gamma.is_finite() && args.gamma > 0.0,
        "--gamma must be positive"
    );
    let expanded = super::convert::expand(&args.frames)?;
    let mut inputs = expanded.protected.clone();
    inputs.push(args.reference.clone());
    inputs.extend(args.target.iter().cloned());
    inputs.extend(args.markers.iter().cloned());
    inputs.extend(args.correspondence.iter().cloned());
    crate::util::require_ply("--out", &args.out, "flexibility colours")?;
    let mut outputs = Plan::new(&inputs)
        .output("--out", &args.out, Kind::Mesh)
        .output_opt("--json", args.json.as_ref(), Kind::Json)
        .check()?;
    let reference = io::read_mesh(&args.reference)?;
    let frames = super::transfer::read_frames(&expanded.files, &args.reference)?;
    frames
        .check_connectivity("reference", &reference)
        .with_context(|| format!("frames vs. {}", args.reference.display()))?;
    // Split seams and hard edges are one vertex (mesh::weld), so that neighbouring triangles
    // across a seam are neighbours; the weld keeps every triangle in its place, so the
    // per-triangle values need no mapping back.
    let weld = {
        let all: Vec<&[morphkit::mesh::Point]> =
            frames.all_positions().iter().map(|p| &p[..]).collect();
        weld_util::mesh_weld(&reference, &all)
    };
    weld_util::announce(&weld, "the reference");
    let welded_ref = weld.mesh(&reference);
    let op = GradientOperator::new(&welded_ref);
    let topo = Topology::new(welded_ref.num_vertices(), &welded_ref.triangles);
    let mut acc = FlexibilityAccumulator::new(&topo, welded_ref.num_triangles());
    let pb = progress(frames.len() as u64, "gradients");
    for i in 0..frames.len() {
        let p = frames.positions(i);
        if weld.is_identity() {
            acc.add(&op.gradients_at(i, p)?)?;
        } else {
            acc.add(&op.gradients_at(i, &weld.gather(p))?)?;
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    let mut flex = acc.finish();
    let mut mesh = reference;
    let mut welded_mesh = welded_ref;
    let mut welded = json!({ "reference": weld.merged() });
    if let Some(t) = &args.target {
        let target = io::read_mesh(t)?;
        let target_weld = weld_util::mesh_weld(&target, &[]);
        weld_util::announce(&target_weld, "the target");
        welded["target"] = json!(target_weld.merged());
        let welded_target = target_weld.mesh(&target);
        let corr = match (&args.markers, &args.correspondence) {
            (Some(m), _) => {
                let markers = weld_util::welded_markers(&Markers::read(m)?, &weld, &target_weld)
                    .with_context(|| format!("{}", m.display()))?;
                correspond(
                    &welded_mesh,
                    &welded_target,
                    &markers,
                    &CorrespondenceOptions::default(),
                )
                .context("correspondence")?
                .correspondence
            }
            (None, Some(c)) => {
                let text = std::fs::read_to_string(c)
                    .with_context(|| format!("{}: cannot read", c.display()))?;
                let corr =
                    Correspondence::from_json(&text).with_context(|| format!("{}", c.display()))?;
                let corr = weld_util::welded_correspondence(corr, &weld, &target_weld);
                corr.check(&welded_mesh, &welded_target)?;
                corr
            }
            (None, None) => anyhow::bail!("--target needs --markers or --correspondence"),
        };
        flex = flex.map_to_target(&corr)?;
        mesh = target;
        welded_mesh = welded_target;
    }
    let topo = Topology::new(welded_mesh.num_vertices(), &welded_mesh.triangles);
    let parts = Partitions::new(&flex, &topo, args.gamma)?;
    let colors = flexibility_colors(&flex.values, args.gamma);
    outputs.colored_ply(&args.out, &mesh, &Colors::PerFace(colors))?;
    let n = flex.values.len().max(1) as f64;
    let mean = flex.values.iter().sum::<f64>() / n;
    let above = flex.values.iter().filter(|&&f| f >= args.gamma).count();
    eprintln!(
        "{} frames, {} triangles: flexibility max {:.3}, mean {:.3}; {} triangles at or above gamma = {}, {} stiff partitions",
        frames.len(),
        mesh.num_triangles(),
        flex.max(),
        mean,
        above,
        args.gamma,
        parts.num_stiff()
    );
    if let Some(j) = &args.json {
        outputs.json(
            j,
            &json!({
                "reference": args.reference,
                "target": args.target,
                "welded_vertices": welded,
                "frames": frames.len(),
                "gamma": args.gamma,
                "max": flex.max(),
                "mean": mean,
                "triangles_at_or_above_gamma": above,
                "stiff_partitions": parts.num_stiff(),
                "partitions": parts.num_partitions(),
                "flexibility": flex.values,
            }),
        )?;
    }
    outputs.commit()?;
    eprintln!("wrote {}", args.out.display());
    if let Some(j) = &args.json {
        eprintln!("wrote {}", j.display());
    }
    Ok(())
}
