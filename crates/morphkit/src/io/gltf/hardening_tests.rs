//! Issue 55 (hardening, third probe): small files that make the reader decode gigabytes by
//! reusing an accessor or a view, external images that are gzip data, and buffer views that
//! reach past their buffer's `byteLength`.

use super::{parse_gltf_morphs, GltfAsset, GltfAssetOptions, GltfReadOptions};
use serde_json::{json, Value};
use std::path::Path;

const F32: u32 = 5126;

/// A GLB of `doc` and, when given, a BIN chunk (padded to 4 bytes).
pub(super) fn glb(doc: &Value, bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = serde_json::to_vec(doc).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let bin_chunk = bin.map_or(0, |b| 8 + b.len().next_multiple_of(4));
    let total = 12 + 8 + j.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if let Some(b) = bin {
        out.extend_from_slice(&(b.len().next_multiple_of(4) as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(b);
        out.resize(total, 0);
    }
    out
}

/// A VEC3 float accessor of `count` vertices, on `view` (or none: all zeros).
fn positions(count: usize, view: Option<usize>) -> Value {
    let mut a = json!({"componentType": F32, "count": count, "type": "VEC3",
        "min": [0, 0, 0], "max": [0, 0, 0]});
    if let Some(v) = view {
        a["bufferView"] = json!(v);
    }
    a
}

/// The message of a refused read, checked to name the file and to be one line.
fn refused(name: &str, bytes: Vec<u8>) -> String {
    let e = parse_gltf_morphs(Path::new(name), bytes)
        .expect_err("the file must be refused")
        .to_string();
    assert!(e.starts_with(name), "{e}");
    assert!(!e.contains('\n'), "{e}");
    e
}

/// Refused by the decoding budget, before anything is decoded.
fn over_budget(name: &str, bytes: Vec<u8>) -> String {
    let e = refused(name, bytes);
    assert!(
        e.contains("would decode about") && e.contains("more than the 4.00 GiB"),
        "{e}"
    );
    e
}

#[test]
fn primitives_sharing_an_accessor_without_a_view_are_refused() {
    // 1 KB: twelve primitives use one all-zero accessor of 2²⁶ components (the old limit per
    // accessor), 6 GiB of f64 together; the old reader allocated 3.8 GB, then aborted.
    let prims: Vec<Value> = (0..12)
        .map(|_| json!({"attributes": {"POSITION": 0}}))
        .collect();
    let doc = json!({"asset": {"version": "2.0"},
        "accessors": [positions(22_369_621, None)],
        "meshes": [{"primitives": prims}]});
    let bytes = glb(&doc, None);
    assert!(bytes.len() < 1100, "{}", bytes.len());
    let e = over_budget("zeros.glb", bytes);
    assert!(e.contains("about 6.00 GiB (12 uses"), "{e}");
}

/// About 100 000 vertices (a multiple of 3: non-indexed triangles).
const VERTICES: usize = 99_999;

/// One POSITION accessor of [`VERTICES`] on a BIN chunk of zeros.
fn shared_vertices() -> (Vec<u8>, Value) {
    let bin = vec![0u8; 12 * VERTICES];
    let views = json!([{"buffer": 0, "byteLength": bin.len()}]);
    (bin, views)
}

#[test]
fn primitives_sharing_one_position_accessor_are_refused() {
    let (bin, views) = shared_vertices();
    let prims: Vec<Value> = (0..5000)
        .map(|_| json!({"attributes": {"POSITION": 0}}))
        .collect();
    let doc = json!({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}], "bufferViews": views,
        "accessors": [positions(VERTICES, Some(0))],
        "meshes": [{"primitives": prims}]});
    let e = over_budget("prims.glb", glb(&doc, Some(&bin)));
    assert!(e.contains("(5000 uses"), "{e}");
}

#[test]
fn morph_targets_sharing_one_accessor_are_refused() {
    let (bin, views) = shared_vertices();
    let targets: Vec<Value> = (0..3000).map(|_| json!({"POSITION": 1})).collect();
    let doc = json!({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}], "bufferViews": views,
        "accessors": [positions(VERTICES, Some(0)), positions(VERTICES, Some(0))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "targets": targets}]}]});
    let e = over_budget("targets.glb", glb(&doc, Some(&bin)));
    assert!(e.contains("(3001 uses"), "{e}");
    // The same file with 20 targets (50 MB decoded) is read.
    let mut few = doc.clone();
    few["meshes"][0]["primitives"][0]["targets"] = json!(targets[..20]);
    let m = parse_gltf_morphs(Path::new("few.glb"), glb(&few, Some(&bin))).unwrap();
    assert_eq!(m.targets.len(), 20);
}

