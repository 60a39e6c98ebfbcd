//! `morphkit correspond`: a triangle correspondence between two meshes from marker pairs
//! (Wang & Lee 2008, Sec. 3.1.2–3.1.3), saved once as JSON for `transfer` and synthesis.

use super::weld_util;
use crate::outputs::{Kind, Plan};
use crate::util::{check_positive, check_range};
use anyhow::Context;
use morphkit::io;
use morphkit::mesh::TriMesh;
use morphkit::transfer::{
    correspond, correspondence_quality, cycle_consistency, match_confidence, Correspondence,
    CorrespondenceOptions, CorrespondenceResult, GradientCombine, Markers, TransferOptions,
    LOW_CONFIDENCE,
};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  morphkit correspond --source horse.obj.gz --target camel.obj.gz --markers markers.json --out corr.json
  morphkit correspond --source cat.obj --target dog.obj --markers m.json --out corr.json \\
      --warped-source cat-warped.obj --warped-target dog-warped.obj --report corr-report.json
  morphkit correspond --source horse.obj.gz --target camel.obj.gz --markers m.json --out corr.json \\
      --refine --report q.json --cycle-frames 'horse-*.obj.gz'
  morphkit correspond --source horse.obj.gz --target camel.obj.gz --markers m.json --out corr.json \\
      --confidence camel-confidence.ply

Markers are JSON {\"pairs\": [[source_vertex, target_vertex], ...]}, 0-based.
The report lists each marker's residual after warping, the target triangles whose only
match fails the normal test (places that need more markers), and quality metrics that need no
reference answer: the fraction of target triangles passing the normal test, the fraction of
source triangles reached, marker residuals, and the match confidence: per target triangle, how
well its matches' reference normals agree with its own (1 alike, towards 0 facing away: its
motion comes through a large turn or from the wrong side; --confidence colours the target by
it, white 1 to red 0; markers near red places help). `morphkit transfer --markers … --report`
adds the cycle consistency (there and back with the reversed markers) and fold counts.";

/// Arguments of `morphkit correspond`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct CorrespondArgs {
    /// Source mesh (the animated one).
    #[arg(long, value_name = "MESH")]
    pub source: PathBuf,
    /// Target mesh.
    #[arg(long, value_name = "MESH")]
    pub target: PathBuf,
    /// Marker pairs, JSON {"pairs": [[source, target], ...]}, 0-based.
    #[arg(long, value_name = "JSON")]
    pub markers: PathBuf,
    /// Output correspondence file (JSON).
    #[arg(long, value_name = "JSON")]
    pub out: PathBuf,
    /// Least-squares-mesh constraint weight ω (the paper's 10 000).
    #[arg(long, default_value_t = morphkit::transfer::OMEGA)]
    pub omega: f64,
    /// Centroid radius, in mean edge lengths of the warped source mesh.
    #[arg(long, default_value_t = CorrespondenceOptions::default().radius_factor)]
    pub radius: f64,
    /// Most source triangles kept per target triangle.
    #[arg(long, default_value_t = CorrespondenceOptions::default().max_matches)]
    pub max_matches: usize,
    /// Write the warped source mesh here (for inspection).
    #[arg(long, value_name = "MESH")]
    pub warped_source: Option<PathBuf>,
    /// Write the warped target mesh here (for inspection).
    #[arg(long, value_name = "MESH")]
    pub warped_target: Option<PathBuf>,
    /// Write a JSON report (timings, marker residuals, normal violations, quality metrics).
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Write the target as a binary PLY coloured per triangle by its match confidence
    /// (white 1: the matches face as it does; red 0: they face away; add markers there).
    #[arg(long, value_name = "PLY")]
    pub confidence: Option<PathBuf>,
    /// Refine the warp by closest points (Sumner & Popović 2004, Sec. 5) before matching:
    /// lower cycle-consistency error and fewer sharp folds, about 1.7× the time. The default
    /// (issue 40); the flag is kept for older scripts.
    #[arg(long, conflicts_with = "no_refine")]
    pub refine: bool,
    /// Match the two least-squares warps directly, without the closest-point refinement (the
    /// default before issue 40).
    #[arg(long)]
    pub no_refine: bool,
    /// Match target → source only (no source → target pass).
    #[arg(long)]
    pub one_way: bool,
    /// Source frames (OBJ files or quoted globs, over the source's connectivity, measured from
    /// --source) for the report's cycle consistency: each frame transferred there and back,
    /// the way back with the markers reversed.
    #[arg(long, num_args = 1.., value_name = "FRAMES")]
    pub cycle_frames: Vec<String>,
}

