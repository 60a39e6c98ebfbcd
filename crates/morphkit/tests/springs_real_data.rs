//! Physical blendshapes on real meshes from `MORPHKIT_DATA` (skipped when it is unset).
//!
//! Quality criterion of the project issue: at α = 0.5 the physical blend's RMS edge-length
//! deviation from the interpolated rest lengths is at least 3× smaller than the linear blend's.

mod common;

use morphkit::io::read_mesh;
use morphkit::mesh::{ShapeSet, Topology, TriMesh};
use morphkit::springs::{blend, blend_metrics, linear_blend, BlendOptions, Weights};

fn check_quality(name: &str, shapes: &ShapeSet) {
    let topo = Topology::new(shapes.num_vertices(), shapes.triangles());
    let w = Weights::Alpha(0.5);
    let r = blend(shapes, &w, &BlendOptions::default()).unwrap();
    assert!(
        r.positions.iter().flatten().all(|v| v.is_finite()),
        "{name}: non-finite output"
    );
    assert!(r.stats.converged, "{name}: not converged: {:?}", r.stats);
    let lin = linear_blend(shapes, &w).unwrap();
    let mp = blend_metrics(shapes, &topo, &w, &r.positions).unwrap();
    let ml = blend_metrics(shapes, &topo, &w, &lin).unwrap();
    eprintln!(
        "{name}: physical {mp:?}\n{name}: linear {ml:?}\n{name}: stats {:?}",
        r.stats
    );
    assert!(
        3.0 * mp.edge_length_rms <= ml.edge_length_rms,
        "{name}: physical edge deviation {} is not 3× below the linear {}",
        mp.edge_length_rms,
        ml.edge_length_rms
    );
}

fn pair(base: &str, target: &str) -> Option<ShapeSet> {
    let (b, t) = (common::data_file(base)?, common::data_file(target)?);
    Some(morphkit::io::read_shape_set(&[b, t]).unwrap())
}

#[test]
fn bending_cylinder_rest_to_bend_4() {
    let Some(s) = pair(
        "cragl-bending-cylinder/cylinder-rest.obj",
        "cragl-bending-cylinder/cylinder-bend-4.obj",
    ) else {
        return common::skip("bending_cylinder_rest_to_bend_4");
    };
    check_quality("cylinder", &s);
}

#[test]
fn horse_reference_to_pose_5() {
    let Some(s) = pair(
        "sumner-horse-camel/horse-reference.obj.gz",
        "sumner-horse-camel/horse-05.obj.gz",
    ) else {
        return common::skip("horse_reference_to_pose_5");
    };
    check_quality("horse", &s);
}

/// The face and head/neck region of the ICT FaceKit (vertices 0..=11247, per its SOURCE.md):
/// the triangles whose vertices all lie in that range.
fn face_region(m: &TriMesh) -> TriMesh {
    const LAST: u32 = 11247;
    let tris: Vec<[u32; 3]> = m
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&v| v <= LAST))
        .collect();
    TriMesh::new(m.positions[..=LAST as usize].to_vec(), tris)
}

#[test]
fn ict_face_neutral_to_jaw_open() {
    let (Some(n), Some(j)) = (
        common::data_file("ict-facekit/generic_neutral_mesh.obj.gz"),
        common::data_file("ict-facekit/jawOpen.obj.gz"),
    ) else {
        return common::skip("ict_face_neutral_to_jaw_open");
    };
    let (n, j) = (
        face_region(&read_mesh(&n).unwrap()),
        face_region(&read_mesh(&j).unwrap()),
    );
    let s = ShapeSet::from_meshes(vec![("neutral".into(), n), ("jawOpen".into(), j)]).unwrap();
    check_quality("ict-face", &s);
}
