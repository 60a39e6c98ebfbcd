//! Reference factors (`BlendOptions::reference_factor_bytes`): frames of a bent tube, on its
//! surface alone and with a lattice interior, precondition with a turned factor from a
//! nearby equilibrium and factorize nothing themselves, yet reach the equilibria of the
//! frames that factorize their own Hessians, keep exact endpoints, and give the same bytes
//! whatever the thread count or frame order; on the horse, whose probe may fail, the frames
//! reach the same equilibria either way.

mod common;

use common::max_dist;
use morphkit::mesh::{bbox_diagonal, generate, Point, ShapeSet};
use morphkit::springs::interior::VolumeResult;
use morphkit::springs::{
    AnchorOptions, BlendOptions, BlendResult, FrameStats, InteriorMode, InteriorOptions,
    PhysicalBlend, VolumetricBlend, Weights,
};

fn bent_tube(around: usize, along: usize) -> ShapeSet {
    common::bent_tube(around, along, 90.0)
}

fn options(references: bool) -> BlendOptions {
    BlendOptions {
        reference_factor_bytes: if references { 1 << 30 } else { 0 },
        ..Default::default()
    }
}

fn alphas(steps: usize) -> Vec<Weights> {
    (0..steps)
        .map(|k| Weights::Alpha(k as f64 / (steps - 1) as f64))
        .collect()
}

/// Frames with and without references: the same equilibria, exact endpoints, and the
/// interior frames on references without a factorization of their own.
fn check_against_factor(
    s: &ShapeSet,
    with: Vec<(Vec<Point>, FrameStats)>,
    without: Vec<(Vec<Point>, FrameStats)>,
) {
    let d = bbox_diagonal(s.positions(0));
    let n = with.len();
    let mut on_reference = 0;
    for (k, ((pa, a), (pb, b))) in with.iter().zip(&without).enumerate() {
        assert!(a.converged && b.converged, "frame {k}: {a:?}");
        // Both reach the gradient tolerance: the same shape, well inside its diagonal.
        let gap = max_dist(pa, pb);
        assert!(gap <= 1e-5 * d, "frame {k}: {gap:e} apart");
        if a.reference_factor && a.factorizations == 0 {
            on_reference += 1;
        }
        assert!(!b.reference_factor, "frame {k} of the reference-free blend");
    }
    for (k, shape) in [(0, 0), (n - 1, 1)] {
        assert!(max_dist(&with[k].0, s.positions(shape)) <= 1e-6 * d);
    }
    // Every frame strictly between the ends converged on its reference alone.
    assert_eq!(on_reference, n - 2, "frames on a reference");
}

#[test]
fn surface_frames_reach_the_factors_equilibria_on_references() {
    let s = bent_tube(16, 40);
    let w = alphas(10);
    let mut on = PhysicalBlend::new(&s, &options(true)).unwrap();
    let mut off = PhysicalBlend::new(&s, &options(false)).unwrap();
    assert!(on.summary().reference_targets == 1 && off.summary().reference_targets == 0);
    let split = |r: Result<BlendResult, _>| {
        let r = r.unwrap();
        (r.positions, r.stats)
    };
    let a: Vec<_> = on.solve_many(&w, 2).into_iter().map(split).collect();
    let b: Vec<_> = off.solve_many(&w, 2).into_iter().map(split).collect();
    let factorizations =
        |r: &[(Vec<Point>, FrameStats)]| r.iter().map(|r| r.1.factorizations).sum::<usize>();
    assert!(factorizations(&b) >= 8, "{}", factorizations(&b));
    check_against_factor(&s, a, b);
}

