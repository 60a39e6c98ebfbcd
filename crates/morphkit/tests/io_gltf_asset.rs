//! Issue 37, "the asset comes back whole": a user's glTF asset (two meshes, a textured
//! material, UVs, a skin, node transforms, names, extras, an extension, weights animations in
//! LINEAR and CUBICSPLINE) goes through `GltfAsset` read → edits → write, and comes back with
//! everything not edited equal in the JSON, the edited mesh reading back as the asset says,
//! and the Khronos validator (`MORPHKIT_GLTF_VALIDATOR`) reporting no error or warning. The
//! same holds for files made by gltfpack (quantized, meshopt-compressed), when the tools of
//! `tools/gltf-assets` are installed (required with `MORPHKIT_REQUIRE_GLTF_TOOLS`).

#[path = "common/gltf_asset.rs"]
mod fixture;

use morphkit::io::{self, GltfAsset, GltfAssetOptions, GltfReadOptions};
use morphkit::mesh::Point;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-io-asset-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn body() -> GltfReadOptions {
    GltfReadOptions {
        mesh: Some("Body".into()),
    }
}

/// Two frames of a physical-looking animation and a new target, applied to `a`.
fn edit(a: &mut GltfAsset) -> (Vec<Point>, Vec<Vec<Point>>) {
    let base = a.morphs().base.positions.clone();
    let twist: Vec<Point> = base
        .iter()
        .map(|q| {
            let (s, c) = (0.1 * q[2]).sin_cos();
            [c * q[0] - s * q[1], s * q[0] + c * q[1], q[2]]
        })
        .collect();
    a.add_targets(&["twist".into()], std::slice::from_ref(&twist))
        .unwrap();
    let frames: Vec<Vec<Point>> = (0..4)
        .map(|k| {
            base.iter()
                .map(|q| [q[0] + 0.02 * k as f64 * q[2] * q[2], q[1], q[2]])
                .collect()
        })
        .collect();
    a.add_frame_animation("Body-physical", &[0.0, 0.5, 1.0, 1.5], &frames)
        .unwrap();
    (twist, frames)
}

fn close(a: &[Point], b: &[Point], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (0..3).all(|k| (p[k] - q[k]).abs() <= tol))
}

/// `v` without the members `keys`.
fn without(v: &Value, keys: &[&str]) -> Value {
    let mut v = v.clone();
    if let Some(o) = v.as_object_mut() {
        for k in keys {
            o.remove(*k);
        }
    }
    v
}

