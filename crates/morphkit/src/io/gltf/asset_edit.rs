//! Edits of a [`GltfAsset`]'s chosen mesh. Each writes new accessors (into a buffer of its
//! own, merged on writing) and repoints the mesh, its nodes and animations at them; accessors
//! that exist are never rewritten, so a quantized or meshopt-compressed accessor shared with
//! another mesh stays as it is. A replaced accessor stays in the file, unused.
//!
//! - New `POSITION` data is `f32` with `min`/`max`; target `POSITION`s are displacements from
//!   the base (glTF 2.0 §3.7.2.2).
//! - **Normals** (only for primitives that have `NORMAL`): a new target's `NORMAL` delta is the
//!   change of the area-weighted vertex normals (see `normals.rs`) from the base to the target,
//!   computed per primitive, so vertices split at a hard edge or seam keep their own sides'
//!   normals. [`GltfAsset::set_base`] turns each stored base normal by the same change:
//!   `normalize(n_stored + n(new) − n(old))` (the computed normal where that vanishes).
//! - **Weights.** New targets get weight 0 everywhere: `mesh.weights` and the `weights` of
//!   nodes using the mesh are padded with zeros, and so is the output of every animation
//!   sampler driving them (a run of `#targets`-vectors for `STEP`, `LINEAR` and `CUBICSPLINE`
//!   alike), rewritten as `f32` (sparse when smaller).

use super::asset::{GltfAsset, WeightSampler};
use super::normals::{to_f32_unit, vertex_normals};
use super::write::to_f32;
use crate::io::IoError;
use crate::mesh::Point;
use serde_json::{json, Value};

const ARRAY_BUFFER: u32 = 34962;
pub(super) const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// `doc[key]` as an array, created when missing.
pub(super) fn array<'a>(doc: &'a mut Value, key: &str) -> &'a mut Vec<Value> {
    if !doc[key].is_array() {
        doc[key] = json!([]);
    }
    doc[key].as_array_mut().expect("an array")
}

/// Appends `v` to `doc[key]`; returns its index.
pub(super) fn push(doc: &mut Value, key: &str, v: Value) -> usize {
    let a = array(doc, key);
    a.push(v);
    a.len() - 1
}

/// `x` padded with zeros: every run of `old` values followed by `new − old` zeros.
pub(super) fn pad_runs(x: &[f64], old: usize, new: usize) -> Vec<f64> {
    if old == 0 {
        return x.to_vec();
    }
    let mut out = Vec::with_capacity(x.len() / old * new);
    for run in x.chunks(old) {
        out.extend_from_slice(run);
        out.extend(std::iter::repeat_n(0.0, new - old));
    }
    out
}

impl GltfAsset {
    /// The index of the buffer edits write into (created on first use).
    pub(super) fn edit_buffer(&mut self) -> usize {
        if let Some(b) = self.edit_buffer {
            return b;
        }
        let b = push(&mut self.doc, "buffers", json!({"byteLength": 0}));
        self.buffers.push(Vec::new());
        self.fallback.push(false);
        self.edit_buffer = Some(b);
        b
    }

