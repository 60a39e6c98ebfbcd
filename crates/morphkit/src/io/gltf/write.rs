//! Writing [`GltfMorphs`] as glTF (JSON with an embedded data URI) or GLB.

use super::split::{windows, Window};
use super::write_vertices::{self, Dequant};
use super::{GltfMorphs, GltfOptions};
use crate::io::{atomic::write_atomic, IoError};
use crate::mesh::Point;
use serde_json::{json, Value};
use std::path::Path;

pub(super) const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
pub(super) const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Buffer and accessor bookkeeping.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
    /// The indices, index size and view of the last sparse accessor, shared by the next one
    /// when it lists the same vertices.
    pub(super) last_sparse: Option<(Vec<u32>, usize, usize)>,
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

    /// A VEC3 f32 accessor without min/max (normals, normal deltas); returns its index.
    pub(super) fn vec3_plain(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view, "componentType": FLOAT, "count": p.len(), "type": "VEC3"
        }));
        self.accessors.len() - 1
    }

    /// The triangle list of `mesh` as a u32 index accessor; returns its index.
    pub(super) fn triangle_indices(&mut self, mesh: &crate::mesh::TriMesh) -> usize {
        let idx: Vec<u8> = mesh
            .triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let count = 3 * mesh.num_triangles();
        self.scalars(idx, count, UNSIGNED_INT, Some(ELEMENT_ARRAY_BUFFER), None)
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

/// What [`write_gltf_with`] wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfSummary {
    /// Morph-target meshes written: 1, or more when a long animation was split.
    pub meshes: usize,
    /// Morph targets in the rig.
    pub targets: usize,
    /// Things a viewer may not play, in words (a mesh above [`GltfOptions::max_targets`] that
    /// could not be split).
    pub warnings: Vec<String>,
    /// With [`GltfOptions::quantize`]: targets whose position deltas did not fit the 16-bit
    /// range (moving farther than the mesh's size) and stayed `f32`.
    pub float_position_targets: usize,
    /// With [`GltfOptions::quantize`]: targets whose normal deltas did not fit 8 bits (some
    /// normal turns so far that a component changes by more than 1, common where limbs rotate
    /// by 90° or more) and stayed `f32`.
    pub float_normal_targets: usize,
}

/// Weight rows of `keys` restricted to `targets`, as `f32`, for keys `k0..=k1`.
fn local_rows(m: &GltfMorphs, targets: &[usize], k0: usize, k1: usize) -> Vec<f32> {
    m.weight_keys[k0..=k1]
        .iter()
        .flat_map(|(_, w)| targets.iter().map(move |&t| w[t] as f32))
        .collect()
}

impl Builder {
    /// A SCALAR f32 accessor of `values`, sparse (§3.6.2.3: no buffer view, only the nonzero
    /// values and their `u32` indices) when that is smaller than dense.
    pub(super) fn weights(&mut self, values: &[f32]) -> usize {
        let nz: Vec<usize> = (0..values.len()).filter(|&i| values[i] != 0.0).collect();
        if nz.is_empty() || 2 * nz.len() >= values.len() {
            let bytes = values.iter().flat_map(|x| x.to_le_bytes()).collect();
            return self.scalars(bytes, values.len(), FLOAT, None, None);
        }
        let ib: Vec<u8> = nz.iter().flat_map(|&i| (i as u32).to_le_bytes()).collect();
        let vb: Vec<u8> = nz.iter().flat_map(|&i| values[i].to_le_bytes()).collect();
        let iv = self.view(&ib, None);
        let vv = self.view(&vb, None);
        self.accessors.push(json!({
            "componentType": FLOAT, "count": values.len(), "type": "SCALAR",
            "sparse": {
                "count": nz.len(),
                "indices": {"bufferView": iv, "componentType": UNSIGNED_INT},
                "values": {"bufferView": vv},
            }
        }));
        self.accessors.len() - 1
    }

    /// An f32 SCALAR key-time accessor with min/max.
    fn times(&mut self, t: &[f32]) -> usize {
        let tb: Vec<u8> = t.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.scalars(tb, t.len(), FLOAT, None, Some((t[0], t[t.len() - 1])))
    }
}

/// True when the mesh has an edge used by one triangle only.
fn is_open(m: &crate::mesh::TriMesh) -> bool {
    !crate::mesh::Topology::new(m.num_vertices(), &m.triangles)
        .boundary_edges()
        .is_empty()
}

/// The document and the builder before the buffer list is written, so that more nodes can be
/// added ([`super::write_scene`]).
pub(super) fn build_with(
    path: &Path,
    m: &GltfMorphs,
    opts: &GltfOptions,
) -> Result<(Value, Builder, GltfSummary), IoError> {
    build_with_normals(path, m, opts, None)
}