#[test]
fn a_users_asset_comes_back_whole_with_its_edits() {
    let d = tmp_dir("whole");
    let spec = fixture::standard(true, 1.0);
    let input = d.join("in.glb");
    let doc = fixture::write(&input, &spec);
    let mut ext = spec.clone();
    ext.external = true;
    let input_gltf = d.join("in.gltf");
    fixture::write(&input_gltf, &ext);
    fixture::assert_valid(&[&input, &input_gltf]);
    for src in [&input, &input_gltf] {
        let mut a = GltfAsset::read(src, &body()).unwrap();
        let before = a.clone();
        let (twist, frames) = edit(&mut a);
        let outs = [d.join("out.glb"), d.join("out.gltf")];
        for out in &outs {
            a.write(out, &GltfAssetOptions::default()).unwrap();
            // Our reader: the edited mesh as the asset says, every new frame where it was put.
            let m = io::read_gltf_morphs_with(out, &body()).unwrap();
            assert_eq!(&m, a.morphs(), "{}", out.display());
            assert_eq!(
                m.target_names,
                [
                    "bend",
                    "lift",
                    "twist",
                    "Body-physical_0000",
                    "Body-physical_0001",
                    "Body-physical_0002",
                    "Body-physical_0003"
                ]
            );
            assert!(close(&m.targets[2], &twist, 1e-6));
            assert!(close(
                &m.base.positions,
                &before.morphs().base.positions,
                0.0
            ));
            let b = GltfAsset::read(out, &body()).unwrap();
            let anim = b.weight_animation(Some("Body-physical")).unwrap().unwrap();
            for (k, (_, w)) in anim.keys.iter().enumerate() {
                assert!(close(&m.evaluate(w), &frames[k], 1e-6), "frame {k}");
            }
            // Everything not edited is equal in the JSON.
            let got = fixture::json_of(out);
            for k in [
                "asset",
                "scene",
                "scenes",
                "materials",
                "textures",
                "samplers",
                "skins",
                "extensionsUsed",
            ] {
                assert_eq!(got[k], doc[k], "{k}");
            }
            assert_eq!(
                without(&got["images"][0], &["bufferView"]),
                without(&doc["images"][0], &["bufferView"])
            );
            assert_eq!(got["meshes"][0], doc["meshes"][0], "the other mesh");
            for n in 0..doc["nodes"].as_array().unwrap().len() {
                let keys: &[&str] = if n == 2 { &["weights"] } else { &[] };
                assert_eq!(
                    without(&got["nodes"][n], keys),
                    without(&doc["nodes"][n], keys),
                    "node {n}"
                );
            }
            assert_eq!(got["nodes"][2]["weights"].as_array().unwrap().len(), 7);
            let (gm, dm) = (&got["meshes"][1], &doc["meshes"][1]);
            assert_eq!(gm["name"], dm["name"]);
            assert_eq!(gm["extras"]["rigger"], "fixture");
            for p in 0..2 {
                let (gp, dp) = (&gm["primitives"][p], &dm["primitives"][p]);
                assert_eq!(
                    without(gp, &["targets"]),
                    without(dp, &["targets"]),
                    "primitive {p}"
                );
                assert_eq!(gp["targets"][0], dp["targets"][0]);
                assert_eq!(gp["targets"][1], dp["targets"][1]);
                assert!(
                    gp["targets"][2].get("NORMAL").is_some(),
                    "a normal delta where NORMAL is"
                );
            }
            // Animations: names, channels and extras as they were; the translation sampler
            // untouched, the weights samplers repointed at padded outputs.
            for a in 0..2 {
                let (ga, da) = (&got["animations"][a], &doc["animations"][a]);
                assert_eq!(ga["channels"], da["channels"]);
                assert_eq!(ga["name"], da["name"]);
                assert_eq!(ga["extras"], da["extras"]);
            }
            assert_eq!(
                got["animations"][0]["samplers"][0],
                doc["animations"][0]["samplers"][0]
            );
            assert_eq!(got["animations"][2]["name"], "Body-physical");
            for (old, new) in before.weight_animations().iter().zip(b.weight_animations()) {
                for ((t0, w0), (t1, w1)) in old.keys.iter().zip(&new.keys) {
                    assert_eq!(t0, t1);
                    assert_eq!(&w1[..2], &w0[..]);
                    assert!(w1[2..].iter().all(|&x| x == 0.0));
                }
            }
        }
        fixture::assert_valid(&[&outs[0], &outs[1]]);
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `tools/gltf-assets` when node and its packages are installed; else `None` (skip), or a
/// panic when `MORPHKIT_REQUIRE_GLTF_TOOLS` is set.
fn tools() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf-assets");
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let bins = ["gltfpack", "gltf-transform"]
        .iter()
        .all(|b| dir.join("node_modules/.bin").join(b).exists());
    if node && bins {
        return Some(dir);
    }
    if std::env::var_os("MORPHKIT_REQUIRE_GLTF_TOOLS").is_some() {
        panic!("MORPHKIT_REQUIRE_GLTF_TOOLS is set but node or tools/gltf-assets/node_modules is missing");
    }
    eprintln!("skipping: node or tools/gltf-assets/node_modules (npm ci) is missing");
    None
}

#[test]
fn quantized_and_meshopt_assets_round_trip() {
    let Some(tools) = tools() else {
        return;
    };
    let d = tmp_dir("packed");
    let input = d.join("in.glb");
    fixture::write(&input, &fixture::standard(false, 100.0));
    let out = d.join("variants");
    let st = Command::new("sh")
        .arg(tools.join("make-variants.sh"))
        .arg(&input)
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success(), "make-variants.sh failed");
    for (name, ext) in [
        ("quantized.glb", "KHR_mesh_quantization"),
        ("meshopt.glb", "EXT_meshopt_compression"),
        ("transform-meshopt.glb", "meshopt_compression"),
    ] {
        let p = out.join(name);
        let src = fixture::json_of(&p);
        assert!(src.to_string().contains(ext), "{name} does not use {ext}");
        let mut a = GltfAsset::read(&p, &GltfReadOptions::default()).unwrap();
        let before = a.clone();
        let (_, frames) = edit(&mut a);
        let written = d.join(format!("edited-{name}"));
        a.write(&written, &GltfAssetOptions::default()).unwrap();
        let m = io::read_gltf_morphs(&written).unwrap();
        assert_eq!(&m, a.morphs(), "{name}");
        // The packed targets are carried as they were (same accessors).
        let got = fixture::json_of(&written);
        let mi = a.mesh_index();
        for p in 0..src["meshes"][mi]["primitives"].as_array().unwrap().len() {
            let (gp, sp) = (
                &got["meshes"][mi]["primitives"][p],
                &src["meshes"][mi]["primitives"][p],
            );
            assert_eq!(gp["attributes"], sp["attributes"], "{name}");
            assert_eq!(gp["targets"][0], sp["targets"][0], "{name}");
        }
        assert_eq!(
            got["extensionsRequired"], src["extensionsRequired"],
            "{name}"
        );
        assert_eq!(
            got["nodes"].as_array().unwrap().len(),
            src["nodes"].as_array().unwrap().len()
        );
        assert_eq!(got["materials"], src["materials"], "{name}");
        assert_eq!(m.base.positions, before.morphs().base.positions);
        let b = GltfAsset::read(&written, &GltfReadOptions::default()).unwrap();
        let anim = b.weight_animation(Some("Body-physical")).unwrap().unwrap();
        for (k, (_, w)) in anim.keys.iter().enumerate() {
            // In the file's own (quantized) units: frames were given in them.
            let diag = morphkit::TriMesh::new(frames[k].clone(), vec![]).bbox_diagonal();
            assert!(
                close(&m.evaluate(w), &frames[k], 1e-6 * diag.max(1.0)),
                "{name}: frame {k}"
            );
        }
        fixture::assert_valid(&[&written]);
    }
    let _ = std::fs::remove_dir_all(&d);
}
