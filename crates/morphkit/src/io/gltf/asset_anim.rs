//! Animations morphkit adds to a [`GltfAsset`]'s chosen mesh: a physical clip written as one
//! morph target per frame ([`GltfAsset::add_frame_animation`]), or compactly, as the asset's
//! own targets at the clip's weights plus a few corrective targets
//! ([`GltfAsset::add_compact_animation`], issue 56). Both are ordinary glTF morph animations
//! (glTF 2.0 §3.11): every viewer plays them with no extension.

use super::asset::{GltfAsset, GltfWeightAnimation, WeightSampler};
use super::asset_edit::{push, FLOAT};
use super::asset_pack::CompactEncoding;
use crate::clip::ClipBasis;
use crate::io::IoError;
use crate::mesh::Point;
use serde_json::{json, Value};

impl GltfAsset {
    /// Fails when an animation `clip_name` of `frames` keys at `times` cannot be added, for
    /// what does not depend on its targets: no frame, times and frames of different counts,
    /// times negative, not finite or not strictly increasing as `f32`, no node using the mesh,
    /// a split rig. A command calls it before it makes the frames, so that these errors come
    /// before the work.
    pub fn check_clip_keys(
        &self,
        clip_name: &str,
        times: &[f64],
        frames: usize,
    ) -> Result<(), IoError> {
        let bad = |m: String| IoError::content(&self.path, format!("animation '{clip_name}': {m}"));
        if frames == 0 {
            return Err(bad("no frames to animate (the frames are empty)".into()));
        }
        if times.len() != frames {
            return Err(bad(format!("{} times for {frames} frames", times.len())));
        }
        if let Some(k) = super::anim::first_unordered_key(times) {
            return Err(bad(super::anim::unordered_key_message(times, k)));
        }
        if times[0] < 0.0 {
            return Err(bad(format!(
                "key time 0 is {} s; glTF key times must not be negative",
                times[0]
            )));
        }
        if self.mesh_nodes().is_empty() {
            return Err(bad("no node uses the mesh, so nothing would play it".into()));
        }
        Ok(())
    }

    /// Fails when [`GltfAsset::add_frame_animation`] would refuse an animation `clip_name` of
    /// `frames` frames at `times`, for what it refuses before the positions: those of
    /// [`GltfAsset::check_clip_keys`], and more morph targets than [`GltfAsset::max_targets`]
    /// (one per frame). A command calls it before it makes the frames, so that these errors
    /// come before the work.
    pub fn check_frame_animation(
        &self,
        clip_name: &str,
        times: &[f64],
        frames: usize,
    ) -> Result<(), IoError> {
        self.check_clip_keys(clip_name, times, frames)?;
        let fresh = (0..frames)
            .filter(|k| {
                let name = format!("{clip_name}_{k:04}");
                !self.morphs.target_names.contains(&name)
            })
            .count();
        self.check_room(fresh)
    }

    /// Adds a physical animation: one new morph target per frame (`frames[k]`, `#V` absolute
    /// positions, named `CLIP_0000`, …) and an animation `clip_name` that keys them one at a
    /// time — key `k` at `times[k]` seconds has weight 1 on frame `k`'s target and 0 on every
    /// other — `LINEAR`, so it plays the frames' positions interpolated. Its output is stored
    /// sparsely. It drives every node that uses the mesh; an existing animation of the same
    /// name is replaced (same index; its frames' targets are replaced by name). Existing
    /// animations get weight 0 for the new targets (see the [module documentation](self)).
    ///
    /// Errors: those of [`GltfAsset::add_targets`]; no frame, times and frames of different
    /// counts, times negative (glTF keys start at 0 s or later), not finite or not strictly
    /// increasing as `f32`, no node using the mesh.
    pub fn add_frame_animation(
        &mut self,
        clip_name: &str,
        times: &[f64],
        frames: &[Vec<Point>],
    ) -> Result<(), IoError> {
        self.check_frame_animation(clip_name, times, frames.len())?;
        let names: Vec<String> = (0..frames.len())
            .map(|k| format!("{clip_name}_{k:04}"))
            .collect();
        let at = self.add_targets_at(&names, frames)?;
        let n = self.morphs.targets.len();
        let mut rows = vec![0.0f32; frames.len() * n];
        for (k, &t) in at.iter().enumerate() {
            rows[k * n + t] = 1.0;
        }
        self.put_animation(clip_name, times, &rows, None);
        Ok(())
    }

