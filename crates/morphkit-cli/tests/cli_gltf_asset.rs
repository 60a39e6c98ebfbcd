//! Issue 37, "glTF rigs blend in place": `convert`, `blend --rig` and `rig --target X.glb` give
//! the user's own asset back. The asset (tests/common/gltf_asset.rs of the library) has a
//! texture, a second mesh, a ×100-scaled node and two weights animations; after each command
//! everything the command does not edit is equal in the JSON, the Khronos validator
//! (`MORPHKIT_GLTF_VALIDATOR`) reports no error or warning, and the physical animation's frames
//! are those of the same blend made the old way (OBJ inputs and frames).

mod common;
#[path = "../../morphkit/tests/common/gltf_asset.rs"]
mod fixture;

use common::split::diagonal;
use common::*;
use morphkit::io::{self, GltfAsset, GltfReadOptions};
use serde_json::Value;
use std::path::Path;

fn body() -> GltfReadOptions {
    GltfReadOptions {
        mesh: Some("Body".into()),
    }
}

/// `doc` without `asset.extras.morphkit` (the command line and sources a run records).
fn unstamped(doc: &Value) -> Value {
    let mut d = doc.clone();
    if let Some(e) = d["asset"]["extras"].as_object_mut() {
        e.remove("morphkit");
    }
    d
}

