//! `morphkit blend --interior … --anchor …`, run as the built binary.

mod common;
use common::*;

#[test]
fn interior_and_anchor_blend_writes_frames_and_reports_inversions() {
    let d = tmp_dir("volume-bar");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let (out, report) = (d.join("frames"), d.join("r.json"));
    ok(&[
        "blend",
        "--base",
        s(&base),
        "--target",
        s(&target),
        "--frames",
        "5",
        "--interior",
        "lattice,2",
        "--anchor",
        "auto",
        "--out",
        s(&out),
        "--report",
        s(&report),
    ]);
    assert!(out.join("frame_0004.obj").is_file());
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["method"], "physical-volumetric");
    assert!(
        r["interior"]["interior_vertices"].as_u64().unwrap() > 0,
        "{r}"
    );
    assert_eq!(r["interior"]["anchor_vertices"], 8);
    let frames = r["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for f in frames {
        assert!(f["inversions"]["tetrahedra"].is_u64(), "{f}");
        assert!(f["inversions"]["triangles"].is_u64(), "{f}");
        assert!(f["anchor_rotation"].is_array(), "{f}");
        assert_eq!(f["solver"]["converged"], true);
    }
}

#[test]
fn an_open_mesh_with_a_lattice_is_blended_on_its_surface_and_says_so() {
    use morphkit::mesh::generate;
    let d = tmp_dir("volume-open");
    let m = generate::tube(0.5, 4.0, 12, 16, false);
    let bent = m.with_positions(generate::bend(&m.positions, 2.0, 2.0, 2.0));
    let (base, target, out) = (d.join("a.obj"), d.join("b.obj"), d.join("half.obj"));
    morphkit::io::write_mesh(&base, &m).unwrap();
    morphkit::io::write_mesh(&target, &bent).unwrap();
    let (_, err) = run_ok(&[
        "blend",
        "--base",
        s(&base),
        "--target",
        s(&target),
        "--alpha",
        "0.5",
        "--interior",
        "lattice",
        "--out",
        s(&out),
    ]);
    assert!(err.contains("has no interior (open)"), "{err}");
    assert!(out.is_file());
    let err = fails(&[
        "blend",
        "--base",
        s(&base),
        "--target",
        s(&target),
        "--alpha",
        "0.5",
        "--interior",
        "tetgen",
        "--out",
        s(&out),
    ]);
    assert!(err.contains("tetgen"), "{err}");
    let err = fails(&[
        "blend",
        "--base",
        s(&base),
        "--target",
        s(&target),
        "--alpha",
        "0.5",
        "--interior",
        "voxels",
        "--out",
        s(&out),
    ]);
    assert!(err.contains("unknown kind"), "{err}");
}
