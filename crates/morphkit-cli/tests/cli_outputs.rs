//! Issue 15: animation outputs from the command line: `.usda` wherever sequences are written,
//! `--max-targets` and `--no-normals`, names from the inputs and the subcommand, extras with
//! the command, rigs as UsdSkel blend shapes, and `--help` saying what the clip lasts.

mod common;
use common::*;
use std::path::Path;

/// Writes `n` OBJ frames of a strip of 4 quads bending upwards into `dir`, named `wave-NN.obj`.
fn write_frames(dir: &Path, n: usize) {
    std::fs::create_dir_all(dir).unwrap();
    for k in 0..n {
        let bend = k as f64 * 0.1;
        let mut t = String::new();
        for i in 0..=4 {
            let x = i as f64 / 4.0;
            t += &format!("v {x} 0 {}\nv {x} 1 {}\n", bend * x * x, bend * x * x);
        }
        for i in 0..4 {
            let a = 2 * i + 1;
            t += &format!("f {} {} {} {}\n", a, a + 2, a + 3, a + 1);
        }
        std::fs::write(dir.join(format!("wave-{k:02}.obj")), t).unwrap();
    }
}

fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}

#[test]
fn sequences_convert_to_usda_and_back() {
    let d = tmp_dir("out-usda");
    write_frames(&d.join("seq"), 6);
    let pattern = format!("{}/seq/wave-*.obj", d.display());
    ok(&["convert", &pattern, "--fps", "30", s(&d.join("wave.usda"))]);
    let text = std::fs::read_to_string(d.join("wave.usda")).unwrap();
    assert!(
        text.contains("def Xform \"wave\""),
        "named after the inputs"
    );
    assert!(text.contains("timeCodesPerSecond = 30") && text.contains("endTimeCode = 5"));
    assert!(
        text.contains("int[] faceVertexCounts = [4, 4, 4, 4]"),
        "quads kept"
    );
    assert!(
        text.contains("\\\"subcommand\\\":\\\"convert\\\""),
        "provenance in customLayerData"
    );
    ok(&["convert", s(&d.join("wave.usda")), s(&d.join("back"))]);
    let last = std::fs::read_to_string(d.join("back/frame_0005.obj")).unwrap();
    let orig = std::fs::read_to_string(d.join("seq/wave-05.obj")).unwrap();
    assert_eq!(last.lines().filter(|l| l.starts_with("f ")).count(), 4);
    let z = |t: &str| -> f64 {
        t.lines()
            .rfind(|l| l.starts_with("v "))
            .unwrap()
            .split_whitespace()
            .nth(3)
            .unwrap()
            .parse()
            .unwrap()
    };
    assert!((z(&last) - z(&orig)).abs() < 1e-6);
    // A single-mesh output of .usda is refused for a sequence only when it is not .usda.
    let e = fails(&["convert", &pattern, s(&d.join("x.ply"))]);
    assert!(e.contains(".usda"), "{e}");
    if let Some(script) = std::env::var_os("MORPHKIT_USD_CHECK") {
        let out = std::process::Command::new("python3")
            .arg(script)
            .args(["--frames", "6"])
            .arg(d.join("wave.usda"))
            .output()
            .unwrap();
        let t = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && t.contains(": 0 errors"), "{t}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn blend_writes_usda_and_split_glb_with_names_extras_and_a_warning() {
    let d = tmp_dir("out-blend");
    write_frames(&d.join("seq"), 2);
    let (base, target) = (d.join("seq/wave-00.obj"), d.join("seq/wave-01.obj"));
    let blend = |out: &Path, extra: &[&str]| {
        let mut a = vec![
            "blend",
            "--base",
            s(&base),
            "--target",
            s(&target),
            "--frames",
            "12",
            "--linear",
            "--out",
            s(out),
        ];
        a.extend_from_slice(extra);
        run_ok(&a).1
    };
    blend(&d.join("b.usda"), &[]);
    let text = std::fs::read_to_string(d.join("b.usda")).unwrap();
    assert_eq!(text.matches("point3f[] points").count(), 2);
    assert!(text.contains("endTimeCode = 11"));
    // One target per frame (shorter than a compact clip would be: cli_compact_frames.rs).
    let err = blend(
        &d.join("b.glb"),
        &["--max-targets", "4", "--per-frame-targets"],
    );
    assert!(
        err.contains("11 morph targets") && err.contains("4") && err.contains("4 meshes"),
        "{err}"
    );
    let doc = glb_json(&d.join("b.glb"));
    assert_eq!(doc["meshes"].as_array().unwrap().len(), 4);
    assert_eq!(doc["nodes"][0]["name"], "wave.0");
    assert_eq!(doc["animations"][0]["name"], "wave-blend");
    let x = &doc["scenes"][0]["extras"]["morphkit"];
    assert_eq!(x["subcommand"], "blend");
    assert!(x["command"].as_str().unwrap().contains("--max-targets 4"));
    assert_eq!(x["weights"].as_array().unwrap().len(), 12);
    assert_eq!(x["sources"][0], s(&base));
    assert!(doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].is_u64());
    blend(&d.join("flat.glb"), &["--no-normals"]);
    let doc = glb_json(&d.join("flat.glb"));
    assert_eq!(doc["meshes"].as_array().unwrap().len(), 1);
    assert!(doc["meshes"][0]["primitives"][0]["attributes"]
        .get("NORMAL")
        .is_none());
    // The split file reads back as all 12 frames.
    ok(&["convert", s(&d.join("b.glb")), s(&d.join("frames"))]);
    assert!(d.join("frames/frame_0011.obj").is_file());
    assert!(!d.join("frames/frame_0012.obj").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_rig_without_animation_becomes_usdskel_blend_shapes() {
    let d = tmp_dir("out-skel");
    write_frames(&d.join("seq"), 3);
    // A rig: base and two targets, no animation (glTF written by the library).
    let set = morphkit::io::read_shape_set(&[
        d.join("seq/wave-00.obj"),
        d.join("seq/wave-01.obj"),
        d.join("seq/wave-02.obj"),
    ])
    .unwrap();
    let rig = morphkit::io::GltfMorphs {
        base: set.base().clone(),
        target_names: vec!["smile".into(), "jaw open".into()],
        targets: vec![set.positions(1).to_vec(), set.positions(2).to_vec()],
        weight_keys: Vec::new(),
    };
    morphkit::io::write_gltf_morphs(&d.join("rig.glb"), &rig).unwrap();
    ok(&["convert", s(&d.join("rig.glb")), s(&d.join("rig.usda"))]);
    let text = std::fs::read_to_string(d.join("rig.usda")).unwrap();
    assert!(text.contains("uniform token[] skel:blendShapes = [\"smile\", \"jaw open\"]"));
    assert!(text.contains("def BlendShape \"jaw_open\""));
    if let Some(script) = std::env::var_os("MORPHKIT_USD_CHECK") {
        let out = std::process::Command::new("python3")
            .arg(script)
            .args(["--blendshapes", "smile,jaw open"])
            .arg(d.join("rig.usda"))
            .output()
            .unwrap();
        let t = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && t.contains(": 0 errors"), "{t}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn help_says_what_the_clip_lasts_and_how_targets_are_limited() {
    for cmd in ["blend", "convert"] {
        let h = ok(&[cmd, "--help"]);
        assert!(h.contains("24"), "{cmd}: {h}");
        assert!(h.contains("(N − 1)/fps"), "{cmd}: {h}");
        assert!(h.contains("--max-targets"), "{cmd}: {h}");
        assert!(h.contains(".usda"), "{cmd}: {h}");
    }
}
