//! The reader on small hand-built glTF documents: non-indexed primitives, sparse and
//! quantized accessors, meshopt-compressed views, CUBICSPLINE weights, required extensions and
//! the choice between several meshes with morph targets.

use super::{parse_gltf_morphs, parse_gltf_morphs_with, GltfReadOptions};
use serde_json::{json, Value};
use std::path::Path;

/// A glTF document under construction: one buffer (a base64 data URI), its views, accessors.
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

const F32: u32 = 5126;
const I16: u32 = 5122;
const I8: u32 = 5120;
const U16: u32 = 5123;

impl Doc {
    fn view(&mut self, data: &[u8], stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len()});
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(data);
        self.views.push(v);
        self.views.len() - 1
    }
    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }
    /// A tightly packed f32 VEC3 accessor (with min/max).
    fn vec3(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes, None);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for q in p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        self.accessor(
            json!({"bufferView": v, "componentType": F32, "count": p.len(),
            "type": "VEC3", "min": lo, "max": hi}),
        )
    }
    fn scalars(&mut self, x: &[f32]) -> usize {
        let bytes: Vec<u8> = x.iter().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes, None);
        let (lo, hi) = (
            x.iter().copied().fold(f32::MAX, f32::min),
            x.iter().copied().fold(f32::MIN, f32::max),
        );
        self.accessor(
            json!({"bufferView": v, "componentType": F32, "count": x.len(),
            "type": "SCALAR", "min": [lo], "max": [hi]}),
        )
    }
    /// The glTF JSON with `meshes` (and the rest of `extra` merged in).
    fn json(&self, extra: Value) -> Vec<u8> {
        let mut d = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": self.bin.len(), "uri": format!(
                "data:application/octet-stream;base64,{}", base64(&self.bin))}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        for (k, v) in extra.as_object().unwrap() {
            d[k] = v.clone();
        }
        serde_json::to_vec(&d).unwrap()
    }
}

