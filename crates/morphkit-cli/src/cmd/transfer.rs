//! `morphkit transfer`: transfer a source animation onto a different target mesh
//! (Wang & Lee 2008, Sec. 3.2.3; Sumner & Popović 2004).

use super::corr_args::CorrespondenceArgs;
use super::weld_util;
use crate::outputs::{Kind, Plan};
use crate::util::{check_fps, check_positive, progress};
use anyhow::Context;
use morphkit::io::{self, Format, FramesOptions};
use morphkit::transfer::{
    correspond, cycle_consistency, sharp_folds, AnimationTransfer, GradientFrame, TransferOptions,
    TranslationMode, TriangleWeighting,
};
use morphkit::ShapeSet;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  morphkit transfer --source-ref horse-ref.obj.gz --source 'horse-0*.obj.gz' \\
      --target camel.obj.gz --markers markers.json --out camel-poses/
  morphkit correspond --source horse-ref.obj.gz --target camel.obj.gz --markers m.json --out corr.json
  morphkit transfer --source-ref horse-ref.obj.gz --source gallop.glb --target camel.obj.gz \\
      --correspondence corr.json --out camel-gallop.glb --report transfer.json
  morphkit transfer --source-ref rest.obj --source anim.pc2 --target t.obj --correspondence c.json --out t.pc2

Source frames: OBJ files, a quoted glob, a directory of OBJ frames, a .glb/.gltf animation, or a
.pc2 cache (whose connectivity is --source-ref). OUT: a directory of numbered OBJ frames
(frame_0000.obj, …), a .glb/.gltf animation, or a .pc2 cache.
By default the target's marker centroid follows the source's (scaled by the size ratio);
--fixed-vertex keeps the paper's fixed constraint vertex instead.";

/// Arguments of `morphkit transfer`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct TransferArgs {
    /// Source reference mesh (the pose the frames' gradients are measured from).
    #[arg(long, value_name = "MESH")]
    pub source_ref: PathBuf,
    /// Source frames: OBJ files, a quoted glob, a directory, a .glb/.gltf or a .pc2.
    #[arg(long, required = true, num_args = 1.., value_name = "FRAMES")]
    pub source: Vec<String>,
    /// Target reference mesh.
    #[arg(long, value_name = "MESH")]
    pub target: PathBuf,
    #[command(flatten)]
    pub corr: CorrespondenceArgs,
    /// Output: a directory of numbered OBJ frames, a .glb/.gltf or a .pc2.
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,
    /// Write a JSON report (timings for correspondence, factorization and per-frame solves,
    /// flipped triangles and sharp folds per frame; with --markers also the cycle
    /// consistency: every frame there and back with the markers reversed, which costs a second
    /// correspondence and twice the solves).
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Keep constraint vertices fixed (the paper's convention); optionally name the vertex.
    #[arg(long, value_name = "VERTEX", num_args = 0..=1, allow_negative_numbers = true)]
    pub fixed_vertex: Option<Option<i64>>,
    /// Weight triangles by area (Eq. 6). The default (issue 40); the flag is kept for older
    /// scripts.
    #[arg(long, conflicts_with = "uniform_weights")]
    pub area_weighted: bool,
    /// Weight triangles uniformly (the paper's Eq. 6 as written; the default before issue 40).
    #[arg(long)]
    pub uniform_weights: bool,
    /// Carry each matched gradient's stretch into the target triangle's own plane (rotation
    /// in the world frame, stretch turned by the smallest rotation between the reference
    /// normals; matches weighted by how well those normals agree, each target triangle in the
    /// solve by its matches' confidence; where that creases a frame, not turned there: see
    /// --no-fold-guard). The default (issue 40: with the refinement and area weights it came
    /// closest in a leave-one-out study over four real pairs, 19–33 % lower cycle error with
    /// fewer sharp folds, about 8× the solve time); the flag is kept for older scripts.
    #[arg(long, conflicts_with = "world_frame")]
    pub local_stretch: bool,
    /// Carry matched gradients over unchanged in world coordinates (Sumner & Popović as
    /// written; the default before issue 40: faster, further from the reference). With
    /// --no-refine --uniform-weights: the old defaults.
    #[arg(long)]
    pub world_frame: bool,
    /// Do not guard against creases (by default, where a frame folds sharply and the unturned
    /// stretches would not, the stretches there are not turned and the frame is solved
    /// again). Not with --world-frame (the guard acts in the local-stretch frame only).
    #[arg(long, conflicts_with = "world_frame")]
    pub no_fold_guard: bool,
    /// Multiply the source frames by this factor about the origin (for frames stored at
    /// another scale than the source reference).
    #[arg(long, default_value_t = 1.0)]
    pub source_scale: f64,
    /// Frames per second of a .glb/.gltf output.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Replace the frame_*.obj files of an existing output directory.
    #[arg(long)]
    pub force: bool,
}

