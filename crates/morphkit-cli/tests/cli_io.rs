//! `morphkit info` and `morphkit convert`, run as the built binary.

mod common;
use common::*;
use std::process::Command;

use std::path::{Path, PathBuf};

/// Writes a strip of `n` quads bent by `bend`, as OBJ.
fn write_strip(path: &Path, n: usize, bend: f64) {
    let mut t = String::new();
    for i in 0..=n {
        let x = i as f64 / n as f64;
        t += &format!("v {x} 0 {}\nv {x} 1 {}\n", bend * x * x, bend * x * x);
    }
    for i in 0..n {
        let a = 2 * i + 1;
        t += &format!("f {} {} {} {}\n", a, a + 2, a + 3, a + 1);
    }
    std::fs::write(path, t).unwrap();
}

fn frames(d: &Path, n: usize) -> Vec<PathBuf> {
    std::fs::create_dir_all(d.join("seq")).unwrap();
    (0..n)
        .map(|k| {
            let p = d.join(format!("seq/f{k:02}.obj"));
            write_strip(&p, 4, k as f64 * 0.1);
            p
        })
        .collect()
}

#[test]
fn help_shows_examples() {
    for cmd in ["info", "convert"] {
        let h = ok(&[cmd, "--help"]);
        assert!(
            h.contains("Examples:") && h.contains(&format!("morphkit {cmd} ")),
            "{h}"
        );
    }
}