#[test]
fn compressed_views_decoding_one_stream_are_refused() {
    // One 1 MiB meshopt stream (4 Mi zero vertices of 16 bytes) that 120 views each decode to
    // 64 MiB: each view is within the codec's ratio, together they are 7.5 GiB.
    let count = 4 << 20;
    let enc = meshopt::encode_vertex_buffer(&vec![[0u32; 4]; count]).unwrap();
    let mut views = vec![json!({"buffer": 0, "byteLength": 36})];
    for _ in 0..120 {
        views.push(
            json!({"buffer": 1, "byteLength": 16 * count, "byteStride": 16,
            "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteLength": enc.len(),
                "byteStride": 16, "count": count, "mode": "ATTRIBUTES"}}}),
        );
    }
    let doc = json!({"asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "buffers": [{"byteLength": enc.len()}, {"byteLength": 16 * count,
            "extensions": {"EXT_meshopt_compression": {"fallback": true}}}],
        "bufferViews": views,
        "accessors": [positions(3, Some(0))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]});
    let e = over_budget("meshopt.glb", glb(&doc, Some(&enc)));
    assert!(e.contains("120 of them compressed views"), "{e}");
}

/// A GLB whose buffer 0 declares 800 bytes over a BIN chunk of 1068, with views `views`.
fn short_buffer(views: Value, position_view: usize) -> Vec<u8> {
    let doc = json!({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": 800}], "bufferViews": views,
        "accessors": [positions(3, Some(position_view))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]});
    glb(&doc, Some(&[0u8; 1068]))
}

#[test]
fn views_past_their_buffer_are_refused() {
    // Used: POSITION on bytes 1000..1036, inside the BIN chunk but past byteLength 800.
    let e = refused(
        "used.glb",
        short_buffer(
            json!([{"buffer": 0, "byteOffset": 1000, "byteLength": 36}]),
            0,
        ),
    );
    assert!(
        e.contains(
            "buffer view 0: byteOffset 1000 + byteLength 36 reaches past the 800 bytes of buffer 0"
        ),
        "{e}"
    );
    // Unused, also refused: a writer keeps only byteLength bytes.
    let views = json!([{"buffer": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": 800, "byteLength": 268}]);
    let e = refused("unused.glb", short_buffer(views, 0));
    assert!(
        e.contains("buffer view 1: byteOffset 800 + byteLength 268"),
        "{e}"
    );
    // An offset that would wrap around.
    let views = json!([{"buffer": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": u64::MAX - 3, "byteLength": 8}]);
    let e = refused("wrap.glb", short_buffer(views, 0));
    assert!(
        e.contains("buffer view 1: byteOffset 18446744073709551612"),
        "{e}"
    );
    // Within byteLength: read.
    let ok = short_buffer(
        json!([{"buffer": 0, "byteOffset": 764, "byteLength": 36}]),
        0,
    );
    assert!(parse_gltf_morphs(Path::new("ok.glb"), ok).is_ok());
}

#[test]
fn a_gzipped_external_image_is_embedded_as_it_is() {
    use std::io::Write;
    let d = std::env::temp_dir().join(format!("morphkit-h55-image-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&[7u8; 100_000]).unwrap();
    let image = gz.finish().unwrap();
    assert_eq!(image[..2], [0x1f, 0x8b]);
    std::fs::write(d.join("image.png"), &image).unwrap();
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    std::fs::write(d.join("tri.bin"), &tri).unwrap();
    let doc = json!({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "tri.bin"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": F32, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0]}],
        "images": [{"uri": "image.png"}],
        "textures": [{"source": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]});
    let src = d.join("a.gltf");
    std::fs::write(&src, serde_json::to_vec(&doc).unwrap()).unwrap();
    let out = d.join("a.glb");
    GltfAsset::read(&src, &GltfReadOptions::default())
        .unwrap()
        .write(&out, &GltfAssetOptions::default())
        .unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let jlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let written: Value = serde_json::from_slice(&bytes[20..20 + jlen]).unwrap();
    let bin = &bytes[20 + jlen + 8..];
    let img = &written["images"][0];
    assert_eq!(img["mimeType"], "image/png");
    let view = &written["bufferViews"][img["bufferView"].as_u64().unwrap() as usize];
    let o = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let n = view["byteLength"].as_u64().unwrap() as usize;
    assert_eq!(&bin[o..o + n], &image[..]);
    let _ = std::fs::remove_dir_all(&d);
}
