//! Reading glTF/GLB into [`GltfMorphs`].

use super::buffers::load_buffers;
use super::GltfMorphs;
use crate::io::Format;
use crate::io::{source::read_file, IoError};
use crate::mesh::{Point, Polygons, TriMesh};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::util::ReadOutputs;
use ::gltf::animation::{Interpolation, Property};
use ::gltf::json::validation::Checked;
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use std::path::Path;

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Checks the GLB container (header and chunk lengths) so that truncation is reported with a
/// byte offset before the `gltf` crate sees the file.
fn check_glb(path: &Path, b: &[u8]) -> Result<(), IoError> {
    if b.len() < 12 {
        return Err(IoError::binary(
            path,
            b.len() as u64,
            "the file ends inside the 12-byte GLB header",
        ));
    }
    let version = u32_at(b, 4);
    if version != 2 {
        return Err(IoError::binary(
            path,
            4,
            format!("GLB version {version}, only 2 is supported"),
        ));
    }
    let length = u32_at(b, 8) as usize;
    if length < 12 {
        return Err(IoError::binary(
            path,
            8,
            format!(
                "the GLB header declares a length of {length} bytes, less than the header itself"
            ),
        ));
    }
    if length > b.len() {
        return Err(IoError::binary(
            path,
            b.len() as u64,
            format!(
                "the GLB header declares {length} bytes but the file has {} (truncated)",
                b.len()
            ),
        ));
    }
    let mut off = 12;
    let mut chunk = 0;
    while off < length {
        if off + 8 > length {
            return Err(IoError::binary(
                path,
                off as u64,
                format!("the file ends inside the header of chunk {chunk}"),
            ));
        }
        let len = u32_at(b, off) as usize;
        if off + 8 + len > length {
            return Err(IoError::binary(
                path,
                off as u64,
                format!(
                    "chunk {chunk} declares {len} bytes but only {} remain (truncated)",
                    length - off - 8
                ),
            ));
        }
        off += 8 + len;
        chunk += 1;
    }
    Ok(())
}

/// Reads the first mesh of a glTF or GLB file with its morph targets and morph-weight
/// animation (see the [module documentation](super)).
///
/// Errors: unreadable, empty or truncated files (GLB truncation names the byte offset), files
/// the `gltf` crate rejects, no mesh, non-triangle primitives, `POSITION` not `f32` VEC3,
/// accessors reaching past their buffer, an index out of range (naming primitive and index),
/// primitives with different numbers of morph targets, a morph target whose `POSITION`
/// accessor has another count than the base `POSITION`, and weight outputs whose count does
/// not match keys × targets.
pub fn read_gltf_morphs(path: &Path) -> Result<GltfMorphs, IoError> {
    parse_gltf_morphs(path, read_file(path)?)
}