/// [`build_with`], the targets' normal deltas given (see [`write_vertices::write`]).
pub(super) fn build_with_normals(
    path: &Path,
    m: &GltfMorphs,
    opts: &GltfOptions,
    normal_deltas: Option<&[Vec<Point>]>,
) -> Result<(Value, Builder, GltfSummary), IoError> {
    check(path, m)?;
    let mut summary = GltfSummary {
        targets: m.targets.len(),
        ..GltfSummary::default()
    };
    let mut b = Builder::default();
    // Accessor order: POSITION 0, indices 1, NORMAL 2, then the targets.
    let vertices = write_vertices::write(path, m, opts, &mut b, normal_deltas)?;
    summary.float_position_targets = vertices.float_positions;
    summary.float_normal_targets = vertices.float_normals;
    let (pos, indices, normal, targets) = (
        vertices.position,
        vertices.indices,
        vertices.normal,
        vertices.targets,
    );
    let rows: Vec<Vec<f64>> = m.weight_keys.iter().map(|(_, w)| w.clone()).collect();
    let windows = match windows(&rows, m.targets.len(), opts.max_targets) {
        Some(w) => w,
        None => {
            summary.warnings.push(format!(
                "{} morph targets in one mesh, above the limit of {} that viewers play \
                 (three.js on WebGL2 leaves such a mesh at its base); the weights cannot be \
                 split into meshes of at most {} targets",
                m.targets.len(),
                opts.max_targets,
                opts.max_targets
            ));
            vec![Window {
                targets: (0..m.targets.len()).collect(),
                keys: (0, m.weight_keys.len().saturating_sub(1)),
            }]
        }
    };
    if opts.max_targets == 0 && m.targets.len() > super::SAFE_MORPH_TARGETS {
        summary.warnings.push(format!(
            "{} morph targets in one mesh, above the {} that WebGL2 viewers such as three.js \
             play (the mesh stays at its base there); splitting is off (max_targets 0)",
            m.targets.len(),
            super::SAFE_MORPH_TARGETS
        ));
    }
    let split = windows.len() > 1;
    summary.meshes = windows.len();
    let mut attributes = json!({"POSITION": pos});
    if let Some(n) = normal {
        attributes["NORMAL"] = json!(n);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("morphkit ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": opts.name, "nodes": []}],
        "nodes": [],
        "meshes": [],
    });
    if opts.material {
        doc["materials"] = json!([{
            "name": opts.name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 0.6
            },
            "doubleSided": is_open(&m.base),
        }]);
    }
    if let Some(e) = &opts.extras {
        doc["scenes"][0]["extras"] = e.clone();
    }
    let dequant = vertices.dequant;
    if dequant.is_some() {
        doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    }
    // The node scale of a shown mesh: the dequantizing scale, or 1.
    let shown = dequant.map_or(1.0, |d| d.scale);
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let last = m.weight_keys.len().saturating_sub(1);
    let time = |k: usize| m.weight_keys[k].0 as f32;
    for (c, win) in windows.iter().enumerate() {
        let name = if split {
            format!("{}.{c}", opts.name)
        } else {
            opts.name.clone()
        };
        let mut primitive = json!({"attributes": attributes, "indices": indices, "mode": 4});
        if opts.material {
            primitive["material"] = json!(0);
        }
        let mut mesh = json!({"name": name});
        if !win.targets.is_empty() {
            primitive["targets"] =
                Value::Array(win.targets.iter().map(|&t| targets[t].clone()).collect());
            mesh["weights"] = json!(vec![0.0; win.targets.len()]);
            let names: Vec<&String> = win.targets.iter().map(|&t| &m.target_names[t]).collect();
            mesh["extras"] = json!({"targetNames": names});
            if split {
                mesh["extras"]["morphkitTargets"] = json!(win.targets);
            }
        }
        mesh["primitives"] = json!([primitive]);
        if let Some(d) = dequant {
            mesh["extras"]["morphkitDequantization"] = dequantization_json(d);
        }
        doc["meshes"].as_array_mut().expect("meshes").push(mesh);
        let mut node = json!({"mesh": c, "name": name});
        if let Some(d) = dequant {
            node["translation"] = json!(d.offset);
            node["scale"] = json!([d.scale, d.scale, d.scale]);
        }
        if split && c > 0 {
            node["scale"] = json!([0.0, 0.0, 0.0]);
        }
        doc["nodes"].as_array_mut().expect("nodes").push(node);
        doc["scenes"][0]["nodes"]
            .as_array_mut()
            .expect("scene")
            .push(json!(c));
        if m.weight_keys.is_empty() {
            continue;
        }
        let (k0, k1) = win.keys;
        let ts: Vec<f32> = (k0..=k1).map(time).collect();
        let input = b.times(&ts);
        let output = b.weights(&local_rows(m, &win.targets, k0, k1));
        samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
        channels
            .push(json!({"sampler": samplers.len() - 1, "target": {"node": c, "path": "weights"}}));
        if split {
            // Visible from the window's first key until the next window's first key.
            let mut keys: Vec<(f32, f32)> = Vec::new();
            if k0 > 0 {
                keys.push((time(0), 0.0));
            }
            keys.push((time(k0), shown));
            if k1 < last {
                keys.push((time(k1), 0.0));
            }
            let st: Vec<f32> = keys.iter().map(|k| k.0).collect();
            let sv: Vec<f32> = keys.iter().flat_map(|k| [k.1; 3]).collect();
            let input = b.times(&st);
            let bytes: Vec<u8> = sv.iter().flat_map(|x| x.to_le_bytes()).collect();
            let view = b.view(&bytes, None);
            b.accessors.push(json!({"bufferView": view, "componentType": FLOAT, "count": keys.len(), "type": "VEC3"}));
            let output = b.accessors.len() - 1;
            samplers.push(json!({"input": input, "output": output, "interpolation": "STEP"}));
            channels.push(
                json!({"sampler": samplers.len() - 1, "target": {"node": c, "path": "scale"}}),
            );
        }
    }
    if !samplers.is_empty() {
        doc["animations"] = json!([{
            "name": opts.clip_name.as_ref().unwrap_or(&opts.name),
            "samplers": samplers,
            "channels": channels,
        }]);
    }
    Ok((doc, b, summary))
}