    /// Appends `bytes` as a new 4-byte-aligned buffer view; returns its index.
    pub(super) fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        let b = self.edit_buffer();
        let buf = &mut self.buffers[b];
        while !buf.len().is_multiple_of(4) {
            buf.push(0);
        }
        let mut v = json!({"buffer": b, "byteOffset": buf.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        buf.extend_from_slice(bytes);
        let len = buf.len();
        self.doc["buffers"][b]["byteLength"] = json!(len);
        push(&mut self.doc, "bufferViews", v)
    }

    /// A VEC3 f32 accessor (with `min`/`max` when `bounds`); returns its index.
    pub(super) fn vec3(&mut self, p: &[[f32; 3]], bounds: bool) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        let mut a =
            json!({"bufferView": view, "componentType": FLOAT, "count": p.len(), "type": "VEC3"});
        if bounds {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for q in p {
                for k in 0..3 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        push(&mut self.doc, "accessors", a)
    }

    /// A new target's VEC3 f32 delta accessor: [`GltfAsset::vec3`], or, with
    /// [`GltfAsset::set_sparse_targets`] and fewer than three quarters of the elements nonzero
    /// (where it is smaller), a
    /// sparse accessor (no buffer view: zeros, then the nonzero elements' `u32` indices and
    /// values; `min`/`max` over all elements, the implicit zeros included).
    pub(super) fn target_vec3(&mut self, p: &[[f32; 3]], bounds: bool) -> usize {
        let nz: Vec<usize> = (0..p.len()).filter(|&i| p[i] != [0.0; 3]).collect();
        // Sparse costs 16 bytes an element listed (index and value), dense 12 an element.
        if !self.sparse_targets || nz.is_empty() || 4 * nz.len() >= 3 * p.len() {
            return self.vec3(p, bounds);
        }
        let ib: Vec<u8> = nz.iter().flat_map(|&i| (i as u32).to_le_bytes()).collect();
        let vb: Vec<u8> = nz
            .iter()
            .flat_map(|&i| p[i])
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let iv = self.view(&ib, None);
        let vv = self.view(&vb, None);
        let mut a = json!({
            "componentType": FLOAT, "count": p.len(), "type": "VEC3",
            "sparse": {
                "count": nz.len(),
                "indices": {"bufferView": iv, "componentType": UNSIGNED_INT},
                "values": {"bufferView": vv},
            }
        });
        if bounds {
            let mut lo = [0.0f32; 3];
            let mut hi = [0.0f32; 3];
            for &i in &nz {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[i][k]);
                    hi[k] = hi[k].max(p[i][k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        push(&mut self.doc, "accessors", a)
    }

    /// A SCALAR f32 accessor of `values`, sparse (no buffer view, the nonzero values and
    /// their `u32` indices; glTF 2.0 §3.6.2.3) when that is smaller than dense.
    pub(super) fn weights(&mut self, values: &[f32]) -> usize {
        let nz: Vec<usize> = (0..values.len()).filter(|&i| values[i] != 0.0).collect();
        if nz.is_empty() || 2 * nz.len() >= values.len() {
            let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
            let view = self.view(&bytes, None);
            let a = json!({"bufferView": view, "componentType": FLOAT, "count": values.len(), "type": "SCALAR"});
            return push(&mut self.doc, "accessors", a);
        }
        let ib: Vec<u8> = nz.iter().flat_map(|&i| (i as u32).to_le_bytes()).collect();
        let vb: Vec<u8> = nz.iter().flat_map(|&i| values[i].to_le_bytes()).collect();
        let iv = self.view(&ib, None);
        let vv = self.view(&vb, None);
        let a = json!({
            "componentType": FLOAT, "count": values.len(), "type": "SCALAR",
            "sparse": {
                "count": nz.len(),
                "indices": {"bufferView": iv, "componentType": UNSIGNED_INT},
                "values": {"bufferView": vv},
            }
        });
        push(&mut self.doc, "accessors", a)
    }

    /// The nodes that use the chosen mesh.
    pub(super) fn mesh_nodes(&self) -> Vec<usize> {
        self.doc["nodes"].as_array().map_or_else(Vec::new, |n| {
            (0..n.len())
                .filter(|&i| n[i]["mesh"].as_u64() == Some(self.mesh as u64))
                .collect()
        })
    }

    /// The primitive's `(positions, local triangles)` in `positions` (`#V` of the merged mesh).
    pub(super) fn local(&self, p: usize, positions: &[Point]) -> (Vec<Point>, Vec<[u32; 3]>) {
        let prim = &self.primitives[p];
        let o = prim.vertices.start as u32;
        let tris = self.morphs.base.triangles[prim.triangles.clone()]
            .iter()
            .map(|t| t.map(|i| i - o))
            .collect();
        (positions[prim.vertices.clone()].to_vec(), tris)
    }

    fn check_positions(&self, what: &str, p: &[Point]) -> Result<(), IoError> {
        let nv = self.morphs.base.num_vertices();
        if p.len() != nv {
            return Err(IoError::content(
                &self.path,
                format!("{what}: {} positions, the mesh has {nv} vertices", p.len()),
            ));
        }
        crate::io::atomic::check_fits_f32(&self.path, what, p)
    }

    /// Gives the chosen mesh new base positions (`#V`, the merged mesh's order, in the mesh's
    /// own space). Targets keep their displacements, as glTF stores them, so each target moves
    /// with the base: [`GltfAsset::morphs`]'s targets become new base + old displacement.
    /// Stored normals turn with the surface (see the [module documentation](self)).
    ///
    /// Errors: a split rig, a count other than `#V`, values `f32` cannot hold.
    pub fn set_base(&mut self, positions: &[Point]) -> Result<(), IoError> {
        self.check_room(0)?;
        self.check_positions("new base", positions)?;
        let new: Vec<Point> = to_f32(&self.path, "new base", positions, None)?
            .iter()
            .map(|q| q.map(f64::from))
            .collect();
        for p in 0..self.primitives.len() {
            let (np, tris) = self.local(p, &new);
            let pos = self.vec3(
                &np.iter().map(|q| q.map(|x| x as f32)).collect::<Vec<_>>(),
                true,
            );
            let prim = &mut self.doc["meshes"][self.mesh]["primitives"][p];
            prim["attributes"]["POSITION"] = json!(pos);
            let Some(stored) = self.primitives[p].normals.clone() else {
                continue;
            };
            let (op, _) = self.local(p, &self.morphs.base.positions);
            let (n0, n1) = (vertex_normals(&op, &tris), vertex_normals(&np, &tris));
            let turned: Vec<Point> = stored
                .iter()
                .zip(n0.iter().zip(&n1))
                .map(|(s, (a, b))| {
                    let q = [s[0] + b[0] - a[0], s[1] + b[1] - a[1], s[2] + b[2] - a[2]];
                    let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                    if len > 1e-6 {
                        q.map(|x| x / len)
                    } else {
                        *b
                    }
                })
                .collect();
            let f = to_f32_unit(&turned);
            let acc = self.vec3(&f, false);
            self.doc["meshes"][self.mesh]["primitives"][p]["attributes"]["NORMAL"] = json!(acc);
            self.primitives[p].normals = Some(f.iter().map(|q| q.map(f64::from)).collect());
        }
        let old = std::mem::replace(&mut self.morphs.base.positions, new);
        for t in &mut self.morphs.targets {
            for ((q, o), b) in t.iter_mut().zip(&old).zip(&self.morphs.base.positions) {
                *q = [
                    b[0] + (q[0] - o[0]),
                    b[1] + (q[1] - o[1]),
                    b[2] + (q[2] - o[2]),
                ];
            }
        }
        Ok(())
    }

    /// Adds morph targets to every primitive of the chosen mesh: `names[i]` at the absolute
    /// positions `positions[i]` (`#V`, the merged mesh's order, in the mesh's own space). A
    /// name equal to an existing target's replaces that target (its index, weights and
    /// animations kept); other names are appended with weight 0 everywhere (see the
    /// [module documentation](self)). Names are stored in `mesh.extras.targetNames`.
    ///
    /// Errors: a split rig, names and positions of different counts, a name given twice or
    /// that [`super::is_valid_target_name`] refuses (empty, `..`, a path), positions of another
    /// count than `#V` or that `f32` cannot hold, more targets than
    /// [`GltfAsset::max_targets`].
    pub fn add_targets(
        &mut self,
        names: &[String],
        positions: &[Vec<Point>],
    ) -> Result<(), IoError> {
        if let Some((i, n)) = names
            .iter()
            .enumerate()
            .find(|(_, n)| !super::is_valid_target_name(n))
        {
            return Err(IoError::content(
                &self.path,
                format!(
                    "target {i}: the name '{n}' cannot be a morph-target or file name (empty, \
                     '.', '..', or holding '/', '\\' or NUL)"
                ),
            ));
        }
        self.add_targets_at(names, positions).map(|_| ())
    }

    /// [`GltfAsset::add_targets`], returning the index of each target.
    pub(super) fn add_targets_at(
        &mut self,
        names: &[String],
        positions: &[Vec<Point>],
    ) -> Result<Vec<usize>, IoError> {
        self.check_new_targets(names, positions.len())?;
        let old = self.morphs.targets.len();
        for (n, p) in names.iter().zip(positions) {
            self.check_positions(&format!("target '{n}'"), p)?;
        }
        let base = self.morphs.base.positions.clone();
        let base_normals: Vec<Option<Vec<[f32; 3]>>> = (0..self.primitives.len())
            .map(|p| {
                self.primitives[p].normals.as_ref().map(|_| {
                    let (bp, tris) = self.local(p, &base);
                    to_f32_unit(&vertex_normals(&bp, &tris))
                })
            })
            .collect();
        let mut at = Vec::with_capacity(names.len());
        for (name, tp) in names.iter().zip(positions) {
            let delta = to_f32(&self.path, &format!("target '{name}'"), tp, Some(&base))?;
            let mut objects = Vec::with_capacity(self.primitives.len());
            for p in 0..self.primitives.len() {
                let r = self.primitives[p].vertices.clone();
                let mut t = json!({"POSITION": self.target_vec3(&delta[r], true)});
                if let Some(n0) = &base_normals[p] {
                    let (q, tris) = self.local(p, tp);
                    let n1 = to_f32_unit(&vertex_normals(&q, &tris));
                    let dn: Vec<[f32; 3]> = n1
                        .iter()
                        .zip(n0)
                        .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                        .collect();
                    t["NORMAL"] = json!(self.target_vec3(&dn, false));
                }
                objects.push(t);
            }
            let stored: Vec<Point> = base
                .iter()
                .zip(&delta)
                .map(|(b, d)| [b[0] + d[0] as f64, b[1] + d[1] as f64, b[2] + d[2] as f64])
                .collect();
            at.push(self.install_target(name, stored, objects));
        }
        self.store_names();
        self.pad_weights(old, self.morphs.targets.len(), None);
        Ok(at)
    }

    /// Sets `key` in the chosen mesh's `extras` (created when absent) to `value`: where a
    /// command records what a client needs to play what it added (e.g. `morphkitBake`, the
    /// mapping from sliders to baked shapes). Errors: `extras` that is not an object.
    pub fn set_mesh_extra(&mut self, key: &str, value: Value) -> Result<(), IoError> {
        let mesh = &mut self.doc["meshes"][self.mesh];
        if mesh["extras"].is_null() {
            mesh["extras"] = json!({});
        }
        match mesh["extras"].as_object_mut() {
            Some(e) => {
                e.insert(key.into(), value);
                Ok(())
            }
            None => Err(IoError::content(
                &self.path,
                format!(
                    "mesh {}: extras is not an object, so '{key}' cannot be added",
                    self.mesh
                ),
            )),
        }
    }

    /// Fails when `count` targets named `names` cannot be added: a split rig, names and
    /// targets of different counts, a name given twice, more targets than
    /// [`GltfAsset::max_targets`].
    pub(super) fn check_new_targets(&self, names: &[String], count: usize) -> Result<(), IoError> {
        self.check_room(0)?;
        if names.len() != count {
            return Err(IoError::content(
                &self.path,
                format!("{} target names for {count} targets", names.len()),
            ));
        }
        for (i, n) in names.iter().enumerate() {
            if names[..i].contains(n) {
                return Err(IoError::content(
                    &self.path,
                    format!("the target name '{n}' is given twice"),
                ));
            }
        }
        let fresh = names
            .iter()
            .filter(|n| !self.morphs.target_names.contains(n))
            .count();
        self.check_room(fresh)
    }

    /// Puts the target `name` (absolute positions `stored`, as a reader decodes them; one
    /// target object per primitive in `objects`) in place of the target of that name, or after
    /// the others; returns its index. The caller then stores the names and pads the weights
    /// ([`GltfAsset::store_names`], [`GltfAsset::pad_weights`]).
    pub(super) fn install_target(
        &mut self,
        name: &str,
        stored: Vec<Point>,
        objects: Vec<Value>,
    ) -> usize {
        let i = match self.morphs.target_names.iter().position(|n| n == name) {
            Some(i) => {
                self.morphs.targets[i] = stored;
                i
            }
            None => {
                self.morphs.target_names.push(name.to_string());
                self.morphs.targets.push(stored);
                self.morphs.targets.len() - 1
            }
        };
        for (p, t) in objects.into_iter().enumerate() {
            let prim = &mut self.doc["meshes"][self.mesh]["primitives"][p];
            let list = array(prim, "targets");
            if i < list.len() {
                list[i] = t;
            } else {
                list.push(t);
            }
        }
        i
    }

    /// Writes the target names into `mesh.extras.targetNames` (when `extras` is an object or
    /// absent).
    pub(super) fn store_names(&mut self) {
        let mesh = &mut self.doc["meshes"][self.mesh];
        if mesh["extras"].is_null() {
            mesh["extras"] = json!({});
        }
        if let Some(e) = mesh["extras"].as_object_mut() {
            e.insert("targetNames".into(), json!(self.morphs.target_names));
        }
    }

    /// Pads `mesh.weights`, nodes' `weights`, the weight keys and every sampler driving the
    /// mesh from `old` to `new` targets with zeros; the padded outputs are compressed with the
    /// extension `meshopt` when given (see `asset_pack.rs`).
    pub(super) fn pad_weights(&mut self, old: usize, new: usize, meshopt: Option<&str>) {
        if new == old {
            return;
        }
        // Only where the document has weights (indexing a Value mutably would add nulls).
        let nodes = self.mesh_nodes();
        let pointers = std::iter::once(format!("/meshes/{}/weights", self.mesh))
            .chain(nodes.iter().map(|n| format!("/nodes/{n}/weights")));
        for pointer in pointers {
            if let Some(a) = self.doc.pointer_mut(&pointer).and_then(Value::as_array_mut) {
                a.resize(a.len() + new - old, json!(0.0));
            }
        }
        // Padded outputs are rewritten as f32: keep what a reader will see.
        let f32_row = |w: &mut Vec<f64>| {
            w.resize(new, 0.0);
            w.iter_mut().for_each(|x| *x = *x as f32 as f64);
        };
        for (_, w) in &mut self.morphs.weight_keys {
            f32_row(w);
        }
        for a in &mut self.animations {
            for (_, w) in &mut a.keys {
                f32_row(w);
            }
        }
        for s in 0..self.samplers.len() {
            let f: Vec<f32> = pad_runs(&self.samplers[s].values, old, new)
                .iter()
                .map(|&x| x as f32)
                .collect();
            let output = match meshopt {
                Some(ext) => self.packed_weights(&f, new, ext),
                None => self.weights(&f),
            };
            let WeightSampler {
                anim,
                sampler,
                ref channels,
                shared,
                ..
            } = self.samplers[s];
            let channels = channels.clone();
            let anim_json = &mut self.doc["animations"][anim];
            let mut copy = anim_json["samplers"][sampler].clone();
            copy["output"] = json!(output);
            let target = if shared {
                // Another mesh's channel uses it too: ours get their own copy.
                let i = push(anim_json, "samplers", copy);
                for &c in &channels {
                    anim_json["channels"][c]["sampler"] = json!(i);
                }
                i
            } else {
                anim_json["samplers"][sampler] = copy;
                sampler
            };
            let w = &mut self.samplers[s];
            w.sampler = target;
            w.shared = false;
            w.values = f.iter().map(|&x| x as f64).collect();
        }
    }
}
