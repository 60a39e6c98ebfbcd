//! Every mesh under `MORPHKIT_DATA` loads with the counts its SOURCE.md states.

mod common;

use morphkit::io;
use morphkit::mesh::Topology;
use std::path::PathBuf;

/// `(file, vertices, triangles, polygons when the file has non-triangle faces)`.
fn expected() -> Vec<(String, usize, usize, Option<usize>)> {
    let mut v = Vec::new();
    let mut add = |f: String, nv, nt, np| v.push((f, nv, nt, np));
    add(
        "cragl-bending-cylinder/cylinder-rest.obj".into(),
        420,
        800,
        None,
    );
    for k in 1..=4 {
        add(
            format!("cragl-bending-cylinder/cylinder-bend-{k}.obj"),
            420,
            800,
            None,
        );
        add(
            format!("cragl-bending-cylinder/cylinder-pose1-{k}.obj"),
            420,
            800,
            None,
        );
    }
    for (f, nv, nt) in [
        ("bunny", 3301, 6598),
        ("armadillo", 14587, 29170),
        ("spot_low_resolution", 829, 1654),
        ("hand_lowres", 810, 1602),
        ("hand_closed", 7993, 15982),
        ("goathead", 2763, 5522),
    ] {
        add(format!("generic-meshes/{f}.obj.gz"), nv, nt, None);
    }
    // 25836 quads + 548 triangles = 26384 polygons, 2 × 25836 + 548 triangles.
    for f in std::iter::once("generic_neutral_mesh").chain(common::ICT_EXPRESSIONS) {
        add(
            format!("ict-facekit/{f}.obj.gz"),
            26719,
            2 * 25836 + 548,
            Some(26384),
        );
    }
    // 170 triangles + 312 quads = 482 polygons.
    add(
        "lowpoly-cat-dog/cat-reference.obj".into(),
        398,
        170 + 2 * 312,
        Some(482),
    );
    for k in 1..=36 {
        add(
            format!("lowpoly-cat-dog/cat-run/cat-run-{k:02}.obj.gz"),
            398,
            170 + 2 * 312,
            Some(482),
        );
    }
    add("lowpoly-cat-dog/dog-reference.obj".into(), 485, 960, None);
    add(
        "sumner-horse-camel/horse-reference.obj.gz".into(),
        8431,
        16843,
        None,
    );
    for k in 1..=10 {
        add(
            format!("sumner-horse-camel/horse-{k:02}.obj.gz"),
            8431,
            16843,
            None,
        );
    }
    add(
        "sumner-horse-camel/camel-reference.obj.gz".into(),
        21887,
        43814,
        None,
    );
    add(
        "sumner-horse-gallop/horse-gallop-reference.obj.gz".into(),
        8431,
        16843,
        None,
    );
    for k in 1..=48 {
        add(
            format!("sumner-horse-gallop/horse-gallop-{k:02}.obj.gz"),
            8431,
            16843,
            None,
        );
    }
    add(
        "sumner-horse-collapse/horse-collapse-reference.obj.gz".into(),
        8431,
        16843,
        None,
    );
    for k in (1..=53).step_by(2) {
        add(
            format!("sumner-horse-collapse/horse-collapse-{k:02}.obj.gz"),
            8431,
            16843,
            None,
        );
    }
    add(
        "sumner-elephant/elephant-reference.obj.gz".into(),
        42321,
        84638,
        None,
    );
    for k in [1, 9, 17, 25, 33, 41] {
        add(
            format!("sumner-elephant/elephant-gallop-{k:02}.obj.gz"),
            42321,
            84638,
            None,
        );
    }
    v
}

#[test]
fn every_data_mesh_has_its_stated_counts() {
    let Some(_) = common::data_dir() else {
        return common::skip("every_data_mesh_has_its_stated_counts");
    };
    let list = expected();
    assert_eq!(list.len(), 9 + 6 + 11 + 38 + 11 + 1 + 49 + 28 + 7);
    for (rel, nv, nt, np) in list {
        let path = common::data_file(&rel).unwrap();
        let m = io::read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.num_vertices(), nv, "{rel}: vertices");
        assert_eq!(m.num_triangles(), nt, "{rel}: triangles");
        assert_eq!(m.polygons.as_ref().map(|p| p.len()), np, "{rel}: polygons");
    }
}

#[test]
fn data_topology_matches_source_notes() {
    let Some(_) = common::data_dir() else {
        return common::skip("data_topology_matches_source_notes");
    };
    for (rel, boundary, non_manifold) in [
        ("sumner-horse-camel/horse-reference.obj.gz", 19, 0),
        ("sumner-horse-camel/camel-reference.obj.gz", 5, 26),
        ("cragl-bending-cylinder/cylinder-rest.obj", 40, 0),
        ("lowpoly-cat-dog/cat-reference.obj", 2, 4),
        ("lowpoly-cat-dog/dog-reference.obj", 12, 0),
        ("generic-meshes/hand_lowres.obj.gz", 16, 0),
        ("generic-meshes/bunny.obj.gz", 0, 0),
    ] {
        let m = io::read_mesh(&common::data_file(rel).unwrap()).unwrap();
        let t = Topology::new(m.num_vertices(), &m.triangles);
        assert_eq!(t.boundary_edges().len(), boundary, "{rel}: boundary edges");
        assert_eq!(
            t.non_manifold_edges().len(),
            non_manifold,
            "{rel}: non-manifold edges"
        );
    }
}

#[test]
fn data_sequences_share_connectivity() {
    let Some(dir) = common::data_dir() else {
        return common::skip("data_sequences_share_connectivity");
    };
    let cat = io::read_animation(&dir.join("lowpoly-cat-dog/cat-run"), None).unwrap();
    assert_eq!(cat.len(), 36);
    assert_eq!(cat.name(0), "cat-run-01.obj.gz");
    let ict: Vec<PathBuf> = ["generic_neutral_mesh", "jawOpen", "eyeBlink_L"]
        .iter()
        .map(|f| common::data_file(&format!("ict-facekit/{f}.obj.gz")).unwrap())
        .collect();
    let set = io::read_shape_set(&ict).unwrap();
    assert_eq!(set.len(), 3);
    // The collapse sequence has another vertex order than the gallop: a clean error.
    let mixed = [
        common::data_file("sumner-horse-gallop/horse-gallop-01.obj.gz").unwrap(),
        common::data_file("sumner-horse-collapse/horse-collapse-01.obj.gz").unwrap(),
    ];
    let e = io::read_shape_set(&mixed).unwrap_err().to_string();
    assert!(e.contains("horse-collapse-01.obj.gz: triangle"), "{e}");
}

#[test]
fn elephant_reads_quickly() {
    let Some(path) = common::data_file("sumner-elephant/elephant-reference.obj.gz") else {
        return common::skip("elephant_reads_quickly");
    };
    let t = std::time::Instant::now();
    let m = io::read_mesh(&path).unwrap();
    let dt = t.elapsed();
    eprintln!("elephant: {} vertices read in {dt:?}", m.num_vertices());
    // "Well under a second" is the release-build target; allow slack for debug builds.
    let limit = if cfg!(debug_assertions) { 5.0 } else { 1.0 };
    assert!(dt.as_secs_f64() < limit, "{dt:?}");
}
