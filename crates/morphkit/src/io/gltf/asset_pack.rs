//! How [`GltfAsset::add_compact_animation`] stores its corrective targets and the clip's
//! weights ([`CompactEncoding`]; issue 56): as `f32`, like every other edit, or as small as
//! the asset's own data when that is quantized or compressed.
//!
//! - **Quantized** correctives ([`CompactEncoding::quantize`]; `KHR_mesh_quantization`, used
//!   and required): `POSITION` deltas as `SHORT` (VEC3 with 2 bytes of padding, `byteStride`
//!   8, §3.6.2.4's 4-byte element alignment; `min`/`max` the stored integers), `NORMAL` deltas
//!   as normalized `BYTE` (`round(127 x)`, `byteStride` 4). A weight is any float, so each
//!   corrective's scale `c` is moved between shape and coefficient: the stored shape is the
//!   displacement at its largest coefficient divided by `c`, and its coefficients peak at `c`.
//!   [`GltfAsset::corrective_grid`] chooses `c` and the grid per corrective. The rounding step
//!   in the mesh's units is `c / 32767` (normalized) or `c` (unnormalized); the coarsest step
//!   allowed is 1/16 of the tolerance (a corrective's rounding moves a vertex by at most
//!   `√3/32` of it), and `c` is at most 10 (Blender clamps shape-key values to `[−10, 10]`).
//!   So `c` is the largest value those allow (the coarsest grid: fewer significant bits, which
//!   compress better), on the first grid where that `c` is at least what the shape needs:
//!   1. normalized `SHORT`, `c ≥ max(A, N)`, where `A` is the largest displacement component
//!      and `N` the largest normal-delta component at the peak (plus 2 %, for the rounding of
//!      the peak coefficient): shape and normal delta both fit `[−1, 1]` (a mesh in metres);
//!   2. unnormalized `SHORT`, `c ≥ max(A / 32767, N)` (a mesh in integer units, as gltfpack
//!      leaves it: its dequantization is on the node, which scales the deltas too);
//!   3. and 4. the same with `c ≥ A` and `c ≥ A / 32767` (normal deltas then `f32`: they
//!      would not fit `[−1, 1]`);
//!   5. `f32`, `c = 1` (as without quantization).
//!
//!   The shape is rounded to its grid before its coefficients are projected
//!   ([`crate::clip::residual_basis_on`]), so the reported error is that of the stored
//!   integers. The normal delta is the change of the vertex normals at the peak (`c` times the
//!   stored shape) divided by `c`: exact at the peak, linear in the coefficient as glTF plays
//!   it.
//! - **meshopt-compressed** buffer views ([`CompactEncoding::meshopt`]: the asset's own
//!   `EXT_meshopt_compression` or `KHR_meshopt_compression`): every vertex attribute of the
//!   correctives and the weights of the clip (and of the padded animations), in mode
//!   `ATTRIBUTES`, filter `NONE`, vertex codec version 0 (which every decoder reads). The
//!   bytes go into the data buffer; the buffer view names a `fallback` buffer without data, as
//!   the extension allows; a weight accessor's codec stride is a whole key (`4 × #targets`
//!   bytes when that is at most 256, so each key is coded against the one before), else 4.
//!
//! Either way, the correctives' `POSITION` accessors share one buffer view per element size,
//! and so do their `NORMAL` accessors (each accessor at its `byteOffset`): a few views instead
//! of two per corrective and primitive, and each attribute's data coded together.

use super::asset::GltfAsset;
use super::asset_edit::{array, push, FLOAT};
use super::meshopt_pack::encode_attributes;
use super::normals::vertex_normals;
use crate::clip::{ClipBasis, Grid};
use crate::io::IoError;
use crate::mesh::Point;
use serde_json::{json, Value};

