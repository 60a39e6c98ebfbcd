//! Putting a split rig back together on reading (the long-animation layout of the
//! [module documentation](super)): meshes whose `extras.morphkitTargets` give the rig index of
//! each of their targets, each played by its own node's `weights` channel over a window of keys.

use super::accessor::{self, Data};
use super::anim::{channel_data, keys_of, target_names, weight_channels, weight_keys};
use crate::io::IoError;
use crate::mesh::Point;
use std::path::Path;

/// `extras.morphkitTargets` of a mesh, when present.
pub(super) fn rig_indices(extras: &::gltf::json::Extras) -> Option<Vec<usize>> {
    let v: serde_json::Value = serde_json::from_str(extras.as_ref()?.get()).ok()?;
    v.get("morphkitTargets")?
        .as_array()?
        .iter()
        .map(|x| x.as_u64().map(|i| i as usize))
        .collect()
}

/// `extras.morphkitDequantization` of a mesh that morphkit quantized: the translation and the
/// uniform scale of its node, `p = translation + scale · stored`. Taken only while a node
/// using the mesh still has that translation and that scale (or 0, a hidden window) and no
/// rotation, so that a file a tool re-quantized (keeping extras) is not dequantized twice.
pub(super) fn dequantization(
    doc: &::gltf::Document,
    mesh: &::gltf::Mesh,
) -> Option<([f64; 3], f64)> {
    let v: serde_json::Value = serde_json::from_str(mesh.extras().as_ref()?.get()).ok()?;
    let d = v.get("morphkitDequantization")?;
    let t = d.get("translation")?.as_array()?;
    let t: Vec<f64> = t.iter().map(|x| x.as_f64()).collect::<Option<_>>()?;
    let s = d.get("scale")?.as_f64()?;
    let t: [f64; 3] = t.try_into().ok()?;
    if !(t.iter().all(|x| x.is_finite()) && s.is_finite()) {
        return None;
    }
    let on_node = doc
        .nodes()
        .filter(|n| n.mesh().is_some_and(|m| m.index() == mesh.index()))
        .any(|n| {
            let (nt, nr, ns) = n.transform().decomposed();
            let same = |a: f32, b: f64| a == b as f32;
            (0..3).all(|k| same(nt[k], t[k]))
                && nr == [0.0, 0.0, 0.0, 1.0]
                && (ns.iter().all(|&x| same(x, s)) || ns == [0.0; 3])
        });
    on_node.then_some((t, s))
}

/// Positions in stored units put back in their own: `translation + scale · p`.
pub(super) fn dequantize((t, s): ([f64; 3], f64), positions: &mut [Point]) {
    for p in positions {
        *p = [0, 1, 2].map(|k| t[k] + s * p[k]);
    }
}

/// Weight keys: `(time in seconds, one weight per target)`.
type Keys = Vec<(f64, Vec<f64>)>;

