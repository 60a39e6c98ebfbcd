//! How close a bake ([`morphkit::bake`]) is to the full physical solve, on the ICT head with
//! ten expressions (welded, as `blend` welds it), against the linear blend (issue 56's
//! accuracy target): every target alone at weights between the in-betweens, and twelve random
//! combinations of three targets at 0.3–1, for combination damping exponents 0 (the plain
//! product), 1 and 2. Distances are fractions of the bounding-box diagonal. `PAIR_SAMPLES=0.5`
//! bakes one combination shape per pair (at (½, ½)) instead of the default ½ and 1.
//!
//! `cargo run --release -p morphkit --example bake_accuracy -- DATA_DIR [THREADS]`

use morphkit::bake::{bake, BakeOptions, BakedRig};
use morphkit::geom::max_distance;
use morphkit::io::read_mesh;
use morphkit::mesh::{Weld, WELD_TOLERANCE};
use morphkit::springs::{linear_blend, BlendOptions, PhysicalBlend, Weights};
use morphkit::ShapeSet;
use rand::{Rng, SeedableRng};
use std::time::Instant;

const EXPRESSIONS: [&str; 10] = [
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(
        args.get(1)
            .ok_or("usage: bake_accuracy DATA_DIR [THREADS]")?,
    )
    .join("ict-facekit");
    let threads: usize = args.get(2).map_or(Ok(2), |t| t.parse())?;
    let base = read_mesh(&dir.join("generic_neutral_mesh.obj.gz"))?;
    let mut named = vec![("base".to_string(), base.positions.clone())];
    for e in EXPRESSIONS {
        named.push((
            e.to_string(),
            read_mesh(&dir.join(format!("{e}.obj.gz")))?.positions,
        ));
    }
    let shapes = ShapeSet::new(base, named)?;
    let weld = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let shapes = weld.shapes(&shapes)?;
    let diag = shapes.base().bbox_diagonal();
    let mut solver = PhysicalBlend::new(&shapes, &BlendOptions::default())?;
    let t = Instant::now();
    let samples: Vec<f64> = std::env::var("PAIR_SAMPLES")
        .map(|s| s.split(',').map(|x| x.parse().expect("a number")).collect())
        .unwrap_or_else(|_| BakeOptions::default().pair_samples);
    let options = BakeOptions {
        pair_samples: samples,
        ..BakeOptions::default()
    };
    let mut baked = bake(&mut solver, &options, threads)?;
    println!(
        "bake: {} shapes ({} combinations) in {:.1} s",
        baked.num_shapes(),
        baked.combinations.len(),
        t.elapsed().as_secs_f64()
    );
    let n = EXPRESSIONS.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(56);
    let mut states: Vec<(String, Vec<f64>)> = Vec::new();
    for i in 0..n {
        let mut w = vec![0.0; n];
        w[i] = rng.random_range(0.06..0.94);
        states.push((format!("single {}", EXPRESSIONS[i]), w));
    }
    for _ in 0..12 {
        let mut w = vec![0.0; n];
        let mut picked = Vec::new();
        while picked.len() < 3 {
            let k = rng.random_range(0..n);
            if !picked.contains(&k) {
                picked.push(k);
            }
        }
        for &k in &picked {
            w[k] = rng.random_range(0.3..1.0);
        }
        states.push((format!("triple {picked:?}"), w));
    }
    let ws: Vec<Weights> = states.iter().map(|s| Weights::Delta(s.1.clone())).collect();
    let solved: Vec<_> = solver
        .solve_many(&ws, threads)
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    for p in [0.0, 1.0, 2.0] {
        baked.damping = p;
        report(&baked, &shapes, &states, &solved, diag, p)?;
    }
    Ok(())
}

fn report(
    baked: &BakedRig,
    shapes: &ShapeSet,
    states: &[(String, Vec<f64>)],
    solved: &[morphkit::springs::BlendResult],
    diag: f64,
    p: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    println!("damping p = {p}");
    let (mut singles, mut triples, mut worse) = (Vec::new(), Vec::new(), 0);
    for ((name, w), r) in states.iter().zip(solved) {
        let b = max_distance(&baked.evaluate(w), &r.positions) / diag;
        let l = max_distance(
            &linear_blend(shapes, &Weights::Delta(w.clone()))?,
            &r.positions,
        ) / diag;
        if b >= l {
            worse += 1;
        }
        println!(
            "  {name:34} baked {b:.2e}  linear {l:.2e}{}",
            if b >= l { "  WORSE" } else { "" }
        );
        if name.starts_with("single") {
            singles.push(b);
        } else {
            triples.push(b);
        }
    }
    triples.sort_by(f64::total_cmp);
    println!(
        "  singles worst {:.2e}; triples median {:.2e} worst {:.2e}; {worse} states not closer than linear",
        singles.iter().copied().fold(0.0, f64::max),
        triples[triples.len() / 2],
        triples[triples.len() - 1]
    );
    Ok(())
}
