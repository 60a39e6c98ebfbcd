//! The glTF extensions the reader understands, and decoding of `EXT_meshopt_compression`
//! buffer views.
//!
//! - `KHR_mesh_quantization`: positions and morph-target deltas stored as (normalized or not)
//!   8- and 16-bit integers; [`super::accessor`] decodes every component type.
//! - `EXT_meshopt_compression` and `KHR_meshopt_compression`: a buffer view's bytes are the
//!   meshoptimizer decoding (modes `ATTRIBUTES`, `TRIANGLES`, `INDICES`; filters `NONE`,
//!   `OCTAHEDRAL`, `QUATERNION`, `EXPONENTIAL`, `COLOR`) of a range of another buffer; a
//!   buffer marked `fallback` needs no data.
//!
//! Required extensions that do not change the geometry (materials, textures, lights,
//! instancing; [`IGNORED`]) are accepted and what they describe is not read. Any other
//! extension in `extensionsRequired` (for example `KHR_draco_mesh_compression`) is an
//! error naming it. The `gltf` crate refuses every required extension it does not implement, so
//! the supported ones are removed from `extensionsRequired` before it sees the document.

use crate::io::IoError;
use std::path::Path;

/// Required extensions the reader decodes itself.
pub(crate) const SUPPORTED: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
];

/// Required extensions that do not change geometry, morph targets or animations (materials,
/// textures, lights, instancing): the reader ignores what they describe. Names ending in `_`
/// are prefixes.
pub(crate) const IGNORED: &[&str] = &[
    "KHR_materials_",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "MSFT_texture_dds",
    "KHR_lights_punctual",
    "EXT_mesh_gpu_instancing",
];

/// Whether the reader accepts the required extension `name`.
fn accepted(name: &str) -> bool {
    SUPPORTED.contains(&name)
        || IGNORED
            .iter()
            .any(|i| name == *i || (i.ends_with('_') && name.starts_with(i)))
}

/// The largest ratio of decoded to compressed bytes accepted for a meshopt view (the vertex
/// codec stores at least 2 bits per 16 bytes, a ratio of 64).
const MAX_RATIO: usize = 256;

