//! Probe of the interactive mode (issue 38): for random slider states of the horse or ICT
//! rig, the interactive shape's distance from the full solve, its iterations and time.
//!
//! `MORPHKIT_DATA=../shared/data cargo run --release -p morphkit --example scrub_probe -- horse|ict [states] [threads]`
use morphkit::io::read_mesh;
use morphkit::mesh::ShapeSet;
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};
use rand::{Rng, SeedableRng};
use std::time::Instant;

fn maxdist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(|s| s.as_str()).unwrap_or("horse");
    let count: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8);
    let threads: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2);
    let data = std::path::PathBuf::from(std::env::var("MORPHKIT_DATA").expect("MORPHKIT_DATA"));
    let (base, names): (std::path::PathBuf, Vec<std::path::PathBuf>) = if which == "ict" {
        let d = data.join("ict-facekit");
        let names = [
            "browInnerUp_L",
            "cheekPuff_L",
            "eyeBlink_L",
            "eyeBlink_R",
            "jawLeft",
            "jawOpen",
            "mouthFunnel",
            "mouthPucker",
            "mouthSmile_L",
            "mouthSmile_R",
        ];
        (
            d.join("generic_neutral_mesh.obj.gz"),
            names
                .iter()
                .map(|n| d.join(format!("{n}.obj.gz")))
                .collect(),
        )
    } else {
        let d = data.join("sumner-horse-camel");
        (
            d.join("horse-reference.obj.gz"),
            (1..=10)
                .map(|i| d.join(format!("horse-{i:02}.obj.gz")))
                .collect(),
        )
    };
    let b = read_mesh(&base).unwrap();
    let targets: Vec<(String, Vec<[f64; 3]>)> =
        std::iter::once(("base".to_string(), b.positions.clone()))
            .chain(
                names
                    .iter()
                    .map(|p| (p.display().to_string(), read_mesh(p).unwrap().positions)),
            )
            .collect();
    let shapes = ShapeSet::new(b.clone(), targets).unwrap();
    let diag = morphkit::mesh::bbox_diagonal(&b.positions);
    let t = Instant::now();
    let mut blend = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    eprintln!("build {:.2}s", t.elapsed().as_secs_f64());
    let space = blend.prepare_interactive(threads);
    eprintln!(
        "prepared: {} snapshots ({} unconverged) in {:.1}s",
        space.len(),
        space.unconverged,
        space.prepare_seconds
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let nt = shapes.len() - 1;
    for trial in 0..count {
        let mut w = vec![0.0; nt];
        let kind = trial % 4;
        if kind == 3 {
            w[rng.random_range(0..nt)] = rng.random_range(0.05..0.95);
        } else if which == "ict" {
            let mut picked = Vec::new();
            while picked.len() < 3 {
                let i = rng.random_range(0..nt);
                if !picked.contains(&i) {
                    picked.push(i);
                }
            }
            for i in picked {
                w[i] = rng.random_range(0.3..1.0);
            }
        } else {
            let i = rng.random_range(0..nt);
            let mut j = rng.random_range(0..nt);
            while j == i {
                j = rng.random_range(0..nt);
            }
            let a: f64 = rng.random_range(0.0..1.0);
            let bb: f64 = rng.random_range(0.0..(1.0 - a));
            w[i] = a;
            w[j] = bb;
        }
        let weights = Weights::Delta(w.clone());
        let t = Instant::now();
        let r = blend.solve(&weights).unwrap();
        let tf = t.elapsed().as_secs_f64();
        let p = blend.predict(&weights).unwrap();
        println!(
            "{trial} w={:?} full {:.0} ms ({} it) | P {:.2e}",
            w.iter()
                .map(|x| (x * 100.0).round() / 100.0)
                .collect::<Vec<_>>(),
            tf * 1e3,
            r.stats.newton_iterations,
            maxdist(&p, &r.positions) / diag,
        );
        for refine in [0, 1] {
            let t = Instant::now();
            let i = blend.solve_interactive(&weights, refine).unwrap();
            let ti = t.elapsed().as_secs_f64();
            println!(
                "    refine {refine}: error {:.2e} estimate {:.2e} in {:.1} ms, {} it {} rej, |g| {:.1e}",
                maxdist(&i.positions, &r.positions) / diag,
                i.stats.error_estimate.unwrap_or(f64::NAN),
                ti * 1e3,
                i.stats.newton_iterations,
                i.stats.rejected_steps,
                i.stats.gradient_norm,
            );
        }
    }
}