const ARRAY_BUFFER: u32 = 34962;
const BYTE: u32 = 5120;
const SHORT: u32 = 5122;
const QUANTIZATION: &str = "KHR_mesh_quantization";
/// The largest coefficient of a quantized corrective (Blender clamps shape-key values to
/// `[−10, 10]`).
const MAX_COEFFICIENT: f64 = 10.0;
/// The names of the meshopt compression extension, in order of preference.
const MESHOPT: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// How [`GltfAsset::add_compact_animation`] stores the correctives and the weights (see the
/// [module documentation](self)). The default stores `f32`, uncompressed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CompactEncoding {
    /// Correctives as 16-bit `POSITION` and 8-bit `NORMAL` deltas (`KHR_mesh_quantization`),
    /// with the grids of [`GltfAsset::corrective_grid`].
    pub quantize: bool,
    /// The meshopt extension (`EXT_meshopt_compression` or `KHR_meshopt_compression`) that
    /// compresses the new buffer views; `None`: uncompressed.
    pub meshopt: Option<String>,
}

/// Which attribute a stream of elements holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stream {
    Position,
    Normal,
}

/// The correctives' elements by `(attribute, stride)`: their bytes and the accessors that
/// read them, one buffer view each once flushed (fewer views, and each attribute's data coded
/// together).
type Streams = Vec<((Stream, usize), Vec<u8>, Vec<usize>)>;

/// The largest absolute component of `p`.
fn peak(p: &[Point]) -> f64 {
    p.iter().flatten().fold(0.0, |m, x| m.max(x.abs()))
}

/// `v` as 4-byte-aligned elements of `N` little-endian `i16`s (padded with zeros).
fn shorts(v: &[[i16; 3]]) -> Vec<u8> {
    v.iter()
        .flat_map(|q| [q[0], q[1], q[2], 0])
        .flat_map(i16::to_le_bytes)
        .collect()
}

impl GltfAsset {
    /// Whether the document's `extensionsUsed` lists `name`.
    pub fn uses_extension(&self, name: &str) -> bool {
        self.doc["extensionsUsed"]
            .as_array()
            .is_some_and(|a| a.iter().any(|e| e.as_str() == Some(name)))
    }

    /// The encoding the asset's own data asks for: quantized when it uses
    /// `KHR_mesh_quantization`, compressed with the meshopt extension it uses.
    pub fn compact_encoding(&self) -> CompactEncoding {
        CompactEncoding {
            quantize: self.uses_extension(QUANTIZATION),
            meshopt: MESHOPT
                .iter()
                .find(|e| self.uses_extension(e))
                .map(|e| e.to_string()),
        }
    }

    /// Per primitive with `NORMAL`: its base's vertex normals (unit, `f64`).
    fn base_normals(&self) -> Vec<Option<Vec<Point>>> {
        let base = &self.morphs.base.positions;
        (0..self.primitives.len())
            .map(|p| {
                self.primitives[p].normals.as_ref().map(|_| {
                    let (bp, tris) = self.local(p, base);
                    vertex_normals(&bp, &tris)
                })
            })
            .collect()
    }

    /// Per primitive with `NORMAL`: the change of its vertex normals when the base moves by
    /// `d` (`#V` displacements), divided by `c`.
    fn normal_deltas(
        &self,
        n0: &[Option<Vec<Point>>],
        d: &[Point],
        c: f64,
    ) -> Vec<Option<Vec<Point>>> {
        let moved: Vec<Point> = self
            .morphs
            .base
            .positions
            .iter()
            .zip(d)
            .map(|(b, x)| [b[0] + x[0], b[1] + x[1], b[2] + x[2]])
            .collect();
        n0.iter()
            .enumerate()
            .map(|(p, n0)| {
                let n0 = n0.as_ref()?;
                let (q, tris) = self.local(p, &moved);
                let n1 = vertex_normals(&q, &tris);
                Some(
                    n1.iter()
                        .zip(n0)
                        .map(|(a, b)| [(a[0] - b[0]) / c, (a[1] - b[1]) / c, (a[2] - b[2]) / c])
                        .collect(),
                )
            })
            .collect()
    }

