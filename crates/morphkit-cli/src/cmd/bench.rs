//! `morphkit bench`: speed of the physical-blend solver (and of transfer and synthesis, with
//! data).
//!
//! The spring suite times a 36-step α sequence (the paper's Table I protocol) at about 2k,
//! 8.5k and 18.6k vertices, on generated bent tubes and, when the data directory is given, on
//! real meshes: the horse (8.4k vertices, reference ↔ pose 5) and the armadillo (14.6k, bent
//! procedurally: it has no poses).
//!
//! Every run opens with the [machine check](super::bench_machine): the speed of a fixed
//! single-precision factorization and solve, so that rows measured on different days can be
//! compared.

use crate::outputs::{Kind, Plan};
use morphkit::mesh::{generate, ShapeSet};
use morphkit::springs::{
    linear_blend, BlendOptions, ContinuityCheck, FillOrdering, PhysicalBlend, Preconditioner,
    Weights, JUMP_BOUND,
};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `morphkit bench`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  morphkit bench\n  morphkit bench --data ../shared/data --report bench.json\n  morphkit bench --suite springs --steps 36\n  morphkit bench --suite synth --data ../shared/data\n  morphkit bench --suite scrub --steps 12 --data ../shared/data\n  morphkit bench --suite continuity --steps 400 --data ../shared/data"
)]
pub struct BenchArgs {
    /// Which suite to run: springs, transfer, rig (blendshape rig transfer), memory, synth,
    /// scene (collisions), volume (internal springs: lattice, and tetgen when on the PATH),
    /// scrub (slider changes on the ICT and horse rigs: full solve and preview latency, the
    /// preview's error; --steps random combinations, at most 24), continuity (every target
    /// swept alone and paths between targets in --steps steps: pops, Newton iterations, frame
    /// times), or all (springs, transfer, rig, synth).
    #[arg(long, default_value = "all")]
    suite: String,
    /// Directory of the real test meshes (defaults to $MORPHKIT_DATA when set).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Interpolation steps per sequence (the paper uses 36).
    #[arg(long, default_value_t = 36)]
    steps: usize,
    /// Write the measurements as JSON.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Threads solving frames in parallel (frames are independent; results do not change).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Springs, volume and scene suites: start frames from the plain predictor (as `blend
    /// --no-sampled-start`), to compare with the default sampled start.
    #[arg(long)]
    no_sampled_start: bool,
    /// Springs and volume suites: the inner CG's preconditioner, cholesky, aggregation (the
    /// two-level cycle) or auto (aggregation where the factor would fill too much; the
    /// default, as in `blend`).
    #[arg(long, default_value = "auto", value_parser = parse_preconditioner)]
    preconditioner: Preconditioner,
    /// Springs, volume and scene suites: every frame factorizes its own Hessians (as `blend
    /// --no-reference-factors`), to compare with the default reference factors.
    #[arg(long)]
    no_reference_factors: bool,
}

/// `cholesky|aggregation|auto` for `--preconditioner`.
pub fn parse_preconditioner(s: &str) -> Result<Preconditioner, String> {
    match s {
        "cholesky" => Ok(Preconditioner::Cholesky),
        "aggregation" => Ok(Preconditioner::Aggregation),
        "auto" => Ok(Preconditioner::Auto),
        _ => Err(format!(
            "unknown preconditioner '{s}': use cholesky, aggregation or auto"
        )),
    }
}

/// How the springs suite runs each sequence.
struct Sequence {
    steps: usize,
    threads: usize,
    options: BlendOptions,
}

/// Most `--steps`: 36 steps of every mesh take about a minute.
const MAX_STEPS: usize = 1000;

