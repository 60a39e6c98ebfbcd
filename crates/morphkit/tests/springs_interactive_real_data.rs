//! Issue 38: the interactive mode on the real rigs, the horse with three of its poses and the
//! ICT head with jawOpen and a smile (a subset, so that the preparation's canonical solves fit
//! the suite's time; the bench measures the 10-target rigs). Checked: one-hot weights give the
//! full solve's bits with a zero estimate; a single target between its snapshots is within its
//! error estimate of the full solve; over all states the median error is under half the
//! predictor's; no state folds more triangles than the full solve or the linear blend; a
//! saved preparation gives the same bits.
//!
//! Not asserted, because it does not hold yet (printed, and in docs/performance.md): that a
//! *combination* is within its estimate. On the horse, poses 01 and 09 at (0.7, 0.2) land
//! 1.5 % of the diagonal from the full solve, farther than the predictor (1.1 %), against an
//! estimate of 0.74 %; the other combinations are 0.14–0.56 % off, within their estimates.
//! Skipped when MORPHKIT_DATA is unset, failing when it is set but a file is missing.

mod common;

use common::{assert_same_frame, max_dist};
use morphkit::io::read_shape_set;
use morphkit::mesh::{bbox_diagonal, ShapeSet, Topology};
use morphkit::springs::{fold_metrics, BlendOptions, PhysicalBlend, Weights};

fn check(name: &str, s: &ShapeSet, states: &[Vec<f64>]) {
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let mut blend = PhysicalBlend::new(s, &BlendOptions::default()).unwrap();
    let space = blend.prepare_interactive(2);
    let k = s.len() - 1;
    assert_eq!(space.len() + space.unconverged, 7 * k + k * (k - 1));
    assert_eq!(space.unconverged, 0, "{name}");
    let diag = bbox_diagonal(s.positions(0));
    for t in 0..k {
        let mut w = vec![0.0; k];
        w[t] = 1.0;
        let w = Weights::Delta(w);
        let fast = blend.solve_interactive(&w, 0).unwrap();
        assert_eq!(fast.stats.error_estimate, Some(0.0));
        assert_same_frame(&fast.positions, &blend.solve(&w).unwrap().positions, name);
    }
    let mut failures = Vec::new();
    let (mut errors, mut predictors) = (Vec::new(), Vec::new());
    for w in states {
        let weights = Weights::Delta(w.clone());
        let full = blend.solve(&weights).unwrap();
        assert!(full.stats.converged, "{name} {w:?}");
        let fast = blend.solve_interactive(&weights, 0).unwrap();
        assert!(fast.positions.iter().flatten().all(|v| v.is_finite()));
        let error = max_dist(&fast.positions, &full.positions) / diag;
        let predictor = max_dist(&blend.predict(&weights).unwrap(), &full.positions) / diag;
        let estimate = fast.stats.error_estimate.unwrap();
        let q = fold_metrics(s, &topo, &weights, &fast.positions).unwrap();
        let qf = fold_metrics(s, &topo, &weights, &full.positions).unwrap();
        eprintln!(
            "{name} {w:?}: error {error:.2e} (predictor {predictor:.2e}, estimate {estimate:.2e}), {} iterations, folds {} (full {}, linear {}), creases {} ({}, {})",
            fast.stats.newton_iterations, q.folds, qf.folds, q.folds_linear, q.creases, qf.creases, q.creases_linear
        );
        errors.push(error);
        predictors.push(predictor);
        let single = w.iter().filter(|&&x| x != 0.0).count() == 1;
        if (single && error > estimate) || q.folds > qf.folds.max(q.folds_linear) {
            failures.push(format!("{w:?}: error {error:.2e}, predictor {predictor:.2e}, estimate {estimate:.2e}, {q:?}"));
        }
    }
    assert!(failures.is_empty(), "{name}: {failures:#?}");
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (e, p) = (median(&mut errors), median(&mut predictors));
    assert!(
        e <= 0.5 * p,
        "{name}: median error {e:.2e}, predictor {p:.2e}"
    );
    // A saved preparation, loaded into a new blend, gives the same bits.
    let bytes = blend.interactive_bytes().unwrap();
    let mut reopened = PhysicalBlend::new(s, &BlendOptions::default()).unwrap();
    reopened.load_interactive(&bytes).unwrap();
    let w = Weights::Delta(states[0].clone());
    assert_same_frame(
        &blend.solve_interactive(&w, 0).unwrap().positions,
        &reopened.solve_interactive(&w, 0).unwrap().positions,
        "loaded",
    );
}

#[test]
fn horse_three_poses() {
    let Some(paths): Option<Vec<_>> = ["horse-reference", "horse-01", "horse-05", "horse-09"]
        .iter()
        .map(|n| common::data_file(&format!("sumner-horse-camel/{n}.obj.gz")))
        .collect()
    else {
        return common::skip("horse_three_poses");
    };
    let s = read_shape_set(&paths).unwrap();
    let states = [
        vec![0.35, 0.4, 0.0],
        vec![0.0, 0.6, 0.3],
        vec![0.7, 0.0, 0.2],
        vec![0.45, 0.0, 0.0],
        vec![0.0, 0.0, 0.8],
    ];
    check("horse", &s, &states);
}

#[test]
fn ict_jaw_open_and_smile() {
    let Some(paths): Option<Vec<_>> = ["generic_neutral_mesh", "jawOpen", "mouthSmile_L"]
        .iter()
        .map(|n| common::data_file(&format!("ict-facekit/{n}.obj.gz")))
        .collect()
    else {
        return common::skip("ict_jaw_open_and_smile");
    };
    let s = read_shape_set(&paths).unwrap();
    let states = [
        vec![0.6, 0.7],
        vec![0.3, 0.9],
        vec![0.45, 0.0],
        vec![0.0, 0.6],
    ];
    check("ict", &s, &states);
}
