//! The synthesis part of `morphkit bench`, against the paper's Table 1 (Wang & Lee 2008:
//! Elephant, 85.8k triangles, Pentium 4: blending weights 6.9 s, factorization 11.6 s, solve
//! 0.39 s per frame). Targets here: weights ≤ 0.5 s, per-frame synthesis ≤ 50 ms including
//! gradient blending.
//!
//! `sumner-elephant` (84.6k triangles) with the identity correspondence and its six gallop
//! frames as two layers: the gallop on the legs (the lowest 30 % of the height, blend) and the
//! gallop played backwards at half speed, looped, on the rest (compound), so both blend modes,
//! frame interpolation and the Eq. 5 bands are in the loop.
//!
//! - "weights": the legs layer's Eq. 1 over all source frames, partitions and the Eq. 5
//!   factorization and solve;
//! - "factorization": the one transfer factorization ([`TransferSolver::new`]);
//! - "per frame": gradient blending of both layers plus the solve and placement;
//! - "pose edit": one [`Synthesizer::edit_pose`] (one Eq. 5 solve and one transfer solve, no
//!   factorization), the interactive call of Sec. 3.2.4.

use morphkit::io::read_mesh;
use morphkit::mesh::Topology;
use morphkit::synth::{
    blend_weights, BlendMode, BlendRegion, Flexibility, LayerSpec, Partitions, PoseSpec, Selection,
    SynthOptions, Synthesizer, Timing, GAMMA, KAPPA,
};
use morphkit::transfer::{Correspondence, SolverOptions, TransferSolver};
use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;

/// Output frames synthesised per round.
const FRAMES: usize = 12;

/// CPU time of this thread in seconds (Linux `/proc/thread-self/schedstat`, first field, ns).
/// On a shared, oversubscribed machine wall time also counts the time other processes held
/// the core; CPU time does not, so the bench reports both.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Wall and CPU seconds of `f`.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, Option<f64>) {
    let c0 = cpu_seconds();
    let t0 = Instant::now();
    let out = f();
    let wall = t0.elapsed().as_secs_f64();
    let cpu = c0.and_then(|c| cpu_seconds().map(|c1| c1 - c));
    (out, wall, cpu)
}

