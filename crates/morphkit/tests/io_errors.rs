//! Bad input gives an error naming the file and the problem, never a panic.

use morphkit::io::{self, FramesOptions, GltfMorphs, IoError};
use morphkit::{ShapeSet, TriMesh};
use std::path::{Path, PathBuf};

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-io-err-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn quad() -> TriMesh {
    TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// The error of reading `path`, which must name the file and contain every one of `parts`.
fn read_err(path: &Path, parts: &[&str]) -> IoError {
    let e = io::read_mesh(path).expect_err("reading should fail");
    let s = e.to_string();
    assert!(
        s.contains(&path.display().to_string()),
        "'{s}' does not name {}",
        path.display()
    );
    for p in parts {
        assert!(s.contains(p), "'{s}' does not contain '{p}'");
    }
    assert_eq!(e.path(), path);
    e
}

#[test]
fn empty_files() {
    let d = tmp_dir("empty");
    for name in ["e.obj", "e.ply", "e.off", "e.glb", "e.gltf"] {
        std::fs::write(d.join(name), b"").unwrap();
        let e = read_err(&d.join(name), &["empty"]);
        assert!(matches!(e, IoError::Empty { .. }));
    }
    // A file with content but no faces.
    std::fs::write(d.join("v.obj"), "v 0 0 0\n").unwrap();
    read_err(&d.join("v.obj"), &["no triangles"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn truncated_binary_ply_names_the_byte_offset() {
    let d = tmp_dir("ply");
    let p = d.join("t.ply");
    io::write_mesh(&p, &quad()).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 7]).unwrap();
    let e = read_err(&p, &["at byte", "face 1", "truncated"]);
    assert!(matches!(e, IoError::Binary { .. }));
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    std::fs::write(&p, &bytes[..body + 30]).unwrap();
    read_err(
        &p,
        &[
            &format!("at byte {}", body + 24),
            "vertex 1, property 'x'",
            "6 left",
        ],
    );
    std::fs::write(&p, &bytes[..body - 5]).unwrap();
    read_err(&p, &["header ends before 'end_header'"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn truncated_glb_names_the_byte_offset() {
    let d = tmp_dir("glb");
    let p = d.join("t.glb");
    io::write_mesh(&p, &quad()).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 10]).unwrap();
    let e = read_err(&p, &["at byte", "truncated"]);
    assert!(matches!(e, IoError::Binary { .. }));
    std::fs::write(&p, &bytes[..7]).unwrap();
    read_err(&p, &["GLB header"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn malformed_numbers_name_the_line() {
    let d = tmp_dir("num");
    let p = d.join("m.obj");
    std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1.2.3 0\nf 1 2 3\n").unwrap();
    let e = read_err(&p, &[":3:", "malformed number '1.2.3'"]);
    assert!(matches!(e, IoError::Parse { line: 3, .. }));
    let p = d.join("m.off");
    std::fs::write(&p, "OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n").unwrap();
    read_err(&p, &[":4:", "malformed number 'x'"]);
    let p = d.join("m.ply");
    std::fs::write(
        &p,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n",
    )
    .unwrap();
    read_err(&p, &[":12:", "malformed number 'one'", "vertex 2"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn face_index_out_of_range() {
    let d = tmp_dir("range");
    let p = d.join("r.obj");
    std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n").unwrap();
    read_err(&p, &[":5:", "face index 4 is out of range", "3 vertices"]);
    let p = d.join("r.ply");
    std::fs::write(
        &p,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
    )
    .unwrap();
    read_err(&p, &["face 0 refers to vertex 5"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn nan_coordinates() {
    let d = tmp_dir("nan");
    let p = d.join("n.obj");
    std::fs::write(&p, "v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    read_err(&p, &[":2:", "non-finite coordinate 'NaN'"]);
    // Binary PLY: caught by validation, naming the vertex.
    let mut m = quad();
    m.positions[2][1] = f64::NAN;
    let p = d.join("n.ply");
    io::write_mesh(&p, &m).unwrap();
    let e = read_err(&p, &["vertex 2", "non-finite"]);
    assert!(matches!(e, IoError::InvalidMesh { .. }));
    let _ = std::fs::remove_dir_all(&d);
}

/// Rewrites the JSON chunk of a GLB written by morphkit.
fn edit_glb_json(path: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let b = std::fs::read(path).unwrap();
    let jlen = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    let mut doc: serde_json::Value = serde_json::from_slice(&b[20..20 + jlen]).unwrap();
    edit(&mut doc);
    let bin = &b[20 + jlen..];
    let mut json = serde_json::to_vec(&doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend(bin);
    std::fs::write(path, out).unwrap();
}

#[test]
fn gltf_morph_target_with_another_count() {
    let d = tmp_dir("gltf");
    let p = d.join("bad.glb");
    let q = quad();
    let rig = GltfMorphs {
        base: q.clone(),
        target_names: vec!["a".into()],
        targets: vec![q.positions.iter().map(|p| [p[0], p[1], 1.0]).collect()],
        weight_keys: Vec::new(),
    };
    io::write_gltf_morphs(&p, &rig).unwrap();
    edit_glb_json(&p, |doc| {
        let t = doc["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        doc["accessors"][t]["count"] = serde_json::json!(3);
    });
    let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
    assert!(
        e.contains("bad.glb")
            && e.contains("morph target 0")
            && e.contains("has 3 elements, the base POSITION has 4"),
        "{e}"
    );
    let e = io::read_animation(&p, None).unwrap_err().to_string();
    assert!(e.contains("bad.glb") && e.contains("morph target 0"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn shape_set_with_different_connectivity_names_file_and_face() {
    let d = tmp_dir("set");
    let a = d.join("a.obj");
    let b = d.join("b.obj");
    io::write_mesh(&a, &quad()).unwrap();
    let mut other = quad();
    other.triangles[1] = [0, 3, 2];
    io::write_mesh(&b, &other).unwrap();
    let e = io::read_shape_set(&[a.clone(), b.clone()]).unwrap_err();
    let s = e.to_string();
    assert!(
        s.contains(&b.display().to_string()) && s.contains("triangle 1"),
        "{s}"
    );
    assert!(s.contains("a.obj"), "names the base: {s}");
    assert_eq!(e.path(), b);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn directory_where_a_file_is_expected() {
    let d = tmp_dir("dir");
    let sub = d.join("x.obj");
    std::fs::create_dir_all(&sub).unwrap();
    let e = read_err(&sub, &["is a directory"]);
    assert!(matches!(e, IoError::IsDirectory { .. }));
    let e = io::write_mesh(&sub, &quad()).unwrap_err();
    assert!(matches!(e, IoError::IsDirectory { .. }), "{e}");
    let e = io::read_shape_set(std::slice::from_ref(&sub)).unwrap_err();
    assert!(e.to_string().contains("is a directory"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn unwritable_output_path_leaves_nothing_behind() {
    let d = tmp_dir("unwritable");
    let file = d.join("plain.txt");
    std::fs::write(&file, "x").unwrap();
    // The parent is a file, so nothing can be created there (even as root).
    for name in ["out.obj", "out.glb", "out.ply", "out.off"] {
        let out = file.join(name);
        let e = io::write_mesh(&out, &quad()).unwrap_err();
        let s = e.to_string();
        assert!(
            s.contains(&out.display().to_string()) && s.contains("cannot create"),
            "{s}"
        );
    }
    let missing = d.join("no-such-dir").join("a.obj");
    let e = io::write_mesh(&missing, &quad()).unwrap_err().to_string();
    assert!(e.contains("no-such-dir"), "{e}");
    let set = ShapeSet::from_meshes(vec![("q".into(), quad())]).unwrap();
    let e = io::write_frames(&file.join("frames"), &set, &FramesOptions::default()).unwrap_err();
    assert!(e.to_string().contains("frames"), "{e}");
    let left: Vec<_> = std::fs::read_dir(&d).unwrap().collect();
    assert_eq!(left.len(), 1, "only plain.txt remains");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn never_overwrites_an_input() {
    let d = tmp_dir("input");
    let a = d.join("a.obj");
    io::write_mesh(&a, &quad()).unwrap();
    let before = std::fs::read(&a).unwrap();
    let set = ShapeSet::from_meshes(vec![("q".into(), quad())]).unwrap();
    let opts = FramesOptions {
        inputs: vec![a.clone()],
        ..FramesOptions::default()
    };
    let e = io::write_frames(&d.join(".").join("a.obj"), &set, &opts).unwrap_err();
    assert!(matches!(e, IoError::WouldOverwriteInput { .. }), "{e}");
    let e = io::write_frames(&d, &set, &opts).unwrap_err();
    assert!(e.to_string().contains("refusing to overwrite"), "{e}");
    assert_eq!(std::fs::read(&a).unwrap(), before);
    assert!(!d.join("frame_0000.obj").exists());
    let bad_fps = FramesOptions {
        fps: 0.0,
        ..FramesOptions::default()
    };
    let e = io::write_frames(&d.join("x.glb"), &set, &bad_fps).unwrap_err();
    assert!(e.to_string().contains("x.glb") && e.to_string().contains("frame rate"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn unknown_extensions_and_bad_pc2() {
    let d = tmp_dir("ext");
    let p = d.join("m.stl");
    std::fs::write(&p, "solid").unwrap();
    read_err(&p, &["unsupported format"]);
    let p = d.join("a.pc2");
    std::fs::write(&p, b"POINTCACHE2\0\x01\0\0\0").unwrap();
    let r = d.join("r.obj");
    io::write_mesh(&r, &quad()).unwrap();
    let e = io::read_animation(&p, Some(&r)).unwrap_err().to_string();
    assert!(
        e.contains("a.pc2") && e.contains("at byte") && e.contains("header"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