/// Like [`read_gltf_morphs`], on the file's bytes (GLB or glTF JSON). `path` names the file in
/// errors, says whether it should be GLB (by extension), and is the base of relative buffer
/// URIs.
pub fn parse_gltf_morphs(path: &Path, bytes: Vec<u8>) -> Result<GltfMorphs, IoError> {
    let is_glb = bytes.starts_with(b"glTF");
    if is_glb {
        check_glb(path, &bytes)?;
    } else if Format::from_path(path) == Some(Format::Glb) {
        let looks_json = super::super::strip_bom(&bytes)
            .trim_ascii_start()
            .starts_with(b"{");
        return Err(IoError::binary(
            path,
            0,
            format!(
                "not a GLB file: it does not start with the magic 'glTF'{}",
                if looks_json {
                    " (it looks like glTF JSON; name it .gltf)"
                } else {
                    ""
                }
            ),
        ));
    }
    let gerr = |source| IoError::Gltf {
        path: path.to_path_buf(),
        cause: source,
    };
    super::precheck::check_positions(path, super::super::strip_bom(&bytes))?;
    let mut gltf = if is_glb {
        ::gltf::Gltf::from_slice(&bytes)
    } else {
        ::gltf::Gltf::from_slice(super::super::strip_bom(&bytes))
    }
    .map_err(gerr)?;
    // The file's bytes are no longer needed: the BIN chunk was copied into the blob.
    drop(bytes);
    let buffers = load_buffers(path, &gltf.document, gltf.blob.take())?;
    // glTF requires count ≥ 1; the gltf crate's readers compute `count - 1` unchecked (an
    // overflow found by cargo fuzz).
    if let Some(a) = gltf.document.accessors().find(|a| a.count() == 0) {
        return Err(IoError::content(
            path,
            format!(
                "accessor {} has count 0; glTF requires at least 1",
                a.index()
            ),
        ));
    }
    let get = |b: ::gltf::Buffer| buffers.get(b.index()).map(|d| &d[..]);
    let doc = &gltf.document;
    let mesh = doc
        .meshes()
        .next()
        .ok_or_else(|| IoError::content(path, "the file has no mesh"))?;
    let mut positions: Vec<Point> = Vec::new();
    let mut polys = Polygons {
        offsets: vec![0],
        indices: Vec::new(),
    };
    let mut displacements: Vec<Vec<Point>> = Vec::new();
    for (pi, prim) in mesh.primitives().enumerate() {
        let at = |m: String| IoError::content(path, format!("mesh 0, primitive {pi}: {m}"));
        if prim.mode() != Mode::Triangles {
            return Err(at(format!(
                "mode {:?}; only triangles are supported",
                prim.mode()
            )));
        }
        let pos_acc = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| at("no POSITION attribute".into()))?;
        if pos_acc.data_type() != DataType::F32 || pos_acc.dimensions() != Dimensions::Vec3 {
            return Err(at(format!(
                "POSITION accessor {} is {:?} {:?}, expected f32 VEC3",
                pos_acc.index(),
                pos_acc.data_type(),
                pos_acc.dimensions()
            )));
        }
        let n = pos_acc.count();
        let reader = prim.reader(get);
        let p: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| at(format!("POSITION accessor {} has no data", pos_acc.index())))?
            .collect();
        if p.len() != n {
            return Err(at(format!(
                "POSITION accessor {} has {n} elements but its buffer holds {}",
                pos_acc.index(),
                p.len()
            )));
        }
        let offset = positions.len() as u32;
        // The gltf crate's index reader panics (unreachable!) on other component types.
        if let Some(acc) = prim.indices() {
            if !matches!(
                acc.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            ) {
                return Err(at(format!(
                    "index accessor {} is {:?}, expected an unsigned integer type",
                    acc.index(),
                    acc.data_type()
                )));
            }
        }
        let idx: Vec<u32> = match reader.read_indices() {
            Some(r) => r.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(acc) = prim.indices() {
            if idx.len() != acc.count() {
                return Err(at(format!(
                    "index accessor {} has {} elements but its buffer holds {}",
                    acc.index(),
                    acc.count(),
                    idx.len()
                )));
            }
        }
        if !idx.len().is_multiple_of(3) {
            return Err(at(format!("{} indices is not a multiple of 3", idx.len())));
        }
        if let Some((k, &i)) = idx.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(at(format!(
                "index {k} is {i}, but the primitive has {n} vertices"
            )));
        }
        for t in idx.chunks_exact(3) {
            polys.indices.extend(t.iter().map(|&i| i + offset));
            polys.offsets.push(polys.indices.len() as u32);
        }
        // Morph targets: check counts first, then read.
        let targets: Vec<_> = prim.morph_targets().collect();
        if pi > 0 && targets.len() != displacements.len() {
            return Err(at(format!(
                "has {} morph targets, primitive 0 has {}",
                targets.len(),
                displacements.len()
            )));
        }
        if pi == 0 {
            displacements = vec![Vec::new(); targets.len()];
        }
        for (t, target) in targets.iter().enumerate() {
            if let Some(acc) = target.positions() {
                if acc.count() != n {
                    return Err(at(format!(
                        "morph target {t}: POSITION accessor {} has {} elements, the base POSITION has {n}",
                        acc.index(),
                        acc.count()
                    )));
                }
                if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
                    return Err(at(format!(
                        "morph target {t}: POSITION accessor {} is not f32 VEC3",
                        acc.index()
                    )));
                }
            }
        }
        for (t, (tp, _, _)) in reader.read_morph_targets().enumerate() {
            let d: Vec<[f32; 3]> = match tp {
                Some(it) => it.collect(),
                None => vec![[0.0; 3]; n],
            };
            if d.len() != n {
                return Err(at(format!(
                    "morph target {t}: the buffer holds only {} of {n} displacements",
                    d.len()
                )));
            }
            if let Some(v) = d.iter().position(|q| q.iter().any(|x| !x.is_finite())) {
                return Err(at(format!(
                    "morph target {t}: vertex {v} has a non-finite displacement {:?}",
                    d[v]
                )));
            }
            displacements[t].extend(d.iter().map(|q| q.map(f64::from)));
        }
        positions.extend(p.iter().map(|q| q.map(f64::from)));
    }
    if let Some(v) = positions
        .iter()
        .position(|q| q.iter().any(|x| !x.is_finite()))
    {
        return Err(IoError::content(
            path,
            format!("mesh 0: vertex {v} has a non-finite coordinate"),
        ));
    }
    let base = TriMesh::from_polygons(positions, polys);
    // Displacements become absolute positions in place (no second copy of every target).
    let mut targets = displacements;
    for d in &mut targets {
        for (q, b) in d.iter_mut().zip(&base.positions) {
            *q = [b[0] + q[0], b[1] + q[1], b[2] + q[2]];
        }
    }
    if let Some((target_names, targets, weight_keys)) =
        super::read_chunks::read_split(path, doc, &buffers, &base.positions)?
    {
        return Ok(GltfMorphs {
            base,
            target_names,
            targets,
            weight_keys,
        });
    }
    let target_names = target_names(mesh.extras(), targets.len());
    let weight_keys = weight_keys(path, doc, mesh.index(), targets.len(), &get)?;
    Ok(GltfMorphs {
        base,
        target_names,
        targets,
        weight_keys,
    })
}

