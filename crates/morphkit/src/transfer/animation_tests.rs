//! Tests of [`super`] (the animation transfer).

use super::*;
use crate::transfer::testmesh::sphere;
use nalgebra::{Rotation3, Vector3};

#[test]
fn identity_transfer_reproduces_frames_and_follows_translation() {
    let m = sphere(12, 8, 2.0);
    let r = Rotation3::from_euler_angles(0.7, -0.4, 1.9).into_inner();
    let t = Vector3::new(3.0, -1.0, 0.25);
    let frame: Vec<Point> = m
        .positions
        .iter()
        .map(|p| [p[0] * 1.2, p[1], p[2] + 0.1 * p[0] * p[1]])
        .map(|p| (r * Vector3::from(p) + t).into())
        .collect();
    let c = Correspondence::identity(&m);
    let tr = AnimationTransfer::new(&m, &m, &c, &TransferOptions::default()).unwrap();
    let x = tr.transfer_frame(&frame).unwrap();
    for (a, b) in x.iter().zip(&frame) {
        assert!(crate::mesh::norm(crate::mesh::sub(*a, *b)) < 1e-9);
    }
    // The paper's convention keeps the constraint vertex in place instead.
    let fixed = TransferOptions {
        translation: TranslationMode::FixedVertex,
        ..Default::default()
    };
    let tr = AnimationTransfer::new(&m, &m, &c, &fixed).unwrap();
    let x = tr.transfer_frame(&frame).unwrap();
    let v = tr.solver().constraint_vertices()[0] as usize;
    assert_eq!(x[v], m.positions[v]);
}

#[test]
fn frames_with_other_connectivity_are_rejected() {
    let m = sphere(8, 6, 1.0);
    let mut other = m.clone();
    other.triangles.swap(3, 4);
    let frames = ShapeSet::from_meshes(vec![("f".into(), other)]).unwrap();
    let e = transfer_animation(
        &m,
        &frames,
        &m,
        &Correspondence::identity(&m),
        &TransferOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        TransferError::FrameConnectivity { triangle: 3, .. }
    ));
}

#[test]
fn identity_correspondence_of_other_sized_meshes_is_an_error_not_a_panic() {
    let s = sphere(8, 6, 1.0);
    let t = sphere(12, 8, 1.0);
    let ns = s.num_triangles() as u32;
    let c = Correspondence {
        target_vertices: t.num_vertices(),
        target_triangles: t.num_triangles(),
        offsets: (0..=t.num_triangles() as u32).collect(),
        matches: (0..t.num_triangles() as u32).map(|k| k % ns).collect(),
        ..Correspondence::identity(&s)
    };
    let e = AnimationTransfer::new(&s, &t, &c, &TransferOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            TransferError::Correspondence(
                crate::transfer::CorrespondenceError::IdentityMismatch { .. }
            )
        ),
        "{e}"
    );
}

#[test]
fn frame_errors_name_the_frame() {
    let m = sphere(8, 6, 1.0);
    let tr = AnimationTransfer::new(
        &m,
        &m,
        &Correspondence::identity(&m),
        &TransferOptions::default(),
    )
    .unwrap();
    let short = &m.positions[..m.num_vertices() - 1];
    assert!(matches!(
        tr.transfer_frame_at(7, short),
        Err(TransferError::FrameVertexCount { frame: 7, .. })
    ));
    assert!(matches!(
        tr.source_gradients_at(3, short),
        Err(TransferError::FrameVertexCount { frame: 3, .. })
    ));
    // Fewer triangles in the frames: reported at the first missing one.
    let mut fewer = m.clone();
    fewer.triangles.pop();
    let frames = ShapeSet::from_meshes(vec![("f".into(), fewer)]).unwrap();
    let last = m.num_triangles() - 1;
    match tr.check_frames(&frames).unwrap_err() {
        TransferError::FrameConnectivity {
            frame: 0,
            triangle,
            expected,
            found,
        } => {
            assert_eq!(triangle, last);
            assert_eq!(expected, m.triangles[last]);
            assert_eq!(found, [u32::MAX; 3]);
        }
        e => panic!("{e}"),
    }
    // Another vertex count.
    let mut more = m.clone();
    more.positions.push([9.0; 3]);
    let frames = ShapeSet::from_meshes(vec![("f".into(), more)]).unwrap();
    assert!(matches!(
        tr.check_frames(&frames),
        Err(TransferError::FrameVertexCount {
            frame: 0,
            expected,
            found,
        }) if expected == m.num_vertices() && found == m.num_vertices() + 1
    ));
}

#[test]
fn precomputed_flip_check_agrees_with_the_one_shot_test() {
    let m = sphere(10, 7, 1.0);
    let tr = AnimationTransfer::new(
        &m,
        &m,
        &Correspondence::identity(&m),
        &TransferOptions::default(),
    )
    .unwrap();
    let mirrored: Vec<Point> = m.positions.iter().map(|p| [-p[0], p[1], p[2]]).collect();
    let g = vec![Matrix3::identity(); m.num_triangles()];
    let want = crate::transfer::flipped_triangles(&m, &mirrored, &g);
    assert!(!want.is_empty());
    assert_eq!(tr.flipped_triangles(&mirrored, &g), want);
}