/// The parts of a split rig (every mesh with `extras.morphkitTargets`, in document order, with
/// those indices) and its target count; `None` when mesh 0 is not one of them.
#[allow(clippy::type_complexity)]
fn split_parts(doc: &::gltf::Document) -> Option<(Vec<(::gltf::Mesh<'_>, Vec<usize>)>, usize)> {
    let parts: Vec<(::gltf::Mesh, Vec<usize>)> = doc
        .meshes()
        .filter_map(|m| rig_indices(m.extras()).map(|r| (m, r)))
        .collect();
    if parts.first().is_none_or(|(m, _)| m.index() != 0) {
        return None;
    }
    let n = parts
        .iter()
        .flat_map(|(_, r)| r.iter().copied())
        .max()
        .map_or(0, |i| i.saturating_add(1));
    Some((parts, n))
}

/// The weight keys of a split rig over all `n` of its targets: each part's keys
/// (`part_keys(mesh index, its target count)`) in their rig's columns, zero elsewhere, the parts
/// in order; a key at or before the last one taken is a window's shared boundary key, skipped.
fn merge_keys(
    parts: &[(::gltf::Mesh, Vec<usize>)],
    n: usize,
    mut part_keys: impl FnMut(usize, usize) -> Result<Keys, IoError>,
) -> Result<Keys, IoError> {
    let mut keys: Keys = Vec::new();
    for (mesh, rig) in parts {
        for (t, w) in part_keys(mesh.index(), rig.len())? {
            if keys.last().is_some_and(|(last, _)| t <= *last) {
                continue;
            }
            let mut row = vec![0.0; n];
            for (j, x) in w.into_iter().enumerate() {
                row[rig[j]] = x;
            }
            keys.push((t, row));
        }
    }
    Ok(keys)
}

/// The keys of animation `anim` over the whole split rig that mesh `mesh` starts (see
/// [`read_split`]), merged as [`read_split`] merges the first animation's: every target once,
/// the windows' keys in time order. `None` when `mesh` does not start a split rig, so that an
/// animation's keys have one column per target of [`read_split`]'s rig, not of the first window.
pub(super) fn split_animation_keys(
    path: &Path,
    doc: &::gltf::Document,
    data: &Data,
    mesh: usize,
    anim: usize,
) -> Result<Option<Keys>, IoError> {
    let Some((parts, n)) = split_parts(doc).filter(|_| mesh == 0) else {
        return Ok(None);
    };
    let keys = merge_keys(&parts, n, |mi, count| {
        let Some(ch) = weight_channels(doc, mi)
            .into_iter()
            .find(|c| c.anim == anim)
        else {
            return Ok(Vec::new());
        };
        let (times, values, cubic) = channel_data(path, doc, ch, count, data)?;
        Ok(keys_of(&times, &values, cubic, count))
    })?;
    Ok(Some(keys))
}

/// The rig of a split file: names, absolute target positions and merged weight keys; `None`
/// when mesh 0 is not part of a split rig. `base` are the base positions of mesh 0, which
/// every part shares, already dequantized with `dequant` (whose scale the deltas need).
#[allow(clippy::type_complexity)]
pub(super) fn read_split(
    path: &Path,
    doc: &::gltf::Document,
    data: &Data,
    base: &[Point],
    dequant: Option<([f64; 3], f64)>,
) -> Result<Option<(Vec<String>, Vec<Vec<Point>>, Vec<(f64, Vec<f64>)>)>, IoError> {
    let Some((parts, n)) = split_parts(doc) else {
        return Ok(None);
    };
    // Every rig index must be held by some part, so there are at most as many as listed (this
    // also bounds the allocations below by the file's own size).
    let listed: usize = parts.iter().map(|(_, r)| r.len()).sum();
    if n > listed {
        return Err(IoError::content(
            path,
            format!(
                "split rig: extras.morphkitTargets names target {}, but the parts list only {listed} targets",
                n - 1
            ),
        ));
    }
    let nv = base.len();
    let mut names = vec![String::new(); n];
    let mut targets: Vec<Option<Vec<Point>>> = vec![None; n];
    for (mesh, rig) in &parts {
        let mi = mesh.index();
        let at =
            |m: String| IoError::content(path, format!("mesh {mi} (part of a split rig): {m}"));
        let prim = mesh
            .primitives()
            .next()
            .ok_or_else(|| at("has no primitive".into()))?;
        let local: Vec<_> = prim.morph_targets().collect();
        if local.len() != rig.len() {
            return Err(at(format!(
                "has {} morph targets but extras.morphkitTargets lists {}",
                local.len(),
                rig.len()
            )));
        }
        let local_names = target_names(mesh.extras(), rig.len());
        for (j, target) in local.iter().enumerate() {
            let mut d = match target.positions() {
                Some(acc) => accessor::read_vec3(&acc, data)
                    .map_err(|m| at(format!("morph target {j}: POSITION {m}")))?,
                None => vec![[0.0; 3]; nv],
            };
            if let Some((_, s)) = dequant {
                d.iter_mut().flatten().for_each(|x| *x *= s);
            }
            if d.len() != nv || d.iter().flatten().any(|x| !x.is_finite()) {
                return Err(at(format!(
                    "morph target {j} has {} finite displacements, the base has {nv} vertices",
                    d.len()
                )));
            }
            let g = rig[j];
            if targets[g].is_none() {
                targets[g] = Some(
                    d.iter()
                        .zip(base)
                        .map(|(q, b)| [b[0] + q[0], b[1] + q[1], b[2] + q[2]])
                        .collect(),
                );
                names[g] = local_names[j].clone();
            }
        }
    }
    let keys = merge_keys(&parts, n, |mi, count| {
        weight_keys(path, doc, mi, count, data)
    })?;
    let targets = targets
        .into_iter()
        .enumerate()
        .map(|(g, t)| {
            t.ok_or_else(|| {
                IoError::content(path, format!("split rig: no mesh holds morph target {g}"))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Some((names, targets, keys)))
}
