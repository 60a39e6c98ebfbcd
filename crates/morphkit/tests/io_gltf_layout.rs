//! Issue 15: glTF animations at production scale. Storage linear in the frame count (sparse
//! weights, frame 0 as the base), normals, material, names, extras, and long animations split
//! into meshes of at most `max_targets` targets that read back as the same frames.

use morphkit::io::{self, FramesOptions, GltfMorphs, GltfOptions};
use morphkit::mesh::generate;
use morphkit::ShapeSet;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "morphkit-gltf-layout-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `n` frames of an open tube bending from straight to 120°.
fn tube_frames(n: usize) -> ShapeSet {
    let tube = generate::tube(0.5, 4.0, 12, 16, false);
    let shapes = (0..n)
        .map(|k| {
            let a = 2.0 * k as f64 / (n.max(2) - 1) as f64;
            (
                format!("f{k:05}.obj"),
                generate::bend(&tube.positions, 0.0, 2.0, a),
            )
        })
        .collect();
    ShapeSet::new(tube, shapes).unwrap()
}

/// The JSON chunk and the BIN chunk of a GLB file.
fn glb(path: &Path) -> (Value, Vec<u8>) {
    let b = std::fs::read(path).unwrap();
    let jl = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    let doc = serde_json::from_slice(&b[20..20 + jl]).unwrap();
    let bin = b[20 + jl + 8..].to_vec();
    (doc, bin)
}

/// The f32 VEC3 values of a (dense) accessor.
fn vec3(doc: &Value, bin: &[u8], acc: usize) -> Vec<[f32; 3]> {
    let a = &doc["accessors"][acc];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let off = v["byteOffset"].as_u64().unwrap_or(0) as usize;
    let n = a["count"].as_u64().unwrap() as usize;
    (0..n)
        .map(|i| {
            let f = |k: usize| {
                let o = off + 12 * i + 4 * k;
                f32::from_le_bytes(bin[o..o + 4].try_into().unwrap())
            };
            [f(0), f(1), f(2)]
        })
        .collect()
}

/// One target per frame (a compact clip is `compact_frames.rs`'s and `cli_compact_frames.rs`'s).
fn opts(max_targets: usize) -> FramesOptions {
    FramesOptions {
        gltf: GltfOptions {
            max_targets,
            layout: io::FrameLayout::PerFrame,
            ..GltfOptions::default()
        },
        ..FramesOptions::default()
    }
}

