//! Target names and morph-weight animation keys of a mesh.

use super::accessor::{self, Data};
use crate::io::IoError;
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::{Interpolation, Property};
use ::gltf::json::validation::Checked;
use std::path::Path;

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

/// The keys of the first animation channel driving the `weights` of a node that uses mesh
/// `mesh`. `STEP` and `LINEAR` keys are taken as they are; of `CUBICSPLINE` keys (in-tangent,
/// value, out-tangent) the value.
pub(super) fn weight_keys(
    path: &Path,
    doc: &::gltf::Document,
    mesh: usize,
    num_targets: usize,
    data: &Data,
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
            let (input, output) = (ch.sampler().input(), ch.sampler().output());
            if input.dimensions() != Dimensions::Scalar || input.data_type() != DataType::F32 {
                return Err(at(format!(
                    "the input accessor {} must be SCALAR float (key times), not {:?} {:?}",
                    input.index(),
                    input.dimensions(),
                    input.data_type()
                )));
            }
            if output.dimensions() != Dimensions::Scalar || output.data_type() == DataType::U32 {
                return Err(at(format!(
                    "the output accessor {} must be SCALAR weights, not {:?} {:?}",
                    output.index(),
                    output.dimensions(),
                    output.data_type()
                )));
            }
            let times = accessor::read(&input, data).map_err(at)?;
            let w = accessor::read(&output, data).map_err(at)?;
            let sampler = aj.samplers.get(aj.channels[ch.index()].sampler.value());
            let interpolation = match sampler.map(|s| s.interpolation) {
                Some(Checked::Valid(i)) => i,
                _ => return Err(at("the sampler's interpolation is not valid".into())),
            };
            let cubic = interpolation == Interpolation::CubicSpline;
            let per_key = if cubic { 3 * num_targets } else { num_targets };
            if Some(w.len()) != times.len().checked_mul(per_key) {
                return Err(at(format!(
                    "{} weights for {} keys × {} targets{}",
                    w.len(),
                    times.len(),
                    num_targets,
                    if cubic {
                        " × 3 (CUBICSPLINE: in-tangent, value, out-tangent)"
                    } else {
                        ""
                    }
                )));
            }
            if let Some(k) = times.iter().position(|t| !t.is_finite()) {
                return Err(at(format!("key {k} has a non-finite time {}", times[k])));
            }
            let skip = if cubic { num_targets } else { 0 };
            let mut keys = Vec::with_capacity(times.len());
            for (k, (&t, c)) in times.iter().zip(w.chunks_exact(per_key)).enumerate() {
                let v = &c[skip..skip + num_targets];
                if let Some(j) = v.iter().position(|x| !x.is_finite()) {
                    return Err(at(format!(
                        "key {k}: the weight of target {j} is not finite ({})",
                        v[j]
                    )));
                }
                keys.push((t, v.to_vec()));
            }
            return Ok(keys);
        }
    }
    Ok(Vec::new())
}