fn peak_rss_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Times one 36-step sequence and prints a table row.
fn time_sequence(
    name: &str,
    shapes: &ShapeSet,
    seq: &Sequence,
) -> anyhow::Result<serde_json::Value> {
    let (steps, threads) = (seq.steps, seq.threads);
    let t0 = Instant::now();
    let mut solver = PhysicalBlend::new(shapes, &seq.options)?;
    let setup = t0.elapsed().as_secs_f64();
    let mut iters = 0;
    let mut facts = 0;
    let mut cgs = 0;
    let mut worst_grad: f64 = 0.0;
    let mut all_converged = true;
    let n = shapes.len() - 1;
    let weights: Vec<Weights> = (0..steps)
        .map(|k| {
            let a = k as f64 / (steps.max(2) - 1) as f64;
            let mut w = vec![0.0; n];
            w[n - 1] = a;
            Weights::Delta(w)
        })
        .collect();
    let t1 = Instant::now();
    let results = solver.solve_many(&weights, threads);
    let per_step = t1.elapsed().as_secs_f64() / steps as f64;
    // Not timed: whether the sequence jumps (see `morphkit blend`'s "Jumps between frames").
    let mut jumps = ContinuityCheck::new(JUMP_BOUND, shapes.base().bbox_diagonal());
    for (r, w) in results.into_iter().zip(&weights) {
        let r = r?;
        iters += r.stats.newton_iterations;
        facts += r.stats.factorizations;
        cgs += r.stats.cg_iterations;
        worst_grad = worst_grad.max(r.stats.gradient_norm / r.stats.gradient_tolerance);
        all_converged &= r.stats.converged;
        jumps.push(&r.positions, &linear_blend(shapes, w)?)?;
    }
    let continuity = jumps.finish();
    let samples = solver.start_samples_solved();
    let row = json!({
        "mesh": name,
        "vertices": shapes.num_vertices(),
        "springs": solver.summary().springs,
        "free_dofs": solver.num_free_dofs(),
        "factor_nnz": solver.factor_nnz(),
        "factor_flops": solver.summary().factor_flops,
        "hessian_entries": solver.summary().hessian_entries,
        "aggregates": solver.summary().aggregates,
        "ordering": solver.summary().ordering,
        "setup_ms": setup * 1e3,
        "ms_per_step": per_step * 1e3,
        "newton_iterations_per_step": iters as f64 / steps as f64,
        "factorizations_per_step": facts as f64 / steps as f64,
        "cg_iterations_per_step": cgs as f64 / steps as f64,
        "start_sample_solves": samples,
        "all_converged": all_converged,
        "worst_gradient_over_tolerance": worst_grad,
        "worst_step_over_linear": continuity.worst_ratio,
        "jumps": continuity.jumps.len(),
        "peak_rss_mib": peak_rss_mib(),
        "threads": threads,
    });
    println!(
        "{:<28} {:>7} {:>8} {:>6} {:>6.2} {:>9.1} {:>10.2} {:>7.2} {:>7.2} {:>7.1} {:>7} {:>9} {:>6.2}",
        name,
        shapes.num_vertices(),
        solver.summary().springs,
        match solver.summary().ordering {
            FillOrdering::Amd => "amd",
            _ => "nd",
        },
        solver.summary().factor_flops / 1e9,
        setup * 1e3,
        per_step * 1e3,
        iters as f64 / steps as f64,
        facts as f64 / steps as f64,
        cgs as f64 / steps as f64,
        samples,
        peak_rss_mib()
            .map(|m| format!("{m:.0}"))
            .unwrap_or_else(|| "-".into()),
        continuity.worst_ratio
    );
    Ok(row)
}

/// A closed tube with about `target` vertices, bent by 90° over its whole length (also the
/// surface of the volume suite's tubes).
pub(super) fn bent_tube(target: usize) -> ShapeSet {
    let around = ((target as f64 / 4.0).sqrt()).round().max(6.0) as usize;
    let along = (target / around).max(2) - 1;
    let m = generate::tube(0.5, 4.0, around, along, true);
    let bent = generate::bend(&m.positions, 0.0, 4.0, 90f64.to_radians());
    ShapeSet::new(
        m.clone(),
        vec![
            ("straight".into(), m.positions.clone()),
            ("bent".into(), bent),
        ],
    )
    .expect("generated shapes share connectivity")
}

