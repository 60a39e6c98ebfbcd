//! The continuity suite of `morphkit bench` (issue 54): each target of each rig swept alone
//! from 0 to 1, and a straight path between consecutive targets (the first at 0.9 to the
//! second at 0.9), in `steps` steps, frame after frame on one thread. A *pop* is a step that
//! moves some vertex more than [`JUMP_BOUND`] times the linear blend's largest move for the
//! same step ([`ContinuityCheck`]). Per rig: sweeps, pops, the worst step ratio, the
//! distribution of Newton iterations (median, 99th percentile, largest) and of frame times
//! (median, largest, and the largest over the median). Each pop's step is then halved: a
//! *snap* (a discontinuity: the motion leaves one equilibrium for another) keeps its move in
//! one half, whose ratio about doubles, while a *fast step* (the equilibrium moving smoothly
//! faster than the bound allows) keeps its ratio; a pop counts as a snap when a half's ratio
//! is over `SNAP_GROWTH` times the step's (`morphkit::springs::snaps`). Rigs: generated
//! necks whose head turns 170–190° with a roll or bends back by 180°, and, with the data,
//! cragl's cylinder with its eight bends and poses, the horse's ten poses and the ICT head's
//! ten expressions, welded as `blend` welds them.

use super::bench_scrub::real_rigs;
use morphkit::mesh::generate::turning_head_rig;
use morphkit::mesh::{bbox_diagonal, ShapeSet};
use morphkit::springs::snaps::is_snap;
use morphkit::springs::{
    linear_blend, BlendOptions, ContinuityCheck, PhysicalBlend, Weights, JUMP_BOUND,
};
use serde_json::{json, Value};
use std::path::Path;

/// The weights of a path from `from` to `to` in `steps` steps.
fn path(from: &[f64], to: &[f64], steps: usize) -> Vec<Weights> {
    (0..=steps)
        .map(|k| {
            let t = k as f64 / steps as f64;
            Weights::Delta(from.iter().zip(to).map(|(a, b)| a + t * (b - a)).collect())
        })
        .collect()
}

/// Sweeps every target of `shapes` alone and every consecutive pair's path; one JSON row.
fn rig_row(name: &str, shapes: &ShapeSet, steps: usize) -> anyhow::Result<Value> {
    let mut solver = PhysicalBlend::new(shapes, &BlendOptions::default())?;
    let n = shapes.len() - 1;
    let mut paths = Vec::new();
    for t in 0..n {
        let mut one = vec![0.0; n];
        one[t] = 1.0;
        paths.push(path(&vec![0.0; n], &one, steps));
    }
    for t in 1..n {
        let (mut from, mut to) = (vec![0.0; n], vec![0.0; n]);
        from[t - 1] = 0.9;
        to[t] = 0.9;
        paths.push(path(&from, &to, steps));
    }
    let diagonal = bbox_diagonal(shapes.positions(0));
    // The sampled start's fields are set-up, solved once per rig (as `blend` does before its
    // frames): timed apart, so that the frame times are those of an artist's scrubbing.
    let t_prepare = std::time::Instant::now();
    solver.prepare(&paths.concat(), 1);
    let prepare_seconds = t_prepare.elapsed().as_secs_f64();
    let (mut pops, mut worst, mut unconverged) = (0, 0.0f64, 0);
    let mut snaps: Vec<Value> = Vec::new();
    let (mut iterations, mut seconds) = (Vec::new(), Vec::new());
    for weights in &paths {
        let mut check = ContinuityCheck::new(JUMP_BOUND, diagonal);
        for w in weights {
            let r = solver.solve(w)?;
            unconverged += usize::from(!r.stats.converged);
            iterations.push(r.stats.newton_iterations);
            seconds.push(r.stats.seconds);
            check.push(&r.positions, &linear_blend(shapes, w)?)?;
        }
        let c = check.finish();
        pops += c.jumps.len();
        worst = worst.max(c.worst_ratio);
        for j in &c.jumps {
            let [a, b] = j.frames;
            if is_snap(&mut solver, &weights[a], &weights[b], j.ratio)? {
                let Weights::Delta(w) = &weights[a] else {
                    continue;
                };
                snaps.push(json!({"from": w, "ratio": j.ratio}));
            }
        }
    }
    iterations.sort_unstable();
    seconds.sort_by(f64::total_cmp);
    let at = |p: usize| iterations[(iterations.len() - 1) * p / 100];
    let median_s = seconds[seconds.len() / 2];
    let max_s = seconds[seconds.len() - 1];
    let row = json!({
        "rig": name,
        "vertices": shapes.num_vertices(),
        "sweeps": paths.len(),
        "frames": iterations.len(),
        "steps": steps,
        "pops": pops,
        "snaps": snaps.len(),
        "fast_steps": pops - snaps.len(),
        "snap_states": snaps,
        "worst_step_ratio": worst,
        "unconverged": unconverged,
        "newton_median": at(50),
        "newton_p99": at(99),
        "newton_max": iterations[iterations.len() - 1],
        "prepare_seconds": prepare_seconds,
        "frame_seconds_median": median_s,
        "frame_seconds_max": max_s,
        "frame_seconds_max_over_median": max_s / median_s.max(1e-9),
    });
    println!(
        "continuity {name}: {} sweeps of {steps} steps, {pops} pops ({} snaps, the rest fast steps), worst step {worst:.2}× linear, {unconverged} unconverged; Newton median {} p99 {} max {}; frame {:.3} s median, {:.3} s max (after {:.1} s of sample solves)",
        paths.len(),
        snaps.len(),
        at(50),
        at(99),
        iterations[iterations.len() - 1],
        median_s,
        max_s,
        prepare_seconds
    );
    Ok(row)
}

/// Runs the suite: the generated rigs always, the real ones where `data_dir` is given.
pub fn run_continuity_bench(data_dir: Option<&Path>, steps: usize) -> anyhow::Result<Value> {
    let mut rows = Vec::new();
    for (turn, roll) in [(170.0, 20.0), (180.0, 20.0), (190.0, 20.0), (0.0, 180.0)] {
        let name = format!("generated neck, head turning {turn}° with a {roll}° roll");
        rows.push(rig_row(&name, &turning_head_rig(turn, roll), steps)?);
    }
    if let Some(dir) = data_dir {
        let cyl = dir.join("cragl-bending-cylinder");
        let cylinder = super::bench_scrub::read_rig(
            &cyl.join("cylinder-rest.obj"),
            &[
                "bend-1", "bend-2", "bend-3", "bend-4", "pose1-1", "pose1-2", "pose1-3", "pose1-4",
            ]
            .map(|t| cyl.join(format!("cylinder-{t}.obj"))),
        )?
        .0;
        rows.push(rig_row(
            "cragl cylinder (8 bends and poses)",
            &cylinder,
            steps,
        )?);
        let [(horse, _), (face, _)] = real_rigs(dir)?;
        rows.push(rig_row("horse (10 poses)", &horse, steps)?);
        rows.push(rig_row(
            "ICT FaceKit (10 expressions), welded",
            &face,
            steps,
        )?);
    } else {
        println!("continuity suite: the real rigs need --data DIR or MORPHKIT_DATA (cragl-bending-cylinder, sumner-horse-camel, ict-facekit)");
    }
    Ok(json!(rows))
}
