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
    m.positions[2][1] = 0.8125;
    let p = d.join("n.ply");
    io::write_mesh(&p, &m).unwrap(); // writers refuse NaN: patch it in afterwards
    patch_bytes(&p, &0.8125f64.to_le_bytes(), &f64::NAN.to_le_bytes());
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

#[test]
fn write_frames_refuses_its_own_input_directory() {
    let d = tmp_dir("own-dir");
    let set = ShapeSet::from_meshes(vec![("q".into(), quad())]).unwrap();
    let opts = FramesOptions {
        inputs: vec![d.clone()],
        ..FramesOptions::default()
    };
    let e = io::write_frames(&d, &set, &opts).unwrap_err();
    assert!(matches!(e, IoError::WouldOverwriteInput { .. }), "{e}");
    assert!(!d.join("frame_0000.obj").exists());
    let _ = std::fs::remove_dir_all(&d);
}

fn dir_names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn frame_directory_removes_stale_frames_and_keeps_old_ones_on_failure() {
    let root = tmp_dir("frames-safe");
    let d = root.join("out");
    std::fs::create_dir_all(&d).unwrap();
    let q = quad();
    let five: Vec<(String, Vec<[f64; 3]>)> = (0..5)
        .map(|k| (format!("s{k}"), q.positions.clone()))
        .collect();
    let set5 = ShapeSet::new(q.clone(), five).unwrap();
    std::fs::write(d.join("notes.txt"), "keep").unwrap();
    io::write_frames(&d, &set5, &FramesOptions::default()).unwrap();
    assert_eq!(dir_names(&d).len(), 6);
    // A shorter run leaves no stale higher-numbered frames behind.
    let set2 =
        ShapeSet::from_meshes(vec![("a".into(), q.clone()), ("b".into(), q.clone())]).unwrap();
    io::write_frames(&d, &set2, &FramesOptions::default()).unwrap();
    assert_eq!(
        dir_names(&d),
        ["frame_0000.obj", "frame_0001.obj", "notes.txt"]
    );
    // A failing later frame changes and deletes nothing that existed before.
    let before0 = std::fs::read(d.join("frame_0000.obj")).unwrap();
    let mut moved = q.positions.clone();
    moved[0] = [9.0, 9.0, 9.0];
    let mut bad = q.positions.clone();
    bad[2] = [f64::NAN, 0.0, 0.0];
    let set3 = ShapeSet::new(
        q.clone(),
        vec![
            ("a".into(), moved),
            ("b".into(), bad),
            ("c".into(), q.positions.clone()),
        ],
    )
    .unwrap();
    let e = io::write_frames(&d, &set3, &FramesOptions::default()).unwrap_err();
    let s = e.to_string();
    assert!(
        s.contains("frame_0001.obj") && s.contains("vertex 2"),
        "{s}"
    );
    assert_eq!(std::fs::read(d.join("frame_0000.obj")).unwrap(), before0);
    assert_eq!(
        dir_names(&d),
        ["frame_0000.obj", "frame_0001.obj", "notes.txt"]
    );
    assert_eq!(dir_names(&root), ["out"], "no temporary directory is left");
    // A new directory that fails is not created at all.
    let e = io::write_frames(&root.join("fresh"), &set3, &FramesOptions::default());
    assert!(e.is_err());
    assert_eq!(dir_names(&root), ["out"]);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn ply_huge_counts_and_propertyless_binary_elements_are_errors() {
    let d = tmp_dir("ply-huge");
    let p = d.join("huge.ply");
    std::fs::write(
        &p,
        "ply\nformat binary_little_endian 1.0\nelement vertex 100000000000000000\n\
         property float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0",
    )
    .unwrap();
    read_err(&p, &["vertex"]);
    let p = d.join("faces.ply");
    std::fs::write(
        &p,
        format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n\
             property float y\nproperty float z\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n\x03",
            usize::MAX
        ),
    )
    .unwrap();
    read_err(&p, &["face"]);
    let p = d.join("empty-el.ply");
    std::fs::write(
        &p,
        format!(
            "ply\nformat binary_little_endian 1.0\nelement junk {}\nelement vertex 0\n\
             property float x\nproperty float y\nproperty float z\nend_header\n",
            u64::MAX
        ),
    )
    .unwrap();
    read_err(&p, &["'junk'", "no properties"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn pc2_with_zero_points_and_many_samples_is_an_error() {
    let d = tmp_dir("pc2-zero");
    let p = d.join("z.pc2");
    let mut b = b"POINTCACHE2\0".to_vec();
    b.extend(1i32.to_le_bytes());
    b.extend(0i32.to_le_bytes());
    b.extend(0f32.to_le_bytes());
    b.extend(1f32.to_le_bytes());
    b.extend(i32::MAX.to_le_bytes());
    std::fs::write(&p, &b).unwrap();
    let e = io::pc2::parse_pc2(&p, &b).unwrap_err().to_string();
    assert!(e.contains("z.pc2") && e.contains("0 points"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Replaces the first occurrence of `from` in the file with `to`.
fn patch_bytes(path: &Path, from: &[u8], to: &[u8]) {
    let mut b = std::fs::read(path).unwrap();
    let i = b
        .windows(from.len())
        .position(|w| w == from)
        .expect("pattern present");
    b[i..i + to.len()].copy_from_slice(to);
    std::fs::write(path, b).unwrap();
}

#[test]
fn gltf_non_finite_displacements_and_weights_name_the_index() {
    let d = tmp_dir("gltf-nan");
    let q = quad();
    let mut t1 = q.positions.clone();
    t1[3][2] = 1234.5;
    let rig = GltfMorphs {
        base: q.clone(),
        target_names: vec!["a".into(), "b".into()],
        targets: vec![q.positions.clone(), t1],
        weight_keys: vec![(0.0, vec![1.0, 0.0]), (1.0, vec![0.0, 0.625])],
    };
    let p = d.join("disp.glb");
    io::write_gltf_morphs(&p, &rig).unwrap();
    patch_bytes(&p, &1234.5f32.to_le_bytes(), &f32::NAN.to_le_bytes());
    let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
    assert!(
        e.contains("disp.glb") && e.contains("morph target 1") && e.contains("vertex 3"),
        "{e}"
    );
    let p = d.join("weight.glb");
    io::write_gltf_morphs(&p, &rig).unwrap();
    patch_bytes(&p, &0.625f32.to_le_bytes(), &f32::INFINITY.to_le_bytes());
    let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
    assert!(
        e.contains("weight.glb") && e.contains("key 1") && e.contains("target 1"),
        "{e}"
    );
    let e = io::read_animation(&p, None).unwrap_err().to_string();
    assert!(e.contains("key 1"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn writers_refuse_non_finite_coordinates() {
    let d = tmp_dir("write-nan");
    let mut m = quad();
    m.positions[2][1] = f64::INFINITY;
    for name in ["m.obj", "m.obj.gz", "m.ply", "m.off"] {
        let p = d.join(name);
        let e = io::write_mesh(&p, &m).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("vertex 2"), "{e}");
        assert!(!p.exists());
    }
    let colors = io::Colors::PerVertex(vec![[0, 0, 0]; 4]);
    let p = d.join("c.ply");
    let e = io::write_ply_colored(&p, &m, &colors)
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 2"), "{e}");
    assert_eq!(dir_names(&d).len(), 0);
    let _ = std::fs::remove_dir_all(&d);
}