/// Reads the source frames in any of the accepted forms.
pub(crate) fn read_frames(paths: &[PathBuf], source_ref: &Path) -> anyhow::Result<ShapeSet> {
    if let [one] = paths {
        let animated = one.is_dir()
            || matches!(
                Format::from_path(one),
                Some(Format::Glb | Format::Gltf | Format::Pc2)
            );
        if animated {
            return Ok(io::read_animation(one, Some(source_ref))?);
        }
    }
    let pb = progress(paths.len() as u64, "reading");
    let set = io::read_shape_set_with(paths, |_, _| pb.inc(1));
    pb.finish_and_clear();
    Ok(set?)
}

pub(crate) fn options(args: &TransferArgs) -> anyhow::Result<TransferOptions> {
    let mut o = TransferOptions::default();
    if let Some(v) = args.fixed_vertex {
        o.translation = TranslationMode::FixedVertex;
        if let Some(v) = v {
            let id = u32::try_from(v).map_err(|_| {
                anyhow::anyhow!(
                    "--fixed-vertex {v}: expected a 0-based vertex index (0 to {}), or the flag \
                     alone for the default constraint vertex",
                    u32::MAX
                )
            })?;
            o.solver.constraint_vertices = vec![id];
        }
    }
    o.combine = args.corr.combine();
    // --area-weighted and --local-stretch name the defaults; clap refuses them together with
    // their opposites.
    if args.area_weighted {
        o.solver.weighting = TriangleWeighting::Area;
    }
    if args.uniform_weights {
        o.solver.weighting = TriangleWeighting::Uniform;
    }
    if args.local_stretch {
        o.frame = GradientFrame::LocalStretch;
    }
    if args.world_frame {
        o.frame = GradientFrame::World;
    }
    if args.no_fold_guard {
        o.fold_guard = None;
    }
    check_positive("--source-scale", args.source_scale)?;
    check_fps(args.fps)?;
    args.corr.require()?;
    Ok(o)
}

