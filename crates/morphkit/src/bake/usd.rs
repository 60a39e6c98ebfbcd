//! A [`BakedRig`] as a `UsdSkel` rig (issue 56): one `BlendShape` per slider, holding the
//! target at weight 1 and its in-betweens as `UsdSkelInbetweenShape`s at their weights, which
//! UsdSkel interpolates piecewise linearly as [`BakedRig::shape_weights`] does; and one per
//! combination, named `A+B`, holding its highest level at weight 1 and the lower levels as
//! in-betweens at `level / highest` (¼ for levels 1 and 4). An animation drives a slider's
//! blend shape with the slider's weight and a combination's with
//! [`BakedRig::combination_weight`] `/ highest level` (docs/bake.md).

use super::BakedRig;
use crate::io::{write_usd_blendshape_rig, IoError, UsdBlendShape, UsdOptions};
use crate::mesh::TriMesh;
use std::path::Path;

/// Writes `baked` (in `base`'s layout, `#V` vertices) as a `UsdSkel` rig at `path`, its slider
/// blend shapes named `sliders` (one per baked target), atomically (see the
/// [module documentation](self)).
///
/// Errors: as many names as baked targets, and those of [`write_usd_blendshape_rig`].
pub fn write_usd(
    path: &Path,
    base: &TriMesh,
    baked: &BakedRig,
    sliders: &[String],
    opts: &UsdOptions,
) -> Result<(), IoError> {
    if sliders.len() != baked.targets.len() {
        return Err(IoError::content(
            path,
            format!(
                "{} slider names for {} baked targets",
                sliders.len(),
                baked.targets.len()
            ),
        ));
    }
    let combo_names: Vec<String> = baked
        .combinations
        .iter()
        .map(|c| format!("{}+{}", sliders[c.targets.0], sliders[c.targets.1]))
        .collect();
    let mut shapes = Vec::new();
    for (name, t) in sliders.iter().zip(&baked.targets) {
        shapes.push(curve(name, &t.weights, &t.deltas, 1.0));
    }
    for (name, c) in combo_names.iter().zip(&baked.combinations) {
        let top = *c.shape.weights.last().unwrap_or(&1.0);
        shapes.push(curve(name, &c.shape.weights, &c.shape.deltas, top));
    }
    write_usd_blendshape_rig(path, base, &shapes, opts)
}

/// A blend shape whose weight 1 is `weights`' last (`= top`), the others in-betweens at
/// `weight / top`.
fn curve<'a>(
    name: &'a str,
    weights: &[f64],
    deltas: &'a [Vec<crate::mesh::Point>],
    top: f64,
) -> UsdBlendShape<'a> {
    let last = deltas.len() - 1;
    UsdBlendShape {
        name,
        offsets: &deltas[last],
        inbetweens: weights[..last]
            .iter()
            .zip(&deltas[..last])
            .map(|(w, d)| (w / top, d.as_slice()))
            .collect(),
    }
}
