//! Issue 56: `GltfOptions::meshopt` (`EXT_meshopt_compression`) applies to every glTF output
//! morphkit writes whole: a rig with one target per frame (f32, quantized, sparse), a compact
//! clip and a split animation. Compression is lossless (the file reads back to the very bits
//! of the same file written without it), shrinks the file, codes a morph-weight output a key
//! at a time, and passes the Khronos validator (`MORPHKIT_GLTF_VALIDATOR`) without errors or
//! warnings.

use morphkit::io::{self, FrameLayout, FramesOptions, GltfMorphs, GltfOptions};
use morphkit::mesh::generate;
use morphkit::ShapeSet;
use serde_json::Value;
use std::path::{Path, PathBuf};

#[path = "common/gltf_asset.rs"]
mod fixture;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "morphkit-gltf-meshopt-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `n` frames of a tube whose far half bends to `angle` radians with a ripple.
fn tube_frames(n: usize, angle: f64) -> ShapeSet {
    let tube = generate::tube(0.5, 4.0, 16, 24, false);
    let shapes = (0..n)
        .map(|k| {
            let a = angle * (k as f64 / (n.max(2) - 1) as f64);
            let mut p = generate::bend(&tube.positions, 2.0, 2.0, a);
            for (v, q) in p.iter_mut().enumerate() {
                if tube.positions[v][0] > 2.0 {
                    q[1] += 0.02 * (0.3 * k as f64 + v as f64 * 0.1).sin();
                }
            }
            (format!("f{k:03}"), p)
        })
        .collect();
    ShapeSet::new(tube, shapes).unwrap()
}

fn glb_json(path: &Path) -> Value {
    let b = std::fs::read(path).unwrap();
    let jl = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + jl]).unwrap()
}

/// The two reads are the same bits: base, targets, names and keys.
fn assert_same(a: &GltfMorphs, b: &GltfMorphs, what: &str) {
    assert_eq!(a.base.positions, b.base.positions, "{what}: base");
    assert_eq!(a.base.triangles, b.base.triangles, "{what}: triangles");
    assert_eq!(a.target_names, b.target_names, "{what}: names");
    assert_eq!(a.targets, b.targets, "{what}: targets");
    assert_eq!(a.weight_keys, b.weight_keys, "{what}: keys");
}

/// Writes `frames` with `gltf` and again with `meshopt` on; returns both paths.
fn pair(d: &Path, name: &str, frames: &ShapeSet, gltf: GltfOptions) -> (PathBuf, PathBuf) {
    let plain = d.join(format!("{name}.glb"));
    let packed = d.join(format!("{name}-meshopt.glb"));
    for (p, meshopt) in [(&plain, false), (&packed, true)] {
        let opts = FramesOptions {
            fps: 30.0,
            gltf: GltfOptions {
                meshopt,
                ..gltf.clone()
            },
            ..FramesOptions::default()
        };
        io::write_frames(p, frames, &opts).unwrap();
    }
    (plain, packed)
}

fn variants(d: &Path) -> Vec<(String, PathBuf, PathBuf)> {
    let frames = tube_frames(40, 1.2);
    let long = tube_frames(260, 1.2);
    let per_frame = GltfOptions {
        layout: FrameLayout::PerFrame,
        ..GltfOptions::default()
    };
    let mut out = Vec::new();
    for (name, frames, gltf) in [
        ("f32", &frames, per_frame.clone()),
        (
            "quantized",
            &frames,
            GltfOptions {
                quantize: true,
                ..per_frame.clone()
            },
        ),
        (
            "sparse",
            &frames,
            GltfOptions {
                sparse_targets: true,
                ..per_frame.clone()
            },
        ),
        (
            "split",
            &frames,
            GltfOptions {
                max_targets: 16,
                ..per_frame.clone()
            },
        ),
        ("compact", &long, GltfOptions::default()),
        (
            "compact-quantized",
            &long,
            GltfOptions {
                quantize: true,
                ..GltfOptions::default()
            },
        ),
    ] {
        let (a, b) = pair(d, name, frames, gltf);
        out.push((name.to_string(), a, b));
    }
    out
}

