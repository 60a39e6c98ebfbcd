//! The vertex data of a rig: base positions and normals and every target's `POSITION` and
//! `NORMAL` deltas, as `f32` or quantized (`KHR_mesh_quantization`), each delta accessor dense
//! or sparse ([`GltfOptions::quantize`], [`GltfOptions::sparse_targets`]).
//!
//! **Quantized** ([`Dequant`]): positions are normalized `i16`, `p = offset + scale · q / 32767`,
//! with the offset (the centre of the base's bounding box) and the uniform scale on the node
//! (glTF applies the node's transform to morphed positions, so the deltas share it). The scale
//! `s` is the base's largest half-extent, grown to the largest delta component (capped at the
//! bounding-box diagonal) so that deltas fit in `[-1, 1]` too. A target's delta is stored as
//! `round((target − offset) / s · 32767) − q_base`, so base and target both land within half a
//! step (`s / 65534` per coordinate, at most `√3 / 65534 ≈ 2.7e-5` of the diagonal as a
//! distance) of the input; a target whose delta does not fit keeps `f32` deltas (in node
//! units). Normals are normalized `i8` (`round(127 n)`), normal deltas `i8` the same way
//! (`round(127 n_target) − q_base`), or `f32` for a target whose normals turn so far that a
//! component changes by more than 1.
//!
//! **Sparse** targets list only the vertices whose stored delta is not zero (quantized: exactly
//! zero; `f32`: every component at most `1e-7` of the diagonal for positions, `1e-7` for unit
//! normals, below what `f32` resolves), without a buffer view (§3.6.2.3), when that is smaller
//! than the dense accessor; a target that moves nothing is an accessor without a view and
//! without sparse values (all zeros, §5.1.1). The POSITION and NORMAL accessors of a target
//! share their index view when they list the same vertices.

use super::normals::{to_f32_unit, vertex_normals};
use super::write::{to_f32, Builder, ARRAY_BUFFER, FLOAT};
use super::{GltfMorphs, GltfOptions};
use crate::io::IoError;
use crate::mesh::{bbox_diagonal, bounding_box, Point};
use serde_json::{json, Value};
use std::path::Path;

const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
/// Largest normalized `i16` and `i8`.
const K16: f64 = 32767.0;
const K8: f64 = 127.0;
/// Sparse `f32` deltas below this (a fraction of the diagonal for positions, absolute for unit
/// normals) count as zero.
const SPARSE_EPS: f64 = 1e-7;

/// The dequantizing transform of quantized positions, put on the node as `translation` and a
/// uniform `scale`: `p = offset + scale · stored`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Dequant {
    pub offset: [f32; 3],
    pub scale: f32,
}

/// The accessors [`write`] made.
pub(super) struct Vertices {
    pub position: usize,
    pub indices: usize,
    pub normal: Option<usize>,
    /// Per target `{"POSITION": a, "NORMAL": b}`.
    pub targets: Vec<Value>,
    /// The node transform quantized positions need.
    pub dequant: Option<Dequant>,
    /// Quantized: targets whose position deltas, and whose normal deltas, stayed `f32`.
    pub float_positions: usize,
    pub float_normals: usize,
}

/// One VEC3 attribute or delta stream in its stored type.
enum Stream {
    F32(Vec<[f32; 3]>),
    I16(Vec<[i16; 3]>),
    I8(Vec<[i8; 3]>),
}

impl Stream {
    fn len(&self) -> usize {
        match self {
            Stream::F32(v) => v.len(),
            Stream::I16(v) => v.len(),
            Stream::I8(v) => v.len(),
        }
    }

    /// Component type and normalized flag.
    fn kind(&self) -> (u32, bool) {
        match self {
            Stream::F32(_) => (FLOAT, false),
            Stream::I16(_) => (SHORT, true),
            Stream::I8(_) => (BYTE, true),
        }
    }

    /// Bytes of one element, and the stride of a vertex buffer view (4-byte aligned).
    fn sizes(&self) -> (usize, usize) {
        match self {
            Stream::F32(_) => (12, 12),
            Stream::I16(_) => (6, 8),
            Stream::I8(_) => (3, 4),
        }
    }

