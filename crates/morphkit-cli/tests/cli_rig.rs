//! `morphkit rig` (issue 9): a blendshape rig moved onto another mesh, run as the built binary
//! on generated tubes. The output GLB must carry one morph target per source shape, named by
//! file stem, in the order given; `--shapes-dir` and `--report` must match it; a bad output
//! is refused before any work. With `MORPHKIT_GLTF_VALIDATOR` set the GLB goes through the
//! Khronos validator.

mod common;
use common::*;

use std::path::Path;
use std::process::Command;

/// The rig tests' tube: 10 × 8 vertices.
fn write_tube(path: &Path, scale: f64, bend: f64) {
    common::write_tube(path, 10, 8, scale, bend);
}

/// A GLB's JSON (without `scenes[0].extras.morphkit.command`) and its binary chunk.
fn glb_parts(b: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&b[20..20 + len]).unwrap();
    if let Some(m) = json["scenes"][0]["extras"]["morphkit"].as_object_mut() {
        m.remove("command");
    }
    (json, b[20 + len..].to_vec())
}

#[test]
fn rig_writes_named_morph_targets_shapes_and_a_report() {
    let d = tmp_dir("rig");
    let expr = d.join("expr");
    std::fs::create_dir_all(&expr).unwrap();
    write_tube(&d.join("neutral.obj"), 1.0, 0.0);
    // Names sort as the glob expands them: a_bend, b_small, c_neutral.
    write_tube(&expr.join("a_bend.obj"), 1.0, 0.8);
    write_tube(&expr.join("b_small.obj"), 1.0, 0.2);
    write_tube(&expr.join("c_neutral.obj"), 1.0, 0.0);
    write_tube(&d.join("target.obj"), 2.0, 0.0);
    // Identity markers on rings 0, 3 and 7 (the tube's vertices keep their ids).
    let pairs: Vec<[u32; 2]> = [0u32, 3, 5, 30, 33, 36, 70, 73, 77]
        .iter()
        .map(|&v| [v, v])
        .collect();
    std::fs::write(
        d.join("m.json"),
        serde_json::json!({ "pairs": pairs }).to_string(),
    )
    .unwrap();
    let glob = format!("{}/*.obj", expr.display());
    let out = d.join("rig.glb");
    let shapes = d.join("shapes");
    let report = d.join("rig.json");
    ok(&[
        "rig",
        "--source-neutral",
        s(&d.join("neutral.obj")),
        "--source-shapes",
        &glob,
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&out),
        "--shapes-dir",
        s(&shapes),
        "--report",
        s(&report),
    ]);
    let rig = morphkit::io::read_gltf_morphs(&out).unwrap();
    assert_eq!(rig.target_names, ["a_bend", "b_small", "c_neutral"]);
    let target = morphkit::io::read_mesh(&d.join("target.obj")).unwrap();
    assert_eq!(rig.base.positions.len(), target.positions.len());
    // The neutral shape gives a zero delta (no root motion); the bend moves the tip.
    let delta = |k: usize| {
        rig.targets[k]
            .iter()
            .zip(&rig.base.positions)
            .map(|(a, b)| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max)
    };
    assert!(delta(2) < 1e-5, "neutral delta {}", delta(2));
    assert!(
        delta(0) > 0.5 && delta(0) > 2.0 * delta(1),
        "{} {}",
        delta(0),
        delta(1)
    );
    for n in ["a_bend", "b_small", "c_neutral"] {
        let m = morphkit::io::read_mesh(&shapes.join(format!("{n}.obj"))).unwrap();
        assert_eq!(m.num_vertices(), target.num_vertices());
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["per_shape"].as_array().unwrap().len(), 3);
    assert_eq!(r["per_shape"][1]["name"], "b_small");
    assert!(r["per_shape"][0]["seconds"].as_f64().unwrap() >= 0.0);
    assert!(r["per_shape"][0]["flipped_triangles"].is_u64());
    if let Some(script) = std::env::var_os("MORPHKIT_GLTF_VALIDATOR") {
        let st = Command::new("node").arg(script).arg(&out).status().unwrap();
        assert!(st.success(), "the Khronos validator rejects the rig");
    }
    // Same input, same bytes.
    let again = d.join("again.glb");
    ok(&[
        "rig",
        "--source-neutral",
        s(&d.join("neutral.obj")),
        "--source-shapes",
        &glob,
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&again),
    ]);
    // Same bytes but for the command line in the extras (its --out differs).
    let (j1, b1) = glb_parts(&std::fs::read(&out).unwrap());
    let (j2, b2) = glb_parts(&std::fs::read(&again).unwrap());
    assert_eq!(b1, b2, "binary chunks differ");
    assert_eq!(j1, j2, "JSON chunks differ beyond the command line");
    // A GLB with morph targets as the source: its names and base are used.
    let from_glb = d.join("from-glb.glb");
    ok(&[
        "rig",
        "--source-shapes",
        s(&out),
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&from_glb),
    ]);
    let rig2 = morphkit::io::read_gltf_morphs(&from_glb).unwrap();
    assert_eq!(rig2.target_names, rig.target_names);
    // Refused before any work: an OBJ rig, a missing neutral.
    let e = fails(&[
        "rig",
        "--source-neutral",
        s(&d.join("neutral.obj")),
        "--source-shapes",
        &glob,
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&d.join("rig.obj")),
    ]);
    assert!(e.contains(".glb, .gltf or .usda"), "{e}");
    let e = fails(&[
        "rig",
        "--source-shapes",
        &glob,
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&d.join("x.glb")),
    ]);
    assert!(e.contains("--source-neutral"), "{e}");
    assert!(!d.join("x.glb").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn rig_as_usd_blend_shapes() {
    let d = tmp_dir("rig-usd");
    write_tube(&d.join("neutral.obj"), 1.0, 0.0);
    write_tube(&d.join("jawOpen.obj"), 1.0, 0.8);
    write_tube(&d.join("smile.obj"), 1.0, 0.3);
    write_tube(&d.join("head.obj"), 2.0, 0.0);
    let pairs: Vec<[u32; 2]> = [0u32, 3, 5, 30, 33, 36, 70, 73, 77]
        .iter()
        .map(|&v| [v, v])
        .collect();
    std::fs::write(
        d.join("m.json"),
        serde_json::json!({ "pairs": pairs }).to_string(),
    )
    .unwrap();
    let out = d.join("head-rig.usda");
    ok(&[
        "rig",
        "--source-neutral",
        s(&d.join("neutral.obj")),
        "--source-shapes",
        s(&d.join("jawOpen.obj")),
        s(&d.join("smile.obj")),
        "--target",
        s(&d.join("head.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&out),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("skel:blendShapes = [\"jawOpen\", \"smile\"]"),
        "{text}"
    );
    assert!(text.contains("def BlendShape \"jawOpen\""));
    if let Some(script) = std::env::var_os("MORPHKIT_USD_CHECK") {
        let r = Command::new("python3")
            .arg(script)
            .args(["--blendshapes", "jawOpen,smile"])
            .arg(&out)
            .output()
            .unwrap();
        let t = String::from_utf8_lossy(&r.stdout);
        assert!(r.status.success() && t.contains(": 0 errors"), "{t}");
    }
    // Other extensions are refused before any work.
    let e = fails(&[
        "rig",
        "--source-neutral",
        s(&d.join("neutral.obj")),
        "--source-shapes",
        s(&d.join("smile.obj")),
        "--target",
        s(&d.join("head.obj")),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&d.join("rig.pc2")),
    ]);
    assert!(e.contains(".usda"), "{e}");
}