#[test]
fn volumetric_frames_reach_the_factors_equilibria_on_references() {
    let s = bent_tube(14, 32);
    let interior = InteriorOptions {
        mode: InteriorMode::Lattice,
        ..Default::default()
    };
    let w = alphas(8);
    let anchor = AnchorOptions::default();
    let mut on = VolumetricBlend::new(&s, &options(true), &interior, &anchor).unwrap();
    let mut off = VolumetricBlend::new(&s, &options(false), &interior, &anchor).unwrap();
    assert!(on.report().interior_vertices > 0);
    let split = |r: Result<VolumeResult, _>| {
        let r = r.unwrap();
        (r.positions, r.stats)
    };
    let a: Vec<_> = on.solve_many(&w, 2).into_iter().map(split).collect();
    let b: Vec<_> = off.solve_many(&w, 2).into_iter().map(split).collect();
    check_against_factor(&s, a, b);
}

#[test]
fn reference_frames_are_the_same_bytes_in_any_order_and_thread_count() {
    let s = bent_tube(16, 40);
    let w = alphas(9);
    let forward: Vec<_> = PhysicalBlend::new(&s, &options(true))
        .unwrap()
        .solve_many(&w, 1)
        .into_iter()
        .map(|r| r.unwrap().positions)
        .collect();
    let mut reversed_w = w.clone();
    reversed_w.reverse();
    let mut reversed: Vec<_> = PhysicalBlend::new(&s, &options(true))
        .unwrap()
        .solve_many(&reversed_w, 2)
        .into_iter()
        .map(|r| r.unwrap().positions)
        .collect();
    reversed.reverse();
    assert_eq!(forward, reversed);
    // One frame alone, on a fresh blend: the references it needs are built for it alone.
    let mut single = PhysicalBlend::new(&s, &options(true)).unwrap();
    let r = single.solve(&w[3]).unwrap();
    assert!(r.stats.reference_factor);
    assert_eq!(r.positions, forward[3]);
}

#[test]
fn horse_frames_reach_the_same_equilibria_with_references_on_or_off() {
    let Some(base) = common::data_file("sumner-horse-camel/horse-reference.obj.gz") else {
        return common::skip("horse_frames_reach_the_same_equilibria_with_references_on_or_off");
    };
    let pose = common::data_file("sumner-horse-camel/horse-05.obj.gz").unwrap();
    let s = morphkit::io::read_shape_set(&[base, pose]).unwrap();
    let d = bbox_diagonal(s.positions(0));
    let mut on = PhysicalBlend::new(&s, &options(true)).unwrap();
    let mut off = PhysicalBlend::new(&s, &options(false)).unwrap();
    for a in [0.3, 0.6] {
        let r = on.solve(&Weights::Alpha(a)).unwrap();
        let q = off.solve(&Weights::Alpha(a)).unwrap();
        assert!(
            r.stats.converged && q.stats.converged,
            "α = {a}: {:?}",
            r.stats
        );
        let gap = max_dist(&r.positions, &q.positions);
        assert!(gap <= 1e-5 * d, "α = {a}: {gap:e} apart");
    }
}

#[test]
fn targets_past_the_memory_budget_factorize_their_own_frames() {
    let m = generate::tube(0.5, 4.0, 12, 30, true);
    let up = generate::bend(&m.positions, 0.0, 4.0, 90f64.to_radians());
    let down = generate::bend(&m.positions, 0.0, 4.0, -60f64.to_radians());
    let s = ShapeSet::new(
        m.clone(),
        vec![
            ("straight".into(), m.positions.clone()),
            ("up".into(), up),
            ("down".into(), down),
        ],
    )
    .unwrap();
    let all = PhysicalBlend::new(&s, &options(true)).unwrap();
    assert_eq!(all.summary().reference_targets, 2);
    // Five single-precision factors: the base's and four of the first target.
    let budget = 5 * 4 * all.factor_nnz() as u64;
    let mut one = PhysicalBlend::new(
        &s,
        &BlendOptions {
            reference_factor_bytes: budget,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(one.summary().reference_targets, 1);
    let first = one.solve(&Weights::Convex(vec![0.6, 0.4, 0.0])).unwrap();
    let second = one.solve(&Weights::Convex(vec![0.6, 0.0, 0.4])).unwrap();
    assert!(first.stats.converged && second.stats.converged);
    assert!(first.stats.reference_factor, "{:?}", first.stats);
    assert!(!second.stats.reference_factor && second.stats.factorizations > 0);
}