/// `doc` with the members that carry an edit of mesh `m` blanked: its primitives' targets,
/// weights and extras, the weights of the nodes using it, the animations' samplers (outputs
/// padded), and the data (accessors, views, buffers).
fn blank_edits(doc: &Value, m: usize) -> Value {
    let mut d = unstamped(doc);
    for k in ["accessors", "bufferViews", "buffers"] {
        d[k] = Value::Null;
    }
    for p in d["meshes"][m]["primitives"].as_array_mut().unwrap() {
        p["targets"] = Value::Null;
    }
    d["meshes"][m]["weights"] = Value::Null;
    d["meshes"][m]["extras"]["targetNames"] = Value::Null;
    for n in d["nodes"].as_array_mut().unwrap() {
        if n["mesh"].as_u64() == Some(m as u64) {
            n["weights"] = Value::Null;
        }
    }
    if let Some(a) = d["animations"].as_array_mut() {
        for a in a {
            a["samplers"] = Value::Null;
        }
    }
    d
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn convert_carries_the_whole_asset() {
    let d = tmp_dir("asset-convert");
    let input = d.join("in.glb");
    let doc = fixture::write(&input, &fixture::standard(false, 100.0));
    let (glb, gltf) = (d.join("out.glb"), d.join("out.gltf"));
    ok(&["convert", s(&input), s(&glb)]);
    ok(&["convert", s(&input), s(&gltf)]);
    for out in [&glb, &gltf] {
        let got = fixture::json_of(out);
        assert_eq!(
            got["nodes"][2]["scale"],
            serde_json::json!([100.0, 100.0, 100.0])
        );
        let mut got = unstamped(&got);
        got["buffers"][0]["uri"] = Value::Null;
        let mut want = doc.clone();
        want["buffers"][0]["uri"] = Value::Null;
        assert_eq!(got, want, "{}", out.display());
        assert_eq!(
            io::read_gltf_morphs(out).unwrap(),
            io::read_gltf_morphs(&input).unwrap()
        );
    }
    let stamp = fixture::json_of(&glb)["asset"]["extras"]["morphkit"].clone();
    assert_eq!(stamp["subcommand"], "convert");
    // An external .gltf comes back as one file with its texture embedded.
    let src = d.join("src");
    std::fs::create_dir_all(&src).unwrap();
    let mut ext = fixture::standard(false, 100.0);
    ext.external = true;
    fixture::write(&src.join("a.gltf"), &ext);
    let moved = d.join("moved.glb");
    ok(&[
        "convert",
        "--mesh",
        "Body",
        s(&src.join("a.gltf")),
        s(&moved),
    ]);
    std::fs::remove_dir_all(&src).unwrap();
    let got = fixture::json_of(&moved);
    assert_eq!(got["images"][0]["mimeType"], "image/png");
    assert!(got["images"][0].get("uri").is_none());
    fixture::assert_valid(&[&input, &glb, &gltf, &moved]);
    // --mesh picks another mesh for info and single-mesh outputs.
    let info = ok(&["info", "--json", "--mesh", "Prop", s(&input)]);
    let info: Value = serde_json::from_str(&info).unwrap();
    assert_eq!(info["files"][0]["vertices"], 4);
    let prop = d.join("prop.obj");
    ok(&["convert", "--mesh", "Prop", s(&input), s(&prop)]);
    assert_eq!(common::split::read(&prop).0.len(), 4);
    // An output of positions and triangles says what it leaves out of the asset.
    let (_, err) = run_ok(&["convert", "--mesh", "Body", s(&input), s(&d.join("frames"))]);
    assert!(
        err.contains("note:") && err.contains("1 texture") && err.contains("1 other mesh"),
        "{err}"
    );
    assert!(
        err.contains("node transform") && err.contains("UV set TEXCOORD_0"),
        "{err}"
    );
    let (_, err) = run_ok(&["convert", s(&input), s(&d.join("again.glb"))]);
    assert!(
        !err.contains("note:"),
        "a glTF output keeps the asset: {err}"
    );
    let e = fails(&["convert", "--mesh", "Nope", s(&input), s(&d.join("x.glb"))]);
    assert!(
        e.contains("no mesh named 'Nope'") && e.contains("'Body'"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The old way: the rig's base and targets as OBJ files (what the reader gives, so the same
/// numbers) and its weight keys as a CSV.
fn old_inputs(d: &Path, rig: &Path) -> (Vec<String>, std::path::PathBuf) {
    let m = io::read_gltf_morphs_with(rig, &body()).unwrap();
    let mut files = Vec::new();
    let base = d.join("base.obj");
    io::write_mesh(&base, &m.base).unwrap();
    files.push(base.display().to_string());
    for (n, t) in m.target_names.iter().zip(&m.targets) {
        let p = d.join(format!("{n}.obj"));
        io::write_mesh(&p, &m.base.with_positions(t.clone())).unwrap();
        files.push(p.display().to_string());
    }
    let csv = d.join("keys.csv");
    let rows: Vec<String> = m
        .weight_keys
        .iter()
        .map(|(_, w)| {
            w.iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect();
    std::fs::write(&csv, rows.join("\n")).unwrap();
    (files, csv)
}

#[test]
fn blend_rig_adds_the_physical_animation_to_the_asset() {
    let d = tmp_dir("asset-blend");
    let input = d.join("in.glb");
    let doc = fixture::write(&input, &fixture::standard(false, 100.0));
    let e = fails(&["blend", "--rig", s(&input), "--out", s(&d.join("x.glb"))]);
    assert!(
        e.contains("2 animations") && e.contains("'Wave', 'Pulse'"),
        "{e}"
    );
    let e = fails(&[
        "--max-targets",
        "4",
        "blend",
        "--rig",
        s(&input),
        "--animation",
        "Wave",
        "--per-frame-targets",
        "--out",
        s(&d.join("x.glb")),
    ]);
    assert!(
        e.contains("5 morph targets (2 + 3), more than 4") && e.contains("--max-targets 0"),
        "{e}"
    );
    let out = d.join("physical.glb");
    let (_, err) = run_ok(&[
        "blend",
        "--rig",
        s(&input),
        "--animation",
        "Wave",
        "--per-frame-targets",
        "--out",
        s(&out),
    ]);
    // The tube is split at a ring (two primitives): 12 vertices welded for the solve.
    assert!(err.contains("welded 12 split vertices"), "{err}");
    let got = fixture::json_of(&out);
    assert_eq!(got["animations"][2]["name"], "Wave-physical");
    let mut carried = blank_edits(&got, 1);
    carried["animations"].as_array_mut().unwrap().truncate(2);
    assert_eq!(carried, blank_edits(&doc, 1));
    assert_eq!(got["images"], doc["images"]);
    fixture::assert_valid(&[&out]);
    // The old way: the same blend of OBJ files, written as OBJ frames.
    let (files, csv) = old_inputs(&d, &input);
    let frames = d.join("frames");
    let mut args = vec!["blend", "--base", &files[0]];
    for t in &files[1..] {
        args.extend(["--target", t.as_str()]);
    }
    args.extend(["--weights-file", s(&csv), "--out", s(&frames)]);
    ok(&args);
    let a = GltfAsset::read(&out, &body()).unwrap();
    let m = a.morphs();
    let base = &m.base.positions;
    let diag = diagonal(base);
    let anim = a.weight_animation(Some("Wave-physical")).unwrap().unwrap();
    let key_times: Vec<f64> = anim.keys.iter().map(|k| k.0).collect();
    assert_eq!(key_times, [0.0, 0.5, 1.0], "frames at the keys' times");
    for (k, (_, w)) in anim.keys.iter().enumerate() {
        let got = m.evaluate(w);
        let want = common::split::read(&frames.join(format!("frame_{k:04}.obj"))).0;
        for ((g, o), b) in got.iter().zip(&want).zip(base) {
            // The old frame as the file stores it: an f32 displacement from the f32 base.
            let stored = [0, 1, 2].map(|i| b[i] + (o[i] - b[i]) as f32 as f64);
            assert!(
                dist(*g, stored) <= 1e-9 * diag,
                "frame {k}: {g:?} vs {stored:?}"
            );
            assert!(dist(*g, *o) <= 1e-6 * diag, "frame {k}: {g:?} vs {o:?}");
        }
    }
    // A weights file whose header names the targets (in another order) instead.
    let named = d.join("named.csv");
    std::fs::write(&named, "lift,bend\n0,0\n0,1\n0.5,0.5\n").unwrap();
    let out2 = d.join("named.glb");
    ok(&[
        "blend",
        "--rig",
        s(&input),
        "--weights-file",
        s(&named),
        "--fps",
        "2",
        "--per-frame-targets",
        "--out",
        s(&out2),
    ]);
    let b = GltfAsset::read(&out2, &body()).unwrap();
    let anim2 = b.weight_animation(Some("named-physical")).unwrap().unwrap();
    assert_eq!(
        anim2.keys.iter().map(|k| k.0).collect::<Vec<_>>(),
        key_times
    );
    for (k1, k2) in anim.keys.iter().zip(&anim2.keys) {
        assert_eq!(m.evaluate(&k1.1), b.morphs().evaluate(&k2.1));
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn rig_into_a_glb_target_keeps_the_asset() {
    let d = tmp_dir("asset-rig");
    let expr = d.join("expr");
    std::fs::create_dir_all(&expr).unwrap();
    write_tube(&d.join("neutral.obj"), 10, 8, 1.0, 0.0);
    write_tube(&expr.join("a_bend.obj"), 10, 8, 1.0, 0.8);
    write_tube(&expr.join("b_small.obj"), 10, 8, 1.0, 0.2);
    // The target: a tube twice as large, one primitive, in an asset with no morph targets.
    let (p, t) = fixture::tube(10, 8, 2.0, 0.0);
    let mut spec = fixture::standard(false, 100.0);
    spec.prims = vec![fixture::Prim {
        positions: p,
        triangles: t,
        targets: vec![],
    }];
    spec.target_names.clear();
    spec.keys.clear();
    spec.cubic = false;
    let head = d.join("head.glb");
    let doc = fixture::write(&head, &spec);
    let head_obj = d.join("head.obj");
    io::write_mesh(
        &head_obj,
        &io::read_gltf_morphs_with(&head, &body()).unwrap().base,
    )
    .unwrap();
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
    let neutral = d.join("neutral.obj");
    let rig = |target: &Path, out: &Path, mesh: bool| {
        let mut a = vec![
            "rig",
            "--source-neutral",
            s(&neutral),
            "--source-shapes",
            &glob,
        ];
        a.extend([
            "--target",
            s(target),
            "--markers",
            "m.json",
            "--out",
            s(out),
        ]);
        if mesh {
            a.extend(["--mesh", "Body"]);
        }
        a.iter().map(|x| x.to_string()).collect::<Vec<_>>()
    };
    let run = |args: Vec<String>| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_morphkit"))
            .args(&args)
            .current_dir(&d)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let (new, old) = (d.join("head-rig.glb"), d.join("old-rig.glb"));
    run(rig(&head, &new, true));
    run(rig(&head_obj, &old, false));
    let got = fixture::json_of(&new);
    assert_eq!(blank_edits(&got, 1), blank_edits(&doc, 1));
    assert_eq!(
        got["meshes"][1]["extras"]["targetNames"],
        serde_json::json!(["a_bend", "b_small"])
    );
    fixture::assert_valid(&[&new]);
    let (a, b) = (
        io::read_gltf_morphs_with(&new, &body()).unwrap(),
        io::read_gltf_morphs(&old).unwrap(),
    );
    assert_eq!(a.base.positions, b.base.positions);
    assert_eq!(a.target_names, b.target_names);
    for (x, y) in a.targets.iter().zip(&b.targets) {
        assert!(
            x.iter().zip(y).all(|(p, q)| dist(*p, *q) < 1e-6),
            "the same transfer"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `transfer` onto a GLB target writes into that asset: the transferred frames become the clip
/// 'transfer' of its mesh, everything else is kept, and the frames are those of the same
/// transfer onto the target's mesh as an OBJ (to the file's f32 storage).
#[test]
fn transfer_into_a_glb_target_adds_a_clip_to_the_asset() {
    let d = tmp_dir("asset-transfer");
    let input = d.join("in.glb");
    let doc = fixture::write(&input, &fixture::standard(false, 100.0));
    let (files, _) = old_inputs(&d, &input);
    let n = io::read_gltf_morphs_with(&input, &body())
        .unwrap()
        .base
        .num_vertices();
    let pairs: Vec<[usize; 2]> = (0..n).step_by(5).map(|v| [v, v]).collect();
    let markers = d.join("markers.json");
    std::fs::write(&markers, serde_json::json!({ "pairs": pairs }).to_string()).unwrap();
    let run = |target: &Path, out: &Path| {
        let mut args = vec!["transfer", "--source-ref", files[0].as_str(), "--source"];
        args.extend(files[1..].iter().map(String::as_str));
        args.extend([
            "--target",
            s(target),
            "--markers",
            s(&markers),
            "--out",
            s(out),
        ]);
        run_ok(&args).1
    };
    let out = d.join("out.glb");
    let err = run(&input, &out);
    assert!(err.contains("added the animation 'transfer'"), "{err}");
    let plain = d.join("plain");
    run(Path::new(&files[0]), &plain);
    let got = fixture::json_of(&out);
    let mut carried = blank_edits(&got, 1);
    let anims = carried["animations"].as_array_mut().unwrap();
    assert_eq!(anims.last().unwrap()["name"], "transfer");
    anims.pop();
    assert_eq!(carried, blank_edits(&doc, 1));
    assert_eq!(got["images"], doc["images"]);
    fixture::assert_valid(&[&out]);
    let a = GltfAsset::read(&out, &body()).unwrap();
    let m = a.morphs();
    let diag = diagonal(&m.base.positions);
    let anim = a.weight_animation(Some("transfer")).unwrap().unwrap();
    assert_eq!(anim.keys.len(), files.len() - 1);
    for (k, (_, w)) in anim.keys.iter().enumerate() {
        let want = common::split::read(&plain.join(format!("frame_{k:04}.obj"))).0;
        for (g, o) in m.evaluate(w).iter().zip(&want) {
            assert!(dist(*g, *o) <= 1e-6 * diag, "frame {k}: {g:?} vs {o:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
