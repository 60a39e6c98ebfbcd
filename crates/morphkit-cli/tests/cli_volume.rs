//! `morphkit blend --interior … --anchor …`, run as the built binary.

mod common;
use common::*;

#[test]
fn interior_and_anchor_blend_writes_frames_and_reports_inversions() {
    let d = tmp_dir("volume-bar");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let (out, report) = (d.join("frames"), d.join("r.json"));
    ok(&blend_args(
        &base,
        &target,
        &[
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
        ],
    ));
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
    let (_, err) = run_ok(&blend_args(
        &base,
        &target,
        &["--alpha", "0.5", "--interior", "lattice", "--out", s(&out)],
    ));
    // The tube's end holes are small: capped for the inside test, the tube gets its interior.
    assert!(!err.contains("has no interior"), "{err}");
    assert!(out.is_file());
    // A flat patch's outline is no small hole: it has no interior, and the blend says so.
    let patch = generate::grid(12, 12, 4.0, 1.0);
    let patch_bent = patch.with_positions(generate::bend(&patch.positions, 2.0, 2.0, 1.0));
    let (pa, pb) = (d.join("patch-a.obj"), d.join("patch-b.obj"));
    morphkit::io::write_mesh(&pa, &patch).unwrap();
    morphkit::io::write_mesh(&pb, &patch_bent).unwrap();
    let (_, err) = run_ok(&blend_args(
        &pa,
        &pb,
        &[
            "--alpha",
            "0.5",
            "--interior",
            "lattice",
            "--out",
            s(&d.join("patch.obj")),
        ],
    ));
    assert!(err.contains("has no interior (open)"), "{err}");
    // Without tetgen on the PATH (an empty PATH for this child only): a clear error.
    let args = [
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
    ];
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .args(args)
        .env("PATH", "")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        err.starts_with("error: ")
            && err.contains("--interior tetgen: no tetgen executable on the PATH")
            && !err.contains("panicked"),
        "{err}"
    );
    // tetgen needs a closed surface: the open tube is blended on its surface alone and says so.
    if have_tetgen() {
        let (_, err) = run_ok(&args);
        assert!(err.contains("tetgen needs a closed surface"), "{err}");
    }
    let err = fails(&blend_args(
        &base,
        &target,
        &["--alpha", "0.5", "--interior", "voxels", "--out", s(&out)],
    ));
    assert!(err.contains("unknown kind"), "{err}");
}

/// True when `tetgen` is on the PATH; a missing one fails under `MORPHKIT_REQUIRE_TETGEN=1`.
fn have_tetgen() -> bool {
    let found = morphkit::springs::interior::tetgen::find_program(None).is_ok();
    assert!(
        found || std::env::var("MORPHKIT_REQUIRE_TETGEN").as_deref() != Ok("1"),
        "MORPHKIT_REQUIRE_TETGEN=1 but no tetgen on the PATH"
    );
    if !found {
        eprintln!("no tetgen on the PATH; skipping the tetgen runs");
    }
    found
}

#[test]
fn a_tetgen_interior_blend_reports_its_tetrahedra() {
    if !have_tetgen() {
        return;
    }
    let d = tmp_dir("volume-tetgen");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let (out, report) = (d.join("frames"), d.join("r.json"));
    ok(&blend_args(
        &base,
        &target,
        &[
            "--frames",
            "3",
            "--interior",
            "tetgen,1.5",
            "--out",
            s(&out),
            "--report",
            s(&report),
        ],
    ));
    assert!(out.join("frame_0002.obj").is_file());
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let tets = r["interior"]["tetrahedra"].as_u64().unwrap();
    assert!(tets > 0, "{r}");
    for f in r["frames"].as_array().unwrap() {
        assert_eq!(
            f["inversions"]["tetrahedra_total"].as_u64(),
            Some(tets),
            "{f}"
        );
        assert_eq!(f["solver"]["converged"], true);
    }
}
