use super::*;
use crate::geom::max_distance;
use crate::mesh::generate::{bar, bend, rotate};
use crate::springs::{linear_blend, BlendOptions};
use crate::ShapeSet;

/// A bar along x (length 2) with three targets: its far half bends 90° about z, its far half
/// bends 90° about y, its tip turns 60° about x. Each pair overlaps at the far end.
fn rig() -> ShapeSet {
    let m = bar(2.0, 0.2, 2, 24);
    let p = m.positions.clone();
    let about_y: Vec<Point> = bend(
        &p.iter().map(|q| [q[0], q[2], q[1]]).collect::<Vec<_>>(),
        1.0,
        1.0,
        std::f64::consts::FRAC_PI_2,
    )
    .iter()
    .map(|q| [q[0], q[2], q[1]])
    .collect();
    let twist: Vec<Point> = p
        .iter()
        .map(|&q| {
            let s = ((q[0] - 1.2) / 0.8).clamp(0.0, 1.0);
            rotate(&[q], [0.0; 3], [1.0, 0.0, 0.0], 60f64.to_radians() * s)[0]
        })
        .collect();
    let targets = vec![
        ("rest".to_string(), p.clone()),
        (
            "bend_z".to_string(),
            bend(&p, 1.0, 1.0, std::f64::consts::FRAC_PI_2),
        ),
        ("bend_y".to_string(), about_y),
        ("twist".to_string(), twist),
    ];
    ShapeSet::new(m, targets).unwrap()
}

fn solve(s: &mut PhysicalBlend, w: &[f64]) -> Vec<Point> {
    s.solve(&Weights::Delta(w.to_vec())).unwrap().positions
}

#[test]
fn a_bake_is_the_solve_at_its_samples_and_the_targets_at_one() {
    let shapes = rig();
    let mut s = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    let opts = BakeOptions {
        inbetweens: 3,
        inbetween_tolerance: 0.0,
        ..BakeOptions::default()
    };
    let b = bake(&mut s, &opts, 2).unwrap();
    assert_eq!(b.targets.len(), 3);
    assert!(b
        .targets
        .iter()
        .all(|t| t.weights == [0.25, 0.5, 0.75, 1.0]));
    let diag = shapes.base().bbox_diagonal();
    // At one-hot weights: the target's own numbers.
    for t in 0..3 {
        let mut w = vec![0.0; 3];
        w[t] = 1.0;
        let e = b.evaluate(&w);
        assert!(max_distance(&e, shapes.positions(t + 1)) <= 1e-12 * diag);
        for a in [0.25, 0.5, 0.75] {
            w[t] = a;
            let e = max_distance(&b.evaluate(&w), &solve(&mut s, &w));
            assert!(e <= 1e-12 * diag, "target {t} at {a}: {e}");
        }
    }
    // Every pair interacts here, and at (½, ½) and (1, 1) the bake is the pair's equilibrium.
    assert_eq!(b.combinations.len(), 3);
    for c in &b.combinations {
        assert_eq!(c.shape.weights, [1.0, 4.0]);
        for (x, level) in [(0.5, 1.0), (1.0, 4.0)] {
            let mut w = vec![0.0; 3];
            w[c.targets.0] = x;
            w[c.targets.1] = x;
            assert_eq!(b.combination_weight(c, &w), level);
            let e = max_distance(&b.evaluate(&w), &solve(&mut s, &w));
            assert!(e <= 1e-12 * diag, "{:?} at {x}: {e}", c.targets);
        }
    }
    // The same bake whatever the thread count.
    let mut s1 = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    assert_eq!(bake(&mut s1, &opts, 1).unwrap(), b);
}

#[test]
fn combination_weights_are_the_product_for_two_and_damped_for_more() {
    let c = Combination {
        targets: (0, 1),
        shape: BakedTarget {
            weights: vec![1.0],
            deltas: Vec::new(),
        },
    };
    let mut b = BakedRig {
        base: Vec::new(),
        targets: Vec::new(),
        combinations: Vec::new(),
        damping: 1.0,
        solves: 0,
    };
    assert_eq!(b.combination_weight(&c, &[0.0, 0.7, 0.3]), 0.0);
    assert_eq!(b.combination_weight(&c, &[-0.2, 0.7, 0.0]), 0.0);
    assert!((b.combination_weight(&c, &[0.5, 0.25, 0.0]) - 0.5).abs() < 1e-15);
    // A third target of equal weight: 2/3 of the product at p = 1, 4/9 at p = 2.
    assert!((b.combination_weight(&c, &[0.5, 0.5, 0.5]) - 2.0 / 3.0).abs() < 1e-15);
    b.damping = 2.0;
    assert!((b.combination_weight(&c, &[0.5, 0.5, 0.5]) - 4.0 / 9.0).abs() < 1e-15);
    b.damping = 0.0;
    assert!((b.combination_weight(&c, &[0.5, 0.5, 0.5]) - 1.0).abs() < 1e-15);
}