    fn push_element(&self, i: usize, out: &mut Vec<u8>) {
        match self {
            Stream::F32(v) => v[i].iter().for_each(|x| out.extend(x.to_le_bytes())),
            Stream::I16(v) => v[i].iter().for_each(|x| out.extend(x.to_le_bytes())),
            Stream::I8(v) => v[i].iter().for_each(|x| out.extend(x.to_le_bytes())),
        }
    }

    /// Component `k` of element `i` as stored (integers as integers).
    fn get(&self, i: usize, k: usize) -> f64 {
        match self {
            Stream::F32(v) => v[i][k] as f64,
            Stream::I16(v) => v[i][k] as f64,
            Stream::I8(v) => v[i][k] as f64,
        }
    }

    /// Whether element `i` counts as zero: every component at most `eps` (`f32`), exactly
    /// zero (integers).
    fn is_zero(&self, i: usize, eps: f64) -> bool {
        (0..3).all(|k| self.get(i, k).abs() <= eps)
    }

    /// `min` and `max` of the elements (§3.6.2.5: the stored values, integers for integer
    /// types), where only `listed` are stored and the rest are zero when `listed` is given.
    fn bounds(&self, listed: Option<&[u32]>) -> (Value, Value) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut visit = |i: usize| {
            for k in 0..3 {
                lo[k] = lo[k].min(self.get(i, k));
                hi[k] = hi[k].max(self.get(i, k));
            }
        };
        match listed {
            Some(l) => {
                l.iter().for_each(|&i| visit(i as usize));
                if l.len() < self.len() {
                    for k in 0..3 {
                        lo[k] = lo[k].min(0.0);
                        hi[k] = hi[k].max(0.0);
                    }
                }
            }
            None => (0..self.len()).for_each(visit),
        }
        let as_json = |b: [f64; 3]| match self {
            Stream::F32(_) => json!(b.map(|x| x as f32)),
            _ => json!(b.map(|x| x as i64)),
        };
        (as_json(lo), as_json(hi))
    }
}