fn springs_suite(data: Option<&Path>, seq: &Sequence) -> anyhow::Result<Vec<serde_json::Value>> {
    let (steps, threads) = (seq.steps, seq.threads);
    let start = if seq.options.sampled_start {
        "sampled start; ms/step includes its sample solves (column samples; their iterations are not in newton/factor/cg)"
    } else {
        "plain predictor start (--no-sampled-start)"
    };
    println!("physical blend, {steps} steps of α in [0, 1], default options (tolerance 1e-6 · k0), {threads} thread(s), {start}");
    println!(
        "{:<28} {:>7} {:>8} {:>6} {:>6} {:>9} {:>10} {:>7} {:>7} {:>7} {:>7} {:>9} {:>6}",
        "mesh",
        "verts",
        "springs",
        "order",
        "Gflop",
        "setup ms",
        "ms/step",
        "newton",
        "factor",
        "cg",
        "samples",
        "peak MiB",
        "step"
    );
    let mut rows = Vec::new();
    for n in [2_200, 8_500, 18_600] {
        rows.push(time_sequence(&format!("tube-{n}"), &bent_tube(n), seq)?);
    }
    if let Some(dir) = data {
        let horse = [
            dir.join("sumner-horse-camel/horse-reference.obj.gz"),
            dir.join("sumner-horse-camel/horse-05.obj.gz"),
        ];
        let set = morphkit::io::read_shape_set(&horse)?;
        rows.push(time_sequence("horse ref↔05 (8.4k)", &set, seq)?);
        let ict = [
            dir.join("ict-facekit/generic_neutral_mesh.obj.gz"),
            dir.join("ict-facekit/jawOpen.obj.gz"),
        ];
        let set = morphkit::io::read_shape_set(&ict)?;
        rows.push(time_sequence("ICT head↔jawOpen (26.7k)", &set, seq)?);
        let arm = morphkit::io::read_mesh(&dir.join("generic-meshes/armadillo.obj.gz"))?;
        let (lo, hi) = arm.bounding_box();
        let mid = 0.5 * (lo[0] + hi[0]);
        let bent = generate::bend(&arm.positions, mid, hi[0] - mid, 60f64.to_radians());
        let set = ShapeSet::new(
            arm.clone(),
            vec![
                ("armadillo".into(), arm.positions.clone()),
                ("bent".into(), bent),
            ],
        )?;
        rows.push(time_sequence("armadillo bent 60° (14.6k)", &set, seq)?);
    }
    Ok(rows)
}

/// Film scale (issue 38): square grids of unit side bent 60° *in their plane* into an annulus
/// sector (every vertex free, so the whole sheet is solved), blended at α = ½ with the
/// defaults: set-up, the sampled start's solve at ½ and the frame, to convergence. In this
/// order, since the peak resident is the process's so far: 100k vertices, then 1.21M, which
/// must be refused by the early checks before its solver is built (a small peak), then 1M,
/// which must fit the default 8 GiB limit with its estimate within 20 % of the peak.
fn memory_suite() -> anyhow::Result<serde_json::Value> {
    let mut rows = Vec::new();
    for side in [316usize, 1100, 1000] {
        let m = generate::grid(side - 1, side - 1, 1.0, 1.0);
        let set = ShapeSet::new(
            m.clone(),
            vec![
                ("flat".into(), m.positions.clone()),
                ("bent".into(), bent_in_plane(&m.positions)),
            ],
        )?;
        let t = Instant::now();
        let row = match PhysicalBlend::new(&set, &BlendOptions::default()) {
            Ok(mut solver) => {
                let setup = t.elapsed().as_secs_f64();
                let r = solver.solve(&Weights::Alpha(0.5))?;
                let sum = solver.summary();
                json!({ "vertices": m.num_vertices(), "outcome": "solved",
                        "converged": r.stats.converged,
                        "frame_newton_iterations": r.stats.newton_iterations,
                        "aggregates": sum.aggregates,
                        "predicted_mib": sum.predicted_bytes as f64 / 1048576.0,
                        "setup_seconds": setup,
                        "seconds": t.elapsed().as_secs_f64(), "peak_rss_mib": peak_rss_mib() })
            }
            Err(e) => json!({ "vertices": m.num_vertices(), "outcome": "refused",
                              "message": e.to_string(), "seconds": t.elapsed().as_secs_f64(),
                              "peak_rss_mib": peak_rss_mib() }),
        };
        println!("{row}");
        rows.push(row);
    }
    Ok(json!(rows))
}

