//! Written glTF passes the Khronos glTF validator.
//!
//! Runs only when `MORPHKIT_GLTF_VALIDATOR` points at `tools/gltf-validate/validate.mjs`
//! (after `npm install` in that folder); skips otherwise.

use morphkit::io::{self, FramesOptions, GltfMorphs};
use morphkit::{ShapeSet, TriMesh};
use std::process::Command;

#[test]
fn written_gltf_and_glb_pass_the_khronos_validator() {
    let Some(script) = std::env::var_os("MORPHKIT_GLTF_VALIDATOR") else {
        eprintln!("MORPHKIT_GLTF_VALIDATOR is unset; skipping the glTF validator test");
        return;
    };
    let d = std::env::temp_dir().join(format!("morphkit-io-validator-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    // A small grid, bent in three frames.
    let n = 6;
    let mut pos = Vec::new();
    for j in 0..n {
        for i in 0..n {
            pos.push([i as f64 * 0.2, j as f64 * 0.2, 0.0]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            tris.push([a, a + 1, a + n as u32 + 1]);
            tris.push([a, a + n as u32 + 1, a + n as u32]);
        }
    }
    let base = TriMesh::new(pos.clone(), tris);
    let frame =
        |s: f64| -> Vec<[f64; 3]> { pos.iter().map(|p| [p[0], p[1], s * p[0] * p[0]]).collect() };
    let set = ShapeSet::new(
        base.clone(),
        vec![
            ("rest".into(), frame(0.0)),
            ("up".into(), frame(1.0)),
            ("down".into(), frame(-1.0)),
        ],
    )
    .unwrap();
    let files = [
        d.join("anim.glb"),
        d.join("anim.gltf"),
        d.join("mesh.glb"),
        d.join("rig.glb"),
    ];
    io::write_frames(&files[0], &set, &FramesOptions::default()).unwrap();
    io::write_frames(&files[1], &set, &FramesOptions::default()).unwrap();
    io::write_mesh(&files[2], &base).unwrap();
    let rig = GltfMorphs {
        base,
        target_names: vec!["up".into()],
        targets: vec![frame(1.0)],
        weight_keys: Vec::new(),
    };
    io::write_gltf_morphs(&files[3], &rig).unwrap();
    let out = Command::new("node")
        .arg(&script)
        .args(&files)
        .output()
        .expect("run node");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "validator failed:\n{text}");
    for f in &files {
        let line = text
            .lines()
            .find(|l| l.starts_with(&f.display().to_string()))
            .unwrap_or_else(|| panic!("no report for {}", f.display()));
        assert!(line.contains(": 0 errors, 0 warnings"), "{line}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
