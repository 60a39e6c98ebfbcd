//! `EXT_meshopt_compression` for what morphkit writes ([`GltfOptions::meshopt`] and the
//! compact clips added to a user's asset, [`super::CompactEncoding::meshopt`]).
//!
//! Every buffer view whose elements are a multiple of 4 bytes and at most 256 (vertex
//! attributes and morph deltas: `f32` VEC3, quantized `i16` VEC3 padded to 8, `i8` normals
//! padded to 4; animation inputs and outputs) is coded by meshoptimizer's vertex codec,
//! version 0 (which every decoder reads), in mode `ATTRIBUTES` with filter `NONE`. A morph-weight
//! output is coded a key at a time (`4 × #targets` bytes per element, when that is at most
//! 256), so each key is coded against the one before. Index buffers, sparse accessors'
//! views and views that would not shrink stay as they are. The compressed bytes lie in the
//! data buffer; a compressed view names a second buffer of the same layout without data, which
//! the extension marks as `fallback` (§ "Fallback buffers"), so the extension is required.
//!
//! [`GltfOptions::meshopt`]: super::GltfOptions::meshopt

use serde_json::{json, Value};

/// The meshopt extension morphkit writes (`EXT_meshopt_compression`).
pub const EXT: &str = "EXT_meshopt_compression";

/// `count` elements of `stride` bytes (a multiple of 4, at most 256) encoded by meshopt's
/// vertex codec, version 0.
pub(super) fn encode_attributes(bytes: &[u8], stride: usize, count: usize) -> Vec<u8> {
    assert!(
        stride.is_multiple_of(4) && (4..=256).contains(&stride) && bytes.len() == stride * count
    );
    // SAFETY: `out` holds the bound the encoder asks for; `bytes` holds count × stride bytes
    // (checked above).
    unsafe {
        let bound = meshopt::ffi::meshopt_encodeVertexBufferBound(count, stride);
        let mut out = vec![0u8; bound];
        let n = meshopt::ffi::meshopt_encodeVertexBufferLevel(
            out.as_mut_ptr(),
            out.len(),
            bytes.as_ptr().cast(),
            count,
            stride,
            2,
            0,
        );
        out.truncate(n);
        out
    }
}

/// Compresses the buffer views of a finished one-buffer document `doc` whose data is `bin`
/// (see the [module documentation](self)); returns the new data buffer. `doc`'s views,
/// buffers and extension lists are rewritten; its accessors are unchanged.
pub(super) fn compress_views(doc: &mut Value, bin: &[u8]) -> Vec<u8> {
    let strides = codec_strides(doc);
    let views = doc["bufferViews"].as_array().cloned().unwrap_or_default();
    let mut out = Vec::with_capacity(bin.len() / 2);
    let mut fallback = 0usize;
    let mut new_views = Vec::with_capacity(views.len());
    for (v, stride) in views.into_iter().zip(strides) {
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap_or(0) as usize;
        let bytes = &bin[off..off + len];
        while !out.len().is_multiple_of(4) {
            out.push(0);
        }
        let encoded = stride
            .filter(|&s| len > 0 && len.is_multiple_of(s))
            .map(|s| (s, encode_attributes(bytes, s, len / s)))
            .filter(|(_, e)| e.len() < len);
        let mut nv = v.clone();
        match encoded {
            Some((s, e)) => {
                fallback = fallback.next_multiple_of(4);
                nv["buffer"] = json!(1);
                nv["byteOffset"] = json!(fallback);
                nv["extensions"] = json!({EXT: {
                    "buffer": 0, "byteOffset": out.len(), "byteLength": e.len(),
                    "byteStride": s, "count": len / s, "mode": "ATTRIBUTES"}});
                out.extend_from_slice(&e);
                fallback += len;
            }
            None => {
                nv["byteOffset"] = json!(out.len());
                out.extend_from_slice(bytes);
            }
        }
        new_views.push(nv);
    }
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
    if fallback == 0 {
        // Nothing shrank: the document stays as it was.
        return bin.to_vec();
    }
    doc["bufferViews"] = Value::Array(new_views);
    doc["buffers"] = json!([
        {"byteLength": out.len()},
        {"byteLength": fallback, "extensions": {EXT: {"fallback": true}}},
    ]);
    for key in ["extensionsUsed", "extensionsRequired"] {
        if !doc[key].is_array() {
            doc[key] = json!([]);
        }
        let list = doc[key].as_array_mut().expect("set above");
        if !list.iter().any(|e| e.as_str() == Some(EXT)) {
            list.push(json!(EXT));
        }
    }
    out
}

