//! Writing [`GltfMorphs`] as glTF (JSON with an embedded data URI) or GLB.

use super::GltfMorphs;
use crate::io::{atomic::write_atomic, IoError};
use crate::mesh::Point;
use serde_json::{json, Value};
use std::path::Path;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Buffer and accessor bookkeeping.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
}

impl Builder {
    /// Appends `bytes` as a new 4-byte-aligned buffer view; returns its index.
    pub(super) fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// A VEC3 f32 accessor with min/max; returns its index.
    pub(super) fn vec3(&mut self, p: &[[f32; 3]]) -> usize {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut bytes = Vec::with_capacity(12 * p.len());
        for q in p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
                bytes.extend_from_slice(&q[k].to_le_bytes());
            }
        }
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view, "componentType": FLOAT, "count": p.len(), "type": "VEC3",
            "min": lo, "max": hi
        }));
        self.accessors.len() - 1
    }

    /// A SCALAR accessor of f32 or u32 values (with min/max when `bounds`).
    pub(super) fn scalars(
        &mut self,
        bytes: Vec<u8>,
        count: usize,
        ty: u32,
        target: Option<u32>,
        bounds: Option<(f32, f32)>,
    ) -> usize {
        let view = self.view(&bytes, target);
        let mut a =
            json!({"bufferView": view, "componentType": ty, "count": count, "type": "SCALAR"});
        if let Some((lo, hi)) = bounds {
            a["min"] = json!([lo]);
            a["max"] = json!([hi]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

pub(super) fn to_f32(
    path: &Path,
    what: &str,
    p: &[Point],
    base: Option<&[Point]>,
) -> Result<Vec<[f32; 3]>, IoError> {
    p.iter()
        .enumerate()
        .map(|(v, q)| {
            let d = match base {
                Some(b) => [q[0] - b[v][0], q[1] - b[v][1], q[2] - b[v][2]],
                None => *q,
            };
            let f = d.map(|x| x as f32);
            if f.iter().all(|x| x.is_finite()) {
                Ok(f)
            } else {
                Err(IoError::content(
                    path,
                    format!("{what}: vertex {v} is {q:?}, not representable as f32"),
                ))
            }
        })
        .collect()
}

/// Checks that the parts of `m` agree with each other.
fn check(path: &Path, m: &GltfMorphs) -> Result<(), IoError> {
    let nv = m.base.num_vertices();
    let nt = m.targets.len();
    if m.target_names.len() != nt {
        return Err(IoError::content(
            path,
            format!("{} target names for {nt} targets", m.target_names.len()),
        ));
    }
    if let Some(t) = m.targets.iter().position(|t| t.len() != nv) {
        return Err(IoError::content(
            path,
            format!(
                "morph target {t} has {} positions, the base has {nv}",
                m.targets[t].len()
            ),
        ));
    }
    if let Some((k, (_, w))) = m
        .weight_keys
        .iter()
        .enumerate()
        .find(|(_, (_, w))| w.len() != nt)
    {
        return Err(IoError::content(
            path,
            format!("weight key {k} has {} weights for {nt} targets", w.len()),
        ));
    }
    let times_ok = m.weight_keys.iter().all(|(t, _)| t.is_finite())
        && m.weight_keys
            .windows(2)
            .all(|w| (w[0].0 as f32) < (w[1].0 as f32));
    if !times_ok {
        return Err(IoError::content(
            path,
            "weight key times must be finite and strictly increasing (as f32)",
        ));
    }
    if !m.weight_keys.is_empty() && nt == 0 {
        return Err(IoError::content(path, "weight keys without morph targets"));
    }
    if let Some(t) = m
        .base
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= nv))
    {
        return Err(IoError::content(
            path,
            format!("triangle {t} refers to a vertex beyond {nv}"),
        ));
    }
    Ok(())
}

/// Builds the JSON document and the binary buffer.
fn build(path: &Path, m: &GltfMorphs) -> Result<(Value, Vec<u8>), IoError> {
    let (doc, b) = build_with(path, m)?;
    Ok(finish(doc, b))
}

/// The document and the builder before the buffer list is written, so that more nodes can be
/// added ([`super::write_scene`]).
pub(super) fn build_with(path: &Path, m: &GltfMorphs) -> Result<(Value, Builder), IoError> {
    check(path, m)?;
    let mut b = Builder::default();
    let base = to_f32(path, "base", &m.base.positions, None)?;
    let pos = b.vec3(&base);
    let idx: Vec<u8> = m
        .base
        .triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let indices = b.scalars(
        idx,
        3 * m.base.num_triangles(),
        UNSIGNED_INT,
        Some(ELEMENT_ARRAY_BUFFER),
        None,
    );
    let mut targets = Vec::with_capacity(m.targets.len());
    for (t, tp) in m.targets.iter().enumerate() {
        let d = to_f32(
            path,
            &format!("morph target {t}"),
            tp,
            Some(&m.base.positions),
        )?;
        targets.push(json!({"POSITION": b.vec3(&d)}));
    }
    let mut primitive = json!({"attributes": {"POSITION": pos}, "indices": indices, "mode": 4});
    let mut mesh = json!({"name": "morphkit", "primitives": []});
    if !targets.is_empty() {
        primitive["targets"] = Value::Array(targets);
        mesh["weights"] = json!(vec![0.0; m.targets.len()]);
        mesh["extras"] = json!({"targetNames": m.target_names});
    }
    mesh["primitives"] = json!([primitive]);
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("morphkit ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "morphkit"}],
        "meshes": [mesh],
    });
    if !m.weight_keys.is_empty() {
        let times: Vec<f32> = m.weight_keys.iter().map(|(t, _)| *t as f32).collect();
        let tb: Vec<u8> = times.iter().flat_map(|t| t.to_le_bytes()).collect();
        let input = b.scalars(
            tb,
            times.len(),
            FLOAT,
            None,
            Some((times[0], times[times.len() - 1])),
        );
        let wb: Vec<u8> = m
            .weight_keys
            .iter()
            .flat_map(|(_, w)| w.iter().flat_map(|&x| (x as f32).to_le_bytes()))
            .collect();
        let output = b.scalars(wb, times.len() * m.targets.len(), FLOAT, None, None);
        doc["animations"] = json!([{
            "name": "morphkit",
            "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
        }]);
    }
    Ok((doc, b))
}