/// A unit square's points `[x, y, 0]` bent 60° in their plane: each line of constant `y`
/// becomes an arc of the same length about a common centre (radius 3/π at `y = ½`).
fn bent_in_plane(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let angle = 60f64.to_radians();
    let radius = 1.0 / angle;
    points
        .iter()
        .map(|p| {
            let (t, r) = ((p[0] - 0.5) * angle, radius + p[1] - 0.5);
            [r * t.sin(), r * t.cos() - radius, 0.0]
        })
        .collect()
}

/// Runs `morphkit bench`.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let data = args
        .data
        .clone()
        .or_else(|| std::env::var_os("MORPHKIT_DATA").map(PathBuf::from));
    if !(1..=MAX_STEPS).contains(&args.steps) {
        anyhow::bail!(
            "--steps {}: must be between 1 and {MAX_STEPS} (each step is one solve per mesh)",
            args.steps
        );
    }
    if !matches!(
        args.suite.as_str(),
        "springs"
            | "transfer"
            | "rig"
            | "memory"
            | "synth"
            | "scene"
            | "volume"
            | "scrub"
            | "continuity"
            | "all"
    ) {
        anyhow::bail!(
            "unknown suite '{}': use springs, transfer, rig, memory, synth, scene, volume, scrub, continuity or all",
            args.suite
        );
    }
    // Check the report location before measuring, so a bad path loses no measurements.
    let mut outputs = Plan::new(&[])
        .output_opt("--report", args.report.as_ref(), Kind::Json)
        .check()?;
    let mut report = json!({ "threads": args.threads });
    report["machine"] = super::bench_machine::machine_check()?;
    let reference_factor_bytes = if args.no_reference_factors {
        0
    } else {
        BlendOptions::default().reference_factor_bytes
    };
    if matches!(args.suite.as_str(), "springs" | "all") {
        let seq = Sequence {
            steps: args.steps,
            threads: args.threads,
            options: BlendOptions {
                sampled_start: !args.no_sampled_start,
                preconditioner: args.preconditioner,
                reference_factor_bytes,
                ..Default::default()
            },
        };
        report["springs"] = json!(springs_suite(data.as_deref(), &seq)?);
    }
    if matches!(args.suite.as_str(), "volume") {
        report["volume"] = super::bench_volume::run_volume_bench(
            args.steps,
            args.threads,
            !args.no_sampled_start,
            args.preconditioner,
            reference_factor_bytes,
        )?;
    }
    if matches!(args.suite.as_str(), "memory") {
        report["memory"] = memory_suite()?;
    }
    if matches!(args.suite.as_str(), "scene") {
        report["scene"] = super::bench_scene::run_scene_bench(
            &bent_tube(18_000),
            3,
            !args.no_sampled_start,
            reference_factor_bytes,
        )?;
    }
    if matches!(args.suite.as_str(), "transfer" | "all") {
        match data.as_deref() {
            Some(dir) => report["transfer"] = super::bench_transfer::run_transfer_bench(dir)?,
            None => println!("transfer suite skipped: it needs --data DIR or MORPHKIT_DATA (elephant, horse, camel)"),
        }
    }
    if matches!(args.suite.as_str(), "rig" | "all") {
        match data.as_deref() {
            Some(dir) => report["rig"] = super::bench_rig::run_rig_bench(dir)?,
            None => {
                println!("rig suite skipped: it needs --data DIR or MORPHKIT_DATA (ict-facekit)")
            }
        }
    }
    if matches!(args.suite.as_str(), "synth" | "all") {
        match data.as_deref() {
            Some(dir) => report["synth"] = super::bench_synth::run_synth_bench(dir)?,
            None => {
                println!("synth suite skipped: it needs --data DIR or MORPHKIT_DATA (elephant)")
            }
        }
    }
    if matches!(args.suite.as_str(), "scrub") {
        match data.as_deref() {
            Some(dir) => {
                report["scrub"] = super::bench_scrub::run_scrub_bench(dir, args.steps.min(24))?
            }
            None => println!(
                "scrub suite skipped: it needs --data DIR or MORPHKIT_DATA (ict-facekit, sumner-horse-camel)"
            ),
        }
    }
    if matches!(args.suite.as_str(), "continuity") {
        report["continuity"] =
            super::bench_continuity::run_continuity_bench(data.as_deref(), args.steps)?;
    }
    if let Some(path) = &args.report {
        outputs.json(path, &report)?;
    }
    outputs.commit()?;
    Ok(())
}