fn base64(b: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in b.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn parse(json: Vec<u8>) -> Result<super::GltfMorphs, String> {
    parse_gltf_morphs(Path::new("t.gltf"), json).map_err(|e| e.to_string())
}

const TRI2: [[f32; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

#[test]
fn non_indexed_primitive_is_consecutive_triples() {
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let mut delta = [[0.0f32; 3]; 6];
    delta[4] = [0.0, 0.0, 0.5];
    let t = d.vec3(&delta);
    let m = parse(d.json(json!({"meshes": [{"primitives": [
        {"attributes": {"POSITION": p}, "targets": [{"POSITION": t}]}]}]})))
    .unwrap();
    assert_eq!(m.base.positions.len(), 6);
    assert_eq!(m.base.num_triangles(), 2);
    assert_eq!(m.base.triangles[1], [3, 4, 5]);
    assert_eq!(m.targets[0][4], [1.0, 1.0, 0.5]);
    assert_eq!(m.targets[0][3], [1.0, 0.0, 0.0]);
}

#[test]
fn sparse_target_accessors_with_and_without_a_view() {
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let idx = d.view(
        &[2u16, 5]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<_>>(),
        None,
    );
    let vals: Vec<u8> = [0.0f32, 0.0, 2.0, 0.0, 0.0, -1.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let val = d.view(&vals, None);
    // Target 0: no buffer view (all zero) plus two sparse values.
    let t0 = d.accessor(json!({"componentType": F32, "count": 6, "type": "VEC3",
        "sparse": {"count": 2, "indices": {"bufferView": idx, "componentType": U16},
                   "values": {"bufferView": val}}}));
    // Target 1: a dense view of ones, the same two sparse values substituted.
    let ones = d.vec3(&[[1.0; 3]; 6]);
    let ones_view = d.accessors[ones]["bufferView"].clone();
    let t1 = d.accessor(
        json!({"bufferView": ones_view, "componentType": F32, "count": 6,
        "type": "VEC3", "sparse": {"count": 2,
        "indices": {"bufferView": idx, "componentType": U16}, "values": {"bufferView": val}}}),
    );
    // Target 2: neither a view nor sparse values: all zeros (gltf-transform writes these).
    let t2 = d.accessor(json!({"componentType": F32, "count": 6, "type": "VEC3"}));
    let m = parse(d.json(
        json!({"meshes": [{"primitives": [{"attributes": {"POSITION": p},
        "targets": [{"POSITION": t0}, {"POSITION": t1}, {"POSITION": t2}]}]}]}),
    ))
    .unwrap();
    assert_eq!(m.targets[2], m.base.positions);
    // An empty sparse substitution (count 0, invalid but harmless) changes nothing.
    let t3 = d.accessor(json!({"componentType": F32, "count": 6, "type": "VEC3",
        "sparse": {"count": 0, "indices": {"bufferView": idx, "componentType": U16},
                   "values": {"bufferView": val}}}));
    let m3 = parse(d.json(
        json!({"meshes": [{"primitives": [{"attributes": {"POSITION": p},
        "targets": [{"POSITION": t3}]}]}]}),
    ));
    if let Ok(m3) = m3 {
        assert_eq!(m3.targets[0], m3.base.positions);
    }
    assert_eq!(m.targets[0][2], [0.0, 1.0, 2.0]);
    assert_eq!(m.targets[0][5], [0.0, 1.0, -1.0]);
    assert_eq!(m.targets[0][1], [1.0, 0.0, 0.0]);
    assert_eq!(m.targets[1][1], [2.0, 1.0, 1.0]);
    assert_eq!(m.targets[1][2], [0.0, 1.0, 2.0]);
}

#[test]
fn cubicspline_weights_take_the_values() {
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let t = d.vec3(&[[0.0, 0.0, 1.0]; 6]);
    let times = d.scalars(&[0.0, 1.0]);
    // Per key: in-tangent, value, out-tangent (one target each).
    let w = d.scalars(&[9.0, 0.25, 8.0, 7.0, 0.75, 6.0]);
    let m = parse(d.json(json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}, "targets": [{"POSITION": t}]}],
                    "extras": {"targetNames": ["up"]}}],
        "nodes": [{"mesh": 0}],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": times, "output": w, "interpolation": "CUBICSPLINE"}]}]})))
    .unwrap();
    assert_eq!(m.target_names, ["up"]);
    assert_eq!(m.weight_keys, [(0.0, vec![0.25]), (1.0, vec![0.75])]);
}

#[test]
fn quantized_positions_and_deltas() {
    let mut d = Doc::default();
    // Normalized i16 positions with a padded stride of 8 bytes.
    let q: [[i16; 3]; 3] = [[0, 0, 0], [32767, 0, -32767], [0, 16384, -32768]];
    let bytes: Vec<u8> = q
        .iter()
        .flat_map(|v| {
            let mut e: Vec<u8> = v.iter().flat_map(|c| c.to_le_bytes()).collect();
            e.extend([0, 0]);
            e
        })
        .collect();
    let v = d.view(&bytes, Some(8));
    let p = d.accessor(
        json!({"bufferView": v, "componentType": I16, "normalized": true,
        "count": 3, "type": "VEC3", "min": [0, 0, -32768], "max": [32767, 16384, 0]}),
    );
    // Deltas: normalized i8 (KHR_mesh_quantization), padded to 4 bytes.
    let tv = d.view(&[0, 0, 127, 0, 0, 0, 0, 0, 0x81, 0, 0, 0], Some(4));
    let t = d.accessor(
        json!({"bufferView": tv, "componentType": I8, "normalized": true,
        "count": 3, "type": "VEC3"}),
    );
    let m = parse(d.json(json!({
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}, "targets": [{"POSITION": t}]}]}]})))
    .unwrap();
    assert_eq!(m.base.positions[1], [1.0, 0.0, -1.0]);
    assert_eq!(m.base.positions[2], [0.0, 16384.0 / 32767.0, -1.0]);
    assert_eq!(m.targets[0][0], [0.0, 0.0, 1.0]);
    assert_eq!(m.targets[0][2], [-1.0, 16384.0 / 32767.0, -1.0]);
}

