//! Issue 9: correspondence quality without a reference answer, on real pairs from
//! `MORPHKIT_DATA` (horse ↔ camel, cat ↔ dog).
//!
//! The baseline is the one-stage correspondence of before issue 9 (least-squares-mesh warps
//! only, one-way matching, `--combine mean`). Compared with it:
//! - the new default (two-way matching, inverse-distance weights) must not be worse in mean
//!   cycle-consistency error (within 1 %) and must reach every source triangle;
//! - the closest-point refinement (Sumner & Popović 2004, Sec. 5; opt-in) must lower the mean
//!   and the largest cycle error and the sharp folds, and horse → camel correspondence with it
//!   must stay within 2 s (release build).
//!
//! Measured (release, 2 shared cores): horse ↔ camel mean 0.994 % (baseline) → 0.990 %
//! (default) → 0.964 % (refined), max 5.49 % → 5.34 % → 4.76 %; cat ↔ dog mean 2.110 % →
//! 2.074 % → 2.003 %, max 10.8 % → 10.6 % → 9.0 %. The target of a 25 % lower mean is
//! **not** reached: the round trip's error is dominated by what the least-squares solve
//! cannot fit on the other mesh, which no variant of the matching changed by more than 7 %
//! (`explore`, ignored, runs any variant: `EXPLORE="refine,two_way,combine,radius,max"`).

mod common;

use morphkit::io::{read_mesh, read_shape_set};
use morphkit::mesh::{Point, TriMesh};
use morphkit::transfer::{
    correspond, correspondence_quality, cycle_consistency, CorrespondenceOptions, GradientCombine,
    Markers, RefineOptions, TransferOptions,
};
use std::path::PathBuf;
use std::time::Instant;

struct Pair {
    name: &'static str,
    /// The mesh the correspondence is computed on.
    a_corr: TriMesh,
    /// The mesh the frames are measured from (same connectivity as `a_corr`).
    a_ref: TriMesh,
    frames: Vec<Vec<Point>>,
    b: TriMesh,
    markers: Markers,
}

#[derive(Debug)]
struct Measured {
    cycle_mean: f64,
    cycle_max: f64,
    folds: usize,
    flipped: usize,
    correspond_s: f64,
    normal_pass: f64,
    coverage: f64,
}

fn measure(p: &Pair, copts: &CorrespondenceOptions, combine: GradientCombine) -> Measured {
    measure_with(
        p,
        copts,
        TransferOptions {
            combine,
            ..Default::default()
        },
    )
}

fn measure_with(p: &Pair, copts: &CorrespondenceOptions, topts: TransferOptions) -> Measured {
    let t0 = Instant::now();
    let fwd = correspond(&p.a_corr, &p.b, &p.markers, copts).unwrap();
    let correspond_s = t0.elapsed().as_secs_f64();
    let bwd = correspond(&p.b, &p.a_corr, &p.markers.reversed(), copts).unwrap();
    let c = cycle_consistency(
        &p.a_ref,
        &p.frames,
        &p.b,
        &fwd.correspondence,
        &bwd.correspondence,
        &topts,
    )
    .unwrap();
    let q = correspondence_quality(&fwd.correspondence);
    let m = Measured {
        cycle_mean: c.mean,
        cycle_max: c.max,
        folds: c.forward_sharp_folds.iter().sum(),
        flipped: c.forward_flipped.iter().sum(),
        correspond_s,
        normal_pass: q.normal_pass_fraction,
        coverage: q.source_coverage,
    };
    eprintln!("{}: {m:?}", p.name);
    m
}

fn baseline() -> (CorrespondenceOptions, GradientCombine) {
    (
        CorrespondenceOptions {
            refine: None,
            two_way: false,
            ..Default::default()
        },
        GradientCombine::Mean,
    )
}