/// `mesh.extras.morphkitDequantization` of a quantized rig: the node transform that gives its
/// positions (`translation`, uniform `scale`), so that the reader puts them back in their
/// units without looking for the node (a hidden window's node has scale 0).
fn dequantization_json(d: Dequant) -> Value {
    json!({"translation": d.offset, "scale": d.scale})
}

/// Pads the buffer and writes the buffer views, accessors and buffer into the document,
/// compressing the views with `EXT_meshopt_compression` when `opts.meshopt`
/// ([`super::meshopt_pack`]).
pub(super) fn finish(mut doc: Value, mut b: Builder, opts: &GltfOptions) -> (Value, Vec<u8>) {
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    doc["bufferViews"] = Value::Array(b.views);
    doc["accessors"] = Value::Array(b.accessors);
    doc["buffers"] = json!([{"byteLength": b.bin.len()}]);
    if opts.meshopt {
        let bin = super::meshopt_pack::compress_views(&mut doc, &b.bin);
        return (doc, bin);
    }
    (doc, b.bin)
}

/// Writes `m` to `path` atomically: GLB for `.glb`, otherwise glTF JSON with the buffer as a
/// base64 data URI (see the [module documentation](super) for the layout).
///
/// Errors: parts that disagree (names vs targets, target or weight counts), times that are not
/// strictly increasing, coordinates that overflow `f32`, and the errors of
/// [`crate::io::write_atomic`].
pub fn write_gltf_morphs(path: &Path, m: &GltfMorphs) -> Result<(), IoError> {
    write_gltf_with(path, m, &GltfOptions::default()).map(|_| ())
}

/// Writes `m` to `path` atomically with `opts` (see the [module documentation](super) for the
/// layout): GLB for `.glb`, otherwise glTF JSON with the buffer as a base64 data URI. The
/// summary says how many meshes were written and what a viewer may not play.
///
/// Errors: those of [`write_gltf_morphs`].
pub fn write_gltf_with(
    path: &Path,
    m: &GltfMorphs,
    opts: &GltfOptions,
) -> Result<GltfSummary, IoError> {
    let (doc, b, summary) = build_with(path, m, opts)?;
    let (doc, bin) = finish(doc, b, opts);
    write_document(path, doc, &bin)?;
    Ok(summary)
}

/// Writes a finished document and its buffer as GLB (`.glb`) or glTF with a data URI
/// (`.gltf`); any other extension is an [`IoError::UnknownFormat`] (glTF written into a file
/// named `.pc2` or `.obj` would be read back as that format).
pub(super) fn write_document(path: &Path, mut doc: Value, bin: &[u8]) -> Result<(), IoError> {
    let glb = match crate::io::Format::from_path(path) {
        Some(crate::io::Format::Glb) => true,
        Some(crate::io::Format::Gltf) => false,
        _ => {
            return Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
                expected: ".glb or .gltf",
            })
        }
    };
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