/// Runs the synthesis benchmark on the meshes under `data_dir` (the `MORPHKIT_DATA` layout).
pub fn run_synth_bench(data_dir: &Path) -> anyhow::Result<Value> {
    let file = |rel: &str| -> anyhow::Result<std::path::PathBuf> {
        let p = data_dir.join(rel);
        anyhow::ensure!(p.is_file(), "{}: missing benchmark data", p.display());
        Ok(p)
    };
    let eref = read_mesh(&file("sumner-elephant/elephant-reference.obj.gz")?)?;
    let mut frames = Vec::new();
    for i in [1, 9, 17, 25, 33, 41] {
        frames.push(
            read_mesh(&file(&format!(
                "sumner-elephant/elephant-gallop-{i:02}.obj.gz"
            ))?)?
            .positions,
        );
    }
    let (lo, hi) = eref.bounding_box();
    let cut = lo[1] + 0.3 * (hi[1] - lo[1]);
    let legs: Vec<bool> = eref
        .triangles
        .iter()
        .map(|t| {
            t.iter()
                .map(|&v| eref.positions[v as usize][1])
                .sum::<f64>()
                / 3.0
                < cut
        })
        .collect();
    let rest: Vec<bool> = legs.iter().map(|&l| !l).collect();
    let corr = Correspondence::identity(&eref);
    let layer = |frames: Vec<Vec<[f64; 3]>>, scribble, mode, timing| LayerSpec {
        source_reference: eref.clone(),
        frames,
        correspondence: corr.clone(),
        scribble,
        mode,
        timing,
        region: BlendRegion::Partitions,
    };
    let backwards: Vec<Vec<[f64; 3]>> = frames.iter().rev().cloned().collect();
    let layers = vec![
        layer(frames, legs.clone(), BlendMode::Blend, Timing::default()),
        layer(
            backwards,
            rest,
            BlendMode::Compound,
            Timing {
                offset: 0,
                speed: 0.5,
                looped: true,
            },
        ),
    ];
    // Weights alone (Eq. 1, partitions, Eq. 5) for the legs layer, as the one-shot calls.
    let (w, weights_wall, weights_cpu) = timed(|| -> anyhow::Result<usize> {
        let flex = Flexibility::from_frames(&eref, &layers[0].frames)?;
        let topo = Topology::new(eref.num_vertices(), &eref.triangles);
        let parts = Partitions::new(&flex, &topo, GAMMA)?;
        let sel = Selection::refine(&parts, &layers[0].scribble)?;
        Ok(blend_weights(&parts, &topo, &sel, KAPPA)?.values.len())
    });
    w?;
    let (factor, factor_wall, factor_cpu) =
        timed(|| TransferSolver::new(&eref, &SolverOptions::default()));
    factor?;
    let (synth, build, _) = timed(|| {
        Synthesizer::new(
            &eref,
            layers,
            &[],
            &SynthOptions {
                frames: FRAMES,
                ..Default::default()
            },
        )
    });
    let mut synth = synth?;
    let (mut wall, mut cpu, mut worst, mut flips) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for f in 0..FRAMES {
        let (fr, w, c) = timed(|| synth.frame(f));
        let fr = fr?;
        anyhow::ensure!(
            fr.positions.iter().flatten().all(|c| c.is_finite()),
            "elephant synthesis: non-finite result"
        );
        wall += w;
        cpu += c.unwrap_or(f64::NAN);
        worst = worst.max(w);
        flips = flips.max(synth.flipped_triangles(&fr).len());
    }
    let n = FRAMES as f64;
    // The interactive pose edit: turn the legs' partitions by 10° about x.
    let (edit, pose_wall, pose_cpu) = timed(|| {
        synth.edit_pose(&PoseSpec {
            scribble: legs,
            layer: 0,
            axis: [1.0, 0.0, 0.0],
            angle: 10f64.to_radians(),
        })
    });
    edit?;
    let ms = |x: Option<f64>| x.map_or_else(|| "-".into(), |v| format!("{:.1}", 1e3 * v));
    println!(
        "synth    elephant, 2 layers   {:>7} tri  weights {:>6.3} s (cpu {} ms)  factorization {:>6.3} s (cpu {} ms)  per frame {:>6.1} ms (cpu {:.1}, max {:.1})  pose edit {:>5.1} ms (cpu {})",
        eref.num_triangles(),
        weights_wall,
        ms(weights_cpu),
        factor_wall,
        ms(factor_cpu),
        1e3 * wall / n,
        1e3 * cpu / n,
        1e3 * worst,
        1e3 * pose_wall,
        ms(pose_cpu),
    );
    let info = synth.layer_info(0);
    Ok(json!({
        "paper_table1": {
            "machine": "Pentium 4",
            "mesh": "Elephant, 85.8k triangles",
            "blending_weights_s": 6.9,
            "factorization_s": 11.6,
            "solve_per_frame_s": 0.39,
        },
        "targets": { "weights_s": 0.5, "per_frame_s": 0.050 },
        "triangles": eref.num_triangles(),
        "frames": FRAMES,
        "build_s": build,
        "weights_s": weights_wall,
        "weights_cpu_s": weights_cpu,
        "factorization_s": factor_wall,
        "factorization_cpu_s": factor_cpu,
        "per_frame_s": wall / n,
        "per_frame_cpu_s": cpu / n,
        "frame_max_s": worst,
        "pose_edit_s": pose_wall,
        "pose_edit_cpu_s": pose_cpu,
        "stiff_partitions_layer0": info.partitions.num_stiff(),
        "selected_triangles_layer0": info.selection.num_triangles(),
        "max_flipped_triangles": flips,
    }))
}
