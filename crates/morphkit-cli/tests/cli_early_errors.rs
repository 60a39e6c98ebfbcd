//! Issue 55 (hardening, third probe): errors that came after all the work. An input clip whose
//! key times do not increase was accepted, every frame solved, and then refused naming the
//! output clip (`Wave-physical`, after a warning pointing to an `OUT-jumps.ply` that was never
//! written); `transfer` of 201 frames onto a `.glb` target was refused for `--max-targets` only
//! after the correspondence and every solve. Both are now refused before any solve (the
//! transfer only where one target per frame is asked for: by default those frames now go into
//! the asset as a compact clip, issue 56).

mod common;
#[path = "../../morphkit/tests/common/gltf_asset.rs"]
mod fixture;

use common::*;
use morphkit::io;

#[test]
fn an_input_clip_out_of_time_order_is_refused_before_any_solve() {
    let d = tmp_dir("early-keys");
    let glb = d.join("in.glb");
    let mut spec = fixture::standard(false, 1.0);
    spec.cubic = false;
    spec.keys = vec![
        (0.0, vec![0.0, 0.0]),
        (0.5, vec![1.0, 0.0]),
        (0.25, vec![0.5, 0.5]),
    ];
    fixture::write(&glb, &spec);
    for out in [d.join("out.glb"), d.join("frames")] {
        let e = fails(&["blend", "--rig", s(&glb), "--out", s(&out)]);
        assert!(
            e.contains(
                "in.glb: animation 0 'Wave': key 2 at 0.25 s does not come after key 1 at 0.5 s"
            ),
            "{e}"
        );
        assert!(!e.contains("Wave-physical") && !e.contains("jumps"), "{e}");
        assert!(!out.exists());
    }
}

#[test]
fn transfer_onto_a_gltf_target_is_refused_for_max_targets_before_any_solve() {
    let d = tmp_dir("early-transfer");
    let glb = d.join("target.glb");
    fixture::write(&glb, &fixture::standard(false, 1.0));
    // The source: the asset's own base and its first target as OBJ, 201 frames between them.
    let rig = io::read_gltf_morphs(&glb).unwrap();
    let (base, bend) = (d.join("base.obj"), d.join("bend.obj"));
    io::write_mesh(&base, &rig.base).unwrap();
    io::write_mesh(&bend, &rig.base.with_positions(rig.targets[0].clone())).unwrap();
    let pc2 = d.join("source.pc2");
    ok(&blend_args(
        &base,
        &bend,
        &["--frames", "201", "--linear", "--out", s(&pc2)],
    ));
    let markers = d.join("markers.json");
    std::fs::write(
        &markers,
        r#"{"pairs": [[0, 0], [30, 30], [90, 90], [119, 119]]}"#,
    )
    .unwrap();
    let out = d.join("out.glb");
    let transfer = [
        "transfer",
        "--source-ref",
        s(&base),
        "--source",
        s(&pc2),
        "--target",
        s(&glb),
        "--markers",
        s(&markers),
        "--out",
        s(&out),
    ];
    let mut per_frame = transfer.to_vec();
    per_frame.push("--per-frame-targets");
    let e = fails(&per_frame);
    assert!(
        e.contains("target.glb: the mesh would have 203 morph targets (2 + 201), more than 200"),
        "{e}"
    );
    // Nothing was welded, matched, factorized or solved first.
    for work in ["welded", "factorized", "transferred"] {
        assert!(!e.contains(work), "{work}: {e}");
    }
    assert!(!out.exists());
    // Allowed, the same command does the work and writes the asset.
    let mut allowed = vec!["--max-targets", "0"];
    allowed.extend(per_frame);
    let (_, err) = run_ok(&allowed);
    assert!(err.contains("factorized") && out.exists(), "{err}");
    assert_eq!(io::read_gltf_morphs(&out).unwrap().targets.len(), 203);
    std::fs::remove_file(&out).unwrap();
    // By default, the 201 frames go into the asset as a compact clip: the asset's two targets
    // and a few of the frames' displacements, played within the default tolerance.
    let report = d.join("report.json");
    let mut compact = transfer.to_vec();
    compact.extend(["--report", s(&report)]);
    let (_, err) = run_ok(&compact);
    assert!(err.contains("targets of their displacements"), "{err}");
    let written = io::read_gltf_morphs(&out).unwrap();
    let added = written.targets.len() - 2;
    assert!((1..=20).contains(&added), "{added} targets added");
    assert_eq!(written.target_names[..2], rig.target_names[..]);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let clip = &r["clip"];
    assert_eq!(clip["kind"], "compact", "{r}");
    let error = clip["max_error"].as_f64().unwrap();
    assert!(error > 0.0 && error <= 1e-3, "{clip}");
}