#[test]
fn unsupported_required_extension_is_named() {
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let e = parse(d.json(json!({
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_mesh_quantization", "KHR_draco_mesh_compression"],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}}]}]})))
    .unwrap_err();
    assert!(e.contains("t.gltf"), "{e}");
    assert!(
        e.contains("requires the glTF extension KHR_draco_mesh_compression"),
        "{e}"
    );
    // Extensions that do not change the geometry are accepted, even with a texture the gltf
    // crate would refuse (no `source`, as with KHR_texture_basisu).
    let m = parse(d.json(json!({
        "extensionsUsed": ["KHR_texture_basisu", "KHR_materials_unlit"],
        "extensionsRequired": ["KHR_texture_basisu", "KHR_materials_unlit"],
        "textures": [{"extensions": {"KHR_texture_basisu": {"source": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}}]}]})))
    .unwrap();
    assert_eq!(m.base.triangles.len(), 2);
}

#[test]
fn several_morph_meshes_are_chosen_by_name() {
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let t = d.vec3(&[[0.0, 0.0, 1.0]; 6]);
    let t2 = d.vec3(&[[0.0, 0.0, 2.0]; 6]);
    let json = d.json(json!({"meshes": [
        {"name": "Plain", "primitives": [{"attributes": {"POSITION": p}}]},
        {"name": "Face", "primitives": [{"attributes": {"POSITION": p}, "targets": [{"POSITION": t}]}]},
        {"name": "Teeth", "primitives": [{"attributes": {"POSITION": p}, "targets": [{"POSITION": t2}]}]}]}));
    let e = parse(json.clone()).unwrap_err();
    assert!(
        e.contains("2 meshes have morph targets (mesh 1 'Face', mesh 2 'Teeth'); choose one"),
        "{e}"
    );
    let path = Path::new("t.gltf");
    let pick = |name: &str| {
        let opts = GltfReadOptions {
            mesh: Some(name.into()),
        };
        parse_gltf_morphs_with(path, json.clone(), &opts).map_err(|e| e.to_string())
    };
    assert_eq!(pick("Teeth").unwrap().targets[0][0], [0.0, 0.0, 2.0]);
    assert_eq!(pick("Face").unwrap().targets[0][0], [0.0, 0.0, 1.0]);
    assert!(pick("Plain").unwrap().targets.is_empty());
    let e = pick("Nose").unwrap_err();
    assert!(
        e.contains("no mesh named 'Nose'") && e.contains("mesh 2 'Teeth'"),
        "{e}"
    );
    // One morph mesh among plain ones is taken without asking.
    let mut d = Doc::default();
    let p = d.vec3(&TRI2);
    let t = d.vec3(&[[0.0, 0.0, 1.0]; 6]);
    let m = parse(d.json(json!({"meshes": [
        {"name": "Plain", "primitives": [{"attributes": {"POSITION": p}}]},
        {"name": "Face", "primitives": [{"attributes": {"POSITION": p}, "targets": [{"POSITION": t}]}]}]})))
    .unwrap();
    assert_eq!(m.targets.len(), 1);
}

#[test]
fn meshopt_compressed_views_are_decoded() {
    let mut d = Doc::default();
    let pos: Vec<[f32; 3]> = TRI2.to_vec();
    let enc = meshopt::encode_vertex_buffer(&pos).unwrap();
    let idx: Vec<u32> = vec![0, 1, 2, 3, 4, 5];
    let ienc = meshopt::encode_index_buffer(&idx, 6).unwrap();
    let ev = d.view(&enc, None);
    let iv = d.view(&ienc, None);
    let (eo, io) = (
        d.views[ev]["byteOffset"].clone(),
        d.views[iv]["byteOffset"].clone(),
    );
    // The views refer to buffer 1 (the fallback, no data); their compressed bytes are in 0.
    d.views.push(
        json!({"buffer": 1, "byteLength": 72, "byteStride": 12, "extensions": {
        "EXT_meshopt_compression": {"buffer": 0, "byteOffset": eo, "byteLength": enc.len(),
            "byteStride": 12, "count": 6, "mode": "ATTRIBUTES"}}}),
    );
    d.views
        .push(json!({"buffer": 1, "byteLength": 24, "extensions": {
        "EXT_meshopt_compression": {"buffer": 0, "byteOffset": io, "byteLength": ienc.len(),
            "byteStride": 4, "count": 6, "mode": "TRIANGLES"}}}));
    let p = d.accessor(json!({"bufferView": 2, "componentType": F32, "count": 6,
        "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}));
    let i = d.accessor(json!({"bufferView": 3, "componentType": 5125, "count": 6,
        "type": "SCALAR"}));
    let mut json: Value = serde_json::from_slice(&d.json(json!({
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}, "indices": i}]}]})))
    .unwrap();
    json["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"byteLength": 96,
        "extensions": {"EXT_meshopt_compression": {"fallback": true}}}));
    let m = parse(serde_json::to_vec(&json).unwrap()).unwrap();
    let want: Vec<[f64; 3]> = TRI2.iter().map(|q| q.map(f64::from)).collect();
    assert_eq!(m.base.positions, want);
    assert_eq!(m.base.triangles[1], [3, 4, 5]);
    // Corrupt compressed data is an error naming the view.
    let mut bad = json.clone();
    bad["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["byteLength"] = json!(3);
    let e = parse(serde_json::to_vec(&bad).unwrap()).unwrap_err();
    assert!(e.contains("buffer view 2 (meshopt compression)"), "{e}");
    // A decoded size far beyond what the compressed bytes can hold is refused unallocated.
    // (Within the file's decoding budget, budget.rs, which refuses larger claims first.)
    let mut big = json.clone();
    big["buffers"][1]["byteLength"] = json!(1_200_000);
    big["bufferViews"][2]["byteLength"] = json!(1_200_000);
    big["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["count"] = json!(100_000);
    let e = parse(serde_json::to_vec(&big).unwrap()).unwrap_err();
    assert!(e.contains("more than meshopt can encode"), "{e}");
}
