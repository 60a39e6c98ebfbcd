//! Writing a [`GltfAsset`] as one self-contained `.glb` or `.gltf`.
//!
//! - **One data buffer.** The bytes of every buffer (the GLB `BIN` chunk, data URIs, external
//!   files, the edits' buffer) are concatenated, each starting 4-byte aligned, into buffer 0
//!   (the GLB `BIN` chunk, or a base64 data URI in a `.gltf`). Every buffer view's `buffer` and
//!   `byteOffset` are renumbered, and so are those of `EXT_meshopt_compression` /
//!   `KHR_meshopt_compression` buffer views, which point at the compressed bytes.
//! - **Meshopt fallback buffers** (marked `fallback`, never read) are kept after it as
//!   buffers without data (no `uri`), so the views that name them stay valid.
//! - **External images** (a `uri` that is not `data:`) are embedded: their bytes become a buffer
//!   view, the image gets `bufferView` and `mimeType` instead of `uri`, so the textures survive
//!   moving the file. Images in data URIs or buffer views stay as they are.
//! - Everything else in the JSON is written as it is.

use super::asset::{GltfAsset, GltfAssetOptions};
use super::write::write_document;
use crate::io::IoError;
use serde_json::{json, Value};
use std::path::Path;

/// The names of the meshopt compression extension.
const MESHOPT: &[&str] = &["EXT_meshopt_compression", "KHR_meshopt_compression"];

fn align4(bin: &mut Vec<u8>) {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
}

/// `v[key]` as an unsigned integer (default `0`).
fn uint(v: &Value, key: &str) -> usize {
    v.get(key).and_then(Value::as_u64).unwrap_or(0) as usize
}

impl GltfAsset {
    /// The document and its one data buffer, as [`GltfAsset::write`] writes them (see the
    /// [module documentation](self)).
    pub(super) fn merged(&self, opts: &GltfAssetOptions) -> Result<(Value, Vec<u8>), IoError> {
        let mut doc = self.doc.clone();
        let mut bin = Vec::new();
        // Per old buffer: (new index, offset of its bytes in the new buffer).
        let mut map = Vec::with_capacity(self.buffers.len());
        let mut kept = Vec::new();
        // The merged buffer keeps the first data buffer's name and extras.
        let mut first = json!({});
        let buffers = doc["buffers"].as_array().cloned().unwrap_or_default();
        for (i, b) in buffers.iter().enumerate() {
            if self.fallback.get(i).copied().unwrap_or(false) {
                let mut f = b.clone();
                if let Some(o) = f.as_object_mut() {
                    o.remove("uri");
                }
                kept.push(f);
                map.push((kept.len(), 0));
                continue;
            }
            if map.iter().all(|m: &(usize, usize)| m.0 != 0) {
                for k in ["name", "extras"] {
                    if let Some(v) = b.get(k) {
                        first[k] = v.clone();
                    }
                }
            }
            align4(&mut bin);
            map.push((0, bin.len()));
            let data = &self.buffers[i];
            let n = uint(b, "byteLength").min(data.len());
            bin.extend_from_slice(&data[..n]);
        }
        let bad = |m: String| IoError::content(&self.path, m);
        if let Some(views) = doc["bufferViews"].as_array_mut() {
            for (vi, v) in views.iter_mut().enumerate() {
                let b = uint(v, "buffer");
                let &(nb, off) = map.get(b).ok_or_else(|| {
                    bad(format!(
                        "buffer view {vi} names buffer {b}, which does not exist"
                    ))
                })?;
                v["buffer"] = json!(nb);
                if off > 0 || v.get("byteOffset").is_some() {
                    v["byteOffset"] = json!(uint(v, "byteOffset") + off);
                }
                for name in MESHOPT {
                    let Some(e) = v.pointer_mut(&format!("/extensions/{name}")) else {
                        continue;
                    };
                    let b = uint(e, "buffer");
                    let &(nb, off) = map.get(b).ok_or_else(|| {
                        bad(format!(
                            "buffer view {vi} ({name}) names buffer {b}, which does not exist"
                        ))
                    })?;
                    e["buffer"] = json!(nb);
                    if off > 0 || e.get("byteOffset").is_some() {
                        e["byteOffset"] = json!(uint(e, "byteOffset") + off);
                    }
                }
            }
        }
        for (i, img) in self.images.iter().enumerate() {
            let Some((bytes, mime)) = img else {
                continue;
            };
            align4(&mut bin);
            let view = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
            bin.extend_from_slice(bytes);
            if !doc["bufferViews"].is_array() {
                doc["bufferViews"] = json!([]);
            }
            let views = doc["bufferViews"].as_array_mut().expect("an array");
            views.push(view);
            let vi = views.len() - 1;
            let image = &mut doc["images"][i];
            if let Some(o) = image.as_object_mut() {
                o.remove("uri");
                o.insert("bufferView".into(), json!(vi));
                o.insert("mimeType".into(), json!(mime));
            }
        }
        if bin.is_empty() {
            // Buffer 0 must hold at least one byte.
            bin.extend_from_slice(&[0; 4]);
        }
        align4(&mut bin);
        first["byteLength"] = json!(bin.len());
        let mut all = vec![first];
        all.extend(kept);
        doc["buffers"] = Value::Array(all);
        if let Some(Value::Object(extra)) = &opts.extras {
            if doc["asset"]["extras"].is_null() {
                doc["asset"]["extras"] = json!({});
            }
            if let Some(e) = doc["asset"]["extras"].as_object_mut() {
                for (k, v) in extra {
                    e.insert(k.clone(), v.clone());
                }
            }
        }
        Ok((doc, bin))
    }

    /// Writes the asset to `path` atomically: GLB for `.glb`, otherwise glTF JSON with its one
    /// buffer as a base64 data URI, so the output is always one file (see the
    /// [module documentation](self)). Everything the edits did not replace is written as read.
    ///
    /// Errors: those of [`crate::io::write_atomic`]; a buffer view naming a buffer that does not
    /// exist; an output over 4 GiB as GLB.
    pub fn write(&self, path: &Path, opts: &GltfAssetOptions) -> Result<(), IoError> {
        let (doc, bin) = self.merged(opts)?;
        write_document(path, doc, &bin)
    }
}