#[test]
fn between_samples_and_in_combinations_the_bake_is_closer_than_the_linear_blend() {
    let shapes = rig();
    let mut s = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    let b = bake(&mut s, &BakeOptions::default(), 2).unwrap();
    let states: Vec<Vec<f64>> = vec![
        vec![0.3, 0.0, 0.0],
        vec![0.0, 0.55, 0.0],
        vec![0.0, 0.0, 0.9],
        vec![0.7, 0.4, 0.0],
        vec![0.0, 0.6, 0.8],
        vec![0.6, 0.5, 0.7],
        vec![0.9, 0.9, 0.4],
    ];
    for w in &states {
        let solved = solve(&mut s, w);
        let baked = max_distance(&b.evaluate(w), &solved);
        let linear = max_distance(
            &linear_blend(&shapes, &Weights::Delta(w.clone())).unwrap(),
            &solved,
        );
        assert!(baked < linear, "{w:?}: baked {baked}, linear {linear}");
    }
}

#[test]
fn bad_options_are_refused() {
    let shapes = rig();
    let mut s = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    for o in [
        BakeOptions {
            inbetweens: 0,
            ..BakeOptions::default()
        },
        BakeOptions {
            damping: f64::NAN,
            ..BakeOptions::default()
        },
        BakeOptions {
            pair_samples: vec![1.0, 0.5],
            ..BakeOptions::default()
        },
    ] {
        assert!(matches!(bake(&mut s, &o, 1), Err(BakeError::Options(_))));
    }
}

#[test]
fn shape_weights_interpolate_between_in_betweens_and_extend_the_end_segments() {
    let t = |weights: Vec<f64>| BakedTarget {
        deltas: vec![vec![[0.0; 3]]; weights.len()],
        weights,
    };
    let b = BakedRig {
        base: vec![[0.0; 3]],
        targets: vec![t(vec![0.25, 0.5, 1.0]), t(vec![1.0])],
        combinations: vec![Combination {
            targets: (0, 1),
            shape: t(vec![1.0, 4.0]),
        }],
        damping: 0.0,
        solves: 0,
    };
    let close = |a: Vec<f64>, b: &[f64]| {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-14, "{a:?} vs {b:?}");
        }
    };
    // Target 0 at 0.375: halfway between its in-betweens at ¼ and ½; target 1 off.
    close(
        b.shape_weights(&[0.375, 0.0]),
        &[0.5, 0.5, 0.0, 0.0, 0.0, 0.0],
    );
    // Below the first in-between: a share of it; beyond 1: the last segment extended (the
    // combination at 4 · 0.1 · 1.2 = 0.48 of its first level).
    close(
        b.shape_weights(&[0.1, 1.2]),
        &[0.4, 0.0, 0.0, 1.2, 0.48, 0.0],
    );
    close(
        b.shape_weights(&[1.25, 0.0]),
        &[0.0, -0.5, 1.5, 0.0, 0.0, 0.0],
    );
    // Both on: the combination at 4 · 0.5 · 0.75 = 1.5, between its levels 1 and 4.
    close(
        b.shape_weights(&[0.5, 0.75]),
        &[0.0, 1.0, 0.0, 0.75, 5.0 / 6.0, 1.0 / 6.0],
    );
    assert_eq!(b.shapes().count(), b.num_shapes());
}

#[test]
fn in_betweens_are_added_where_the_tolerance_needs_them_within_the_budget() {
    let shapes = rig();
    let diag = shapes.base().bbox_diagonal();
    let mut s = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    let regular = BakeOptions {
        inbetweens: 3,
        inbetween_tolerance: 0.0,
        max_pairs: 0,
        ..BakeOptions::default()
    };
    let tol = 2e-3;
    let refined = BakeOptions {
        inbetween_tolerance: tol,
        ..regular.clone()
    };
    let (r, f) = (
        bake(&mut s, &regular, 2).unwrap(),
        bake(&mut s, &refined, 2).unwrap(),
    );
    let added: usize = f.targets.iter().map(|t| t.weights.len() - 4).sum();
    assert!(added > 0, "a 90° bend at the quarters needs more");
    assert!(f.solves > r.solves);
    // Each added weight is a dyadic midpoint of the quarters, and its shape the solve there.
    let mut worst = [0.0f64; 2];
    for t in 0..3 {
        for (&a, d) in f.targets[t].weights.iter().zip(&f.targets[t].deltas) {
            assert_eq!((a * 32.0).fract(), 0.0, "{a}");
            let mut w = vec![0.0; 3];
            w[t] = a;
            let solved = solve(&mut s, &w);
            let baked: Vec<Point> = r
                .base
                .iter()
                .zip(d)
                .map(|(b, x)| [b[0] + x[0], b[1] + x[1], b[2] + x[2]])
                .collect();
            assert!(max_distance(&baked, &solved) <= 1e-12 * diag);
        }
        // Off the samples, the refined bake is closer to the solve than the regular one.
        for k in 1..20 {
            let mut w = vec![0.0; 3];
            w[t] = k as f64 / 20.0;
            let solved = solve(&mut s, &w);
            for (i, b) in [&r, &f].iter().enumerate() {
                worst[i] = worst[i].max(max_distance(&b.evaluate(&w), &solved) / diag);
            }
        }
    }
    assert!(worst[1] < worst[0] && worst[1] < 2.0 * tol, "{worst:?}");
    // The budget holds, the farthest segments first, and the result does not depend on threads.
    let two = BakeOptions {
        max_refined: 2,
        ..refined.clone()
    };
    let b2 = bake(&mut s, &two, 1).unwrap();
    assert_eq!(b2.num_shapes(), r.num_shapes() + 2);
    assert_eq!(bake(&mut s, &refined, 1).unwrap(), f);
}