#[test]
fn meshopt_outputs_read_back_to_the_same_bits_and_are_smaller() {
    let d = tmp_dir("roundtrip");
    for (name, plain, packed) in variants(&d) {
        let (a, b) = (
            io::read_gltf_morphs(&plain).unwrap(),
            io::read_gltf_morphs(&packed).unwrap(),
        );
        assert_same(&a, &b, &name);
        let (sa, sb) = (
            std::fs::metadata(&plain).unwrap().len(),
            std::fs::metadata(&packed).unwrap().len(),
        );
        // Sparse targets hold only the moving vertices' deltas, which code less well than a
        // whole mesh's; everything else shrinks by a quarter at least.
        let bound = if name == "sparse" {
            sa * 9 / 10
        } else {
            sa * 3 / 4
        };
        assert!(sb < bound, "{name}: {sb} bytes with meshopt, {sa} without");
        let doc = glb_json(&packed);
        for key in ["extensionsUsed", "extensionsRequired"] {
            assert!(
                doc[key]
                    .as_array()
                    .is_some_and(|l| l.iter().any(|e| e == "EXT_meshopt_compression")),
                "{name}: {key}"
            );
        }
        assert_eq!(
            doc["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"],
            true
        );
        assert!(
            doc["buffers"][1].get("uri").is_none(),
            "{name}: the fallback has no data"
        );
        let compressed: Vec<&Value> = doc["bufferViews"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|v| v["extensions"].get("EXT_meshopt_compression"))
            .collect();
        assert!(
            compressed.len() >= 2,
            "{name}: {} views compressed",
            compressed.len()
        );
        // Index buffers stay as they are.
        for v in doc["bufferViews"].as_array().unwrap() {
            if v["target"] == 34963 {
                assert!(v.get("extensions").is_none(), "{name}: indices compressed");
            }
        }
        eprintln!("{name}: {sa} → {sb} bytes ({:.2}×)", sa as f64 / sb as f64);
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_compact_clips_weights_are_coded_a_key_at_a_time() {
    let d = tmp_dir("keys");
    let (_, packed) = pair(
        &d,
        "compact",
        &tube_frames(260, 1.2),
        GltfOptions::default(),
    );
    let doc = glb_json(&packed);
    let anim = &doc["animations"][0];
    let ch = anim["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["path"] == "weights")
        .expect("a weights channel");
    let sampler = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
    let output = &doc["accessors"][sampler["output"].as_u64().unwrap() as usize];
    let keys = doc["accessors"][sampler["input"].as_u64().unwrap() as usize]["count"]
        .as_u64()
        .unwrap();
    let per_key = output["count"].as_u64().unwrap() / keys;
    assert!(per_key >= 2, "{per_key} shapes");
    let view = &doc["bufferViews"][output["bufferView"].as_u64().unwrap() as usize];
    let ext = &view["extensions"]["EXT_meshopt_compression"];
    assert_eq!(ext["byteStride"], 4 * per_key, "{view}");
    assert_eq!(ext["count"], keys, "{view}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn meshopt_files_pass_the_khronos_validator() {
    let d = tmp_dir("validate");
    let mut files: Vec<PathBuf> = variants(&d).into_iter().map(|v| v.2).collect();
    // And as .gltf, the data as a data URI beside the fallback buffer.
    let gltf_opts = GltfOptions {
        quantize: true,
        layout: FrameLayout::PerFrame,
        ..GltfOptions::default()
    };
    let (plain, _) = pair(&d, "small", &tube_frames(12, 1.0), gltf_opts.clone());
    let gltf = d.join("quantized-meshopt.gltf");
    let opts = FramesOptions {
        fps: 30.0,
        gltf: GltfOptions {
            meshopt: true,
            ..gltf_opts
        },
        ..FramesOptions::default()
    };
    io::write_frames(&gltf, &tube_frames(12, 1.0), &opts).unwrap();
    assert_same(
        &io::read_gltf_morphs(&gltf).unwrap(),
        &io::read_gltf_morphs(&plain).unwrap(),
        "gltf",
    );
    files.push(gltf);
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    fixture::assert_valid(&refs);
    let _ = std::fs::remove_dir_all(&d);
}