fn max_err(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn size_is_linear_in_the_frame_count_and_frame_0_is_the_base() {
    let d = tmp_dir("linear");
    let mut sizes = Vec::new();
    for n in [50, 100, 200] {
        let p = d.join(format!("t{n}.glb"));
        io::write_frames(&p, &tube_frames(n), &opts(0)).unwrap();
        sizes.push(std::fs::metadata(&p).unwrap().len() as f64);
        let (doc, _) = glb(&p);
        let mesh = &doc["meshes"][0];
        assert_eq!(
            mesh["primitives"][0]["targets"].as_array().unwrap().len(),
            n - 1
        );
        // The weights output is sparse: n − 1 nonzero values for n keys × (n − 1) targets.
        let out = doc["animations"][0]["samplers"][0]["output"]
            .as_u64()
            .unwrap() as usize;
        let acc = &doc["accessors"][out];
        assert_eq!(acc["count"], n * (n - 1));
        assert!(acc.get("bufferView").is_none());
        assert_eq!(acc["sparse"]["count"], n - 1);
    }
    // Equal steps in frames give equal steps in bytes (a quadratic term would double them).
    let (a, b) = (sizes[1] - sizes[0], sizes[2] - sizes[1]);
    assert!((b / a - 2.0).abs() < 0.01, "sizes {sizes:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn targets_are_nonzero_normals_unit_and_names_kept() {
    let d = tmp_dir("normals");
    let f = tube_frames(6);
    let p = d.join("t.glb");
    let mut o = opts(0);
    o.gltf.name = "tube-bend".into();
    o.gltf.clip_name = Some("tube-bend-blend".into());
    o.gltf.extras = Some(serde_json::json!({"command": "test"}));
    io::write_frames(&p, &f, &o).unwrap();
    let (doc, bin) = glb(&p);
    let prim = &doc["meshes"][0]["primitives"][0];
    let base = vec3(
        &doc,
        &bin,
        prim["attributes"]["POSITION"].as_u64().unwrap() as usize,
    );
    let f0: Vec<[f32; 3]> = f.positions(0).iter().map(|q| q.map(|x| x as f32)).collect();
    assert_eq!(base, f0, "the base is frame 0");
    let normals = vec3(
        &doc,
        &bin,
        prim["attributes"]["NORMAL"].as_u64().unwrap() as usize,
    );
    assert_eq!(normals.len(), base.len());
    for n in &normals {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-6, "normal {n:?}");
    }
    for (t, target) in prim["targets"].as_array().unwrap().iter().enumerate() {
        let dp = vec3(&doc, &bin, target["POSITION"].as_u64().unwrap() as usize);
        assert!(
            dp.iter().flatten().any(|&x| x != 0.0),
            "target {t} is all zero"
        );
        assert!(
            target.get("NORMAL").is_some(),
            "target {t} has normal deltas"
        );
    }
    assert_eq!(doc["nodes"][0]["name"], "tube-bend");
    assert_eq!(doc["meshes"][0]["name"], "tube-bend");
    assert_eq!(doc["animations"][0]["name"], "tube-bend-blend");
    assert_eq!(doc["scenes"][0]["extras"]["command"], "test");
    assert_eq!(
        doc["meshes"][0]["extras"]["targetNames"],
        serde_json::json!(["f00001", "f00002", "f00003", "f00004", "f00005"])
    );
    let mat = &doc["materials"][0];
    assert_eq!(prim["material"], 0);
    assert_eq!(mat["doubleSided"], true, "an open tube is double-sided");
    assert!(mat["pbrMetallicRoughness"]["baseColorFactor"].is_array());
    // A closed mesh is single-sided; no normals on request.
    let sphere = generate::uv_sphere(1.0, 8, 12);
    let q = d.join("s.glb");
    let rig = GltfMorphs {
        base: sphere,
        ..GltfMorphs::default()
    };
    let no_normals = GltfOptions {
        normals: false,
        ..GltfOptions::default()
    };
    io::write_gltf_with(&q, &rig, &no_normals).unwrap();
    let (doc, _) = glb(&q);
    assert_eq!(doc["materials"][0]["doubleSided"], false);
    assert!(doc["meshes"][0]["primitives"][0]["attributes"]
        .get("NORMAL")
        .is_none());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_rig_keeps_its_target_names_and_frames_equal_to_frame_0_are_no_targets() {
    let f = tube_frames(3);
    let still = ShapeSet::new(
        f.base().clone(),
        vec![
            ("a".into(), f.positions(0).to_vec()),
            ("b".into(), f.positions(0).to_vec()),
            ("c".into(), f.positions(2).to_vec()),
        ],
    )
    .unwrap();
    let rig = io::frames_to_gltf(&still, 24.0);
    assert_eq!(rig.target_names, ["c"]);
    assert_eq!(rig.weight_keys.len(), 3);
    assert_eq!(rig.weight_keys[1].1, [0.0], "frame b is the base");
}

#[test]
fn a_long_animation_splits_and_reads_back_as_the_same_frames() {
    let d = tmp_dir("split");
    let n = 450;
    let f = tube_frames(n);
    let p = d.join("long.glb");
    let summary = io::write_gltf_with(
        &p,
        &io::frames_to_gltf(&f, 24.0),
        &GltfOptions {
            max_targets: 200,
            ..GltfOptions::default()
        },
    )
    .unwrap();
    assert_eq!(summary.meshes, 3);
    assert_eq!(summary.targets, n - 1);
    let (doc, _) = glb(&p);
    let meshes = doc["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 3);
    for m in meshes {
        assert!(m["primitives"][0]["targets"].as_array().unwrap().len() <= 200);
    }
    // Every node but the first starts hidden; each has a STEP scale channel.
    assert_eq!(doc["nodes"][1]["scale"], serde_json::json!([0.0, 0.0, 0.0]));
    let steps = doc["animations"][0]["samplers"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["interpolation"] == "STEP")
        .count();
    assert_eq!(steps, 3);
    // Base positions and targets are stored once, whatever the split.
    let unsplit = d.join("unsplit.glb");
    io::write_frames(&unsplit, &f, &opts(0)).unwrap();
    let (a, b) = (
        std::fs::metadata(&p).unwrap().len(),
        std::fs::metadata(&unsplit).unwrap().len(),
    );
    assert!((a as f64) < 1.01 * b as f64, "split {a} bytes, unsplit {b}");
    let back = io::read_animation(&p, None).unwrap();
    assert_eq!(back.len(), n);
    let tol = 1e-6 * f.base().bbox_diagonal();
    for k in 0..n {
        let e = max_err(back.positions(k), f.positions(k));
        assert!(e < tol, "frame {k}: {e}");
    }
    assert_eq!(back.name(n - 1), "f00449");
    let rig = io::read_gltf_morphs(&p).unwrap();
    assert_eq!(rig.targets.len(), n - 1);
    assert!((rig.weight_keys[n - 1].0 - (n - 1) as f64 / 24.0).abs() < 1e-5);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn split_and_unsplit_files_pass_the_khronos_validator() {
    let Some(script) = std::env::var_os("MORPHKIT_GLTF_VALIDATOR") else {
        eprintln!("MORPHKIT_GLTF_VALIDATOR is unset; skipping the glTF validator test");
        return;
    };
    let d = tmp_dir("validate");
    let f = tube_frames(30);
    let files = [d.join("split.glb"), d.join("split.gltf"), d.join("one.glb")];
    io::write_frames(&files[0], &f, &opts(8)).unwrap();
    io::write_frames(&files[1], &f, &opts(8)).unwrap();
    io::write_frames(&files[2], &f, &opts(0)).unwrap();
    let out = std::process::Command::new("node")
        .arg(&script)
        .args(&files)
        .output()
        .expect("run node");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    for p in &files {
        let line = text
            .lines()
            .find(|l| l.starts_with(&p.display().to_string()))
            .unwrap_or_else(|| panic!("no report for {}", p.display()));
        assert!(line.contains(": 0 errors, 0 warnings"), "{line}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_corrupt_split_rig_is_an_error_naming_the_file() {
    let d = tmp_dir("corrupt");
    let p = d.join("s.gltf");
    io::write_frames(&p, &tube_frames(12), &opts(4)).unwrap();
    let mut doc: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    doc["meshes"][1]["extras"]["morphkitTargets"][0] = serde_json::json!(u64::MAX);
    std::fs::write(&p, doc.to_string()).unwrap();
    let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
    assert!(e.contains("s.gltf") && e.contains("morphkitTargets"), "{e}");
    doc["meshes"][1]["extras"]["morphkitTargets"] = serde_json::json!([0, 1]);
    std::fs::write(&p, doc.to_string()).unwrap();
    let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
    assert!(e.contains("s.gltf") && e.contains("mesh 1"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
