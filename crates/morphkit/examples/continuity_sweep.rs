//! Sweeps one target of a rig in fine steps and reports the steps that jump (issue 54): every
//! step's largest vertex move against the linear blend's ([`ContinuityCheck`], bound 4), the
//! Newton iterations and seconds per frame. The rig is welded as `blend` welds it.
//!
//! ```sh
//! MORPHKIT_DATA=$(cd ../shared/data && pwd) cargo run --release -p morphkit \
//!     --example continuity_sweep -- RIG TARGET FROM TO STEPS
//! ```
//!
//! RIG: `horse` (ten poses), `ict` (ten expressions), `twist:DEG` (a generated neck whose head
//! turns DEG° about the neck with a 20° roll), `buckle` (a thin sheet pushed together),
//! `files:BASE,TARGET,…` (meshes under MORPHKIT_DATA, the first the base), or `bulges` (the
//! compact-clip tests' tube with 4 bends and 12 bulges, which kinks).
//!
//! What is swept: TARGET (an index from 0) alone from FROM to TO in STEPS steps, or
//! - `PATH_W="W;V"` (comma-separated weights of every target): the straight path from W to V,
//!   from FROM to TO of the way, on any rig;
//! - on `bulges`, `PATH_KEYS=A:B`: the straight path from its clip's key A to key B in STEPS
//!   steps, and `KEYS=A:B`: keys A to B themselves.
//!
//! How each frame is solved: the canonical start by default; `STEPS_ALONG=K` by continuation
//! along the ray from the rest shape in K steps ([`BlendOptions::continuation_steps`]);
//! `EIGHTHS=1` from
//! the predictor corrected by the target's own equilibria at every eighth (a single-target
//! sweep); `CONTINUE=1` from the previous frame moved as the predictor moves (path-dependent).
//! `STAGES=μ,…`, `TETHER`, `HINGE`, `GUARD` (the fold guard's weight), `HOLD_RAMP`,
//! `KINEMATIC` (the kinematic stretch; `inf` for none) and
//! `NO_SAMPLED=1` try the variants docs/choices.md measured ("Continuity in the weights").
//! `PROFILE=1` prints every frame, `BOUND=0` every step's ratio, `DUMP=DIR` writes every
//! frame's positions and its predictor's, `ONE="i:w,j:w"` solves one frame.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/common/gltf_asset.rs"]
mod fixture;
#[path = "../tests/common/bulging_tube.rs"]
mod tube;

