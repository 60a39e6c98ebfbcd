//! Issue 7's whole-sequence properties on the real rigs: each target blended from the base
//! over `STEPS` frames (α = k / (STEPS − 1)), every frame checked by the tests'
//! `common::sequence::check_sequence` (convergence, steps against the linear blend's, folds,
//! distance from the linear blend). The test `springs_sequences_real_data` asserts the same on
//! 36 steps; this prints the numbers and can vary the options.
//!
//! ```sh
//! MORPHKIT_DATA=$(cd ../shared/data && pwd) cargo run --release -p morphkit \
//!     --example sequence_check -- [horse|ict|all] [STEPS] [NAME-FILTER]
//! ```
//!
//! `PROFILE=1` prints every consecutive pair's step ratio. `HINGE=c` sets the hinge weight,
//! `TETHER=μ` the predictor tether, `MARGIN=m` its fold margin (radians), `BANDS=r` the
//! thin-band rings, `NO_SAMPLED=1` starts from the plain predictor, and `DUMP=DIR` writes
//! every frame's physical, predicted and linear positions as raw little-endian f64 (`#V × 3`)
//! to `DIR/NAME-{phys,pred,lin}-KK.f64` for pictures.

#[path = "../tests/common/mod.rs"]
mod common;

use common::sequence::{check_sequence, ramp};
use morphkit::io::read_shape_set;
use morphkit::mesh::Point;
use morphkit::mesh::Topology;
use morphkit::springs::{
    blend_metrics, fold_metrics, linear_blend, BlendOptions, BlendResult, ContinuityCheck,
    PhysicalBlend,
};

fn env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

fn options() -> BlendOptions {
    let mut o = BlendOptions {
        sampled_start: std::env::var("NO_SAMPLED").is_err(),
        ..Default::default()
    };
    if let Some(h) = env("HINGE") {
        o.hinges.weight = h;
    }
    if let Some(t) = env("TETHER") {
        o.tether = t;
    }
    if let Some(r) = env("BANDS") {
        o.thin_band_rings = r;
    }
    if let Some(m) = env("MARGIN") {
        o.hinges.min_fold_margin = m;
    }
    if let Some(b) = env("BENDING_SCALE") {
        o.springs.bending_scale = b;
    }
    if std::env::var("NO_BENDING").is_ok() {
        o.springs.bending = false;
    }
    o
}

fn dump(name: &str, solver: &PhysicalBlend, targets: usize, target: usize, frames: &[BlendResult]) {
    let Ok(dir) = std::env::var("DUMP") else {
        return;
    };
    let write = |kind: &str, k: usize, p: &[Point]| {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        std::fs::write(format!("{dir}/{name}-{kind}-{k:02}.f64"), bytes).unwrap();
    };
    for (k, (w, r)) in ramp(targets, target, frames.len())
        .iter()
        .zip(frames)
        .enumerate()
    {
        write("phys", k, &r.positions);
        write("pred", k, &solver.predict(w).unwrap());
        write("lin", k, &linear_blend(solver.shapes(), w).unwrap());
    }
}

/// Creases and edge-length RMS against the linear blend, summed over the frames.
fn quality(
    name: &str,
    solver: &PhysicalBlend,
    targets: usize,
    target: usize,
    frames: &[BlendResult],
) {
    let s = solver.shapes();
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let (mut cr, mut cr_lin, mut rms, mut rms_lin) = (0, 0, 0.0, 0.0);
    for (w, r) in ramp(targets, target, frames.len()).iter().zip(frames) {
        let q = fold_metrics(s, &topo, w, &r.positions).unwrap();
        cr += q.creases;
        cr_lin += q.creases_linear;
        rms += blend_metrics(s, &topo, w, &r.positions)
            .unwrap()
            .edge_length_rms;
        rms_lin += blend_metrics(s, &topo, w, &linear_blend(s, w).unwrap())
            .unwrap()
            .edge_length_rms;
    }
    let n = frames.len() as f64;
    println!(
        "{name}: creases {cr} vs {cr_lin} linear, edge RMS {:.5} vs {:.5} linear (mean over frames)",
        rms / n,
        rms_lin / n
    );
}

fn run(
    name: &str,
    solver: &mut PhysicalBlend,
    targets: usize,
    target: usize,
    steps: usize,
) -> bool {
    let t0 = std::time::Instant::now();
    let rep = check_sequence(name, solver, targets, target, steps);
    let secs = t0.elapsed().as_secs_f64();
    quality(name, solver, targets, target, &rep.frames);
    dump(name, solver, targets, target, &rep.frames);
    for f in &rep.failures {
        println!("  {f}");
    }
    if std::env::var("PROFILE").is_ok() {
        // Every consecutive pair's step ratio (a bound of 0 lists them all).
        let s = solver.shapes();
        let mut all = ContinuityCheck::new(0.0, morphkit::mesh::bbox_diagonal(s.positions(0)));
        for (w, r) in ramp(targets, target, steps).iter().zip(&rep.frames) {
            all.push(&r.positions, &linear_blend(s, w).unwrap())
                .unwrap();
        }
        for j in all.finish().jumps {
            println!(
                "  frames {:?}: {:.2}× (vertex {})",
                j.frames, j.ratio, j.vertex
            );
        }
    }
    println!(
        "{name}: {} — worst step {:.2}× linear, folds over linear {}, from linear {:.3}, {} Newton, {secs:.1} s",
        if rep.failures.is_empty() { "ok" } else { "FAILS" },
        rep.worst_step,
        rep.worst_fold_excess,
        rep.worst_from_linear,
        rep.newton
    );
    rep.failures.is_empty()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("all");
    let steps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(36);
    let filter = args.get(3).cloned().unwrap_or_default();
    let data = |rel: &str| common::data_file(rel).expect("set MORPHKIT_DATA to ../shared/data");
    let mut failures = Vec::new();
    if which == "horse" || which == "all" {
        for pose in 1..=10 {
            let name = format!("horse-{pose:02}");
            if !name.contains(&filter) {
                continue;
            }
            let s = read_shape_set(&[
                data("sumner-horse-camel/horse-reference.obj.gz"),
                data(&format!("sumner-horse-camel/{name}.obj.gz")),
            ])
            .unwrap();
            let mut solver = PhysicalBlend::new(&s, &options()).unwrap();
            if !run(&name, &mut solver, 1, 0, steps) {
                failures.push(name);
            }
        }
    }
    if which == "ict" || which == "all" {
        let paths = common::ict_rig_paths().expect("set MORPHKIT_DATA to ../shared/data");
        let s = read_shape_set(&paths).unwrap();
        let mut solver = PhysicalBlend::new(&s, &options()).unwrap();
        let ict = common::ICT_EXPRESSIONS;
        for (k, e) in ict.iter().enumerate() {
            if e.contains(&filter) && !run(e, &mut solver, ict.len(), k, steps) {
                failures.push(e.to_string());
            }
        }
    }
    println!("failing sequences: {failures:?}");
}
