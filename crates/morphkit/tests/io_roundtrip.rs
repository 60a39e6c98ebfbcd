//! Round trips through every writer and reader of `morphkit::io`.

use morphkit::io::{self, Colors, FramesOptions, GltfMorphs, PlyEncoding};
use morphkit::mesh::Polygons;
use morphkit::{ShapeSet, TriMesh};
use std::path::PathBuf;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-io-rt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small open mesh of two quads and a triangle, with awkward coordinates.
fn mesh() -> TriMesh {
    TriMesh::from_polygons(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.1],
            [1.0, 1.0, 1.0 / 3.0],
            [0.0, 1.0, -2e-7],
            [2.0, 0.0, 0.25],
            [2.0, 1.0, std::f64::consts::PI],
            [3.0, 0.5, 1e-3],
        ],
        Polygons {
            offsets: vec![0, 4, 8, 11],
            indices: vec![0, 1, 2, 3, 1, 4, 5, 2, 4, 6, 5],
        },
    )
}

fn bent(m: &TriMesh, s: f64) -> Vec<[f64; 3]> {
    m.positions
        .iter()
        .map(|p| [p[0], p[1] + s * p[0] * p[0], p[2] - s * p[1]])
        .collect()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn obj_glb_obj_keeps_positions_within_f32_precision() {
    let d = tmp_dir("obj-glb");
    let m = mesh();
    io::write_mesh(&d.join("a.obj"), &m).unwrap();
    let a = io::read_mesh(&d.join("a.obj")).unwrap();
    assert_eq!(a, m, "OBJ is lossless, polygons included");
    io::write_mesh(&d.join("a.glb"), &a).unwrap();
    let g = io::read_mesh(&d.join("a.glb")).unwrap();
    io::write_mesh(&d.join("b.obj"), &g).unwrap();
    let b = io::read_mesh(&d.join("b.obj")).unwrap();
    assert_eq!(b.triangles, m.triangles);
    assert!(max_diff(&b.positions, &m.positions) <= 4.0 * f32::EPSILON as f64 * 3.2);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn obj_gz_and_off_round_trips_are_exact() {
    let d = tmp_dir("gz-off");
    let m = mesh();
    for name in ["a.obj.gz", "a.off"] {
        io::write_mesh(&d.join(name), &m).unwrap();
        assert_eq!(io::read_mesh(&d.join(name)).unwrap(), m, "{name}");
    }
    let raw = std::fs::read(d.join("a.obj.gz")).unwrap();
    assert_eq!(&raw[..2], &[0x1f, 0x8b], "gzip magic");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ply_ascii_and_binary_round_trips_are_exact() {
    let d = tmp_dir("ply");
    let m = mesh();
    for (i, enc) in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ]
    .into_iter()
    .enumerate()
    {
        let p = d.join(format!("m{i}.ply"));
        io::ply::write_ply(&p, &m, enc).unwrap();
        assert_eq!(io::read_mesh(&p).unwrap(), m, "{enc:?}");
    }
    // write_mesh defaults to binary little endian.
    io::write_mesh(&d.join("d.ply"), &m).unwrap();
    let head = std::fs::read(d.join("d.ply")).unwrap();
    assert!(String::from_utf8_lossy(&head[..60]).contains("binary_little_endian"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn colored_ply_has_colors_and_still_reads() {
    let d = tmp_dir("color");
    let m = TriMesh::new(mesh().positions, mesh().triangles);
    let vc = io::scalar_colors(&m.positions.iter().map(|p| p[0] - 1.0).collect::<Vec<_>>());
    io::write_ply_colored(&d.join("v.ply"), &m, &Colors::PerVertex(vc)).unwrap();
    let fc = io::scalar_colors(&(0..m.num_triangles()).map(|t| t as f64).collect::<Vec<_>>());
    io::write_ply_colored(&d.join("f.ply"), &m, &Colors::PerFace(fc)).unwrap();
    for f in ["v.ply", "f.ply"] {
        let bytes = std::fs::read(d.join(f)).unwrap();
        assert!(String::from_utf8_lossy(&bytes[..400]).contains("property uchar red"));
        assert_eq!(io::read_mesh(&d.join(f)).unwrap(), m, "{f}");
    }
    let e = io::write_ply_colored(&d.join("bad.ply"), &m, &Colors::PerVertex(vec![[0; 3]; 2]))
        .unwrap_err();
    assert!(e.to_string().contains("bad.ply") && e.to_string().contains("2 vertex colours"));
    assert!(!d.join("bad.ply").exists());
    let _ = std::fs::remove_dir_all(&d);
}

fn frames() -> ShapeSet {
    let m = mesh();
    ShapeSet::new(
        m.clone(),
        vec![
            ("rest".into(), m.positions.clone()),
            ("bend-a".into(), bent(&m, 0.3)),
            ("bend-b".into(), bent(&m, -0.7)),
        ],
    )
    .unwrap()
}

#[test]
fn pc2_round_trip_with_reference() {
    let d = tmp_dir("pc2");
    let f = frames();
    io::write_mesh(&d.join("ref.obj"), f.base()).unwrap();
    io::write_frames(&d.join("a.pc2"), &f, &FramesOptions::default()).unwrap();
    let bytes = std::fs::read(d.join("a.pc2")).unwrap();
    assert_eq!(&bytes[..12], b"POINTCACHE2\0");
    assert_eq!(bytes.len(), 32 + 12 * 7 * 3);
    let back = io::read_animation(&d.join("a.pc2"), Some(&d.join("ref.obj"))).unwrap();
    assert_eq!(back.len(), 3);
    assert_eq!(back.triangles(), f.triangles());
    for i in 0..3 {
        assert!(max_diff(back.positions(i), f.positions(i)) < 1e-6);
    }
    let e = io::read_animation(&d.join("a.pc2"), None).unwrap_err();
    assert!(e.to_string().contains("a.pc2") && e.to_string().contains("reference"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn gltf_morph_round_trip_keeps_names_targets_and_keys() {
    let d = tmp_dir("morphs");
    let m = mesh();
    let rig = GltfMorphs {
        base: TriMesh::new(m.positions.clone(), m.triangles.clone()),
        target_names: vec!["jawOpen".into(), "smile_L".into()],
        targets: vec![bent(&m, 0.5), bent(&m, -0.2)],
        weight_keys: vec![
            (0.0, vec![0.0, 0.0]),
            (0.5, vec![1.0, 0.25]),
            (1.25, vec![0.0, 1.0]),
        ],
    };
    for name in ["r.glb", "r.gltf"] {
        let p = d.join(name);
        io::write_gltf_morphs(&p, &rig).unwrap();
        let back = io::read_gltf_morphs(&p).unwrap();
        assert_eq!(back.target_names, rig.target_names, "{name}");
        assert_eq!(back.base.triangles, rig.base.triangles);
        assert!(max_diff(&back.base.positions, &rig.base.positions) < 1e-6);
        for t in 0..2 {
            assert!(
                max_diff(&back.targets[t], &rig.targets[t]) < 1e-6,
                "{name} target {t}"
            );
        }
        assert_eq!(back.weight_keys.len(), 3);
        for (a, b) in back.weight_keys.iter().zip(&rig.weight_keys) {
            assert!((a.0 - b.0).abs() < 1e-6);
            assert_eq!(a.1, b.1);
        }
    }
    // Without an animation, read_animation gives the base then each target by name.
    let still = GltfMorphs {
        weight_keys: Vec::new(),
        ..rig.clone()
    };
    io::write_gltf_morphs(&d.join("s.glb"), &still).unwrap();
    let set = io::read_animation(&d.join("s.glb"), None).unwrap();
    assert_eq!(set.names(), ["base", "jawOpen", "smile_L"]);
    assert!(max_diff(set.positions(1), &rig.targets[0]) < 1e-6);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn frames_through_glb_and_directory_come_back_in_order() {
    let d = tmp_dir("frames");
    let f = frames();
    let opts = FramesOptions {
        fps: 10.0,
        ..FramesOptions::default()
    };
    io::write_frames(&d.join("anim.glb"), &f, &opts).unwrap();
    let rig = io::read_gltf_morphs(&d.join("anim.glb")).unwrap();
    let times: Vec<f64> = rig.weight_keys.iter().map(|k| k.0).collect();
    assert!(max_diff(&[[times[0], times[1], times[2]]], &[[0.0, 0.1, 0.2]]) < 1e-6);
    // Frame 0 is the base itself, not an all-zero morph target (issue 15), so it has no
    // target name to come back with; the later frames keep theirs.
    assert_eq!(rig.targets.len(), f.len() - 1);
    assert_eq!(rig.target_names, ["bend-a", "bend-b"]);
    assert!(max_diff(&rig.base.positions, f.positions(0)) < 1e-6);
    let back = io::read_animation(&d.join("anim.glb"), None).unwrap();
    assert_eq!(back.names(), ["frame_0000", "bend-a", "bend-b"]);
    for i in 0..f.len() {
        assert!(max_diff(back.positions(i), f.positions(i)) < 1e-6);
    }
    io::write_frames(&d.join("frames"), &back, &opts).unwrap();
    assert!(d.join("frames/frame_0002.obj").is_file());
    let again = io::read_animation(&d.join("frames"), None).unwrap();
    assert_eq!(
        again.names(),
        ["frame_0000.obj", "frame_0001.obj", "frame_0002.obj"]
    );
    assert_eq!(
        again.all_positions(),
        back.all_positions(),
        "OBJ frames are exact"
    );
    assert!(again.base().polygons.is_none(), "glTF holds triangles only");
    io::write_frames(&d.join("quads"), &f, &opts).unwrap();
    let quads = io::read_animation(&d.join("quads"), None).unwrap();
    assert_eq!(
        quads.base().polygons,
        f.base().polygons,
        "OBJ frames keep polygons"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn read_shape_set_names_shapes_by_file() {
    let d = tmp_dir("set");
    let f = frames();
    let paths: Vec<PathBuf> = (0..3).map(|i| d.join(format!("s{i}.obj"))).collect();
    for (i, p) in paths.iter().enumerate() {
        io::write_mesh(p, &f.mesh(i)).unwrap();
    }
    let set = io::read_shape_set(&paths).unwrap();
    assert_eq!(set.names(), ["s0.obj", "s1.obj", "s2.obj"]);
    assert_eq!(set.all_positions(), f.all_positions());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn gltf_with_an_external_bin_file_reads() {
    let d = tmp_dir("external");
    let m = TriMesh::new(mesh().positions, mesh().triangles);
    io::write_mesh(&d.join("inline.gltf"), &m).unwrap();
    // Move the embedded buffer into a .bin file beside the JSON.
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("inline.gltf")).unwrap()).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let b64 = uri.split_once("base64,").unwrap().1;
    let bin = decode_base64(b64);
    assert_eq!(
        bin.len() as u64,
        doc["buffers"][0]["byteLength"].as_u64().unwrap()
    );
    std::fs::write(d.join("data.bin"), &bin).unwrap();
    doc["buffers"][0]["uri"] = serde_json::json!("data.bin");
    std::fs::write(d.join("external.gltf"), serde_json::to_vec(&doc).unwrap()).unwrap();
    let back = io::read_mesh(&d.join("external.gltf")).unwrap();
    assert_eq!(back.triangles, m.triangles);
    assert!(max_diff(&back.positions, &m.positions) < 1e-6);
    // Without the .bin file: a clean error naming the glTF file.
    std::fs::remove_file(d.join("data.bin")).unwrap();
    let e = io::read_mesh(&d.join("external.gltf"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("external.gltf"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

fn decode_base64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    } as u32;
    let mut out = Vec::new();
    for chunk in s.as_bytes().chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let n = chunk
            .iter()
            .map(|&c| if c == b'=' { 0 } else { val(c) })
            .fold(0u32, |a, v| a << 6 | v);
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&bytes[..3 - pad]);
    }
    out
}