/// Runs `morphkit transfer`.
pub fn run(args: &TransferArgs) -> anyhow::Result<()> {
    let mut opts = options(args)?;
    let expanded = super::convert::expand(&args.source)?;
    let frame_paths = expanded.files;
    let mut inputs = expanded.protected;
    inputs.extend([args.source_ref.clone(), args.target.clone()]);
    inputs.extend(args.corr.inputs());
    let mut outputs = Plan::new(&inputs)
        .force(args.force)
        .output("--out", &args.out, Kind::Animation)
        .output_opt("--report", args.report.as_ref(), Kind::Json)
        .check()?;

    crate::util::announce_reading(&inputs);
    let source_ref = io::read_mesh(&args.source_ref)?;
    let target = io::read_mesh(&args.target)?;
    let mut frames = read_frames(&frame_paths, &args.source_ref)?;
    if args.source_scale != 1.0 {
        let s = args.source_scale;
        let scaled: Vec<(String, Vec<[f64; 3]>)> = (0..frames.len())
            .map(|i| {
                let p = frames
                    .positions(i)
                    .iter()
                    .map(|q| q.map(|x| s * x))
                    .collect();
                (frames.name(i).to_string(), p)
            })
            .collect();
        frames = ShapeSet::new(frames.base().clone(), scaled)?;
    }
    // An edit of a glTF target is checked now (--max-targets, flags it does not apply), not
    // after the correspondence and every frame's solve.
    crate::outputs::check_frames_of_target(
        &args.out,
        &args.target,
        target.num_vertices(),
        frames.len(),
        "transfer",
        args.fps,
    )?;
    let ratio = morphkit::mesh::bbox_diagonal(frames.positions(0)) / source_ref.bbox_diagonal();
    if !(0.5..=2.0).contains(&ratio) {
        eprintln!(
            "warning: the first source frame is {ratio:.3}× the size of the source reference; \
             the target will be scaled alike (use --source-scale, or the first frame as --source-ref)"
        );
    }

    let mut report = json!({
        "source_ref": args.source_ref,
        "target": args.target,
        "frames": frames.len(),
        "out": args.out,
    });
    // Split seams and hard edges are one vertex for the solves (mesh::weld): the source's
    // where they coincide in the reference and every frame, the target's where they coincide
    // in the target; results go back in the target's own layout.
    let input_target = target;
    let (source_weld, target_weld) =
        weld_util::source_and_target(&source_ref, &frames, &input_target, &mut report);
    let source_ref = source_weld.mesh(&source_ref);
    let target = target_weld.mesh(&input_target);
    if !source_weld.is_identity() {
        frames = source_weld.shapes(&frames)?;
    }
    if let Some(v) = opts.solver.constraint_vertices.first_mut() {
        *v = weld_util::welded_id(&target_weld, *v, "--fixed-vertex")?;
    }
    let mut cycle = None;
    let obtained = weld_util::obtain_welded(
        &args.corr,
        (&source_ref, &source_weld),
        (&target, &target_weld),
        &mut report,
        true,
    )?;
    if args.report.is_some() {
        cycle = obtained.computed_from;
    }
    let corr = obtained.correspondence;

    crate::util::announce_work("factorizing the transfer system", target.num_vertices());
    let t0 = Instant::now();
    let tr = AnimationTransfer::new(&source_ref, &target, &corr, &opts)?;
    let factor_s = t0.elapsed().as_secs_f64();
    tr.check_frames(&frames)
        .with_context(|| format!("source frames vs. {}", args.source_ref.display()))?;
    eprintln!(
        "factorized the {}-vertex target in {:.3} s ({} nonzeros in the factor)",
        target.num_vertices(),
        factor_s,
        tr.solver().factor_nnz()
    );

    let pb = progress(frames.len() as u64, "transfer");
    let mut out = Vec::with_capacity(frames.len());
    let (mut solve_total, mut solve_max, mut grad_total) = (0.0f64, 0.0f64, 0.0f64);
    let mut flips = Vec::with_capacity(frames.len());
    let mut sharp = Vec::with_capacity(frames.len());
    let mut guarded = Vec::with_capacity(frames.len());
    let topo_t = morphkit::mesh::Topology::new(target.num_vertices(), &target.triangles);
    for i in 0..frames.len() {
        let f = frames.positions(i);
        let t1 = Instant::now();
        let sg = tr
            .source_gradients_at(i, f)
            .with_context(|| format!("source frame {i} ({})", frames.name(i)))?;
        let t2 = Instant::now();
        // Gradients combined, solved and (local stretch) guarded against creases.
        let (x, g, guard) = tr
            .transfer_gradients(&sg, Some(f))
            .with_context(|| format!("source frame {i} ({})", frames.name(i)))?;
        guarded.push(guard.unturned_triangles);
        let solve = t2.elapsed().as_secs_f64();
        grad_total += (t2 - t1).as_secs_f64();
        solve_total += solve;
        solve_max = solve_max.max(solve);
        flips.push(tr.flipped_triangles(&x, &g).len());
        if args.report.is_some() {
            sharp.push(sharp_folds(&target, &topo_t, &x));
        }
        out.push((format!("frame_{i:04}"), target_weld.scatter(&x)));
        pb.inc(1);
    }
    pb.finish_and_clear();
    let n = frames.len().max(1) as f64;
    eprintln!(
        "transferred {} frames: {:.2} ms per frame solve, {:.2} ms per frame for gradients",
        frames.len(),
        1e3 * solve_total / n,
        1e3 * grad_total / n
    );
    let worst_flips = flips.iter().copied().max().unwrap_or(0);
    if worst_flips > 0 {
        eprintln!(
            "note: up to {worst_flips} of {} target triangles face against their transferred orientation in a frame",
            target.num_triangles()
        );
    }
    let set = ShapeSet::new(input_target.clone(), out)?;
    // The target comes back as the artist's own file: an OBJ's records (io::ObjTemplate), a
    // glTF asset with the transfer added as a clip (io::GltfAsset).
    let frame_opts = FramesOptions {
        fps: args.fps,
        inputs,
        ..FramesOptions::default()
    };
    outputs.frames_of_target(&args.out, &set, &frame_opts, &args.target, "transfer")?;
    if let Some(r) = &args.report {
        report["timings"] = json!({
            "correspondence_s": report["correspondence"]["seconds"],
            "factorization_s": factor_s,
            "solve_per_frame_s": solve_total / n,
            "solve_max_s": solve_max,
            "gradients_per_frame_s": grad_total / n,
        });
        // How a .glb/.gltf animation was laid out (a compact clip or a target per frame).
        if let Some(clip) = outputs.clips().last() {
            report["clip"] = clip.clone();
        }
        report["target_vertices"] = json!(target.num_vertices());
        report["target_triangles"] = json!(target.num_triangles());
        let constraint: Vec<u32> = tr
            .solver()
            .constraint_vertices()
            .iter()
            .map(|&v| target_weld.representative()[v as usize])
            .collect();
        report["constraint_vertices"] = json!(constraint);
        report["flipped_triangles_per_frame"] = json!(flips);
        report["sharp_folds_per_frame"] = json!(sharp);
        report["fold_guard_unturned_triangles_per_frame"] = json!(guarded);
        if let Some((markers, copts)) = cycle {
            // There and back with the reversed markers (quality without a reference answer).
            let t0 = Instant::now();
            let back = correspond(&target, &source_ref, &markers.reversed(), &copts)
                .context("correspondence of the way back (cycle consistency)")?;
            let c = cycle_consistency(
                &source_ref,
                frames.all_positions(),
                &target,
                &corr,
                &back.correspondence,
                &opts,
            )
            .context("cycle consistency")?;
            eprintln!(
                "cycle consistency (there and back): mean {:.3e}, max {:.3e} of the source diagonal",
                c.mean, c.max
            );
            report["cycle_consistency"] = json!({
                "mean_relative": c.mean,
                "max_relative": c.max,
                "frame_mean_relative": c.frame_mean,
                "frame_max_relative": c.frame_max,
                "seconds": t0.elapsed().as_secs_f64(),
            });
        }
        outputs.json(r, &report)?;
    }
    outputs.commit()?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