use morphkit::io::read_shape_set;
use morphkit::mesh::generate::{buckling_sheet_rig, turning_head_rig};
use morphkit::mesh::{bbox_diagonal, Weld, WELD_TOLERANCE};
use morphkit::springs::{linear_blend, BlendOptions, ContinuityCheck, PhysicalBlend, Weights};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rig = args.get(1).map(String::as_str).unwrap_or("twist:180");
    let target: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(0);
    let from: f64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(0.0);
    let to: f64 = args.get(4).and_then(|a| a.parse().ok()).unwrap_or(1.0);
    let steps: usize = args.get(5).and_then(|a| a.parse().ok()).unwrap_or(100);
    let data = |rel: &str| common::data_file(rel).expect("set MORPHKIT_DATA to ../shared/data");
    let shapes = match rig {
        "horse" => {
            let mut p = vec![data("sumner-horse-camel/horse-reference.obj.gz")];
            p.extend((1..=10).map(|k| data(&format!("sumner-horse-camel/horse-{k:02}.obj.gz"))));
            read_shape_set(&p).unwrap()
        }
        "ict" => read_shape_set(&common::ict_rig_paths().expect("set MORPHKIT_DATA")).unwrap(),
        "buckle" => buckling_sheet_rig(),
        r if r.starts_with("files:") => {
            // files:BASE,TARGET,…: meshes under MORPHKIT_DATA, the first the base.
            let p: Vec<_> = r["files:".len()..].split(',').map(data).collect();
            read_shape_set(&p).unwrap()
        }
        "bulges" => {
            let (p, tris) = fixture::tube(tube::NU, tube::NV, 1.0, 0.0);
            let (bent, _) = fixture::tube(tube::NU, tube::NV, 1.0, tube::BEND);
            let (targets, names) = tube::targets(&p, &bent);
            let base = morphkit::mesh::TriMesh::new(p.clone(), tris);
            let mut all = vec![("rest".to_string(), p)];
            all.extend(names.into_iter().zip(targets));
            morphkit::mesh::ShapeSet::new(base, all).unwrap()
        }
        r => {
            let mut it = r.trim_start_matches("twist:").split(':');
            let deg: f64 = it.next().and_then(|d| d.parse().ok()).unwrap_or(180.0);
            let roll: f64 = it.next().and_then(|d| d.parse().ok()).unwrap_or(20.0);
            turning_head_rig(deg, roll)
        }
    };
    let weld = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let welded = weld.shapes(&shapes).unwrap();
    eprintln!(
        "{rig}: {} vertices ({} welded), {} targets",
        welded.num_vertices(),
        weld.merged(),
        welded.len() - 1
    );
    let mut options = BlendOptions::default();
    if let Some(t) = std::env::var("TETHER").ok().and_then(|v| v.parse().ok()) {
        options.tether = t;
    }
    if let Some(h) = std::env::var("HINGE").ok().and_then(|v| v.parse().ok()) {
        options.hinges.weight = h;
    }
    if let Some(k) = std::env::var("STEPS_ALONG")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        options.continuation_steps = k;
    }
    if let Some(g) = std::env::var("GUARD").ok().and_then(|v| v.parse().ok()) {
        options.fold_guard = g;
    }
    if let Some(h) = std::env::var("HOLD_RAMP").ok().and_then(|v| v.parse().ok()) {
        options.hold_ramp = h;
    }
    if let Some(k) = std::env::var("KINEMATIC").ok().and_then(|v| v.parse().ok()) {
        options.kinematic_stretch = k;
    }
    if let Some(m) = std::env::var("MAXIT").ok().and_then(|v| v.parse().ok()) {
        options.max_newton_iterations = m;
    }
    if std::env::var("NO_SAMPLED").is_ok() {
        options.sampled_start = false;
    }
    let mut solver = PhysicalBlend::new(&welded, &options).unwrap();
    // STAGES=μ1,μ2,…: a homotopy in the predictor tether, each stage started from the last.
    let mut stages: Vec<PhysicalBlend> = std::env::var("STAGES")
        .map(|v| {
            v.split(',')
                .map(|m| {
                    let o = BlendOptions {
                        tether: m.parse().unwrap(),
                        ..Default::default()
                    };
                    PhysicalBlend::new(&welded, &o).unwrap()
                })
                .collect()
        })
        .unwrap_or_default();
    let n = welded.len() - 1;
    // ONE="i:w,j:w": solve that one frame and print its statistics.
    if let Ok(one) = std::env::var("ONE") {
        let mut w = vec![0.0; n];
        for kv in one.split(',') {
            let (i, v) = kv.split_once(':').unwrap();
            w[i.parse::<usize>().unwrap()] = v.parse().unwrap();
        }
        let t = std::time::Instant::now();
        let r = solver.solve(&Weights::Delta(w.clone())).unwrap();
        println!(
            "{w:?}: converged {}, {} Newton, {} rejected, {} factorizations, {:.1} s",
            r.stats.converged,
            r.stats.newton_iterations,
            r.stats.rejected_steps,
            r.stats.factorizations,
            t.elapsed().as_secs_f64()
        );
        return;
    }
    let keys = |v: &str| -> (usize, usize) {
        let (a, b) = v.split_once(':').expect("A:B");
        (a.parse().unwrap(), b.parse().unwrap())
    };
    let clip = || tube::keys().into_iter().map(|(_, w)| w).collect::<Vec<_>>();
    let weights: Vec<Weights> = if let Ok(v) = std::env::var("PATH_KEYS") {
        let ((a, b), k) = (keys(&v), clip());
        (0..=steps)
            .map(|s| {
                let t = s as f64 / steps as f64;
                Weights::Delta(
                    k[a].iter()
                        .zip(&k[b])
                        .map(|(x, y)| x + t * (y - x))
                        .collect(),
                )
            })
            .collect()
    } else if let Ok(v) = std::env::var("PATH_W") {
        // PATH_W="w1,w2,…;v1,v2,…": the straight path between two weight vectors.
        let (a, b) = v.split_once(';').expect("FROM;TO");
        let parse = |x: &str| -> Vec<f64> { x.split(',').map(|t| t.parse().unwrap()).collect() };
        let (a, b) = (parse(a), parse(b));
        let (from_t, to_t) = (from, to);
        (0..=steps)
            .map(|s| {
                let t = from_t + (to_t - from_t) * s as f64 / steps as f64;
                Weights::Delta(a.iter().zip(&b).map(|(x, y)| x + t * (y - x)).collect())
            })
            .collect()
    } else if let Ok(v) = std::env::var("KEYS") {
        let ((a, b), k) = (keys(&v), clip());
        k[a..=b].iter().map(|w| Weights::Delta(w.clone())).collect()
    } else {
        (0..=steps)
            .map(|k| {
                let mut w = vec![0.0; n];
                w[target] = from + (to - from) * k as f64 / steps as f64;
                Weights::Delta(w)
            })
            .collect()
    };
    let eighths: Option<Vec<Vec<morphkit::mesh::Point>>> =
        std::env::var("EIGHTHS").ok().map(|_| {
            (0..=8)
                .map(|k| {
                    let mut w = vec![0.0; n];
                    w[target] = k as f64 / 8.0;
                    let w = Weights::Delta(w);
                    let x = solver.solve(&w).unwrap().positions;
                    let p = solver.predict(&w).unwrap();
                    x.iter()
                        .zip(&p)
                        .map(|(x, p)| std::array::from_fn(|i| x[i] - p[i]))
                        .collect()
                })
                .collect()
        });

    let bound: f64 = std::env::var("BOUND")
        .ok()
        .and_then(|b| b.parse().ok())
        .unwrap_or(4.0);
    let mut check = ContinuityCheck::new(bound, bbox_diagonal(welded.positions(0)));
    let (mut iters, mut secs) = (Vec::new(), Vec::new());
    let t0 = std::time::Instant::now();
    let continuation = std::env::var("CONTINUE").is_ok();
    let mut prev: Option<(Vec<morphkit::mesh::Point>, Vec<morphkit::mesh::Point>)> = None;
    for (k, w) in weights.iter().enumerate() {
        let r = match (&prev, continuation) {
            // Naive continuation: the previous frame moved as the predictor moves.
            (Some((x, p)), true) => {
                let q = solver.predict(w).unwrap();
                let start: Vec<_> = x
                    .iter()
                    .zip(p.iter().zip(&q))
                    .map(|(x, (p, q))| std::array::from_fn(|i| x[i] + q[i] - p[i]))
                    .collect();
                solver.solve_with(w, &[], Some(&start)).unwrap()
            }
            _ if !stages.is_empty() => {
                let mut extra = 0;
                let mut x = stages[0].solve(w).unwrap();
                for st in stages.iter_mut().skip(1) {
                    extra += x.stats.newton_iterations;
                    x = st.solve_with(w, &[], Some(&x.positions)).unwrap();
                }
                extra += x.stats.newton_iterations;
                let mut r = solver.solve_with(w, &[], Some(&x.positions)).unwrap();
                r.stats.newton_iterations += extra;
                r
            }
            _ if eighths.is_some() => {
                // EIGHTHS=1: the predictor corrected by the target's own equilibria at the
                // eighths (solved first, canonically), interpolated linearly.
                let e = eighths.as_ref().unwrap();
                let Weights::Delta(d) = w else { panic!() };
                let a = d[target];
                let q = solver.predict(w).unwrap();
                let k = ((a * 8.0).floor() as usize).min(7);
                let t = a * 8.0 - k as f64;
                let start: Vec<_> = (0..q.len())
                    .map(|v| {
                        std::array::from_fn(|i| {
                            q[v][i] + (1.0 - t) * e[k][v][i] + t * e[k + 1][v][i]
                        })
                    })
                    .collect();
                solver.solve_with(w, &[], Some(&start)).unwrap()
            }
            _ => solver.solve(w).unwrap(),
        };
        if continuation {
            prev = Some((r.positions.clone(), solver.predict(w).unwrap()));
        }
        if std::env::var("PROFILE").is_ok() {
            println!(
                "{k:4} {:?}: {} Newton, {:.2} s, converged {}",
                w, r.stats.newton_iterations, r.stats.seconds, r.stats.converged
            );
        }
        if let Ok(dir) = std::env::var("DUMP") {
            // Raw little-endian f64 positions (#V × 3) per frame, and the triangles once.
            let bytes: Vec<u8> = r
                .positions
                .iter()
                .flatten()
                .flat_map(|c| c.to_le_bytes())
                .collect();
            std::fs::write(format!("{dir}/frame-{k:04}.f64"), bytes).unwrap();
            let p = solver.predict(w).unwrap();
            let bytes: Vec<u8> = p.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
            std::fs::write(format!("{dir}/predicted-{k:04}.f64"), bytes).unwrap();
            if k == 0 {
                let t: Vec<u8> = welded
                    .triangles()
                    .iter()
                    .flatten()
                    .flat_map(|i| i.to_le_bytes())
                    .collect();
                std::fs::write(format!("{dir}/triangles.u32"), t).unwrap();
            }
        }
        iters.push(r.stats.newton_iterations);
        secs.push(r.stats.seconds);
        check
            .push(&r.positions, &linear_blend(&welded, w).unwrap())
            .unwrap();
    }
    let c = check.finish();
    for j in &c.jumps {
        println!("  jump at frames {:?}: {:.2}× linear", j.frames, j.ratio);
    }
    iters.sort_unstable();
    secs.sort_by(f64::total_cmp);
    let pct = |v: &[usize], p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    println!(
        "{rig} target {target} {from}..{to} in {steps}: {} jumps, worst {:.2}×; Newton median {} p99 {} max {}; frame s median {:.3} max {:.3}; {:.1} s",
        c.jumps.len(),
        c.worst_ratio,
        pct(&iters, 0.5),
        pct(&iters, 0.99),
        iters.last().unwrap(),
        secs[secs.len() / 2],
        secs.last().unwrap(),
        t0.elapsed().as_secs_f64()
    );
}
