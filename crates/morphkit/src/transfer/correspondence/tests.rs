//! Unit tests of the correspondence.

use super::*;
use crate::mesh::dot;
use crate::transfer::error::TransferError;
use crate::transfer::gradients::GradientOperator;
use crate::transfer::testmesh::sphere;

fn markers_on(m: &TriMesh) -> Markers {
    // Six "poles" of the sphere as markers.
    let mut pairs = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let v = (0..m.num_vertices())
                .max_by(|&a, &b| {
                    (sign * m.positions[a][axis]).total_cmp(&(sign * m.positions[b][axis]))
                })
                .unwrap() as u32;
            pairs.push(v);
        }
    }
    Markers::new(pairs.into_iter().map(|v| [v, v]).collect())
}

#[test]
fn self_correspondence_matches_each_triangle_to_itself_first() {
    let m = sphere(16, 10, 1.0);
    let r = correspond(&m, &m, &markers_on(&m), &CorrespondenceOptions::default()).unwrap();
    let c = &r.correspondence;
    assert!(c.normal_violations.is_empty());
    for t in 0..m.num_triangles() {
        assert_eq!(c.matches_of(t)[0], t as u32, "triangle {t}");
    }
    assert!(c.mean_matches() > 1.0, "neighbours within one edge length");
    let back = Correspondence::from_json(&c.to_json()).unwrap();
    assert_eq!((&back.offsets, &back.matches), (&c.offsets, &c.matches));
    assert_eq!(back.markers, c.markers);
    for res in &c.marker_residuals {
        assert!(res.relative < 1e-3);
    }
}

#[test]
fn different_tessellations_and_a_scaled_target_correspond() {
    let s = sphere(16, 10, 1.0);
    let t0 = sphere(23, 13, 1.0);
    let t = t0.with_positions(
        t0.positions
            .iter()
            .map(|p| p.map(|x| 5.0 * x + 2.0))
            .collect(),
    );
    // Markers: poles of both meshes, matched by direction.
    let ms = markers_on(&s);
    let mt = markers_on(&t);
    let pairs = ms
        .pairs
        .iter()
        .zip(&mt.pairs)
        .map(|(a, b)| [a[0], b[1]])
        .collect();
    let r = correspond(
        &s,
        &t,
        &Markers::new(pairs),
        &CorrespondenceOptions::default(),
    )
    .unwrap();
    let c = &r.correspondence;
    assert!(c.normal_violations.is_empty());
    // Matched triangles point the same way on the original spheres.
    let (_, ns) = centroids_and_normals(&s.positions, &s.triangles);
    let (_, nt) = centroids_and_normals(&t.positions, &t.triangles);
    for (tt, n) in nt.iter().enumerate() {
        for &ss in c.matches_of(tt) {
            assert!(dot(ns[ss as usize], *n) > 0.5, "{tt} ↔ {ss}");
        }
    }
    let bad = Correspondence {
        offsets: vec![0; c.offsets.len()],
        ..c.clone()
    };
    assert!(matches!(
        Correspondence::from_json(&bad.to_json()),
        Err(CorrespondenceError::Invalid(_))
    ));
}

#[test]
fn identity_flag_with_unequal_counts_is_a_typed_error() {
    let s = sphere(8, 6, 1.0);
    let t = sphere(12, 8, 1.0);
    let ns = s.num_triangles() as u32;
    let bad = Correspondence {
        target_vertices: t.num_vertices(),
        target_triangles: t.num_triangles(),
        offsets: (0..=t.num_triangles() as u32).collect(),
        matches: (0..t.num_triangles() as u32).map(|k| k % ns).collect(),
        ..Correspondence::identity(&s)
    };
    let e = Correspondence::from_json(&bad.to_json()).unwrap_err();
    match e {
        CorrespondenceError::IdentityMismatch {
            source_vertices,
            target_vertices,
            source_triangles,
            target_triangles,
        } => {
            assert_eq!(source_vertices, s.num_vertices());
            assert_eq!(target_vertices, t.num_vertices());
            assert_eq!(source_triangles, s.num_triangles());
            assert_eq!(target_triangles, t.num_triangles());
        }
        e => panic!("{e}"),
    }
    // `check` validates too, so a hand-built correspondence cannot slip through.
    assert!(matches!(
        bad.check(&s, &t),
        Err(TransferError::Correspondence(
            CorrespondenceError::IdentityMismatch { .. }
        ))
    ));
    // Equal counts but matches other than t ↔ [t].
    let mut swapped = Correspondence::identity(&s);
    swapped.matches.swap(2, 3);
    assert!(matches!(
        Correspondence::from_json(&swapped.to_json()),
        Err(CorrespondenceError::IdentityMatches {
            target_triangle: 2,
            ..
        })
    ));
}