    /// The scale and grid of each corrective, for [`crate::clip::residual_basis_on`] with
    /// `tolerance` (a distance in the mesh's units): `(1, F32)` without
    /// [`CompactEncoding::quantize`], else the first of the rules in the
    /// [module documentation](self) that holds. The closure takes a corrective at its largest
    /// coefficient (`#V` displacements).
    pub fn corrective_grid(
        &self,
        encoding: &CompactEncoding,
        tolerance: f64,
    ) -> impl FnMut(&[Point]) -> (f64, Grid) + '_ {
        let quantize = encoding.quantize;
        let n0 = if quantize {
            self.base_normals()
        } else {
            Vec::new()
        };
        let r: f64 = std::env::var("MK_R")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(16.0);
        let fine = tolerance / r;
        move |shape: &[Point]| {
            let a = peak(shape);
            if !(quantize && a > 0.0 && a.is_finite()) {
                return (1.0, Grid::F32);
            }
            // 2 % above the normals' peak: the stored coefficients' peak differs from `c` by
            // the rounding of the shape, and the normal deltas must stay within [−1, 1].
            let n = 1.02
                * self
                    .normal_deltas(&n0, shape, 1.0)
                    .iter()
                    .flatten()
                    .map(|d| peak(d))
                    .fold(0.0, f64::max);
            let k = 32767.0;
            // (grid, the mesh units of one step per unit of c, the least c).
            [
                (Grid::I16Normalized, 1.0 / k, a.max(n)),
                (Grid::I16, 1.0, (a / k).max(n)),
                (Grid::I16Normalized, 1.0 / k, a),
                (Grid::I16, 1.0, a / k),
            ]
            .into_iter()
            .find_map(|(g, unit, least)| {
                let c = (fine / unit).min(MAX_COEFFICIENT);
                (least <= c).then_some((c, g))
            })
            .unwrap_or((1.0, Grid::F32))
        }
    }

    /// Adds `basis`'s shapes as morph targets `names` of every primitive, stored as
    /// `encoding` says (see the [module documentation](self)); returns their indices. A name
    /// equal to an existing target's replaces it; the others are appended, with weight 0 in
    /// every existing animation (padded outputs compressed as `encoding` says).
    ///
    /// Errors: a split rig, names and shapes of different counts, a name given twice, a shape
    /// of another count than `#V`, more targets than [`GltfAsset::max_targets`].
    pub(super) fn add_correctives(
        &mut self,
        names: &[String],
        basis: &ClipBasis,
        encoding: &CompactEncoding,
    ) -> Result<Vec<usize>, IoError> {
        self.check_new_targets(names, basis.shapes.len())?;
        let nv = self.morphs.base.num_vertices();
        if let Some(j) = basis.shapes.iter().position(|s| s.len() != nv) {
            return Err(IoError::content(
                &self.path,
                format!(
                    "corrective '{}': {} displacements, the mesh has {nv} vertices",
                    names[j],
                    basis.shapes[j].len()
                ),
            ));
        }
        let old = self.morphs.targets.len();
        let meshopt = encoding.meshopt.as_deref();
        let n0 = self.base_normals();
        let mut streams = Streams::new();
        let mut at = Vec::with_capacity(names.len());
        for (j, (name, shape)) in names.iter().zip(&basis.shapes).enumerate() {
            let grid = basis.grids.get(j).copied().unwrap_or(Grid::F32);
            // The coefficient at the peak: the normal deltas are exact there.
            let c = basis
                .coefficients
                .iter()
                .filter_map(|row| row.get(j))
                .fold(0.0f64, |m, x| m.max(x.abs()));
            let c = if c > 0.0 && c.is_finite() { c } else { 1.0 };
            let at_peak: Vec<Point> = shape.iter().map(|d| d.map(|x| x * c)).collect();
            let normals = self.normal_deltas(&n0, &at_peak, c);
            let mut objects = Vec::with_capacity(self.primitives.len());
            for (p, dn) in normals.iter().enumerate() {
                let r = self.primitives[p].vertices.clone();
                let mut t =
                    json!({"POSITION": self.position_deltas(&shape[r], grid, &mut streams)});
                if let Some(dn) = dn {
                    let quantized = encoding.quantize && peak(dn) <= 1.0;
                    t["NORMAL"] = json!(self.normal_deltas_accessor(dn, quantized, &mut streams));
                }
                objects.push(t);
            }
            let stored: Vec<Point> = self
                .morphs
                .base
                .positions
                .iter()
                .zip(shape)
                .map(|(b, d)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]])
                .collect();
            at.push(self.install_target(name, stored, objects));
        }
        self.flush(streams, meshopt);
        self.store_names();
        self.pad_weights(old, self.morphs.targets.len(), meshopt);
        Ok(at)
    }

    /// A target `POSITION` accessor of `d` (displacements on `grid`), with `min`/`max`, its
    /// elements appended to `streams`.
    fn position_deltas(&mut self, d: &[Point], grid: Grid, streams: &mut Streams) -> usize {
        let (lo, hi) = bounds(d);
        if grid == Grid::F32 {
            let bytes: Vec<u8> = d
                .iter()
                .flatten()
                .flat_map(|&x| (x as f32).to_le_bytes())
                .collect();
            let a = json!({"componentType": FLOAT, "count": d.len(), "type": "VEC3",
                           "min": lo.map(|x| x as f32), "max": hi.map(|x| x as f32)});
            return self.streamed(a, Stream::Position, 12, &bytes, streams);
        }
        self.require(QUANTIZATION);
        let q: Vec<[i16; 3]> = d.iter().map(|p| p.map(|x| grid.integer(x))).collect();
        let mut a = json!({"componentType": SHORT, "count": q.len(), "type": "VEC3",
                           "min": lo.map(|x| grid.integer(x)), "max": hi.map(|x| grid.integer(x))});
        if grid == Grid::I16Normalized {
            a["normalized"] = json!(true);
        }
        self.streamed(a, Stream::Position, 8, &shorts(&q), streams)
    }

    /// A target `NORMAL` accessor of `dn`: normalized `BYTE` when `quantized` (every component
    /// within `[−1, 1]`), else `f32`, its elements appended to `streams`.
    fn normal_deltas_accessor(
        &mut self,
        dn: &[Point],
        quantized: bool,
        streams: &mut Streams,
    ) -> usize {
        if quantized {
            self.require(QUANTIZATION);
            let b: Vec<u8> = dn
                .iter()
                .flat_map(|q| {
                    let [x, y, z] = q.map(|x| (x * 127.0).round().clamp(-127.0, 127.0) as i8 as u8);
                    [x, y, z, 0]
                })
                .collect();
            let a = json!({"componentType": BYTE, "normalized": true, "count": dn.len(), "type": "VEC3"});
            return self.streamed(a, Stream::Normal, 4, &b, streams);
        }
        let b: Vec<u8> = dn
            .iter()
            .flatten()
            .flat_map(|&x| (x as f32).to_le_bytes())
            .collect();
        let a = json!({"componentType": FLOAT, "count": dn.len(), "type": "VEC3"});
        self.streamed(a, Stream::Normal, 12, &b, streams)
    }

    /// Pushes the accessor `a` (no view yet) whose elements (`stride` bytes each) are `bytes`,
    /// appended to the stream `(kind, stride)`; [`GltfAsset::flush`] gives it its view.
    fn streamed(
        &mut self,
        mut a: Value,
        kind: Stream,
        stride: usize,
        bytes: &[u8],
        streams: &mut Streams,
    ) -> usize {
        let s = match streams.iter_mut().find(|s| s.0 == (kind, stride)) {
            Some(s) => s,
            None => {
                streams.push(((kind, stride), Vec::new(), Vec::new()));
                streams.last_mut().expect("a stream")
            }
        };
        a["byteOffset"] = json!(s.1.len());
        s.1.extend_from_slice(bytes);
        let i = push(&mut self.doc, "accessors", a);
        s.2.push(i);
        i
    }

    /// One vertex-attribute buffer view per stream (compressed with `meshopt` when given), and
    /// its accessors pointed at it.
    fn flush(&mut self, streams: Streams, meshopt: Option<&str>) {
        for ((_, stride), bytes, accessors) in streams {
            let view = self.attribute_view(&bytes, stride, Some(ARRAY_BUFFER), meshopt);
            for i in accessors {
                self.doc["accessors"][i]["bufferView"] = json!(view);
            }
        }
    }

    /// Lists `name` in `extensionsUsed` and `extensionsRequired` (once).
    fn require(&mut self, name: &str) {
        for key in ["extensionsUsed", "extensionsRequired"] {
            let list = array(&mut self.doc, key);
            if !list.iter().any(|e| e.as_str() == Some(name)) {
                list.push(json!(name));
            }
        }
    }

    /// A buffer view of `bytes`, elements of `stride` bytes (a multiple of 4): plain (with
    /// `byteStride` for a vertex attribute whose elements are padded), or meshopt-compressed
    /// with the extension `meshopt` (see the [module documentation](self)).
    fn attribute_view(
        &mut self,
        bytes: &[u8],
        stride: usize,
        target: Option<u32>,
        meshopt: Option<&str>,
    ) -> usize {
        let Some(ext) = meshopt else {
            let view = self.view(bytes, target);
            if target == Some(ARRAY_BUFFER) {
                self.doc["bufferViews"][view]["byteStride"] = json!(stride);
            }
            return view;
        };
        self.require(ext);
        let count = bytes.len() / stride;
        let encoded = encode_attributes(bytes, stride, count);
        // The compressed bytes, in the data buffer (no view of their own).
        let b = self.edit_buffer();
        let buf = &mut self.buffers[b];
        while !buf.len().is_multiple_of(4) {
            buf.push(0);
        }
        let offset = buf.len();
        buf.extend_from_slice(&encoded);
        let len = buf.len();
        self.doc["buffers"][b]["byteLength"] = json!(len);
        // The view proper, in a fallback buffer that holds no bytes.
        let fb = self.fallback_buffer(ext);
        let at = self.doc["buffers"][fb]["byteLength"].as_u64().unwrap_or(0) as usize;
        let at = at.next_multiple_of(4);
        self.doc["buffers"][fb]["byteLength"] = json!(at + bytes.len());
        let mut v = json!({
            "buffer": fb, "byteOffset": at, "byteLength": bytes.len(),
            "extensions": {ext: {"buffer": b, "byteOffset": offset, "byteLength": encoded.len(),
                                 "byteStride": stride, "count": count, "mode": "ATTRIBUTES"}},
        });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if target == Some(ARRAY_BUFFER) {
            v["byteStride"] = json!(stride);
        }
        push(&mut self.doc, "bufferViews", v)
    }

    /// The buffer the compressed views name as theirs (created on first use): `byteLength`
    /// and the extension's `fallback`, no data.
    fn fallback_buffer(&mut self, ext: &str) -> usize {
        if let Some(b) = self.edit_fallback {
            return b;
        }
        let b = push(
            &mut self.doc,
            "buffers",
            json!({"byteLength": 0, "extensions": {ext: {"fallback": true}}}),
        );
        self.buffers.push(Vec::new());
        self.fallback.push(true);
        self.edit_fallback = Some(b);
        b
    }

    /// A dense `f32` SCALAR accessor of `values` (runs of `n` weights, one per key),
    /// meshopt-compressed with the extension `meshopt` (a whole key per codec element when it
    /// is at most 256 bytes).
    pub(super) fn packed_weights(&mut self, values: &[f32], n: usize, meshopt: &str) -> usize {
        let stride = if n > 0 && 4 * n <= 256 { 4 * n } else { 4 };
        let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.attribute_view(&bytes, stride, None, Some(meshopt));
        let a = json!({"bufferView": view, "componentType": FLOAT, "count": values.len(), "type": "SCALAR"});
        push(&mut self.doc, "accessors", a)
    }
}

/// The componentwise `(min, max)` of `p`.
fn bounds(p: &[Point]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in p {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    (lo, hi)
}