fn check(p: &Pair, time_budget: Option<f64>) {
    let (bo, bc) = baseline();
    let base = measure(p, &bo, bc);
    let new = measure(
        p,
        &CorrespondenceOptions::default(),
        GradientCombine::default(),
    );
    let refined_opts = CorrespondenceOptions {
        refine: Some(RefineOptions::default()),
        ..Default::default()
    };
    let refined = measure(p, &refined_opts, GradientCombine::default());
    eprintln!(
        "{}: cycle mean {:.5} → {:.5} → {:.5} (refined {:.1} % lower), max {:.4} → {:.4} → {:.4}, \
         sharp folds {} → {} → {}, flipped {} → {} → {}, correspondence {:.3} s → {:.3} s → {:.3} s",
        p.name,
        base.cycle_mean,
        new.cycle_mean,
        refined.cycle_mean,
        100.0 * (1.0 - refined.cycle_mean / base.cycle_mean),
        base.cycle_max,
        new.cycle_max,
        refined.cycle_max,
        base.folds,
        new.folds,
        refined.folds,
        base.flipped,
        new.flipped,
        refined.flipped,
        base.correspond_s,
        new.correspond_s,
        refined.correspond_s
    );
    assert!(
        new.cycle_mean <= 1.01 * base.cycle_mean,
        "{}: default mean cycle error {:.5} is worse than the baseline {:.5}",
        p.name,
        new.cycle_mean,
        base.cycle_mean
    );
    assert!(
        new.coverage == 1.0 && base.coverage < 1.0,
        "{new:?} {base:?}"
    );
    assert!(new.normal_pass >= 0.99, "{new:?}");
    assert!(
        refined.cycle_mean < new.cycle_mean && refined.cycle_max < new.cycle_max,
        "{}: refinement does not lower the cycle error ({refined:?} vs {new:?})",
        p.name
    );
    assert!(refined.folds <= base.folds, "{refined:?} vs {base:?}");
    if let Some(t) = time_budget {
        if !cfg!(debug_assertions) {
            assert!(
                refined.correspond_s <= t,
                "{}: refined correspondence took {:.2} s (budget {t} s)",
                p.name,
                refined.correspond_s
            );
        }
    }
}

#[test]
fn horse_camel_cycle_consistency_improves() {
    let (Some(h), Some(c), Some(mk)) = (
        common::data_file("sumner-horse-camel/horse-reference.obj.gz"),
        common::data_file("sumner-horse-camel/camel-reference.obj.gz"),
        common::data_file("sumner-horse-camel/markers-horse-camel.json"),
    ) else {
        return common::skip("horse_camel_cycle_consistency_improves");
    };
    let horse = read_mesh(&h).unwrap();
    let dir = common::data_dir().unwrap().join("sumner-horse-camel");
    let paths: Vec<PathBuf> = (1..=10)
        .map(|i| dir.join(format!("horse-{i:02}.obj.gz")))
        .collect();
    let poses = read_shape_set(&paths).unwrap();
    let p = Pair {
        name: "horse↔camel",
        a_corr: horse.clone(),
        a_ref: horse,
        frames: poses.all_positions().to_vec(),
        b: read_mesh(&c).unwrap(),
        markers: Markers::read(&mk).unwrap(),
    };
    check(&p, Some(2.0));
}

#[test]
fn cat_dog_cycle_consistency_improves() {
    let (Some(cat), Some(dog), Some(mk)) = (
        common::data_file("lowpoly-cat-dog/cat-reference.obj"),
        common::data_file("lowpoly-cat-dog/dog-reference.obj"),
        common::data_file("lowpoly-cat-dog/markers-cat-dog.json"),
    ) else {
        return common::skip("cat_dog_cycle_consistency_improves");
    };
    let dir = common::data_dir().unwrap().join("lowpoly-cat-dog/cat-run");
    let paths: Vec<PathBuf> = (1..=36)
        .map(|i| dir.join(format!("cat-run-{i:02}.obj.gz")))
        .collect();
    let run = read_shape_set(&paths).unwrap();
    let p = Pair {
        name: "cat↔dog",
        a_corr: read_mesh(&cat).unwrap(),
        // The run frames are at 0.1× the reference scale: frame 0 is the gradients' reference.
        a_ref: run.mesh(0),
        frames: run.all_positions().to_vec(),
        b: read_mesh(&dog).unwrap(),
        markers: Markers::read(&mk).unwrap(),
    };
    check(&p, None);
}