#[test]
fn malformed_correspondence_files_are_errors_not_panics() {
    let m = sphere(16, 10, 1.0);
    let r = correspond(&m, &m, &markers_on(&m), &CorrespondenceOptions::default()).unwrap();
    let good = r.correspondence;
    let nf = good.target_triangles;
    type Corrupt = Box<dyn Fn(&mut Correspondence)>;
    let corruptions: Vec<(&str, Corrupt)> = vec![
        ("offsets not increasing", Box::new(|c| c.offsets.swap(1, 2))),
        (
            "offset beyond matches",
            Box::new(|c| c.offsets[1] = u32::MAX),
        ),
        (
            "offsets too short",
            Box::new(|c| {
                c.offsets.pop();
            }),
        ),
        (
            "last offset",
            Box::new(|c| *c.offsets.last_mut().unwrap() -= 1),
        ),
        ("match range", Box::new(move |c| c.matches[0] = nf as u32)),
        ("marker source", Box::new(|c| c.markers[0][0] = u32::MAX)),
        (
            "marker target",
            Box::new(|c| c.markers[1][1] = c.target_vertices as u32),
        ),
        (
            "normal violation",
            Box::new(move |c| c.normal_violations.push(nf as u32)),
        ),
        (
            "residual source",
            Box::new(|c| c.marker_residuals[0].source = u32::MAX),
        ),
        (
            "residual target",
            Box::new(|c| c.marker_residuals[0].target = u32::MAX),
        ),
        ("huge count", Box::new(|c| c.target_triangles = usize::MAX)),
        (
            "identity sizes",
            Box::new(|c| {
                c.identity = true;
                c.source_vertices -= 1;
            }),
        ),
        ("format", Box::new(|c| c.format = "x".into())),
    ];
    for (what, f) in corruptions {
        let mut c = good.clone();
        f(&mut c);
        let res = std::panic::catch_unwind(|| Correspondence::from_json(&c.to_json()));
        assert!(matches!(res, Ok(Err(_))), "{what}: {res:?}");
    }
    assert!(Correspondence::from_json(&good.to_json()).is_ok());
}

#[test]
fn tiny_source_triangles_are_unusable_exactly_when_gradients_call_them_degenerate() {
    // A tetrahedron and a sliver fan: areas 0, below and above the gradient
    // operator's tolerance (1e-14 · diag²; diag ≈ 4 here).
    let mut m = crate::mesh::TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.1, 0.0],
            [0.2, 1.0, 0.1],
            [0.3, 0.2, 1.0],
            [2.0, 0.0, 0.0],
            [2.0, 1e-14, 0.0],
            [3.0, 1e-11, 0.0],
            [4.0, 0.0, 0.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    );
    m.triangles.push([1, 4, 5]); // doubled area ≈ 1e-14: non-zero but degenerate
    m.triangles.push([1, 4, 6]); // doubled area ≈ 1e-11: usable
    m.triangles.push([0, 4, 7]); // exactly collinear
    let (_, n) = centroids_and_normals(&m.positions, &m.triangles);
    assert!(norm(n[4]) > 0.0, "the sliver has a (non-zero) normal");
    let usable = usable_source_triangles(&m, &n);
    assert_eq!(usable, vec![true, true, true, true, false, true, false]);
    let op = GradientOperator::new(&m);
    let degenerate: Vec<usize> = (0..usable.len()).filter(|&t| !usable[t]).collect();
    assert_eq!(op.degenerate(), degenerate.as_slice());
}

#[test]
fn refinement_pulls_the_source_onto_the_target_and_two_way_reaches_every_source_triangle() {
    // A coarse sphere onto a finer, stretched one: the least-squares warp leaves the source
    // off the target surface; the refinement steps bring it closer every time.
    let s = sphere(12, 8, 1.0);
    let t0 = sphere(23, 15, 1.0);
    let t = t0.with_positions(
        t0.positions
            .iter()
            .map(|p| [1.5 * p[0], p[1], 0.8 * p[2]])
            .collect(),
    );
    let ms = markers_on(&s);
    let mt = markers_on(&t);
    let pairs = ms
        .pairs
        .iter()
        .zip(&mt.pairs)
        .map(|(a, b)| [a[0], b[1]])
        .collect();
    let markers = Markers::new(pairs);
    let opts = CorrespondenceOptions {
        refine: Some(RefineOptions::default()),
        ..Default::default()
    };
    let r = correspond(&s, &t, &markers, &opts).unwrap();
    let steps = &r.correspondence.refinement;
    assert_eq!(steps.len(), RefineOptions::default().closest_weights.len());
    for w in steps.windows(2) {
        assert!(w[1].mean_distance < w[0].mean_distance, "{steps:?}");
    }
    assert!(steps.last().unwrap().mean_distance < 2e-3, "{steps:?}");
    // Markers are hard constraints.
    for &[a, b] in &markers.pairs {
        let d = norm(sub(r.warped_source[a as usize], t.positions[b as usize]));
        assert!(d < 1e-9, "marker {a}: {d}");
    }
    let c = &r.correspondence;
    let mut reached = vec![false; s.num_triangles()];
    for &m in &c.matches {
        reached[m as usize] = true;
    }
    assert!(
        reached.iter().all(|&x| x),
        "two-way matching reaches every source triangle"
    );
    assert_eq!(c.distances.len(), c.matches.len());
    let back = Correspondence::from_json(&c.to_json()).unwrap();
    assert_eq!(back.distances, c.distances);
    // Unsorted distances are rejected.
    let mut bad = c.clone();
    let k = (0..c.target_triangles)
        .find(|&t| c.matches_of(t).len() > 1)
        .unwrap();
    let o = c.offsets[k] as usize;
    bad.distances.swap(o, o + 1);
    if bad.distances[o] != bad.distances[o + 1] {
        assert!(Correspondence::from_json(&bad.to_json()).is_err());
    }
    let bad_weight = CorrespondenceOptions {
        refine: Some(RefineOptions {
            identity: -1.0,
            ..Default::default()
        }),
        ..Default::default()
    };
    assert!(matches!(
        correspond(&s, &t, &markers, &bad_weight),
        Err(CorrespondenceError::Invalid(_))
    ));
}

