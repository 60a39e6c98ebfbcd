//! Physical blendshapes on generated meshes: reproduction of the inputs, convergence, the
//! rotation test, and bad input.

use morphkit::mesh::{bbox_diagonal, generate, ShapeSet, Topology, TriMesh};
use morphkit::springs::{
    blend, blend_metrics, linear_blend, BlendError, BlendOptions, FillOrdering, FixedVertices,
    LinearSolver, PhysicalBlend, Weights,
};

fn two(m: &TriMesh, other: Vec<[f64; 3]>) -> ShapeSet {
    ShapeSet::new(
        m.clone(),
        vec![
            ("base".into(), m.positions.clone()),
            ("target".into(), other),
        ],
    )
    .unwrap()
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// A closed bar bent by 120° over its second half.
fn bent_bar() -> ShapeSet {
    let m = generate::bar(4.0, 0.6, 2, 24);
    let b = generate::bend(&m.positions, 2.0, 2.0, 120f64.to_radians());
    two(&m, b)
}

#[test]
fn endpoints_reproduce_base_and_target() {
    for fixed in [FixedVertices::Auto, FixedVertices::None] {
        let s = bent_bar();
        let d = bbox_diagonal(s.positions(0));
        let opts = BlendOptions {
            fixed: fixed.clone(),
            ..Default::default()
        };
        let mut solver = PhysicalBlend::new(&s, &opts).unwrap();
        let r0 = solver.solve(&Weights::Alpha(0.0)).unwrap();
        assert!(
            max_dist(&r0.positions, s.positions(0)) <= 1e-6 * d,
            "{fixed:?}: α = 0 error {}",
            max_dist(&r0.positions, s.positions(0))
        );
        let r1 = solver.solve(&Weights::Alpha(1.0)).unwrap();
        assert!(r1.stats.converged);
        let err = max_dist(&r1.positions, s.positions(1));
        assert!(err <= 1e-6 * d, "{fixed:?}: α = 1 error {err} (diag {d})");
    }
}

#[test]
fn every_frame_converges_and_beats_the_linear_blend() {
    let s = bent_bar();
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    let frames = 12;
    for f in 0..frames {
        let a = f as f64 / (frames - 1) as f64;
        let r = solver.solve(&Weights::Alpha(a)).unwrap();
        assert!(r.stats.converged, "frame {f}");
        assert!(r.stats.gradient_norm <= r.stats.gradient_tolerance);
        assert!(r.positions.iter().flatten().all(|v| v.is_finite()));
        if f == frames / 2 {
            let lin = linear_blend(&s, &Weights::Alpha(a)).unwrap();
            let mp = blend_metrics(&s, &topo, &Weights::Alpha(a), &r.positions).unwrap();
            let ml = blend_metrics(&s, &topo, &Weights::Alpha(a), &lin).unwrap();
            assert!(
                mp.edge_length_rms * 3.0 < ml.edge_length_rms,
                "physical {mp:?} vs linear {ml:?}"
            );
            let vp = mp.volume_ratio.unwrap();
            let vl = ml.volume_ratio.unwrap();
            assert!(
                (vp - 1.0).abs() < (vl - 1.0).abs(),
                "volume ratio physical {vp}, linear {vl}"
            );
        }
    }
}

#[test]
fn rotated_copy_blends_to_a_rotation_and_linear_shrinks() {
    let m = generate::uv_sphere(1.0, 10, 16);
    // Make it non-symmetric so that a rotation is observable: stretch along x.
    let m = m.with_positions(
        m.positions
            .iter()
            .map(|p| [2.0 * p[0], p[1], 0.5 * p[2]])
            .collect(),
    );
    let rotated = generate::rotate(&m.positions, [0.0; 3], [0.0, 0.0, 1.0], 90f64.to_radians());
    let s = two(&m, rotated);
    let d = bbox_diagonal(&m.positions);
    let r = blend(
        &s,
        &Weights::Alpha(0.5),
        &BlendOptions {
            fixed: FixedVertices::None,
            ..Default::default()
        },
    )
    .unwrap();
    let expect = generate::rotate(&m.positions, [0.0; 3], [0.0, 0.0, 1.0], 45f64.to_radians());
    // Up to a rigid transform: align, then compare.
    let fit = morphkit::geom::kabsch(&r.positions, &expect, &[]);
    let aligned: Vec<[f64; 3]> = r.positions.iter().map(|p| fit.apply(*p)).collect();
    assert!(max_dist(&aligned, &expect) <= 1e-3 * d);
    // And it is oriented like the 45° rotation (the gauge alignment puts it there).
    let angle = fit.rotation.trace().clamp(-1.0, 3.0);
    let residual_angle = ((angle - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(
        residual_angle < 1.0,
        "physical blend is {residual_angle}° away from the 45° pose"
    );
    // The linear blend shrinks by cos 45° in the rotation plane.
    let lin = linear_blend(&s, &Weights::Alpha(0.5)).unwrap();
    let extent = |p: &[[f64; 3]]| {
        p.iter()
            .map(|q| (q[0] * q[0] + q[1] * q[1]).sqrt())
            .fold(0.0, f64::max)
    };
    let ratio = extent(&lin) / extent(&m.positions);
    assert!(
        (ratio - 0.5f64.sqrt()).abs() < 0.02,
        "linear blend extent ratio {ratio}"
    );
    let ratio_phys = extent(&r.positions) / extent(&m.positions);
    assert!(
        (ratio_phys - 1.0).abs() < 1e-3,
        "physical blend extent ratio {ratio_phys}"
    );
}

#[test]
fn multi_target_convex_and_delta_forms_agree() {
    let m = generate::tube(0.5, 4.0, 12, 16, true);
    let b1 = generate::bend(&m.positions, 2.0, 2.0, 1.2);
    let b2 = generate::bend(&m.positions, 1.0, 3.0, -0.8);
    let s = ShapeSet::new(
        m.clone(),
        vec![
            ("b".into(), m.positions.clone()),
            ("t1".into(), b1),
            ("t2".into(), b2),
        ],
    )
    .unwrap();
    let mut a = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    let mut b = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    let ra = a.solve(&Weights::Convex(vec![0.4, 0.3, 0.3])).unwrap();
    let rb = b.solve(&Weights::Delta(vec![0.3, 0.3])).unwrap();
    assert!(ra.stats.converged && rb.stats.converged);
    assert!(max_dist(&ra.positions, &rb.positions) < 1e-6 * bbox_diagonal(&m.positions));
    // All-zero delta weights give the base back.
    let r0 = b.solve(&Weights::Delta(vec![0.0, 0.0])).unwrap();
    assert!(max_dist(&r0.positions, s.positions(0)) < 1e-6 * bbox_diagonal(&m.positions));
}

#[test]
fn scale_invariance() {
    let s = bent_bar();
    let reference = blend(&s, &Weights::Alpha(0.5), &BlendOptions::default()).unwrap();
    for scale in [1e-6, 1e6] {
        let scaled: Vec<Vec<[f64; 3]>> = (0..2)
            .map(|i| {
                s.positions(i)
                    .iter()
                    .map(|p| p.map(|v| v * scale))
                    .collect()
            })
            .collect();
        let ss = ShapeSet::new(
            s.base().clone(),
            vec![
                ("a".into(), scaled[0].clone()),
                ("b".into(), scaled[1].clone()),
            ],
        )
        .unwrap();
        let r = blend(&ss, &Weights::Alpha(0.5), &BlendOptions::default()).unwrap();
        assert!(r.stats.converged, "scale {scale}");
        let back: Vec<[f64; 3]> = r.positions.iter().map(|p| p.map(|v| v / scale)).collect();
        let err = max_dist(&back, &reference.positions);
        assert!(
            err < 1e-6 * bbox_diagonal(s.positions(0)),
            "scale {scale}: {err}"
        );
    }
}

#[test]
fn bad_input_gives_errors_or_documented_outcomes() {
    let s = bent_bar();
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    assert!(matches!(
        solver.solve(&Weights::Alpha(f64::NAN)),
        Err(BlendError::NonFiniteWeight { .. })
    ));
    assert!(matches!(
        solver.solve(&Weights::Convex(vec![0.7, 0.7])),
        Err(BlendError::NotConvex { .. })
    ));
    // Different connectivity cannot even form a shape set.
    let mut other = s.mesh(1);
    other.triangles.swap(0, 1);
    assert!(ShapeSet::from_meshes(vec![("a".into(), s.mesh(0)), ("b.obj".into(), other)]).is_err());
    // Under-constrained explicit boundary conditions are rejected before any factorization.
    let e = PhysicalBlend::new(
        &s,
        &BlendOptions {
            fixed: FixedVertices::Ids(vec![0]),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, BlendError::UnderConstrained { .. }), "{e}");
    // An unreachable tolerance: the best state comes back, flagged, without NaNs.
    let opts = BlendOptions {
        gradient_tolerance: 1e-300,
        max_newton_iterations: 8,
        ..Default::default()
    };
    let r = blend(&s, &Weights::Alpha(0.5), &opts).unwrap();
    assert!(!r.stats.converged);
    assert!(r.positions.iter().flatten().all(|v| v.is_finite()));
    assert!(r.stats.gradient_norm.is_finite());
    assert!(!r.stats.unconverged_vertices.is_empty());
    // Extreme delta weights drive rest lengths negative: clamped and reported.
    let r = blend(&s, &Weights::Delta(vec![-30.0]), &BlendOptions::default()).unwrap();
    assert!(r.stats.clamped_springs > 0);
    assert!(r.positions.iter().flatten().all(|v| v.is_finite()));
    assert!(matches!(
        PhysicalBlend::new(
            &s,
            &BlendOptions {
                gradient_tolerance: -1.0,
                ..Default::default()
            }
        ),
        Err(BlendError::InvalidOption(_))
    ));
}

#[test]
fn solver_variants_agree() {
    let s = bent_bar();
    let d = bbox_diagonal(s.positions(0));
    let mut results = Vec::new();
    for linear_solver in [LinearSolver::Direct, LinearSolver::TrustRegion] {
        for ordering in [
            FillOrdering::Amd,
            FillOrdering::NestedDissection,
            FillOrdering::Cheapest,
        ] {
            let opts = BlendOptions {
                linear_solver,
                ordering,
                gradient_tolerance: 1e-10,
                ..Default::default()
            };
            let mut solver = PhysicalBlend::new(&s, &opts).unwrap();
            let mut last = None;
            for a in [0.25, 0.5, 0.75] {
                let r = solver.solve(&Weights::Alpha(a)).unwrap();
                assert!(
                    r.stats.converged,
                    "{linear_solver:?}/{ordering:?} at α = {a}"
                );
                last = Some(r);
            }
            let r = last.unwrap();
            if linear_solver == LinearSolver::Direct {
                assert_eq!(r.stats.cg_iterations, 0);
            }
            results.push(r.positions);
        }
    }
    for r in &results[1..] {
        assert!(max_dist(r, &results[0]) < 1e-6 * d);
    }
}

/// Regression (review): the gauge must not strain a component whose size changes. A bar lying
/// diagonally blended with a copy at half the size must reach that copy exactly (up to a rigid
/// motion) at α = 1.
#[test]
fn uniform_scale_in_gives_uniform_scale_out_without_fixed_vertices() {
    let m = generate::bar(4.0, 0.6, 2, 16);
    let m = m.with_positions(generate::rotate(
        &m.positions,
        [0.0; 3],
        [1.0, 1.0, 0.3],
        0.9,
    ));
    let half: Vec<[f64; 3]> = m.positions.iter().map(|p| p.map(|v| 0.5 * v)).collect();
    let s = two(&m, half.clone());
    let opts = BlendOptions {
        fixed: FixedVertices::None,
        ..Default::default()
    };
    let r = blend(&s, &Weights::Alpha(1.0), &opts).unwrap();
    assert!(r.stats.converged);
    assert!(r.stats.energy < 1e-12, "energy {}", r.stats.energy);
    let fit = morphkit::geom::kabsch(&r.positions, &half, &[]);
    let aligned: Vec<[f64; 3]> = r.positions.iter().map(|p| fit.apply(*p)).collect();
    assert!(max_dist(&aligned, &half) < 1e-6 * bbox_diagonal(&half));
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let mid = blend(&s, &Weights::Alpha(0.5), &opts).unwrap();
    let q = blend_metrics(&s, &topo, &Weights::Alpha(0.5), &mid.positions).unwrap();
    assert!(
        q.edge_length_max < 1e-6,
        "a uniform scale is reachable exactly: {q:?}"
    );
}
