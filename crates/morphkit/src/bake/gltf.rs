//! A [`BakedRig`] written into a [`GltfAsset`] (issue 56): its in-between and combination shapes
//! as morph targets of the chosen mesh, and the mapping from the rig's sliders (the mesh's own
//! targets) to every target's weight in `mesh.extras.morphkitBake`, which a client evaluates
//! (docs/bake.md has it in JavaScript for three.js):
//!
//! ```json
//! "morphkitBake": {
//!   "version": 1,
//!   "sliders": ["jawOpen", ...],          // the mesh's own targets, in order
//!   "damping": 0.0,
//!   "inbetweens": [{"slider": 0, "weights": [0.125, ..., 1.0], "targets": [12, ..., 0]}],
//!   "combinations": [{"sliders": [0, 1], "levels": [1.0, 4.0], "targets": [80, 81]}]
//! }
//! ```
//!
//! A slider at `x` weighs the targets of its in-betweens by the piecewise-linear "hat"
//! [`BakedRig::shape_weights`] computes (from 0 at `x = 0`; the end segments extended); a
//! combination does the same at `4 xᵢ xⱼ · ((xᵢ + xⱼ) / Σ positive x)^damping` (0 unless both
//! are positive). The in-between at 1 of a slider is its own target.

use super::BakedRig;
use crate::io::{is_valid_target_name, GltfAsset, IoError};
use crate::mesh::Point;
use serde_json::json;

/// How a number appears in a target name: up to four decimals, no trailing zeros.
fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Fails when the chosen mesh of `asset` cannot be baked, before any solve: it is baked
/// already (`mesh.extras.morphkitBake`; its targets include baked shapes), or it is a split
/// rig.
pub fn check_gltf(asset: &GltfAsset) -> Result<(), IoError> {
    if !asset.document()["meshes"][asset.mesh_index()]["extras"]["morphkitBake"].is_null() {
        return Err(IoError::content(
            asset.path(),
            "the mesh is already baked (mesh.extras.morphkitBake): its targets include \
                 baked shapes; bake the rig it was made from",
        ));
    }
    asset.check_room(0)
}

/// Adds `baked`'s shapes to the chosen mesh of `asset` (see the [module documentation](self)): the
/// in-betweens of slider `NAME` at weight `w < 1` as targets `NAME@w`, the combination of
/// sliders `A` and `B` at level `l` as `A+B@l` (names equal to existing targets replace
/// them), and the mapping as `mesh.extras.morphkitBake`. `baked` must be in the mesh's
/// layout (`#V` of the merged mesh), with one baked target per mesh target.
///
/// Errors: a mesh baked already, another count of targets or vertices, more targets than
/// [`GltfAsset::max_targets`], those of [`GltfAsset::add_targets`].
pub fn add_to_gltf(asset: &mut GltfAsset, baked: &BakedRig) -> Result<(), IoError> {
    check_gltf(asset)?;
    let sliders = asset.morphs().target_names.clone();
    let nv = asset.morphs().base.num_vertices();
    if baked.targets.len() != sliders.len() || baked.base.len() != nv {
        return Err(IoError::content(
            asset.path(),
            format!(
                "the bake has {} targets of {} vertices, the mesh {} of {nv}",
                baked.targets.len(),
                baked.base.len(),
                sliders.len()
            ),
        ));
    }
    let base = asset.morphs().base.positions.clone();
    // Displacements under 1e-8 of the diagonal (a solve's far field, where the shape does not
    // act) are stored as 0, so that local shapes are stored sparsely: a few 1e-8 of the
    // diagonal at most in any evaluation.
    let floor = 1e-8 * asset.morphs().base.bbox_diagonal();
    let absolute = |d: &[Point]| -> Vec<Point> {
        base.iter()
            .zip(d)
            .map(|(b, p)| {
                if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() < floor {
                    *b
                } else {
                    [b[0] + p[0], b[1] + p[1], b[2] + p[2]]
                }
            })
            .collect()
    };
    let (mut names, mut shapes) = (Vec::new(), Vec::new());
    for (t, bt) in baked.targets.iter().enumerate() {
        for (w, d) in bt.weights.iter().zip(&bt.deltas) {
            if *w != 1.0 {
                names.push(format!("{}@{}", sliders[t], short(*w)));
                shapes.push(absolute(d));
            }
        }
    }
    for c in &baked.combinations {
        let (a, b) = c.targets;
        for (l, d) in c.shape.weights.iter().zip(&c.shape.deltas) {
            names.push(format!("{}+{}@{}", sliders[a], sliders[b], short(*l)));
            shapes.push(absolute(d));
        }
    }
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) || !is_valid_target_name(n) {
            return Err(IoError::content(
                    asset.path(),
                    format!("the baked shape name '{n}' is not unique or not a valid name; rename the targets"),
                ));
        }
    }
    // Most in-betweens and combinations move a part of the mesh: sparse where smaller.
    asset.set_sparse_targets(true);
    let added = asset.add_targets(&names, &shapes);
    asset.set_sparse_targets(false);
    added?;
    let index = |n: &String| {
        asset
            .morphs()
            .target_names
            .iter()
            .position(|t| t == n)
            .expect("an added target")
    };
    let at: Vec<usize> = names.iter().map(index).collect();
    let mut next = at.iter();
    let mut inbetweens = Vec::new();
    for (t, bt) in baked.targets.iter().enumerate() {
        let targets: Vec<usize> = bt
            .weights
            .iter()
            .map(|w| {
                if *w == 1.0 {
                    t
                } else {
                    *next.next().expect("a target")
                }
            })
            .collect();
        inbetweens.push(json!({"slider": t, "weights": bt.weights, "targets": targets}));
    }
    let combinations: Vec<_> = baked
            .combinations
            .iter()
            .map(|c| {
                let targets: Vec<usize> = c.shape.weights.iter().map(|_| *next.next().expect("a target")).collect();
                json!({"sliders": [c.targets.0, c.targets.1], "levels": c.shape.weights, "targets": targets})
            })
            .collect();
    let mapping = json!({
        "version": 1,
        "sliders": sliders,
        "damping": baked.damping,
        "inbetweens": inbetweens,
        "combinations": combinations,
    });
    asset.set_mesh_extra("morphkitBake", mapping)
}
