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

/// A channel that drives the morph weights of a node using a given mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct WeightChannel {
    /// Animation index.
    pub anim: usize,
    /// Channel index in the animation.
    pub channel: usize,
    /// Sampler index in the animation.
    pub sampler: usize,
    /// The node it drives.
    pub node: usize,
}

/// Every channel, in document order, that drives the `weights` of a node using mesh `mesh`.
pub(super) fn weight_channels(doc: &::gltf::Document, mesh: usize) -> Vec<WeightChannel> {
    let mut out = Vec::new();
    for (a, aj) in doc.as_json().animations.iter().enumerate() {
        for (c, cj) in aj.channels.iter().enumerate() {
            // Read the raw JSON: `property()` and `node()` unwrap values that the `gltf`
            // crate's validation lets through (an unknown path panicked; found by cargo fuzz).
            let node = cj.target.node.value();
            if cj.target.path != Checked::Valid(Property::MorphTargetWeights)
                || doc
                    .nodes()
                    .nth(node)
                    .and_then(|n| n.mesh())
                    .map(|m| m.index())
                    != Some(mesh)
                || cj.sampler.value() >= aj.samplers.len()
            {
                continue;
            }
            out.push(WeightChannel {
                anim: a,
                channel: c,
                sampler: cj.sampler.value(),
                node,
            });
        }
    }
    out
}

/// The key times and the raw output values (`keys × num_targets`, or `keys × 3 × num_targets`
/// for `CUBICSPLINE`: in-tangents, values, out-tangents) of a weights channel, checked; and
/// whether it is `CUBICSPLINE`.
pub(super) fn channel_data(
    path: &Path,
    doc: &::gltf::Document,
    ch: WeightChannel,
    num_targets: usize,
    data: &Data,
) -> Result<(Vec<f64>, Vec<f64>, bool), IoError> {
    let at = |m: String| {
        IoError::content(
            path,
            format!("animation {}, channel {}: {m}", ch.anim, ch.channel),
        )
    };
    let anim = doc
        .animations()
        .nth(ch.anim)
        .ok_or_else(|| at("is not in the file".into()))?;
    let sampler = anim
        .samplers()
        .nth(ch.sampler)
        .ok_or_else(|| at("its sampler is not in the file".into()))?;
    let (input, output) = (sampler.input(), sampler.output());
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
    let aj = &doc.as_json().animations[ch.anim];
    let interpolation = match aj.samplers.get(ch.sampler).map(|s| s.interpolation) {
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
    if let Some(i) = w.iter().position(|x| !x.is_finite()) {
        return Err(at(format!(
            "key {}: the weight of target {} is not finite ({})",
            i / per_key,
            i % num_targets.max(1),
            w[i]
        )));
    }
    Ok((times, w, cubic))
}

/// The keys `(time, weights)` of channel data ([`channel_data`]): `STEP` and `LINEAR` keys as
/// they are; of `CUBICSPLINE` keys (in-tangent, value, out-tangent) the value.
pub(super) fn keys_of(
    times: &[f64],
    values: &[f64],
    cubic: bool,
    num_targets: usize,
) -> Vec<(f64, Vec<f64>)> {
    let per_key = if cubic { 3 * num_targets } else { num_targets };
    let skip = if cubic { num_targets } else { 0 };
    times
        .iter()
        .zip(values.chunks_exact(per_key.max(1)))
        .map(|(&t, c)| (t, c[skip..skip + num_targets].to_vec()))
        .collect()
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
    let Some(&ch) = weight_channels(doc, mesh).first() else {
        return Ok(Vec::new());
    };
    let (times, w, cubic) = channel_data(path, doc, ch, num_targets, data)?;
    Ok(keys_of(&times, &w, cubic, num_targets))
}

/// The first key whose time is not finite or, as `f32` (what a file stores), not after the
/// time before it; `None` when the times are finite and strictly increasing, as glTF 2.0
/// requires of an animation sampler's input.
pub(super) fn first_unordered_key(times: &[f64]) -> Option<usize> {
    (0..times.len())
        .find(|&k| !times[k].is_finite() || (k > 0 && times[k - 1] as f32 >= times[k] as f32))
}

/// A message for key `k` of `times`, found by [`first_unordered_key`].
pub(super) fn unordered_key_message(times: &[f64], k: usize) -> String {
    let rule = "key times must be finite and strictly increasing (as f32)";
    if !times[k].is_finite() {
        return format!("key {k} is at {} s: {rule}", times[k]);
    }
    format!(
        "key {k} at {} s does not come after key {} at {} s: {rule}",
        times[k] as f32,
        k - 1,
        times[k - 1] as f32
    )
}

impl super::GltfWeightAnimation {
    /// Fails when the key times are not finite and strictly increasing (as `f32`), as glTF 2.0
    /// requires and as an animation made from these keys needs ([`super::GltfAsset::add_frame_animation`]):
    /// a caller checks this before the work the keys drive. The error names the file `path`,
    /// the animation and the keys.
    pub fn check_times(&self, path: &Path) -> Result<(), IoError> {
        let times: Vec<f64> = self.keys.iter().map(|k| k.0).collect();
        match first_unordered_key(&times) {
            None => Ok(()),
            Some(k) => {
                let name = match &self.name {
                    Some(n) => format!("animation {} '{n}'", self.index),
                    None => format!("animation {} (unnamed)", self.index),
                };
                Err(IoError::content(
                    path,
                    format!("{name}: {}", unordered_key_message(&times, k)),
                ))
            }
        }
    }
}
