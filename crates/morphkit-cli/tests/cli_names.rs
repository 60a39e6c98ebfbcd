//! Issue 55 (hardening, third probe): names that several elements share. glTF names are not
//! unique: `--mesh Face` took the first of two meshes named `Face` (the second could not be
//! chosen), and a weights CSV whose header named a target that two targets share drove only
//! the first. Shared names are refused, naming the file, the name and the indices, and an
//! index chooses (`--mesh 1`, `--animation 0`).

mod common;
#[path = "../../morphkit/tests/common/gltf_asset.rs"]
mod fixture;

use common::*;
use serde_json::{json, Value};
use std::path::Path;

/// The fixture's asset with every name shared: meshes 0 (the tetrahedron "Prop"), 1 (the tube
/// with morph targets) and 2 (a copy of 1) all named "Body", both weights animations named
/// "Wave", and both targets named "same".
fn shared_asset(path: &Path) {
    let mut spec = fixture::standard(false, 1.0);
    spec.target_names = vec!["same".into(), "same".into()];
    let (mut doc, bin) = fixture::build(&spec);
    doc["meshes"][0]["name"] = json!("Body");
    let copy = doc["meshes"][1].clone();
    doc["meshes"].as_array_mut().unwrap().push(copy);
    for a in doc["animations"].as_array_mut().unwrap() {
        a["name"] = json!("Wave");
    }
    std::fs::write(path, fixture::glb(&doc, &bin)).unwrap();
}

fn vertices(info: &str) -> u64 {
    let v: Value = serde_json::from_str(info).unwrap();
    v["files"][0]["vertices"].as_u64().unwrap()
}

#[test]
fn a_shared_mesh_name_is_refused_and_an_index_chooses() {
    let d = tmp_dir("names-mesh");
    let glb = d.join("shared.glb");
    shared_asset(&glb);
    // Without a choice: two meshes have morph targets, and their names cannot tell them apart.
    let e = fails(&["info", s(&glb)]);
    assert!(
        e.contains("2 meshes have morph targets (mesh 1 'Body', mesh 2 'Body'); choose one by index (names are shared)"),
        "{e}"
    );
    // By the shared name: refused, naming the file, the name and the indices.
    let e = fails(&["info", "--json", "--mesh", "Body", s(&glb)]);
    assert!(
        e.contains("shared.glb: 3 meshes are named 'Body' (mesh 0, mesh 1, mesh 2)"),
        "{e}"
    );
    assert!(
        e.contains("choose one by its index ('0' or '1' or '2')"),
        "{e}"
    );
    // By index: each mesh, the tetrahedron included.
    assert_eq!(
        vertices(&ok(&["info", "--json", "--mesh", "0", s(&glb)])),
        4
    );
    let tube = vertices(&ok(&["info", "--json", "--mesh", "1", s(&glb)]));
    assert!(tube > 100, "{tube}");
    assert_eq!(
        vertices(&ok(&["info", "--json", "--mesh", "2", s(&glb)])),
        tube
    );
    let e = fails(&["info", "--mesh", "7", s(&glb)]);
    assert!(
        e.contains("no mesh named '7' or index; its meshes: mesh 0 'Body'"),
        "{e}"
    );
    // The same rule in blend --rig, with its animation chosen by index too.
    let out = d.join("out.glb");
    let rig = |rest: &[&str]| -> Vec<String> {
        let mut v = vec!["blend", "--rig", s(&glb)];
        v.extend_from_slice(rest);
        v.extend(["--out", s(&out)]);
        v.into_iter().map(String::from).collect()
    };
    let e = fails(&strs(&rig(&["--mesh", "Body", "--animation", "0"])));
    assert!(e.contains("3 meshes are named 'Body'"), "{e}");
    let e = fails(&strs(&rig(&["--mesh", "1", "--animation", "Wave"])));
    assert!(
        e.contains("2 animations driving the morph weights of mesh 'Body' are named 'Wave' (animation 0, animation 1)"),
        "{e}"
    );
    let e = fails(&strs(&rig(&["--mesh", "1"])));
    assert!(
        e.contains("(animation 0 'Wave', animation 1 'Wave'); choose one by index"),
        "{e}"
    );
    ok(&strs(&rig(&["--mesh", "1", "--animation", "0"])));
    assert!(out.exists());
}

#[test]
fn a_weights_header_naming_a_shared_target_is_refused() {
    let d = tmp_dir("names-targets");
    let glb = d.join("shared.glb");
    shared_asset(&glb);
    let out = d.join("frames");
    let run = |csv: &Path| {
        vec![
            "blend".to_string(),
            "--rig".into(),
            s(&glb).into(),
            "--mesh".into(),
            "1".into(),
            "--weights-file".into(),
            s(csv).into(),
            "--out".into(),
            s(&out).into(),
        ]
    };
    let named = d.join("named.csv");
    std::fs::write(&named, "same\n0\n0.5\n1\n").unwrap();
    let e = fails(&strs(&run(&named)));
    assert!(
        e.contains("named.csv:1: column 1 of the header is 'same', which 2 morph targets share (targets 0, 1)"),
        "{e}"
    );
    assert!(e.contains("write the rows without a header"), "{e}");
    assert!(!out.exists());
    // Rows without a header give one weight per target, in order: both can be driven.
    let plain = d.join("plain.csv");
    std::fs::write(&plain, "0,0\n0,1\n1,0\n").unwrap();
    ok(&strs(&run(&plain)));
    assert!(out.join("frame_0002.obj").exists());
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}