/// Measures any variants on both pairs, for tuning: `EXPLORE="r,w,c,radius,max[,wc/wc/…[,wi[,a]]];…"`
/// with r = 1 to refine, w = 1 for two-way, c = m(ean), n(earest) or i(nverse distance), the
/// radius factor, the most matches, the closest-point weights, the identity weight, and `a`
/// for area-weighted solves.
#[test]
#[ignore = "a tuning tool, not a check: it prints measurements of the EXPLORE variants and asserts nothing; run it with --ignored"]
fn explore() {
    let (Some(h), Some(c), Some(mk)) = (
        common::data_file("sumner-horse-camel/horse-reference.obj.gz"),
        common::data_file("sumner-horse-camel/camel-reference.obj.gz"),
        common::data_file("sumner-horse-camel/markers-horse-camel.json"),
    ) else {
        return common::skip("explore");
    };
    let horse = read_mesh(&h).unwrap();
    let dir = common::data_dir().unwrap().join("sumner-horse-camel");
    let paths: Vec<PathBuf> = (1..=10)
        .map(|i| dir.join(format!("horse-{i:02}.obj.gz")))
        .collect();
    let poses = read_shape_set(&paths).unwrap();
    let hp = Pair {
        name: "horse",
        a_corr: horse.clone(),
        a_ref: horse,
        frames: poses.all_positions().to_vec(),
        b: read_mesh(&c).unwrap(),
        markers: Markers::read(&mk).unwrap(),
    };
    let spec = std::env::var("EXPLORE").unwrap_or_default();
    for item in spec.split(';').filter(|s| !s.is_empty()) {
        let f: Vec<&str> = item.split(',').collect();
        let mut refine = (f[0] == "1").then(RefineOptions::default);
        if let Some(r) = refine.as_mut() {
            if let Some(w) = f.get(5) {
                r.closest_weights = w.split('/').map(|x| x.parse().unwrap()).collect();
            }
            if let Some(w) = f.get(6) {
                r.identity = w.parse().unwrap();
            }
        }
        let o = CorrespondenceOptions {
            refine,
            two_way: f[1] == "1",
            radius_factor: f[3].parse().unwrap(),
            max_matches: f[4].parse().unwrap(),
            ..Default::default()
        };
        let combine = match f[2] {
            "m" => GradientCombine::Mean,
            "n" => GradientCombine::Nearest,
            _ => GradientCombine::InverseDistance,
        };
        let mut t = TransferOptions {
            combine,
            ..Default::default()
        };
        if f.get(7) == Some(&"a") {
            t.solver.weighting = morphkit::transfer::TriangleWeighting::Area;
        }
        eprintln!("== {item}");
        measure_with(&hp, &o, t);
    }
}

/// Issue 9, `--combine`: a self-transfer with identity markers is exact with the default
/// (inverse-distance weights: both warps are the same, so every triangle's own match is at
/// distance 0), where `mean` blurs it (about 4 % of the diagonal at worst on the cat run).
#[test]
fn cat_self_transfer_is_exact_with_the_default_combine() {
    let Some(cat) = common::data_file("lowpoly-cat-dog/cat-reference.obj") else {
        return common::skip("cat_self_transfer_is_exact_with_the_default_combine");
    };
    let Some(mk) = common::data_file("lowpoly-cat-dog/markers-cat-dog.json") else {
        return common::skip("cat_self_transfer_is_exact_with_the_default_combine");
    };
    let cat = read_mesh(&cat).unwrap();
    let markers = Markers::read(&mk).unwrap();
    let selfm = Markers::new(markers.pairs.iter().map(|p| [p[0], p[0]]).collect());
    let dir = common::data_dir().unwrap().join("lowpoly-cat-dog/cat-run");
    let paths: Vec<PathBuf> = (1..=36)
        .map(|i| dir.join(format!("cat-run-{i:02}.obj.gz")))
        .collect();
    let run = read_shape_set(&paths).unwrap();
    let src = run.mesh(0);
    let c = correspond(&cat, &cat, &selfm, &CorrespondenceOptions::default())
        .unwrap()
        .correspondence;
    let worst = |combine| {
        let tr = morphkit::transfer::AnimationTransfer::new(
            &src,
            &src,
            &c,
            &TransferOptions {
                combine,
                ..Default::default()
            },
        )
        .unwrap();
        let d = src.bbox_diagonal();
        let mut w = 0.0f64;
        for f in run.all_positions() {
            let x = tr.transfer_frame(f).unwrap();
            for (a, b) in x.iter().zip(f) {
                let e = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
                w = w.max(e / d);
            }
        }
        w
    };
    let (idw, mean) = (
        worst(GradientCombine::default()),
        worst(GradientCombine::Mean),
    );
    eprintln!("cat self-transfer worst error: inverse distance {idw:.2e}, mean {mean:.2e}");
    assert!(idw < 1e-9, "{idw}");
    assert!(mean > 0.01, "mean should blur: {mean}");
}