/// The names of the meshopt compression extension.
const MESHOPT: &[&str] = &["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The JSON text with the supported extensions removed from `extensionsRequired` (`None` when
/// nothing needs removing), or an error naming an unsupported required extension.
pub(crate) fn strip_required(path: &Path, json: &[u8]) -> Result<Option<Vec<u8>>, IoError> {
    // Cheap test first: most files require nothing.
    if !json
        .windows(b"extensionsRequired".len())
        .any(|w| w == b"extensionsRequired")
    {
        return Ok(None);
    }
    let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(json) else {
        // Left to the gltf crate, which reports the syntax error.
        return Ok(None);
    };
    let Some(req) = v
        .get_mut("extensionsRequired")
        .and_then(|r| r.as_array_mut())
    else {
        return Ok(None);
    };
    if let Some(bad) = req.iter().find(|e| !e.as_str().is_some_and(accepted)) {
        let name = bad.as_str().map_or_else(|| bad.to_string(), str::to_string);
        return Err(IoError::content(
            path,
            format!(
                "the file requires the glTF extension {name}, which morphkit does not support \
                 (supported: {}; ignored, as they do not change the geometry: {}*); re-export it \
                 without {name}",
                SUPPORTED.join(", "),
                IGNORED.join("*, ")
            ),
        ));
    }
    req.clear();
    serde_json::to_vec(&v)
        .map(Some)
        .map_err(|e| IoError::content(path, format!("re-encoding the JSON: {e}")))
}

/// The meshopt extension object of a buffer or buffer view.
fn meshopt_ext(
    ext: Option<&serde_json::Map<String, serde_json::Value>>,
) -> Option<&serde_json::Value> {
    let ext = ext?;
    MESHOPT.iter().find_map(|n| ext.get(*n))
}

/// Whether a buffer view is meshopt-compressed (decoded by [`decode_views`]).
pub(crate) fn is_compressed(view: &::gltf::buffer::View) -> bool {
    meshopt_ext(view.extensions()).is_some()
}

/// Per buffer: whether it is a meshopt `fallback` buffer (its data is never read, and it may
/// have neither a URI nor bytes).
pub(crate) fn fallback_buffers(doc: &::gltf::Document) -> Vec<bool> {
    doc.buffers()
        .map(|b| {
            meshopt_ext(b.extensions())
                .and_then(|e| e.get("fallback"))
                .and_then(|f| f.as_bool())
                .unwrap_or(false)
        })
        .collect()
}

/// The decoded bytes of every meshopt-compressed buffer view (`None` for plain views), in view
/// order. Errors name the buffer view.
pub(crate) fn decode_views(
    path: &Path,
    doc: &::gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Vec<Option<Vec<u8>>>, IoError> {
    let mut out = Vec::with_capacity(doc.views().len());
    for view in doc.views() {
        let Some(e) = meshopt_ext(view.extensions()) else {
            out.push(None);
            continue;
        };
        let at = |m: String| {
            IoError::content(
                path,
                format!("buffer view {} (meshopt compression): {m}", view.index()),
            )
        };
        let field = |k: &str| e.get(k).and_then(|x| x.as_u64()).map(|x| x as usize);
        let buffer = field("buffer").ok_or_else(|| at("no buffer".into()))?;
        let offset = field("byteOffset").unwrap_or(0);
        let length = field("byteLength").ok_or_else(|| at("no byteLength".into()))?;
        let stride = field("byteStride").ok_or_else(|| at("no byteStride".into()))?;
        let count = field("count").ok_or_else(|| at("no count".into()))?;
        let mode = e.get("mode").and_then(|m| m.as_str()).unwrap_or("");
        let filter = e.get("filter").and_then(|m| m.as_str()).unwrap_or("NONE");
        // Within the source buffer's declared byteLength (its data may hold more: a GLB's BIN
        // chunk padding, or bytes a writer would drop).
        let declared = doc.buffers().nth(buffer).map(|b| b.length());
        let src = buffers
            .get(buffer)
            .zip(declared)
            .and_then(|(b, n)| b.get(offset..offset.checked_add(length).filter(|&e| e <= n)?))
            .ok_or_else(|| {
                at(format!(
                    "bytes {offset}..+{length} of buffer {buffer} are not in the file"
                ))
            })?;
        let size = count
            .checked_mul(stride)
            .filter(|&s| s == view.length() && stride > 0 && stride <= 256)
            .ok_or_else(|| {
                at(format!(
                    "count {count} × byteStride {stride} does not match the view's byteLength {}",
                    view.length()
                ))
            })?;
        // The document declares the decoded size; meshopt's codecs shrink data by far less
        // than MAX_RATIO, so a larger claim is refused before allocating.
        if size > src.len().saturating_mul(MAX_RATIO).max(1 << 16) {
            return Err(at(format!(
                "{size} decoded bytes from {} compressed ones is more than meshopt can encode",
                src.len()
            )));
        }
        let mut dst = Vec::new();
        dst.try_reserve_exact(size)
            .map_err(|e| at(format!("cannot allocate {size} decoded bytes: {e}")))?;
        dst.resize(size, 0u8);
        let code = match mode {
            "ATTRIBUTES" if stride.is_multiple_of(4) => unsafe {
                // SAFETY: `dst` holds count × stride bytes; the decoder validates `src`.
                meshopt::ffi::meshopt_decodeVertexBuffer(
                    dst.as_mut_ptr().cast(),
                    count,
                    stride,
                    src.as_ptr(),
                    src.len(),
                )
            },
            "TRIANGLES" | "INDICES" if stride == 2 || stride == 4 => unsafe {
                // SAFETY: as above; the index size is 2 or 4.
                if mode == "TRIANGLES" {
                    if !count.is_multiple_of(3) {
                        return Err(at(format!("TRIANGLES with {count} indices")));
                    }
                    meshopt::ffi::meshopt_decodeIndexBuffer(
                        dst.as_mut_ptr().cast(),
                        count,
                        stride,
                        src.as_ptr(),
                        src.len(),
                    )
                } else {
                    meshopt::ffi::meshopt_decodeIndexSequence(
                        dst.as_mut_ptr().cast(),
                        count,
                        stride,
                        src.as_ptr(),
                        src.len(),
                    )
                }
            },
            _ => {
                return Err(at(format!(
                    "mode '{mode}' with byteStride {stride} is not valid"
                )))
            }
        };
        if code != 0 {
            return Err(at(format!(
                "the compressed data is invalid (decoder code {code})"
            )));
        }
        if mode == "ATTRIBUTES" {
            apply_filter(filter, &mut dst, count, stride).map_err(at)?;
        } else if filter != "NONE" {
            return Err(at(format!("filter {filter} on an index view")));
        }
        out.push(Some(dst));
    }
    Ok(out)
}

/// Undoes a meshopt filter in place on `count` elements of `stride` bytes.
fn apply_filter(filter: &str, dst: &mut [u8], count: usize, stride: usize) -> Result<(), String> {
    let ok = match filter {
        "NONE" => return Ok(()),
        "OCTAHEDRAL" | "COLOR" => stride == 4 || stride == 8,
        "QUATERNION" => stride == 8,
        "EXPONENTIAL" => stride.is_multiple_of(4),
        _ => return Err(format!("unknown filter {filter}")),
    };
    if !ok {
        return Err(format!(
            "filter {filter} with byteStride {stride} is not valid"
        ));
    }
    let p = dst.as_mut_ptr().cast();
    // SAFETY: `dst` holds count × stride bytes and the stride suits the filter (checked above).
    unsafe {
        match filter {
            "OCTAHEDRAL" => meshopt::ffi::meshopt_decodeFilterOct(p, count, stride),
            "COLOR" => meshopt::ffi::meshopt_decodeFilterColor(p, count, stride),
            "QUATERNION" => meshopt::ffi::meshopt_decodeFilterQuat(p, count, stride),
            _ => meshopt::ffi::meshopt_decodeFilterExp(p, count, stride),
        }
    }
    Ok(())
}