#[test]
fn a_stricter_normal_test_keeps_only_closer_normals() {
    let s = sphere(16, 10, 1.0);
    let t = s.with_positions(
        s.positions
            .iter()
            .map(|p| [1.3 * p[0], p[1], 0.7 * p[2]])
            .collect(),
    );
    let ms = markers_on(&s);
    let opts = CorrespondenceOptions {
        min_normal_cos: 0.9,
        ..Default::default()
    };
    let r = correspond(&s, &t, &ms, &opts).unwrap();
    let c = &r.correspondence;
    let unit = |p: &[Point], tri: [u32; 3]| {
        let n = triangle_normal(p, tri);
        n.map(|x| x / norm(n))
    };
    for tt in 0..c.target_triangles {
        if c.normal_violations.contains(&(tt as u32)) {
            continue;
        }
        let nt = unit(&r.warped_target, t.triangles[tt]);
        for &m in c.matches_of(tt) {
            let ns = unit(&r.warped_source, s.triangles[m as usize]);
            assert!(dot(ns, nt) > 0.9, "target {tt}, source {m}");
        }
    }
}

#[test]
fn the_local_stretch_map_of_an_identity_correspondence_is_the_identity() {
    let m = sphere(10, 7, 1.0);
    let def: Vec<Point> = m
        .positions
        .iter()
        .map(|p| {
            [
                p[0] * (1.0 + 0.3 * p[2]),
                p[1] + 0.2 * p[0] * p[0],
                0.8 * p[2],
            ]
        })
        .collect();
    let g = GradientOperator::new(&m).gradients(&def).unwrap();
    let c = Correspondence::identity(&m);
    let normals: Vec<nalgebra::Vector3<f64>> = (0..m.num_triangles())
        .map(|t| nalgebra::Vector3::from(m.triangle_normal(t)).normalize())
        .collect();
    let pol: Vec<_> = g.iter().map(polar).collect();
    let local = c.map_gradients_local(&pol, &normals, &normals, GradientCombine::default());
    for (a, b) in local.iter().zip(&g) {
        assert!((a - b).norm() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn local_confidence_follows_the_reference_normals_agreement() {
    assert_eq!(normal_agreement(1.0), 1.0);
    assert!((normal_agreement(0.0) - 0.25).abs() < 1e-15);
    assert_eq!(normal_agreement(-1.0), 0.0);
    let m = sphere(8, 6, 1.0);
    let c = Correspondence::identity(&m);
    let n: Vec<nalgebra::Vector3<f64>> = (0..m.num_triangles())
        .map(|t| nalgebra::Vector3::from(m.triangle_normal(t)).normalize())
        .collect();
    let same = c.local_confidence(&n, &n, GradientCombine::default());
    assert!(same.iter().all(|&x| (x - 1.0).abs() < 1e-12), "{same:?}");
    // Every target normal turned by 90° about an axis in its plane: 1/4; reversed: the floor.
    let turned: Vec<_> = n
        .iter()
        .map(|v| {
            let a = v.cross(&nalgebra::Vector3::new(0.3, -0.5, 0.8)).normalize();
            a.cross(v)
        })
        .collect();
    let quarter = c.local_confidence(&n, &turned, GradientCombine::default());
    assert!(
        quarter.iter().all(|&x| (x - 0.25).abs() < 1e-9),
        "{quarter:?}"
    );
    let back: Vec<_> = n.iter().map(|v| -v).collect();
    let away = c.local_confidence(&n, &back, GradientCombine::default());
    assert!(away.iter().all(|&x| x == CONFIDENCE_FLOOR), "{away:?}");
}