/// Bytes of one element of accessor `a` (its component size times its components).
fn element_bytes(a: &Value) -> Option<usize> {
    let component = match a["componentType"].as_u64()? {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => return None,
    };
    let n = match a["type"].as_str()? {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    };
    Some(component * n)
}

/// The codec stride of each buffer view, `None` for a view left as it is: index buffers,
/// views no accessor reads, and views whose element is not a multiple of 4 bytes or is
/// larger than 256 (a sparse accessor's `u32` indices and its values are read like any other).
fn codec_strides(doc: &Value) -> Vec<Option<usize>> {
    let views = doc["bufferViews"].as_array().map_or(0, Vec::len);
    let mut stride: Vec<Option<usize>> = vec![None; views];
    let mut blocked = vec![false; views];
    let empty = Vec::new();
    let accessors = doc["accessors"].as_array().unwrap_or(&empty);
    // Each view read as elements of `s` bytes (`None`: not a multiple of 4, or unknown).
    let mut read_as = |v: Option<usize>, s: Option<usize>| {
        let Some(v) = v.filter(|&v| v < views) else {
            return;
        };
        let view = &doc["bufferViews"][v];
        let s = view["byteStride"].as_u64().map(|s| s as usize).or(s);
        match s {
            Some(s) if s.is_multiple_of(4) && s <= 256 && stride[v].is_none_or(|t| t == s) => {
                stride[v] = Some(s)
            }
            _ => blocked[v] = true,
        }
        if view["target"].as_u64() == Some(34963) {
            blocked[v] = true;
        }
    };
    let index = |v: &Value| v.as_u64().map(|i| i as usize);
    for a in accessors {
        if let Some(sp) = a.get("sparse") {
            let indices = match sp["indices"]["componentType"].as_u64() {
                Some(5125) => Some(4),
                _ => None,
            };
            read_as(index(&sp["indices"]["bufferView"]), indices);
            read_as(index(&sp["values"]["bufferView"]), element_bytes(a));
        }
        read_as(index(&a["bufferView"]), element_bytes(a));
    }
    // A morph-weight output: a whole key per element.
    for anim in doc["animations"].as_array().unwrap_or(&empty) {
        for ch in anim["channels"].as_array().unwrap_or(&empty) {
            if ch["target"]["path"].as_str() != Some("weights") {
                continue;
            }
            let sampler = &anim["samplers"][ch["sampler"].as_u64().unwrap_or(u64::MAX) as usize];
            let (input, output) = (
                &accessors.get(sampler["input"].as_u64().unwrap_or(u64::MAX) as usize),
                &accessors.get(sampler["output"].as_u64().unwrap_or(u64::MAX) as usize),
            );
            let (Some(input), Some(output)) = (input, output) else {
                continue;
            };
            let (Some(v), Some(keys), Some(count)) = (
                output["bufferView"].as_u64().map(|i| i as usize),
                input["count"].as_u64().map(|c| c as usize),
                output["count"].as_u64().map(|c| c as usize),
            ) else {
                continue;
            };
            let per_key = if keys > 0 && count.is_multiple_of(keys) {
                count / keys
            } else {
                0
            };
            if v < views && element_bytes(output) == Some(4) && (1..=64).contains(&per_key) {
                stride[v] = Some(4 * per_key);
            }
        }
    }
    stride
        .into_iter()
        .zip(blocked)
        .map(|(s, b)| if b { None } else { s })
        .collect()
}