/// Options from the command line.
pub(crate) fn options(args: &CorrespondArgs) -> anyhow::Result<CorrespondenceOptions> {
    check_positive("--omega", args.omega)?;
    check_range("--radius", args.radius, 0.0, false, f64::INFINITY)?;
    anyhow::ensure!(args.max_matches >= 1, "--max-matches must be at least 1");
    let mut o = CorrespondenceOptions::default();
    o.lsmesh.omega = args.omega;
    o.radius_factor = args.radius;
    o.max_matches = args.max_matches;
    super::corr_args::apply_refine_flags(&mut o, args.refine, args.no_refine);
    o.two_way = !args.one_way;
    Ok(o)
}

/// Summary of a correspondence as JSON (shared with `morphkit transfer`'s report).
pub fn summary(r: &CorrespondenceResult, seconds: f64) -> serde_json::Value {
    let c = &r.correspondence;
    let worst = c
        .marker_residuals
        .iter()
        .map(|m| m.relative)
        .fold(0.0, f64::max);
    json!({
        "seconds": seconds,
        "source_triangles": c.source_triangles,
        "target_triangles": c.target_triangles,
        "markers": c.markers.len(),
        "radius": c.radius,
        "omega": c.omega,
        "mean_matches_per_target_triangle": c.mean_matches(),
        "normal_violations": c.normal_violations,
        "max_marker_residual_relative": worst,
        "marker_residuals": c.marker_residuals,
        "quality": correspondence_quality(c),
        "refined": !c.refinement.is_empty(),
        "refinement_steps": c.refinement,
        "two_way_added_matches": r.added_by_source,
    })
}

/// The [`match_confidence`] of `c`: prints its mean and the share below [`LOW_CONFIDENCE`]
/// (followed by `hint`), and returns the values with their JSON summary for a report.
pub fn confidence_summary(
    source: &TriMesh,
    target: &TriMesh,
    c: &Correspondence,
    combine: GradientCombine,
    hint: &str,
) -> anyhow::Result<(Vec<f64>, serde_json::Value)> {
    let confidence = match_confidence(source, target, c, combine)?;
    let low: Vec<usize> = (0..confidence.len())
        .filter(|&t| confidence[t] < LOW_CONFIDENCE)
        .collect();
    let n = confidence.len().max(1) as f64;
    let mean = confidence.iter().sum::<f64>() / n;
    let low_fraction = low.len() as f64 / n;
    eprintln!(
        "match confidence: mean {mean:.2}; {:.1} % of the target triangles below {LOW_CONFIDENCE} (their matches face away in the reference meshes{hint})",
        100.0 * low_fraction,
    );
    let summary = json!({
        "mean": mean,
        "low_threshold": LOW_CONFIDENCE,
        "low_fraction": low_fraction,
        "low_triangles": low,
    });
    Ok((confidence, summary))
}

/// Prints the human-readable summary.
pub fn print_summary(r: &CorrespondenceResult, seconds: f64) {
    let c = &r.correspondence;
    let worst = c
        .marker_residuals
        .iter()
        .max_by(|a, b| a.relative.total_cmp(&b.relative));
    eprintln!(
        "correspondence: {} target triangles, {:.2} source triangles each on average, {:.2} s",
        c.target_triangles,
        c.mean_matches(),
        seconds
    );
    if let Some(w) = worst {
        eprintln!(
            "largest marker residual after warping: marker [{}, {}], {:.2e} of the target size",
            w.source, w.target, w.relative
        );
    }
    if !c.normal_violations.is_empty() {
        let head: Vec<String> = c
            .normal_violations
            .iter()
            .take(10)
            .map(|t| t.to_string())
            .collect();
        eprintln!(
            "warning: {} target triangles have no source triangle with a compatible normal (add markers near them): {}{}",
            c.normal_violations.len(),
            head.join(", "),
            if c.normal_violations.len() > 10 { ", …" } else { "" }
        );
    }
}

