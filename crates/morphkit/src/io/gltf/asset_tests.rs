//! Unit tests of [`GltfAsset`]: reading keeps everything, edits touch only what they say, and
//! the written file reads back to [`GltfAsset::morphs`].

use super::asset_edit::pad_runs;
use super::normals::{to_f32_unit, vertex_normals};
use super::{read_gltf_morphs, GltfAsset, GltfAssetOptions, GltfReadOptions};
use crate::mesh::Point;
use serde_json::Value;
use std::path::{Path, PathBuf};

#[path = "../../../tests/common/gltf_asset.rs"]
pub(super) mod fixture;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-asset-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn read(p: &Path) -> GltfAsset {
    GltfAsset::read(p, &GltfReadOptions::default()).unwrap()
}

/// The BIN chunk of a GLB.
fn glb_bin(bytes: &[u8]) -> &[u8] {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    &bytes[20 + len + 8..]
}

/// A plain (dense, tightly packed) f32 VEC3 accessor of a GLB.
fn vec3_of(doc: &Value, bin: &[u8], acc: usize) -> Vec<[f32; 3]> {
    let a = &doc["accessors"][acc];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let o = v["byteOffset"].as_u64().unwrap_or(0) as usize
        + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let f = |i: usize| f32::from_le_bytes(bin[o + 4 * i..o + 4 * i + 4].try_into().unwrap());
    (0..a["count"].as_u64().unwrap() as usize)
        .map(|i| [f(3 * i), f(3 * i + 1), f(3 * i + 2)])
        .collect()
}

fn close(a: &[Point], b: &[Point], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (0..3).all(|k| (p[k] - q[k]).abs() <= tol))
}

#[test]
fn pad_runs_appends_zeros_to_every_vector() {
    assert_eq!(
        pad_runs(&[1.0, 2.0, 3.0, 4.0], 2, 3),
        [1.0, 2.0, 0.0, 3.0, 4.0, 0.0]
    );
    assert_eq!(pad_runs(&[1.0, 2.0], 1, 1), [1.0, 2.0]);
}