impl Builder {
    /// A vertex-attribute accessor of `s`: dense, or, with `sparse_eps`, sparse when that is
    /// smaller (elements within `sparse_eps` of zero left out); `min`/`max` when `bounds`.
    fn stream(&mut self, s: &Stream, bounds: bool, sparse_eps: Option<f64>) -> usize {
        let (ty, normalized) = s.kind();
        let (elem, stride) = s.sizes();
        let n = s.len();
        let mut acc = json!({"componentType": ty, "count": n, "type": "VEC3"});
        if normalized {
            acc["normalized"] = json!(true);
        }
        let mut listed = None;
        if let Some(eps) = sparse_eps {
            let nz: Vec<u32> = (0..n)
                .filter(|&i| !s.is_zero(i, eps))
                .map(|i| i as u32)
                .collect();
            let (ity, isize) = match n {
                0..=256 => (UNSIGNED_BYTE, 1),
                257..=65536 => (UNSIGNED_SHORT, 2),
                _ => (UNSIGNED_INT, 4),
            };
            // Each view is padded to 4 bytes.
            let sparse_bytes =
                (nz.len() * isize).next_multiple_of(4) + (nz.len() * elem).next_multiple_of(4);
            if nz.len() < n && sparse_bytes < n * stride {
                if !nz.is_empty() {
                    let iv = self.sparse_indices(&nz, isize);
                    let mut vb = Vec::with_capacity(nz.len() * elem);
                    nz.iter().for_each(|&i| s.push_element(i as usize, &mut vb));
                    let vv = self.view(&vb, None);
                    acc["sparse"] = json!({
                        "count": nz.len(),
                        "indices": {"bufferView": iv, "componentType": ity},
                        "values": {"bufferView": vv},
                    });
                }
                listed = Some(nz);
            }
        }
        if listed.is_none() {
            let mut bytes = Vec::with_capacity(n * stride);
            for i in 0..n {
                s.push_element(i, &mut bytes);
                bytes.resize(bytes.len() + stride - elem, 0);
            }
            let view = self.view(&bytes, Some(ARRAY_BUFFER));
            if stride != elem {
                self.views[view]["byteStride"] = json!(stride);
            }
            acc["bufferView"] = json!(view);
        }
        if bounds {
            let (lo, hi) = s.bounds(listed.as_deref());
            acc["min"] = lo;
            acc["max"] = hi;
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// The index view of a sparse accessor listing `nz`: the previous one when it listed the
    /// same vertices with the same index size.
    fn sparse_indices(&mut self, nz: &[u32], isize: usize) -> usize {
        if let Some((prev, size, view)) = &self.last_sparse {
            if prev == nz && *size == isize {
                return *view;
            }
        }
        let bytes: Vec<u8> = nz
            .iter()
            .flat_map(|&i| i.to_le_bytes()[..isize].to_vec())
            .collect();
        let view = self.view(&bytes, None);
        self.last_sparse = Some((nz.to_vec(), isize, view));
        view
    }
}

/// The dequantization of `m`'s positions: the centre of the base's bounding box and the uniform
/// scale described in the [module documentation](self).
fn dequant(m: &GltfMorphs) -> Dequant {
    let p = &m.base.positions;
    if p.is_empty() {
        return Dequant {
            offset: [0.0; 3],
            scale: 1.0,
        };
    }
    let (lo, hi) = bounding_box(p);
    let offset = [0, 1, 2].map(|k| (0.5 * (lo[k] + hi[k])) as f32);
    let half = p
        .iter()
        .flat_map(|q| (0..3).map(move |k| (q[k] - offset[k] as f64).abs()))
        .fold(0.0, f64::max);
    let delta = m
        .targets
        .iter()
        .flat_map(|t| t.iter().zip(p))
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0, f64::max);
    // K / (K − 1): a delta of s rounds to at most K steps whatever the base's rounding.
    let s = half.max(delta.min(bbox_diagonal(p)) * K16 / (K16 - 1.0));
    let s = if s > 0.0 && s.is_finite() { s } else { 1.0 };
    // Never below s, so that |p − offset| / scale ≤ 1.
    let mut scale = s as f32;
    if (scale as f64) < s {
        scale = scale.next_up();
    }
    Dequant { offset, scale }
}

impl Dequant {
    /// `p` in stored units, `(p − offset) / scale`, times `k`.
    fn units(&self, p: &Point, k: f64) -> [f64; 3] {
        [0, 1, 2].map(|c| (p[c] - self.offset[c] as f64) / self.scale as f64 * k)
    }
}

/// Normalized `i8` of unit normals.
fn normals_i8(n: &[Point]) -> Vec<[i8; 3]> {
    n.iter()
        .map(|q| q.map(|x| (x * K8).round().clamp(-K8, K8) as i8))
        .collect()
}

/// Normal deltas of a target with normals `n` (unit vectors when `unit`, renormalised after
/// rounding to `f32`) over quantized base normals `qb`: `i8` when every component fits, else
/// `f32`.
fn normal_deltas_quantized(n: &[Point], qb: &[[i8; 3]], unit: bool) -> Stream {
    let qt = normals_i8(n);
    let d: Vec<[i16; 3]> = qt
        .iter()
        .zip(qb)
        .map(|(a, b)| [0, 1, 2].map(|k| a[k] as i16 - b[k] as i16))
        .collect();
    if d.iter().flatten().all(|&x| (x as f64).abs() <= K8) {
        return Stream::I8(d.iter().map(|q| q.map(|x| x as i8)).collect());
    }
    let n32: Vec<[f32; 3]> = if unit {
        to_f32_unit(n)
    } else {
        n.iter().map(|q| q.map(|x| x as f32)).collect()
    };
    Stream::F32(
        n32.iter()
            .zip(qb)
            .map(|(a, b)| [0, 1, 2].map(|k| a[k] - (b[k] as f64 / K8) as f32))
            .collect(),
    )
}

/// Writes the base's `POSITION`, indices, `NORMAL` and every target's deltas (in that
/// accessor order) into `b`, as `opts` asks (see the [module documentation](self)).
/// `normal_deltas`: each target's normal deltas as given (`#targets × #V`, not unit vectors:
/// a compact clip's fitted deltas, [`super::compact_frames`]) instead of those of the
/// target's own vertex normals.
pub(super) fn write(
    path: &Path,
    m: &GltfMorphs,
    opts: &GltfOptions,
    b: &mut Builder,
    normal_deltas: Option<&[Vec<Point>]>,
) -> Result<Vertices, IoError> {
    crate::io::atomic::check_fits_f32(path, "base", &m.base.positions)?;
    let base = to_f32(path, "base", &m.base.positions, None)?;
    if opts.quantize {
        // The f32 path checks each target as it converts it.
        for (t, tp) in m.targets.iter().enumerate() {
            to_f32(
                path,
                &format!("morph target {t}"),
                tp,
                Some(&m.base.positions),
            )?;
        }
    }
    let diag = bbox_diagonal(&m.base.positions);
    let dq = opts.quantize.then(|| dequant(m));
    // Quantized base positions (stored units) and their stream.
    let qbase: Option<Vec<[i16; 3]>> = dq.map(|d| {
        m.base
            .positions
            .iter()
            .map(|p| d.units(p, K16).map(|x| x.round().clamp(-K16, K16) as i16))
            .collect()
    });
    let position = match &qbase {
        Some(q) => b.stream(&Stream::I16(q.clone()), true, None),
        None => b.vec3(&base),
    };
    let indices = b.triangle_indices(&m.base);
    let base_normals = opts
        .normals
        .then(|| vertex_normals(&m.base.positions, &m.base.triangles));
    let qnormals = match (&base_normals, opts.quantize) {
        (Some(n), true) => Some(normals_i8(n)),
        _ => None,
    };
    let normal = match (&base_normals, &qnormals) {
        (_, Some(q)) => Some(b.stream(&Stream::I8(q.clone()), false, None)),
        (Some(n), None) => Some(b.vec3_plain(&to_f32_unit(n))),
        _ => None,
    };
    let sparse = |eps: f64| opts.sparse_targets.then_some(eps);
    // f32 position deltas are in node units: scaled by 1 / scale when quantized.
    let unit = dq.map_or(1.0, |d| d.scale as f64);
    let pos_eps = SPARSE_EPS * diag / unit;
    let mut targets = Vec::with_capacity(m.targets.len());
    let (mut float_positions, mut float_normals) = (0, 0);
    for (t, tp) in m.targets.iter().enumerate() {
        let dp = match (&dq, &qbase) {
            (Some(d), Some(qb)) => {
                let qd: Vec<[i64; 3]> = tp
                    .iter()
                    .zip(qb)
                    .map(|(p, q)| {
                        let u = d.units(p, K16);
                        [0, 1, 2].map(|k| u[k].round() as i64 - q[k] as i64)
                    })
                    .collect();
                if qd.iter().flatten().all(|&x| (x as f64).abs() <= K16) {
                    Stream::I16(qd.iter().map(|q| q.map(|x| x as i16)).collect())
                } else {
                    Stream::F32(
                        tp.iter()
                            .zip(qb)
                            .map(|(p, q)| {
                                let u = d.units(p, 1.0);
                                [0, 1, 2].map(|k| (u[k] - q[k] as f64 / K16) as f32)
                            })
                            .collect(),
                    )
                }
            }
            _ => Stream::F32(to_f32(
                path,
                &format!("morph target {}", targets.len()),
                tp,
                Some(&m.base.positions),
            )?),
        };
        if opts.quantize && matches!(dp, Stream::F32(_)) {
            float_positions += 1;
        }
        let mut target = json!({"POSITION": b.stream(&dp, true, sparse(pos_eps))});
        if let Some(n0) = &base_normals {
            let given = normal_deltas.and_then(|d| d.get(t));
            let n = match given {
                // Base normals plus the given deltas (not unit: what the viewer adds).
                Some(d) => n0
                    .iter()
                    .zip(d)
                    .map(|(a, e)| [a[0] + e[0], a[1] + e[1], a[2] + e[2]])
                    .collect(),
                None => vertex_normals(tp, &m.base.triangles),
            };
            let dn = match (&qnormals, given) {
                (Some(qb), _) => normal_deltas_quantized(&n, qb, given.is_none()),
                (None, Some(d)) => Stream::F32(d.iter().map(|e| e.map(|x| x as f32)).collect()),
                (None, None) => Stream::F32(
                    to_f32_unit(&n)
                        .iter()
                        .zip(to_f32_unit(n0))
                        .map(|(a, c)| [a[0] - c[0], a[1] - c[1], a[2] - c[2]])
                        .collect(),
                ),
            };
            if opts.quantize && matches!(dn, Stream::F32(_)) {
                float_normals += 1;
            }
            target["NORMAL"] = json!(b.stream(&dn, false, sparse(SPARSE_EPS)));
        }
        targets.push(target);
    }
    Ok(Vertices {
        position,
        indices,
        normal,
        targets,
        dequant: dq,
        float_positions,
        float_normals,
    })
}