#[test]
fn info_text_and_json() {
    let d = tmp_dir("io-info");
    let f = frames(&d, 2);
    let text = ok(&["info", s(&f[0]), s(&f[1])]);
    assert!(text.contains("vertices               10"), "{text}");
    assert!(text.contains("triangles              8"), "{text}");
    assert!(text.contains("polygons               4"), "{text}");
    assert!(text.contains("boundary edges         10"), "{text}");
    assert!(text.contains("shared connectivity: yes"), "{text}");
    let json: serde_json::Value = serde_json::from_str(&ok(&["info", "--json", s(&f[0])])).unwrap();
    let r = &json["files"][0];
    assert_eq!(r["vertices"], 10);
    assert_eq!(r["components"], 1);
    assert_eq!(r["closed"], false);
    assert_eq!(r["consistently_oriented"], true);
    assert!((r["bbox_diagonal"].as_f64().unwrap() - 2f64.sqrt()).abs() < 1e-12);
    // Different connectivity is reported, not an error.
    let other = d.join("other.obj");
    write_strip(&other, 5, 0.0);
    let json: serde_json::Value =
        serde_json::from_str(&ok(&["info", "--json", s(&f[0]), s(&other)])).unwrap();
    assert_eq!(json["shared_connectivity"], false);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn convert_single_meshes_between_formats() {
    let d = tmp_dir("io-single");
    let f = frames(&d, 1);
    let mut prev = f[0].clone();
    for ext in ["ply", "off", "glb", "gltf", "obj.gz", "obj"] {
        let out = d.join(format!("m.{ext}"));
        ok(&["convert", s(&prev), s(&out)]);
        prev = out;
    }
    let json: serde_json::Value = serde_json::from_str(&ok(&["info", "--json", s(&prev)])).unwrap();
    assert_eq!(json["files"][0]["vertices"], 10);
    assert_eq!(json["files"][0]["triangles"], 8);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn convert_sequences_to_animations_and_back() {
    let d = tmp_dir("io-seq");
    let f = frames(&d, 5);
    // A glob pattern, a directory and a list of files.
    let pattern = format!("{}/seq/f*.obj", d.display());
    ok(&["convert", &pattern, "--fps", "10", s(&d.join("a.glb"))]);
    ok(&["convert", s(&d.join("seq")), s(&d.join("b.gltf"))]);
    let list: Vec<&str> = f.iter().map(|p| s(p)).collect();
    ok(&[&["convert"], list.as_slice(), &[s(&d.join("c.pc2"))]].concat());
    // Back to frames.
    ok(&["convert", s(&d.join("a.glb")), s(&d.join("from-glb"))]);
    ok(&[
        "convert",
        s(&d.join("c.pc2")),
        "--reference",
        s(&f[0]),
        s(&d.join("from-pc2")),
    ]);
    for dir in ["from-glb", "from-pc2"] {
        let names: Vec<String> = (0..5).map(|k| format!("frame_{k:04}.obj")).collect();
        for n in &names {
            assert!(d.join(dir).join(n).is_file(), "{dir}/{n}");
        }
        assert!(!d.join(dir).join("frame_0005.obj").exists());
        let last = std::fs::read_to_string(d.join(dir).join("frame_0004.obj")).unwrap();
        let z: f64 = last
            .lines()
            .rfind(|l| l.starts_with("v "))
            .unwrap()
            .split_whitespace()
            .nth(3)
            .unwrap()
            .parse()
            .unwrap();
        assert!((z - 0.4).abs() < 1e-6, "{dir}: last vertex z = {z}");
    }
    // glTF to glTF keeps the rig.
    ok(&["convert", s(&d.join("a.glb")), s(&d.join("copy.gltf"))]);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("copy.gltf")).unwrap()).unwrap();
    // Frame 0 (f00.obj) is the base, not a target; targets are named by file stem (issue 15).
    assert_eq!(doc["meshes"][0]["extras"]["targetNames"][3], "f04");
    assert_eq!(
        doc["meshes"][0]["extras"]["targetNames"]
            .as_array()
            .unwrap()
            .len(),
        4
    );
    // The asset comes back whole (issue 37): its names are the input's.
    let glb = std::fs::read(d.join("a.glb")).unwrap();
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let src: serde_json::Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    assert_eq!(doc["nodes"], src["nodes"], "the input's nodes, names kept");
    assert_eq!(doc["meshes"], src["meshes"]);
    assert_eq!(
        doc["animations"][0]["channels"][0]["target"]["path"],
        "weights"
    );
    if let Some(script) = std::env::var_os("MORPHKIT_GLTF_VALIDATOR") {
        let st = Command::new("node")
            .arg(script)
            .args([d.join("a.glb"), d.join("b.gltf"), d.join("copy.gltf")])
            .status()
            .unwrap();
        assert!(st.success());
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn convert_errors_are_one_line() {
    let d = tmp_dir("io-errors");
    let f = frames(&d, 2);
    let missing = d.join("missing.obj");
    let e = fails(&["convert", s(&missing), s(&d.join("x.ply"))]);
    assert!(e.contains("missing.obj"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    let e = fails(&["convert", s(&f[0]), s(&f[0])]);
    assert!(e.contains("refusing to overwrite"), "{e}");
    let e = fails(&["convert", s(&f[0]), s(&f[1]), s(&d.join("x.obj"))]);
    assert!(e.contains("a sequence converts to an animation"), "{e}");
    let e = fails(&["convert", s(&d.join("seq")), s(&d.join("seq"))]);
    assert!(e.contains("refusing to overwrite"), "{e}");
    ok(&["convert", s(&f[0]), s(&d.join("a.pc2"))]);
    let e = fails(&["convert", s(&d.join("a.pc2")), s(&d.join("out"))]);
    assert!(e.contains("reference"), "{e}");
    let e = fails(&[
        "convert",
        &format!("{}/nothing-*.obj", d.display()),
        s(&d.join("o.glb")),
    ]);
    assert!(e.contains("no files match"), "{e}");
    let e = fails(&["info", s(&d.join("seq"))]);
    assert!(e.contains("is a directory"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn output_directory_that_is_the_input_directory_is_refused() {
    let d = tmp_dir("io-same-dir");
    let f = frames(&d, 3);
    let seq = d.join("seq");
    let before: Vec<Vec<u8>> = f.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let e = fails(&["convert", s(&seq), s(&seq)]);
    assert!(e.contains("refusing to overwrite"), "{e}");
    let e = fails(&[
        "transfer",
        "--source-ref",
        s(&f[0]),
        "--source",
        s(&seq),
        "--target",
        s(&f[1]),
        "--markers",
        s(&d.join("m.json")),
        "--out",
        s(&seq),
    ]);
    assert!(e.contains("refusing to overwrite"), "{e}");
    let after: Vec<Vec<u8>> = f.iter().map(|p| std::fs::read(p).unwrap()).collect();
    assert_eq!(before, after);
    assert_eq!(std::fs::read_dir(&seq).unwrap().count(), 3);
}

#[test]
fn convert_into_a_frame_directory_drops_stale_frames() {
    let d = tmp_dir("io-stale");
    let f = frames(&d, 4);
    let out = d.join("out");
    ok(&["convert", s(&d.join("seq")), s(&out)]);
    assert!(out.join("frame_0003.obj").exists());
    // Replacing (and deleting) earlier frames needs --force, and the refusal names them.
    let e = fails(&["convert", s(&f[0]), s(&f[1]), s(&out)]);
    assert!(
        e.contains("frame_0000.obj … frame_0003.obj") && e.contains("--force"),
        "{e}"
    );
    assert!(out.join("frame_0003.obj").exists());
    ok(&["convert", s(&f[0]), s(&f[1]), "--force", s(&out)]);
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["frame_0000.obj", "frame_0001.obj"]);
}

#[test]
fn unpadded_frame_numbers_convert_in_frame_order() {
    // Blender's OBJ exporter numbers an animation's files without padding (anim1 … anim12):
    // a directory and a glob of them play in frame order, not anim1, anim10, anim11, anim12, anim2.
    let d = tmp_dir("io-unpadded");
    let seq = d.join("anim");
    std::fs::create_dir_all(&seq).unwrap();
    for k in 1..=12 {
        write_strip(&seq.join(format!("anim{k}.obj")), 4, k as f64 * 0.1);
    }
    let glob = format!("{}/anim*.obj", s(&seq));
    for (input, out) in [
        (s(&seq), d.join("from-dir")),
        (glob.as_str(), d.join("from-glob")),
    ] {
        ok(&["convert", input, s(&out)]);
        for k in 0..12 {
            let v = obj_vertices(&out.join(format!("frame_{k:04}.obj")));
            // The strip's last vertex rises by bend × 1 = (k + 1) × 0.1.
            let z = v[v.len() - 1][2];
            assert!(
                (z - (k + 1) as f64 * 0.1).abs() < 1e-9,
                "{input}: frame {k} has z {z}"
            );
        }
    }
}