#[test]
fn read_keeps_the_mesh_its_primitives_and_animations() {
    let d = tmp("read");
    let p = d.join("a.glb");
    fixture::write(&p, &fixture::standard(true, 1.0));
    let a = read(&p);
    assert_eq!(a.morphs(), &read_gltf_morphs(&p).unwrap());
    assert_eq!(a.mesh_index(), 1);
    assert_eq!(a.mesh_name(), Some("Body"));
    assert_eq!(a.primitive_vertices(), [0..60, 60..120]);
    let names: Vec<_> = a
        .weight_animations()
        .iter()
        .map(|w| w.name.clone().unwrap())
        .collect();
    assert_eq!(names, ["Wave", "Pulse"]);
    let e = a.weight_animation(None).unwrap_err().to_string();
    assert!(
        e.contains("2 animations") && e.contains("'Wave', 'Pulse'"),
        "{e}"
    );
    let e = a.weight_animation(Some("Run")).unwrap_err().to_string();
    assert!(e.contains("no animation named 'Run'"), "{e}");
    // CUBICSPLINE: the values (0.25 (k + t)), not the tangents.
    let pulse = a.weight_animation(Some("Pulse")).unwrap().unwrap();
    assert_eq!(pulse.keys, [(0.0, vec![0.0, 0.25]), (1.0, vec![0.25, 0.5])]);
    assert_eq!(
        a.weight_animation(Some("Wave")).unwrap().unwrap().keys,
        a.morphs().weight_keys
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_written_asset_without_edits_is_the_same_file() {
    let d = tmp("same");
    let p = d.join("a.glb");
    let doc = fixture::write(&p, &fixture::standard(true, 1.0));
    let a = read(&p);
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let (x, y) = (std::fs::read(&p).unwrap(), std::fs::read(&out).unwrap());
    assert_eq!(fixture::glb_json(&y), doc);
    assert_eq!(glb_bin(&x), glb_bin(&y));
    // Provenance goes to asset.extras only.
    let opts = GltfAssetOptions {
        extras: Some(serde_json::json!({"morphkit": {"command": "test"}})),
    };
    a.write(&out, &opts).unwrap();
    let got = fixture::json_of(&out);
    assert_eq!(got["asset"]["extras"]["morphkit"]["command"], "test");
    assert_eq!(got["asset"]["extras"]["source"], "fixture");
    assert_eq!(got["meshes"], doc["meshes"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn added_targets_pad_every_weight_and_keep_primitives_apart() {
    let d = tmp("targets");
    let p = d.join("a.glb");
    let spec = fixture::standard(false, 100.0);
    let doc = fixture::write(&p, &spec);
    let mut a = read(&p);
    let before = a.clone();
    let base = a.morphs().base.positions.clone();
    let twist: Vec<Point> = base
        .iter()
        .map(|q| {
            let (s, c) = (0.2 * q[2]).sin_cos();
            [c * q[0] - s * q[1], s * q[0] + c * q[1], q[2]]
        })
        .collect();
    let flat: Vec<Point> = base.iter().map(|q| [q[0], 0.5 * q[1], q[2]]).collect();
    // "bend" is replaced, "twist" appended.
    a.add_targets(
        &["bend".into(), "twist".into()],
        &[flat.clone(), twist.clone()],
    )
    .unwrap();
    assert_eq!(a.morphs().target_names, ["bend", "lift", "twist"]);
    assert!(close(&a.morphs().targets[0], &flat, 1e-6));
    assert!(close(&a.morphs().targets[2], &twist, 1e-6));
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let b = read(&out);
    assert_eq!(
        b.morphs(),
        a.morphs(),
        "the written file reads back as the asset"
    );
    let got = fixture::json_of(&out);
    assert_eq!(
        got["meshes"][1]["weights"],
        serde_json::json!([0.0, 0.0, 0.0])
    );
    assert_eq!(
        got["nodes"][2]["weights"],
        serde_json::json!([0.0, 0.0, 0.0])
    );
    assert_eq!(got["meshes"][1]["extras"]["rigger"], "fixture");
    for k in [
        "materials",
        "textures",
        "images",
        "samplers",
        "scenes",
        "asset",
        "extensionsUsed",
    ] {
        assert_eq!(got[k], doc[k], "{k}");
    }
    let mut nodes = got["nodes"].clone();
    nodes[2]["weights"] = doc["nodes"][2]["weights"].clone();
    assert_eq!(nodes, doc["nodes"], "nodes but the padded weights");
    assert_eq!(got["meshes"][0], doc["meshes"][0], "the other mesh");
    // Every animation: the new target has weight 0, the others keep theirs.
    for (old, new) in before.weight_animations().iter().zip(b.weight_animations()) {
        assert_eq!(old.name, new.name);
        for ((t0, w0), (t1, w1)) in old.keys.iter().zip(&new.keys) {
            assert_eq!(t0, t1);
            assert_eq!(w1, &[w0[0], w0[1], 0.0]);
        }
    }
    // CUBICSPLINE: tangents padded too (a run of 3-vectors).
    let pulse = |x: &GltfAsset| {
        x.samplers
            .iter()
            .find(|s| s.anim == 1)
            .unwrap()
            .values
            .clone()
    };
    assert_eq!(pulse(&b), pad_runs(&pulse(&before), 2, 3));
    // The translation channel of "Wave" is untouched.
    assert_eq!(
        got["animations"][0]["samplers"][0],
        doc["animations"][0]["samplers"][0]
    );
    // NORMAL deltas per primitive: at the seam, each side's from its own triangles only.
    let bin = std::fs::read(&out).unwrap();
    let bin = glb_bin(&bin);
    for (pi, r) in a.primitive_vertices().into_iter().enumerate() {
        let t = &a.morphs().base.triangles[if pi == 0 { 0..96 } else { 96..192 }];
        let local: Vec<[u32; 3]> = t.iter().map(|t| t.map(|i| i - r.start as u32)).collect();
        let n0 = to_f32_unit(&vertex_normals(&base[r.clone()], &local));
        let n1 = to_f32_unit(&vertex_normals(&twist[r.clone()], &local));
        let acc = got["meshes"][1]["primitives"][pi]["targets"][2]["NORMAL"]
            .as_u64()
            .unwrap();
        let dn = vec3_of(&got, bin, acc as usize);
        for v in 0..dn.len() {
            for k in 0..3 {
                assert_eq!(dn[v][k], n1[v][k] - n0[v][k], "primitive {pi}, vertex {v}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_new_base_moves_the_targets_and_turns_the_normals() {
    let d = tmp("base");
    let p = d.join("a.glb");
    fixture::write(&p, &fixture::standard(true, 1.0));
    let mut a = read(&p);
    let m0 = a.morphs().clone();
    // Stretched along z: the tube's normals stay radial, the cone of a flare would not.
    let new: Vec<Point> = m0
        .base
        .positions
        .iter()
        .map(|q| {
            [
                q[0] * (1.0 + 0.1 * q[2]),
                q[1] * (1.0 + 0.1 * q[2]),
                2.0 * q[2],
            ]
        })
        .collect();
    a.set_base(&new).unwrap();
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let b = read(&out);
    assert!(close(&b.morphs().base.positions, &new, 1e-6));
    for (t, t0) in b.morphs().targets.iter().zip(&m0.targets) {
        let want: Vec<Point> = t0
            .iter()
            .zip(&m0.base.positions)
            .zip(&b.morphs().base.positions)
            .map(|((q, o), n)| [n[0] + q[0] - o[0], n[1] + q[1] - o[1], n[2] + q[2] - o[2]])
            .collect();
        assert!(close(t, &want, 1e-6), "targets keep their displacements");
    }
    // The fixture's normals are the area-weighted ones, so turned they are the new ones.
    for (pi, prim) in b.primitives.iter().enumerate() {
        let r = prim.vertices.clone();
        let t = &b.morphs().base.triangles[prim.triangles.clone()];
        let local: Vec<[u32; 3]> = t.iter().map(|t| t.map(|i| i - r.start as u32)).collect();
        let want = vertex_normals(&b.morphs().base.positions[r], &local);
        let got = prim.normals.as_ref().unwrap();
        assert!(close(got, &want, 1e-5), "primitive {pi}");
        let old = read(&p).primitives[pi].normals.clone().unwrap();
        assert!(
            !close(got, &old, 1e-2),
            "primitive {pi}: the normals did turn"
        );
    }
    let e = a.set_base(&new[1..]).unwrap_err().to_string();
    assert!(
        e.contains("119 positions, the mesh has 120 vertices"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_frame_animation_keys_one_new_target_per_frame() {
    let d = tmp("frames");
    let p = d.join("a.gltf");
    fixture::write(&p, &fixture::standard(false, 100.0));
    let mut a = read(&p);
    let base = a.morphs().base.positions.clone();
    let frames: Vec<Vec<Point>> = (1..=3)
        .map(|k| {
            base.iter()
                .map(|q| [q[0] + 0.01 * k as f64 * q[2], q[1], q[2]])
                .collect()
        })
        .collect();
    let times = [0.0, 0.1, 0.2];
    let mut small = a.clone();
    small.set_max_targets(4);
    let e = small
        .add_frame_animation("physical", &times, &frames)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("5 morph targets (2 + 3), more than 4") && e.contains("--max-targets 0"),
        "{e}"
    );
    a.add_frame_animation("physical", &times, &frames).unwrap();
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let b = read(&out);
    assert_eq!(b.morphs(), a.morphs());
    assert_eq!(
        b.morphs().target_names[2..],
        ["physical_0000", "physical_0001", "physical_0002"]
    );
    let anim = b.weight_animation(Some("physical")).unwrap().unwrap();
    for (k, (t, w)) in anim.keys.iter().enumerate() {
        assert_eq!(*t, times[k] as f32 as f64);
        let mut want = vec![0.0; 5];
        want[2 + k] = 1.0;
        assert_eq!(w, &want);
        assert!(
            close(&b.morphs().evaluate(w), &frames[k], 1e-6),
            "frame {k}"
        );
    }
    let json = fixture::json_of(&out);
    let anim = &json["animations"][2];
    assert_eq!(anim["samplers"][0]["interpolation"], "LINEAR");
    assert_eq!(
        anim["channels"][0]["target"],
        serde_json::json!({"node": 2, "path": "weights"})
    );
    let output = anim["samplers"][0]["output"].as_u64().unwrap() as usize;
    assert!(
        json["accessors"][output].get("sparse").is_some(),
        "one-hot keys are stored sparsely"
    );
    // The same clip again replaces it: same animation, same targets.
    let mut again = b.clone();
    again
        .add_frame_animation("physical", &times[..2], &frames[..2])
        .unwrap();
    assert_eq!(again.morphs().targets.len(), 5);
    assert_eq!(again.document()["animations"].as_array().unwrap().len(), 3);
    assert_eq!(
        again
            .weight_animation(Some("physical"))
            .unwrap()
            .unwrap()
            .keys
            .len(),
        2
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn edits_refuse_what_gltf_or_the_name_rule_forbids() {
    let d = tmp("refusals");
    let p = d.join("a.gltf");
    fixture::write(&p, &fixture::standard(false, 100.0));
    let a = read(&p);
    let base = a.morphs().base.positions.clone();
    let frames = vec![base.clone(), base.clone(), base.clone()];
    let err = |r: Result<(), crate::io::IoError>| r.unwrap_err().to_string();
    // glTF key times are not negative.
    let e = err(a
        .clone()
        .add_frame_animation("c", &[-2.0, -1.0, 0.0], &frames));
    assert!(
        e.contains("animation 'c': key time 0 is -2 s; glTF key times must not be negative"),
        "{e}"
    );
    // No frames is said as such, not as a count mismatch.
    let e = err(a.clone().add_frame_animation("c", &[], &[]));
    assert!(e.contains("animation 'c': no frames to animate"), "{e}");
    // Target names follow the name rule (the CLI's `rig` applies the same one).
    for bad in ["", ".", "..", "../x", "a\\b"] {
        let e = err(a.clone().add_targets(&[bad.to_string()], &frames[..1]));
        assert!(
            e.contains("cannot be a morph-target or file name"),
            "{bad:?}: {e}"
        );
    }
    // An asset is written as .glb or .gltf only, never as glTF in a file of another format.
    for name in ["anim.pc2", "anim.obj", "anim.usda", "anim"] {
        let out = d.join(name);
        let e = err(a.write(&out, &GltfAssetOptions::default()));
        assert!(
            e.contains("unsupported format; expected .glb or .gltf"),
            "{e}"
        );
        assert!(!out.exists());
    }
    a.write(&d.join("ok.GLB"), &GltfAssetOptions::default())
        .unwrap();
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn external_buffers_and_images_are_embedded() {
    let d = tmp("external");
    let (src, dst) = (d.join("src"), d.join("dst"));
    std::fs::create_dir_all(&src).unwrap();
    std::fs::create_dir_all(&dst).unwrap();
    let mut spec = fixture::standard(false, 1.0);
    spec.external = true;
    let p = src.join("a.gltf");
    fixture::write(&p, &spec);
    let a = read(&p);
    let (glb, gltf) = (dst.join("b.glb"), dst.join("b.gltf"));
    a.write(&glb, &GltfAssetOptions::default()).unwrap();
    a.write(&gltf, &GltfAssetOptions::default()).unwrap();
    std::fs::remove_dir_all(&src).unwrap();
    let bytes = std::fs::read(&glb).unwrap();
    let doc = fixture::glb_json(&bytes);
    let img = &doc["images"][0];
    assert!(img.get("uri").is_none());
    assert_eq!(img["mimeType"], "image/png");
    assert_eq!(img["name"], "skin");
    let v = &doc["bufferViews"][img["bufferView"].as_u64().unwrap() as usize];
    let o = v["byteOffset"].as_u64().unwrap() as usize;
    assert_eq!(&glb_bin(&bytes)[o..o + fixture::PNG.len()], fixture::PNG);
    assert_eq!(doc["buffers"].as_array().unwrap().len(), 1);
    // The .gltf is one file: its buffer is a data URI.
    let g = fixture::json_of(&gltf);
    assert!(g["buffers"][0]["uri"]
        .as_str()
        .unwrap()
        .starts_with("data:"));
    assert_eq!(read(&gltf).morphs(), a.morphs());
    assert_eq!(read(&glb).morphs(), a.morphs());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn meshopt_buffers_are_renumbered_and_fallbacks_kept() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/gltf");
    let d = tmp("meshopt");
    for name in [
        "meshopt.glb",
        "transform-meshopt.glb",
        "quantized.glb",
        "s.gltf",
    ] {
        let p = seeds.join(name);
        let mut a = read(&p);
        let base = a.morphs().base.positions.clone();
        let frames = vec![
            base.clone(),
            base.iter().map(|q| [q[0], q[1], q[2] + 1.0]).collect(),
        ];
        a.add_frame_animation("physical", &[0.0, 1.0], &frames)
            .unwrap();
        let out = d.join(format!("{name}.glb"));
        a.write(&out, &GltfAssetOptions::default()).unwrap();
        let b = read(&out);
        assert_eq!(b.morphs(), a.morphs(), "{name}");
        let doc = fixture::json_of(&out);
        let src = fixture::json_of(&p);
        assert_eq!(
            doc["extensionsRequired"], src["extensionsRequired"],
            "{name}"
        );
        for (i, buf) in doc["buffers"].as_array().unwrap().iter().enumerate() {
            let fallback = buf
                .pointer("/extensions/EXT_meshopt_compression/fallback")
                .is_some();
            assert_eq!(fallback, i > 0, "{name}: buffer {i}");
            assert!(buf.get("uri").is_none());
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn targets_on_a_mesh_without_any_add_no_weights_members() {
    let d = tmp("plain");
    let p = d.join("a.glb");
    let mut spec = fixture::standard(false, 1.0);
    spec.prims.iter_mut().for_each(|q| q.targets.clear());
    spec.target_names.clear();
    spec.keys.clear();
    spec.cubic = false;
    fixture::write(&p, &spec);
    let opts = GltfReadOptions {
        mesh: Some("Body".into()),
    };
    let mut a = GltfAsset::read(&p, &opts).unwrap();
    let up: Vec<Point> = a
        .morphs()
        .base
        .positions
        .iter()
        .map(|q| [q[0], q[1], q[2] + 0.5])
        .collect();
    a.add_targets(&["up".into()], std::slice::from_ref(&up))
        .unwrap();
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let doc = fixture::json_of(&out);
    // glTF's default weights are zeros: nothing to pad, and no `null` added.
    assert!(doc["meshes"][1].get("weights").is_none());
    assert!(doc["nodes"][2].get("weights").is_none());
    assert_eq!(
        doc["meshes"][1]["extras"]["targetNames"],
        serde_json::json!(["up"])
    );
    assert_eq!(doc["meshes"][1]["extras"]["rigger"], "fixture");
    let m = super::read_gltf_morphs_with(&out, &opts).unwrap();
    assert!(close(&m.targets[0], &up, 1e-6));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_split_rig_is_carried_but_not_edited() {
    let d = tmp("split");
    let p = d.join("a.glb");
    let base = crate::mesh::generate::grid(4, 3, 1.0, 1.0);
    let n = 5;
    let targets: Vec<Vec<Point>> = (0..n)
        .map(|k| {
            base.positions
                .iter()
                .map(|q| [q[0], q[1], q[2] + k as f64])
                .collect()
        })
        .collect();
    let rig = super::GltfMorphs {
        target_names: (0..n).map(|k| format!("t{k}")).collect(),
        weight_keys: (0..n)
            .map(|k| {
                (
                    k as f64,
                    (0..n).map(|t| if t == k { 1.0 } else { 0.0 }).collect(),
                )
            })
            .collect(),
        base,
        targets,
    };
    let opts = super::GltfOptions {
        max_targets: 2,
        ..Default::default()
    };
    assert!(super::write_gltf_with(&p, &rig, &opts).unwrap().meshes > 1);
    let mut a = read(&p);
    assert!(a.is_split_rig());
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    assert_eq!(
        read_gltf_morphs(&out).unwrap(),
        read_gltf_morphs(&p).unwrap()
    );
    let e = a
        .add_targets(&["x".into()], std::slice::from_ref(&rig.base.positions))
        .unwrap_err()
        .to_string();
    assert!(e.contains("split into") && e.contains("a.glb"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