/// `extras.targetNames` when it is an array of as many strings as targets, else `target_k`.
pub(super) fn target_names(extras: &::gltf::json::Extras, n: usize) -> Vec<String> {
    let names = extras
        .as_ref()
        .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
        .and_then(|v| {
            let a = v.get("targetNames")?.as_array()?.clone();
            a.iter()
                .map(|s| s.as_str().map(str::to_string))
                .collect::<Option<Vec<_>>>()
        });
    match names {
        Some(v) if v.len() == n => v,
        _ => (0..n).map(|k| format!("target_{k}")).collect(),
    }
}

pub(super) fn weight_keys<'a, 's>(
    path: &Path,
    doc: &'a ::gltf::Document,
    mesh: usize,
    num_targets: usize,
    get: &(impl Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>),
) -> Result<Vec<(f64, Vec<f64>)>, IoError> {
    if num_targets == 0 {
        return Ok(Vec::new());
    }
    for anim in doc.animations() {
        for ch in anim.channels() {
            let target = ch.target();
            // Read the raw JSON: `property()` and `node()` unwrap values that the `gltf`
            // crate's validation lets through (an unknown path panicked; found by cargo fuzz).
            let aj = &doc.as_json().animations[anim.index()];
            let tj = &aj.channels[ch.index()].target;
            if tj.path != Checked::Valid(Property::MorphTargetWeights)
                || tj.node.value() >= doc.nodes().len()
                || target.node().mesh().map(|m| m.index()) != Some(mesh)
            {
                continue;
            }
            let at = |m: String| {
                IoError::content(
                    path,
                    format!("animation {}, channel {}: {m}", anim.index(), ch.index()),
                )
            };
            // The gltf crate's readers assert that an accessor's element size matches what
            // they decode (a VEC3 input panicked; found by cargo fuzz): check types first.
            let (input, output) = (ch.sampler().input(), ch.sampler().output());
            if input.dimensions() != Dimensions::Scalar || input.data_type() != DataType::F32 {
                return Err(at(format!(
                    "the input accessor {} must be SCALAR float (key times), not {:?} {:?}",
                    input.index(),
                    input.dimensions(),
                    input.data_type()
                )));
            }
            let weight_type = matches!(
                output.data_type(),
                DataType::F32 | DataType::I8 | DataType::U8 | DataType::I16 | DataType::U16
            );
            if output.dimensions() != Dimensions::Scalar || !weight_type {
                return Err(at(format!(
                    "the output accessor {} must be SCALAR weights, not {:?} {:?}",
                    output.index(),
                    output.dimensions(),
                    output.data_type()
                )));
            }
            let reader = ch.reader(get.clone());
            let times: Vec<f32> = reader
                .read_inputs()
                .ok_or_else(|| at("the input accessor has no data".into()))?
                .collect();
            let Some(ReadOutputs::MorphTargetWeights(w)) = reader.read_outputs() else {
                return Err(at("the output accessor has no weight data".into()));
            };
            let w: Vec<f32> = w.into_f32().collect();
            let sampler = aj.samplers.get(aj.channels[ch.index()].sampler.value());
            let interpolation = match sampler.map(|s| s.interpolation) {
                Some(Checked::Valid(i)) => i,
                _ => return Err(at("the sampler's interpolation is not valid".into())),
            };
            let per_key = if interpolation == Interpolation::CubicSpline {
                3 * num_targets
            } else {
                num_targets
            };
            if w.len() != times.len() * per_key {
                return Err(at(format!(
                    "{} weights for {} keys × {} targets",
                    w.len(),
                    times.len(),
                    num_targets
                )));
            }
            if let Some(k) = times.iter().position(|t| !t.is_finite()) {
                return Err(at(format!("key {k} has a non-finite time {}", times[k])));
            }
            let skip = if per_key > num_targets {
                num_targets
            } else {
                0
            };
            for (k, c) in w.chunks_exact(per_key).enumerate() {
                if let Some(t) = c[skip..skip + num_targets]
                    .iter()
                    .position(|x| !x.is_finite())
                {
                    return Err(at(format!(
                        "key {k}: the weight of target {t} is not finite ({})",
                        c[skip + t]
                    )));
                }
            }
            return Ok(times
                .iter()
                .zip(w.chunks_exact(per_key))
                .map(|(&t, c)| {
                    (
                        t as f64,
                        c[skip..skip + num_targets]
                            .iter()
                            .map(|&x| x as f64)
                            .collect(),
                    )
                })
                .collect());
        }
    }
    Ok(Vec::new())
}
