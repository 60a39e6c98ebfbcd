//! Issue 8 (hardening): byte-order marks, gzip framing, GLB magic and glTF buffer URIs.

use morphkit::io::{self, GltfMorphs};
use morphkit::TriMesh;
use std::path::{Path, PathBuf};

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-io-hard-{name}-{}", std::process::id()));
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

const BOM: &[u8] = b"\xEF\xBB\xBF";

fn with_bom(text: &str) -> Vec<u8> {
    [BOM, text.as_bytes()].concat()
}

fn err(path: &Path) -> String {
    let e = io::read_mesh(path)
        .expect_err("reading should fail")
        .to_string();
    assert!(e.contains(&path.display().to_string()), "{e}");
    e
}

#[test]
fn a_byte_order_mark_is_accepted_in_every_text_format() {
    let d = tmp_dir("bom");
    let q = quad();
    let obj = d.join("q.obj");
    std::fs::write(
        &obj,
        with_bom("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"),
    )
    .unwrap();
    let m = io::read_mesh(&obj).unwrap();
    assert_eq!(m.positions, q.positions);
    assert_eq!(m.triangles, q.triangles);
    let off = d.join("q.off");
    std::fs::write(
        &off,
        with_bom("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"),
    )
    .unwrap();
    assert_eq!(io::read_mesh(&off).unwrap().positions, q.positions);
    let ply = d.join("q.ply");
    std::fs::write(
        &ply,
        with_bom(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
        ),
    )
    .unwrap();
    assert_eq!(io::read_mesh(&ply).unwrap().triangles, q.triangles);
    // glTF JSON written by morphkit, with a BOM prepended.
    let gltf = d.join("q.gltf");
    io::write_gltf_morphs(
        &gltf,
        &GltfMorphs {
            base: q.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    let text = std::fs::read_to_string(&gltf).unwrap();
    std::fs::write(&gltf, with_bom(&text)).unwrap();
    assert_eq!(io::read_mesh(&gltf).unwrap().triangles, q.triangles);
    let markers = morphkit::transfer::Markers::from_json("\u{feff}{\"pairs\": [[0, 1]]}").unwrap();
    assert_eq!(markers.pairs, [[0, 1]]);
    let rows = io::parse_weights(Path::new("w.csv"), "\u{feff}0.5\n", false).unwrap();
    assert_eq!(rows[0].values, [0.5]);
    let _ = std::fs::remove_dir_all(&d);
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn gzip_framing_errors_say_what_is_wrong() {
    let d = tmp_dir("gz");
    let obj = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    let random = d.join("random.obj.gz");
    std::fs::write(&random, b"\x13\x37 not gzip at all, just bytes\n").unwrap();
    let e = err(&random);
    assert!(e.contains("not gzip data"), "{e}");
    let trailing = d.join("trailing.obj.gz");
    std::fs::write(&trailing, [gzip(obj), b"GARBAGE!".to_vec()].concat()).unwrap();
    let e = err(&trailing);
    assert!(
        e.contains("trailing data after the end of the gzip stream"),
        "{e}"
    );
    let truncated = d.join("truncated.obj.gz");
    let g = gzip(obj);
    std::fs::write(&truncated, &g[..g.len() - 6]).unwrap();
    let e = err(&truncated);
    assert!(e.contains("truncated"), "{e}");
    // Two members and zero padding are fine, as for gunzip.
    let two = d.join("two.obj.gz");
    let (a, b) = obj.split_at(16);
    std::fs::write(&two, [gzip(a), gzip(b), vec![0; 7]].concat()).unwrap();
    assert_eq!(io::read_mesh(&two).unwrap().num_triangles(), 1);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_glb_with_a_wrong_magic_is_not_read_as_json() {
    let d = tmp_dir("glb-magic");
    let glb = d.join("x.glb");
    std::fs::write(&glb, b"GLTF\x02\0\0\0\x20\0\0\0 whatever bytes follow here").unwrap();
    let e = err(&glb);
    assert!(e.contains("not a GLB file"), "{e}");
    assert!(!e.contains("expected value"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A `.gltf` whose buffer is an external file `uri` (the data written next to it).
fn gltf_with_uri(d: &Path, uri: &str) -> PathBuf {
    let g = d.join("m.gltf");
    io::write_gltf_morphs(
        &g,
        &GltfMorphs {
            base: quad(),
            ..Default::default()
        },
    )
    .unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).unwrap()).unwrap();
    doc["buffers"][0]["uri"] = uri.into();
    std::fs::write(&g, doc.to_string()).unwrap();
    g
}

#[test]
fn gltf_buffer_uris_stay_inside_the_file_directory() {
    let d = tmp_dir("uri");
    for bad in ["/dev/zero", "../outside.bin", "file:///dev/zero"] {
        let g = gltf_with_uri(&d, bad);
        let e = err(&g);
        assert!(e.contains("buffer 0"), "{e}");
        assert!(
            e.contains("absolute") || e.contains("leaves the glTF file's directory"),
            "{e}"
        );
    }
    let g = gltf_with_uri(&d, "missing.bin");
    let e = err(&g);
    assert!(e.contains("missing.bin"), "{e}");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", d.join("zero.bin")).unwrap();
        let g = gltf_with_uri(&d, "zero.bin");
        let e = err(&g);
        assert!(e.contains("outside the glTF file's directory"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_external_buffer_is_read_up_to_its_byte_length_only() {
    let d = tmp_dir("uri-len");
    // The written .gltf has its data in a base64 URI: move it into a file, padded with a
    // megabyte of junk that must not be read.
    let g = d.join("m.gltf");
    io::write_gltf_morphs(
        &g,
        &GltfMorphs {
            base: quad(),
            ..Default::default()
        },
    )
    .unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).unwrap()).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let len = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
    let b64 = uri.split_once(";base64,").unwrap().1;
    // Decode through a GLB-free path: write the same mesh as GLB and take its BIN chunk.
    let glb = d.join("m.glb");
    io::write_gltf_morphs(
        &glb,
        &GltfMorphs {
            base: quad(),
            ..Default::default()
        },
    )
    .unwrap();
    let bytes = std::fs::read(&glb).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin = &bytes[20 + json_len + 8..20 + json_len + 8 + len];
    assert!(!b64.is_empty());
    std::fs::write(d.join("data bin.bin"), [bin, &vec![0xAB; 1 << 20]].concat()).unwrap();
    let g2 = gltf_with_uri(&d, "data%20bin.bin");
    assert_eq!(io::read_mesh(&g2).unwrap().positions, quad().positions);
    // A file shorter than byteLength names the file and both sizes.
    std::fs::write(d.join("short.bin"), &bin[..len / 2]).unwrap();
    let g3 = gltf_with_uri(&d, "short.bin");
    let e = err(&g3);
    assert!(
        e.contains("short.bin") && e.contains(&format!("byteLength declares {len}")),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Found by `cargo fuzz` (target `gltf`): a GLB header declaring a length below 12 bytes made
/// the `gltf` crate subtract with overflow.
#[test]
fn a_glb_length_below_its_header_is_an_error() {
    let d = tmp_dir("glb-len");
    let glb = d.join("x.glb");
    std::fs::write(&glb, b"glTF\x02\0\0\0\0\0\0\0\x16\x20\x20{\"b    ").unwrap();
    let e = err(&glb);
    assert!(e.contains("less than the header itself"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Found by `cargo fuzz` (target `gltf`): a POSITION attribute naming a missing accessor made
/// the `gltf-json` crate index out of bounds.
#[test]
fn a_position_accessor_that_does_not_exist_is_an_error() {
    let d = tmp_dir("gltf-pos");
    let g = d.join("x.gltf");
    std::fs::write(
        &g,
        r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}"#,
    )
    .unwrap();
    let e = err(&g);
    assert!(
        e.contains("mesh 0, primitive 0: POSITION names accessor 0, but the file has 0 accessors"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Found by `cargo fuzz` (target `gltf`): an animation channel with an unknown target path
/// made the `gltf` crate unwrap an invalid value.
#[test]
fn an_unknown_animation_path_is_not_a_panic() {
    let d = tmp_dir("gltf-path");
    let frames = d.join("a.gltf");
    let set = morphkit::ShapeSet::new(
        quad(),
        vec![
            ("a".into(), quad().positions),
            // A frame that moves: a frame equal to the first is no morph target, and a
            // sequence without targets has no weights channel.
            (
                "b".into(),
                quad().positions.iter().map(|p| [p[0], p[1], 1.0]).collect(),
            ),
        ],
    )
    .unwrap();
    io::write_frames(&frames, &set, &Default::default()).unwrap();
    let text = std::fs::read_to_string(&frames).unwrap();
    assert!(text.contains("\"weights\""));
    std::fs::write(&frames, text.replace("\"weights\"", "\"igewhts\"")).unwrap();
    // Either an error naming the file or the rig without its animation; never a panic.
    match io::read_gltf_morphs(&frames) {
        Ok(rig) => assert!(rig.weight_keys.is_empty()),
        Err(e) => assert!(e.to_string().contains("a.gltf"), "{e}"),
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Found by `cargo fuzz` (target `gltf`): an accessor with count 0 made the `gltf` crate's
/// reader compute `count - 1`, which overflows.
#[test]
fn an_empty_accessor_is_an_error() {
    let d = tmp_dir("gltf-count");
    let g = d.join("x.gltf");
    io::write_gltf_morphs(
        &g,
        &GltfMorphs {
            base: quad(),
            ..Default::default()
        },
    )
    .unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).unwrap()).unwrap();
    doc["accessors"][1]["count"] = 0.into();
    std::fs::write(&g, doc.to_string()).unwrap();
    let e = err(&g);
    assert!(e.contains("accessor 1 has count 0"), "{e}");
    // Found by cargo fuzz: float indices reached an unreachable!() in the gltf crate.
    doc["accessors"][1]["count"] = 6.into();
    doc["accessors"][1]["componentType"] = 5126.into();
    std::fs::write(&g, doc.to_string()).unwrap();
    let e = err(&g);
    assert!(e.contains("expected an unsigned integer type"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Found by `cargo fuzz` (target `gltf`, 10-minute run): an animation sampler whose input (or
/// output) accessor is a VEC3 made the `gltf` crate's reader fail an element-size assertion.
#[test]
fn a_sampler_accessor_of_the_wrong_type_is_an_error() {
    let d = tmp_dir("gltf-sampler");
    let g = d.join("a.gltf");
    let set = morphkit::ShapeSet::new(
        quad(),
        vec![
            ("a".into(), quad().positions),
            (
                "b".into(),
                quad().positions.iter().map(|p| [p[0], p[1], 1.0]).collect(),
            ),
        ],
    )
    .unwrap();
    io::write_frames(&g, &set, &Default::default()).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).unwrap()).unwrap();
    let vec3 = doc["accessors"]
        .as_array()
        .unwrap()
        .iter()
        .position(|a| a["type"] == "VEC3")
        .unwrap();
    for field in ["input", "output"] {
        let mut bad = doc.clone();
        bad["animations"][0]["samplers"][0][field] = vec3.into();
        std::fs::write(&g, bad.to_string()).unwrap();
        let e = err(&g);
        assert!(
            e.contains(&format!("the {field} accessor {vec3} must be SCALAR")),
            "{e}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}
