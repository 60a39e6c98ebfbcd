//! A user's glTF rig in Python: [`read_rig`] gives its base, targets, names and a weights
//! animation as arrays; [`write_rig`] and `write_animation(..., template=...)` write new
//! targets or a frame animation into that same asset ([`morphkit::io::GltfAsset`]), so its
//! materials, textures, skins, other meshes, nodes and transforms come back untouched.

use crate::arrays::{self, faces_to_array, to_array, to_array3};
use crate::errors::{new_err, IntoPyResult, Kind};
use morphkit::io::{GltfAsset, GltfAssetOptions, GltfReadOptions};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// Reads the asset at `template` with the mesh `mesh` chosen (or the rule of [`read_rig`]).
pub(crate) fn read_asset(
    py: Python<'_>,
    template: &Path,
    mesh: Option<String>,
) -> PyResult<GltfAsset> {
    let opts = GltfReadOptions { mesh };
    py.detach(|| GltfAsset::read(template, &opts))
        .py(Kind::File)
}

/// Reads a glTF/GLB rig and returns a dict:
///
/// - `base` `(n, 3) float64` and `faces` `(m, 3) int64`: the mesh with morph targets (all its
///   primitives merged, in the mesh's own space, node transforms not applied);
/// - `targets` `(k, n, 3)` absolute positions and `names` (`k` strings);
/// - `times` `(K,)` seconds and `weights` `(K, k)`: the keys of the weights animation
///   `animation` (by name; the only one when `None`; empty arrays when the file has none);
/// - `animation` (its name or `None`) and `animations` (the names of every animation that
///   drives the mesh, `None` for unnamed ones).
///
/// `mesh` chooses a mesh by name when several carry morph targets (the error lists them).
///
/// >>> rig = morphkit.read_rig("face.glb", animation="talk")
/// >>> frames = morphkit.PhysicalBlend(rig["base"], rig["targets"], rig["faces"]).solve_many(rig["weights"])
#[pyfunction]
#[pyo3(signature = (path, mesh=None, animation=None))]
pub fn read_rig<'py>(
    py: Python<'py>,
    path: PathBuf,
    mesh: Option<String>,
    animation: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let asset = read_asset(py, &path, mesh)?;
    let m = asset.morphs();
    let n = m.base.num_vertices();
    let k = m.targets.len();
    let chosen = asset
        .weight_animation(animation.as_deref())
        .py(Kind::File)?;
    let keys: &[(f64, Vec<f64>)] = chosen.map_or(&[], |a| a.keys.as_slice());
    let times: Vec<f64> = keys.iter().map(|(t, _)| *t).collect();
    let weights = PyArray2::from_vec2(py, &keys.iter().map(|(_, w)| w.clone()).collect::<Vec<_>>())
        .map_err(|e| new_err(Kind::File, format!("{}: {e}", path.display())))?;
    let weights = if keys.is_empty() {
        numpy::PyArray2::<f64>::zeros(py, [0, k], false)
    } else {
        weights
    };
    let d = PyDict::new(py);
    d.set_item("base", to_array(py, &m.base.positions))?;
    d.set_item("faces", faces_to_array(py, &m.base.triangles))?;
    d.set_item("targets", to_array3(py, &m.targets, n))?;
    d.set_item("names", m.target_names.clone())?;
    d.set_item("times", numpy::PyArray1::from_vec(py, times))?;
    d.set_item("weights", weights)?;
    d.set_item("animation", chosen.and_then(|a| a.name.clone()))?;
    d.set_item(
        "animations",
        asset
            .weight_animations()
            .iter()
            .map(|a| a.name.clone())
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// Writes the asset `template` (a `.glb`/`.gltf`) to `path` with morph targets added to its
/// mesh: `targets` `(k, n, 3)` absolute positions in the mesh's own space, named `names`
/// (by the CLI's rule: not empty, `.` or `..`, no `/`, `\` or NUL); a name the mesh already
/// has replaces that target. `path` is a `.glb` or `.gltf`. `base` `(n, 3)` gives the mesh new base
/// positions first (existing targets keep their displacements). Everything else in the asset
/// is kept. `max_targets` (default 200, what WebGL2 viewers play; 0 for no limit) refuses a
/// mesh that would get more targets. The write is atomic; `template` is never overwritten.
///
/// >>> morphkit.write_rig("head-rig.glb", "head.glb", shapes, names)
#[pyfunction]
#[pyo3(signature = (path, template, targets, names, base=None, mesh=None, max_targets=morphkit::io::SAFE_MORPH_TARGETS))]
#[allow(clippy::too_many_arguments)]
pub fn write_rig(
    py: Python<'_>,
    path: PathBuf,
    template: PathBuf,
    targets: &Bound<'_, PyAny>,
    names: Vec<String>,
    base: Option<&Bound<'_, PyAny>>,
    mesh: Option<String>,
    max_targets: usize,
) -> PyResult<()> {
    let mut asset = read_asset(py, &template, mesh)?;
    asset.set_max_targets(max_targets);
    let n = asset.morphs().base.num_vertices();
    let targets = arrays::frames("targets", targets, Some(n))?;
    if names.len() != targets.len() {
        return Err(new_err(
            Kind::Mesh,
            format!("names: {} names for {} targets", names.len(), targets.len()),
        ));
    }
    let base = match base {
        Some(b) => {
            let p = arrays::points("base", b)?;
            if p.len() != n {
                return Err(new_err(
                    Kind::Mesh,
                    format!("base: {} points, the mesh has {n} vertices", p.len()),
                ));
            }
            Some(p)
        }
        None => None,
    };
    py.detach(|| {
        if let Some(b) = &base {
            asset.set_base(b)?;
        }
        asset.add_targets(&names, &targets)?;
        asset.write(&path, &GltfAssetOptions::default())
    })
    .py(Kind::File)
}

/// `write_animation(..., template=...)`: the frames as a physical animation added to the asset.
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_animation_into(
    py: Python<'_>,
    path: &Path,
    template: &Path,
    frames: Vec<Vec<morphkit::mesh::Point>>,
    fps: f64,
    times: Option<Vec<f64>>,
    clip: Option<String>,
    mesh: Option<String>,
    max_targets: usize,
) -> PyResult<()> {
    let mut asset = read_asset(py, template, mesh)?;
    asset.set_max_targets(max_targets);
    let n = asset.morphs().base.num_vertices();
    if let Some((k, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != n) {
        return Err(new_err(
            Kind::Mesh,
            format!(
                "frames[{k}]: {} points, the template's mesh has {n} vertices",
                f.len()
            ),
        ));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "fps: {fps} is not a positive number"
        )));
    }
    let times = times.unwrap_or_else(|| (0..frames.len()).map(|k| k as f64 / fps).collect());
    let clip = clip.unwrap_or_else(|| "morphkit".into());
    py.detach(|| {
        asset.add_frame_animation(&clip, &times, &frames)?;
        asset.write(path, &GltfAssetOptions::default())
    })
    .py(Kind::File)
}