/// Runs `morphkit correspond`.
pub fn run(args: &CorrespondArgs) -> anyhow::Result<()> {
    let opts = options(args)?;
    if !args.cycle_frames.is_empty() && args.report.is_none() {
        anyhow::bail!("--cycle-frames needs --report (the cycle consistency goes there)");
    }
    if let Some(p) = &args.confidence {
        crate::util::require_ply("--confidence", p, "the confidence colours")?;
    }
    let cycle_files = if args.cycle_frames.is_empty() {
        None
    } else {
        Some(super::convert::expand(&args.cycle_frames)?)
    };
    let mut inputs = vec![
        args.source.clone(),
        args.target.clone(),
        args.markers.clone(),
    ];
    if let Some(c) = &cycle_files {
        inputs.extend(c.protected.iter().cloned());
    }
    let mut outputs = Plan::new(&inputs)
        .output("--out", &args.out, Kind::Json)
        .output_opt("--warped-source", args.warped_source.as_ref(), Kind::Mesh)
        .output_opt("--warped-target", args.warped_target.as_ref(), Kind::Mesh)
        .output_opt("--report", args.report.as_ref(), Kind::Json)
        .output_opt("--confidence", args.confidence.as_ref(), Kind::Mesh)
        .check()?;
    crate::util::announce_reading(&inputs);
    let source = io::read_mesh(&args.source)?;
    let target = io::read_mesh(&args.target)?;
    let markers = Markers::read(&args.markers)?;
    // Split seams and hard edges are one vertex for the solves (mesh::weld): the
    // correspondence is computed on the welded meshes (markers mapped) and written for the
    // input ones (triangles keep their ids, markers their input vertices).
    let source_weld = weld_util::mesh_weld(&source, &[]);
    let target_weld = weld_util::mesh_weld(&target, &[]);
    weld_util::announce(&source_weld, "the source");
    weld_util::announce(&target_weld, "the target");
    let (welded_source, welded_target) = (source_weld.mesh(&source), target_weld.mesh(&target));
    let welded_markers = weld_util::welded_markers(&markers, &source_weld, &target_weld)
        .with_context(|| format!("{}", args.markers.display()))?;
    crate::util::announce_work("computing the correspondence", target.num_vertices());
    let t0 = Instant::now();
    let mut r =
        correspond(&welded_source, &welded_target, &welded_markers, &opts).with_context(|| {
            format!(
                "correspondence of {} and {}",
                args.source.display(),
                args.target.display()
            )
        })?;
    let welded_corr = r.correspondence.clone();
    if !(source_weld.is_identity() && target_weld.is_identity()) {
        r.correspondence =
            weld_util::input_correspondence(r.correspondence, &source_weld, &target_weld);
        // The input's markers as given (a welded vertex's first input vertex may be another).
        if r.correspondence.markers.len() == markers.pairs.len() && !r.correspondence.identity {
            r.correspondence.markers = markers.pairs.clone();
        }
        r.warped_source = source_weld.scatter(&r.warped_source);
        r.warped_target = target_weld.scatter(&r.warped_target);
    }
    let secs = t0.elapsed().as_secs_f64();
    print_summary(&r, secs);
    let hint = if args.confidence.is_some() {
        ""
    } else {
        "; --confidence FILE.ply shows where"
    };
    let (confidence, confidence_json) = confidence_summary(
        &source,
        &target,
        &r.correspondence,
        GradientCombine::default(),
        hint,
    )?;
    if let Some(p) = &args.confidence {
        let colors = confidence.iter().map(|&c| io::diverging(1.0 - c)).collect();
        outputs.colored_ply(p, &target, &io::Colors::PerFace(colors))?;
    }
    outputs.text(&args.out, &r.correspondence.to_json())?;
    if let Some(p) = &args.warped_source {
        outputs.mesh(p, &source.with_positions(r.warped_source.clone()))?;
    }
    if let Some(p) = &args.warped_target {
        outputs.mesh(p, &target.with_positions(r.warped_target.clone()))?;
    }
    if let Some(p) = &args.report {
        let mut v = summary(&r, secs);
        v["source"] = json!(args.source);
        v["target"] = json!(args.target);
        v["correspondence"] = json!(args.out);
        v["match_confidence"] = confidence_json;
        v["welded_vertices"] = json!({
            "source": source_weld.merged(),
            "target": target_weld.merged(),
        });
        if let Some(c) = &cycle_files {
            let frames = io::read_shape_set(&c.files)?;
            frames
                .check_connectivity(&args.source.display().to_string(), &source)
                .with_context(|| "--cycle-frames vs. --source".to_string())?;
            let t0 = Instant::now();
            let back = correspond(
                &welded_target,
                &welded_source,
                &welded_markers.reversed(),
                &opts,
            )
            .context("correspondence of the way back (cycle consistency)")?;
            let frames: Vec<Vec<morphkit::mesh::Point>> = frames
                .all_positions()
                .iter()
                .map(|p| source_weld.gather(p))
                .collect();
            let cyc = cycle_consistency(
                &welded_source,
                &frames,
                &welded_target,
                &welded_corr,
                &back.correspondence,
                &TransferOptions::default(),
            )
            .context("cycle consistency")?;
            eprintln!(
                "cycle consistency (there and back): mean {:.3e}, max {:.3e} of the source diagonal",
                cyc.mean, cyc.max
            );
            v["cycle_consistency"] = json!({
                "frames": frames.len(),
                "mean_relative": cyc.mean,
                "max_relative": cyc.max,
                "frame_mean_relative": cyc.frame_mean,
                "frame_max_relative": cyc.frame_max,
                "forward_flipped_triangles": cyc.forward_flipped,
                "forward_sharp_folds": cyc.forward_sharp_folds,
                "seconds": t0.elapsed().as_secs_f64(),
            });
        }
        outputs.json(p, &v)?;
    }
    outputs.commit()?;
    for p in [
        Some(&args.out),
        args.warped_source.as_ref(),
        args.warped_target.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
