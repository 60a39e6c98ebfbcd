//! Animation transfer on generated meshes: identity reproduction, rigid motions, bad input.

use morphkit::geom::kabsch;
use morphkit::mesh::{Point, ShapeSet, TriMesh};
use morphkit::transfer::{
    correspond, transfer_animation, AnimationTransfer, Correspondence, CorrespondenceError,
    CorrespondenceOptions, MarkerError, Markers, Side, TransferError, TransferOptions,
};
use nalgebra::{Rotation3, Vector3};

/// An open tube along z: `nu` segments around, `nv` rings, radius `r`, height `h`.
fn cylinder(nu: usize, nv: usize, r: f64, h: f64) -> TriMesh {
    let mut p = Vec::new();
    for j in 0..nv {
        let z = h * j as f64 / (nv - 1) as f64;
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            p.push([r * a.cos(), r * a.sin(), z]);
        }
    }
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    let mut t = Vec::new();
    for j in 0..nv - 1 {
        for i in 0..nu {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(p, t)
}

/// Bends the tube about the y axis by `angle` over its height (a smooth non-rigid frame).
fn bend(m: &TriMesh, angle: f64) -> Vec<Point> {
    let (_, hi) = m.bounding_box();
    let h = hi[2];
    if angle == 0.0 {
        return m.positions.clone();
    }
    let rad = h / angle;
    m.positions
        .iter()
        .map(|p| {
            let th = p[2] / h * angle;
            [
                (rad - p[0]) * -th.cos() + rad,
                p[1] * (1.0 + 0.1 * th),
                (rad - p[0]) * th.sin(),
            ]
        })
        .collect()
}

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn identity_correspondence_reproduces_every_frame() {
    let m = cylinder(24, 15, 1.0, 6.0);
    let frames: Vec<(String, Vec<Point>)> = [0.0, 0.4, 1.0, 1.8, 2.6]
        .iter()
        .enumerate()
        .map(|(k, &a)| {
            let r = Rotation3::from_euler_angles(0.1 * k as f64, 0.3, -0.2 * k as f64);
            let t = Vector3::new(k as f64, -2.0, 0.5 * k as f64);
            let p = bend(&m, a)
                .into_iter()
                .map(|p| (r * Vector3::from(p) + t).into())
                .collect();
            (format!("f{k}"), p)
        })
        .collect();
    let set = ShapeSet::new(m.clone(), frames.clone()).unwrap();
    let out = transfer_animation(
        &m,
        &set,
        &m,
        &Correspondence::identity(&m),
        &TransferOptions::default(),
    )
    .unwrap();
    let tol = 1e-6 * m.bbox_diagonal();
    for (f, (x, (_, want))) in out.iter().zip(&frames).enumerate() {
        let err = x
            .iter()
            .zip(want)
            .map(|(a, b)| dist(*a, *b))
            .fold(0.0, f64::max);
        assert!(err < tol, "frame {f}: max error {err:e} > {tol:e}");
    }
}

/// Source and target are tubes with different tessellations, sizes and placements.
fn source_and_target() -> (TriMesh, TriMesh, Markers) {
    let s = cylinder(16, 9, 1.0, 4.0);
    let t0 = cylinder(23, 13, 1.0, 4.0);
    let t = t0.with_positions(
        t0.positions
            .iter()
            .map(|p| [2.0 * p[0] + 5.0, 2.0 * p[1], 2.0 * p[2] - 1.0])
            .collect(),
    );
    // Markers: four directions on the bottom, middle and top rings.
    let mut pairs = Vec::new();
    for (js, jt) in [(0, 0), (4, 6), (8, 12)] {
        for q in 0..4 {
            pairs.push([
                (js * 16 + 4 * q) as u32,
                (jt * 23 + (23 * q + 2) / 4) as u32,
            ]);
        }
    }
    (s, t, Markers::new(pairs))
}

#[test]
fn a_rigid_source_motion_moves_the_target_rigidly() {
    let (s, t, markers) = source_and_target();
    let r = correspond(&s, &t, &markers, &CorrespondenceOptions::default()).unwrap();
    let c = r.correspondence;
    assert!(c.normal_violations.is_empty());
    let rot = Rotation3::from_euler_angles(0.9, -0.6, 2.2).into_inner();
    let shift = Vector3::new(1.0, 2.0, -3.0);
    let frame: Vec<Point> = s
        .positions
        .iter()
        .map(|p| (rot * Vector3::from(*p) + shift).into())
        .collect();
    let tr = AnimationTransfer::new(&s, &t, &c, &TransferOptions::default()).unwrap();
    let x = tr.transfer_frame(&frame).unwrap();
    let fit = kabsch(&t.positions, &x, &[]);
    assert!(
        (fit.rotation - rot).norm() < 1e-9,
        "rotation differs by {}",
        (fit.rotation - rot).norm()
    );
    let diag = t.bbox_diagonal();
    for (v, p) in t.positions.iter().enumerate() {
        let e = dist(fit.apply(*p), x[v]);
        assert!(e < 1e-9 * diag, "vertex {v} off the rigid motion by {e:e}");
    }
    // The target's marker centroid follows the source's, scaled by the size ratio (2).
    let cen = |p: &[Point], side: usize| {
        let mut c = Vector3::zeros();
        for m in &markers.pairs {
            c += Vector3::from(p[m[side] as usize]);
        }
        c / markers.len() as f64
    };
    let ratio = t.bbox_diagonal() / s.bbox_diagonal();
    let want = cen(&t.positions, 1) + ratio * (cen(&frame, 0) - cen(&s.positions, 0));
    assert!((cen(&x, 1) - want).norm() < 1e-9 * diag);
}

#[test]
fn bad_markers_are_clear_errors() {
    let (s, t, markers) = source_and_target();
    let opts = CorrespondenceOptions::default();
    let mut out_of_range = markers.clone();
    out_of_range.pairs[2][1] = 100_000;
    let e = correspond(&s, &t, &out_of_range, &opts).unwrap_err();
    assert!(matches!(
        e,
        CorrespondenceError::Markers(MarkerError::OutOfRange {
            marker: 2,
            side: Side::Target,
            vertex: 100_000,
            ..
        })
    ));
    assert!(e
        .to_string()
        .contains("marker 2: target vertex 100000 is out of range"));

    let mut dup = markers.clone();
    dup.pairs[5][0] = dup.pairs[1][0];
    let e = correspond(&s, &t, &dup, &opts).unwrap_err();
    assert!(matches!(
        e,
        CorrespondenceError::Markers(MarkerError::Duplicate {
            first: 1,
            second: 5,
            side: Side::Source,
            ..
        })
    ));
    assert!(e
        .to_string()
        .contains("markers 1 and 5 both use source vertex"));

    let few = Markers::new(markers.pairs[..3].to_vec());
    let e = correspond(&s, &t, &few, &opts).unwrap_err();
    assert!(e.to_string().contains("3 markers given, at least 4"), "{e}");
}

#[test]
fn frames_with_other_connectivity_and_isolated_target_vertices_are_rejected() {
    let m = cylinder(10, 5, 1.0, 2.0);
    let mut other = m.clone();
    other.triangles[7] = [
        other.triangles[7][0],
        other.triangles[7][2],
        other.triangles[7][1],
    ];
    let set = ShapeSet::from_meshes(vec![("frame_0001.obj".into(), other)]).unwrap();
    let e = transfer_animation(
        &m,
        &set,
        &m,
        &Correspondence::identity(&m),
        &TransferOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        TransferError::FrameConnectivity { triangle: 7, .. }
    ));
    assert!(e.to_string().contains("triangle 7"), "{e}");

    let mut target = m.clone();
    target.positions.push([9.0, 9.0, 9.0]);
    target.positions.push([8.0, 9.0, 9.0]);
    // Triangle t ↔ t, but not the identity (the vertex counts differ): anchored by a marker.
    let c = Correspondence {
        target_vertices: target.num_vertices(),
        identity: false,
        markers: vec![[0, 0]],
        ..Correspondence::identity(&m)
    };
    let e = AnimationTransfer::new(&m, &target, &c, &TransferOptions::default()).unwrap_err();
    assert!(
        matches!(e, TransferError::IsolatedVertices { ref vertices } if vertices == &[50, 51]),
        "{e}"
    );
    assert!(e.to_string().contains("first: 50, 51"), "{e}");
}

#[test]
fn identity_correspondence_of_other_sized_meshes_is_rejected_when_loaded() {
    // Regression: `identity: true` with more target than source vertices used to pass
    // validation and panic in the anchor centroid of `AnimationTransfer::new`.
    let s = cylinder(10, 5, 1.0, 2.0);
    let t = cylinder(12, 6, 1.0, 2.0);
    let ns = s.num_triangles() as u32;
    let c = Correspondence {
        target_vertices: t.num_vertices(),
        target_triangles: t.num_triangles(),
        offsets: (0..=t.num_triangles() as u32).collect(),
        matches: (0..t.num_triangles() as u32).map(|k| k % ns).collect(),
        ..Correspondence::identity(&s)
    };
    let e = Correspondence::from_json(&c.to_json()).unwrap_err();
    let msg = e.to_string();
    for n in [s.num_vertices(), t.num_vertices()] {
        assert!(msg.contains(&n.to_string()), "{msg}");
    }
    let e = AnimationTransfer::new(&s, &t, &c, &TransferOptions::default()).unwrap_err();
    assert!(matches!(e, TransferError::Correspondence(_)), "{e}");
}