/// Pads the buffer and writes the buffer views, accessors and buffer into the document.
pub(super) fn finish(mut doc: Value, mut b: Builder) -> (Value, Vec<u8>) {
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    doc["bufferViews"] = Value::Array(b.views);
    doc["accessors"] = Value::Array(b.accessors);
    doc["buffers"] = json!([{"byteLength": b.bin.len()}]);
    (doc, b.bin)
}

/// Writes `m` to `path` atomically: GLB for `.glb`, otherwise glTF JSON with the buffer as a
/// base64 data URI (see the [module documentation](super) for the layout).
///
/// Errors: parts that disagree (names vs targets, target or weight counts), times that are not
/// strictly increasing, coordinates that overflow `f32`, and the errors of
/// [`crate::io::write_atomic`].
pub fn write_gltf_morphs(path: &Path, m: &GltfMorphs) -> Result<(), IoError> {
    let (doc, bin) = build(path, m)?;
    write_document(path, doc, &bin)
}

/// Writes a finished document and its buffer as GLB (`.glb`) or glTF with a data URI.
pub(super) fn write_document(path: &Path, mut doc: Value, bin: &[u8]) -> Result<(), IoError> {
    let glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let bytes = if glb {
        let mut json =
            serde_json::to_vec(&doc).map_err(|e| IoError::content(path, e.to_string()))?;
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let total32 = u32::try_from(total)
            .map_err(|_| IoError::content(path, "too large for GLB (4 GiB)"))?;
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&total32.to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out
    } else {
        doc["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64(bin)
        ));
        serde_json::to_vec_pretty(&doc).map_err(|e| IoError::content(path, e.to_string()))?
    };
    write_atomic(path, &bytes)
}

/// Standard base64 with padding.
fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        s.push(A[(n >> 18) as usize & 63] as char);
        s.push(A[(n >> 12) as usize & 63] as char);
        s.push(if c.len() > 1 {
            A[(n >> 6) as usize & 63] as char
        } else {
            '='
        });
        s.push(if c.len() > 2 {
            A[n as usize & 63] as char
        } else {
            '='
        });
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