    /// Adds (or replaces, by name) the animation `clip_name` keying every target of the mesh
    /// with `rows` (`times.len()` rows of `#targets` weights), `LINEAR`, on every node using the
    /// mesh, and records it as the asset's animations do; the output is compressed with the
    /// extension `meshopt` when given. The caller has checked the keys
    /// ([`GltfAsset::check_clip_keys`]).
    fn put_animation(
        &mut self,
        clip_name: &str,
        times: &[f64],
        rows: &[f32],
        meshopt: Option<&str>,
    ) {
        let nodes = self.mesh_nodes();
        let n = self.morphs.targets.len();
        let ts: Vec<f32> = times.iter().map(|&t| t as f32).collect();
        let tb: Vec<u8> = ts.iter().flat_map(|x| x.to_le_bytes()).collect();
        let tv = self.view(&tb, None);
        let input = push(
            &mut self.doc,
            "accessors",
            json!({"bufferView": tv, "componentType": FLOAT, "count": ts.len(), "type": "SCALAR",
                   "min": [ts[0]], "max": [ts[ts.len() - 1]]}),
        );
        let output = match meshopt {
            Some(ext) => self.packed_weights(rows, n, ext),
            None => self.weights(rows),
        };
        let channels: Vec<Value> = nodes
            .iter()
            .map(|&node| json!({"sampler": 0, "target": {"node": node, "path": "weights"}}))
            .collect();
        let anim = json!({
            "name": clip_name,
            "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}],
            "channels": channels,
        });
        let existing = self.doc["animations"]
            .as_array()
            .and_then(|a| a.iter().position(|x| x["name"].as_str() == Some(clip_name)));
        let index = match existing {
            Some(i) => {
                self.doc["animations"][i] = anim;
                self.samplers.retain(|s| s.anim != i);
                self.animations.retain(|a| a.index != i);
                i
            }
            None => push(&mut self.doc, "animations", anim),
        };
        let keys: Vec<(f64, Vec<f64>)> = ts
            .iter()
            .zip(rows.chunks(n))
            .map(|(&t, w)| (t as f64, w.iter().map(|&x| x as f64).collect()))
            .collect();
        self.samplers.push(WeightSampler {
            anim: index,
            sampler: 0,
            channels: (0..nodes.len()).collect(),
            shared: false,
            values: rows.iter().map(|&x| x as f64).collect(),
        });
        self.animations.push(GltfWeightAnimation {
            index,
            name: Some(clip_name.to_string()),
            keys,
        });
        self.animations.sort_by_key(|a| a.index);
        // What a reader takes: the first animation driving the mesh.
        self.morphs.weight_keys = self.animations[0].keys.clone();
    }

    /// Adds a compact physical animation `clip_name`: key `k` at `times[k]` s weighs the
    /// mesh's existing targets by `weights[k]` (one per existing target, in the mesh's order)
    /// and `basis.shapes.len()` new corrective targets (displacements `basis.shapes[j]`, named
    /// `CLIP_corrective_00`, …) by `basis.coefficients[k]`, `LINEAR`. When `basis` spans the
    /// physical frames minus the linear blend of `weights`, the clip plays the physical frames
    /// within its error; [`super::GltfMorphs::evaluate`] plays a key as a viewer does.
    /// Existing animations weigh the correctives 0; an animation of the same name is replaced.
    /// The correctives are stored on `basis.grids` and, like the weights, as `encoding` says
    /// (`asset_pack.rs`: quantized, meshopt-compressed, or `f32`); the asset's
    /// [`GltfAsset::morphs`] then holds the stored numbers.
    ///
    /// Errors: those of [`GltfAsset::check_clip_keys`] and [`GltfAsset::add_targets`];
    /// `weights` or `basis` rows of other counts than the keys, a row of other length than the
    /// existing targets; a corrective name that is an existing target the clip weighs (a rerun
    /// on a clip that drives its own correctives).
    pub fn add_compact_animation(
        &mut self,
        clip_name: &str,
        times: &[f64],
        weights: &[Vec<f64>],
        basis: &ClipBasis,
        encoding: &CompactEncoding,
    ) -> Result<(), IoError> {
        self.check_clip_keys(clip_name, times, weights.len())?;
        let bad = |m: String| IoError::content(&self.path, format!("animation '{clip_name}': {m}"));
        let n0 = self.morphs.targets.len();
        if basis.coefficients.len() != weights.len() {
            return Err(bad(format!(
                "{} rows of corrective weights for {} keys",
                basis.coefficients.len(),
                weights.len()
            )));
        }
        if let Some(k) = weights.iter().position(|w| w.len() != n0) {
            return Err(bad(format!(
                "key {k}: {} weights for the mesh's {n0} targets",
                weights[k].len()
            )));
        }
        let names: Vec<String> = (0..basis.shapes.len())
            .map(|j| format!("{clip_name}_corrective_{j:02}"))
            .collect();
        for name in &names {
            if let Some(i) = self.morphs.target_names.iter().position(|n| n == name) {
                if weights.iter().any(|w| w[i] != 0.0) {
                    return Err(bad(format!(
                        "the clip weighs the target '{name}', which its correctives would replace"
                    )));
                }
            }
        }
        let at = self.add_correctives(&names, basis, encoding)?;
        let n = self.morphs.targets.len();
        let mut rows = vec![0.0f32; weights.len() * n];
        for (k, (w, c)) in weights.iter().zip(&basis.coefficients).enumerate() {
            let row = &mut rows[k * n..(k + 1) * n];
            for (r, x) in row.iter_mut().zip(w) {
                *r = *x as f32;
            }
            for (&t, x) in at.iter().zip(c) {
                row[t] = *x as f32;
            }
        }
        self.put_animation(clip_name, times, &rows, encoding.meshopt.as_deref());
        Ok(())
    }
}
