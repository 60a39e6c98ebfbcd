//! File I/O: meshes, glTF morph targets and animations, through the library's readers and
//! writers (atomic writes; an input is never overwritten).

use crate::arrays::{self, faces_to_array, to_array, to_array3};
use crate::errors::{IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::io::{self as mio, FramesOptions, GltfMorphs};
use morphkit::mesh::ShapeSet;
use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use std::path::PathBuf;

type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// Reads one mesh (`.obj`, `.obj.gz`, `.ply`, `.off`, `.gltf`, `.glb`) and returns `(V, F)`:
/// `V` `(n, 3) float64`, `F` `(m, 3) int64` (polygons fan-triangulated).
///
/// >>> V, F = morphkit.read("horse.obj")
#[pyfunction]
pub fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<MeshArrays<'py>> {
    let mesh = py.detach(|| mio::read_mesh(&path)).py(Kind::File)?;
    Ok((
        to_array(py, &mesh.positions),
        faces_to_array(py, &mesh.triangles),
    ))
}

/// Writes `(V, F)` atomically; the format follows the extension (`.obj`, `.obj.gz`, `.ply`,
/// `.off`, `.glb`, `.gltf`).
///
/// >>> morphkit.write("out.ply", V, F)
#[pyfunction]
pub fn write(
    py: Python<'_>,
    path: PathBuf,
    v: &Bound<'_, PyAny>,
    f: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mesh = from_arrays("mesh", v, f)?;
    py.detach(|| mio::write_mesh(&path, &mesh)).py(Kind::File)
}

/// Reads a glTF/GLB file's first mesh with its morph targets and returns
/// `(V, F, targets, names)`: `targets` `(k, n, 3)` absolute positions, `names` a list of `k`
/// strings (`target_0`, … when the file gives none).
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn read_morphs<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray3<f64>>,
    Vec<String>,
)> {
    let m = py.detach(|| mio::read_gltf_morphs(&path)).py(Kind::File)?;
    let n = m.base.num_vertices();
    Ok((
        to_array(py, &m.base.positions),
        faces_to_array(py, &m.base.triangles),
        to_array3(py, &m.targets, n),
        m.target_names,
    ))
}

/// Writes a glTF/GLB file with the base mesh `(V, F)` and one morph target per row of
/// `targets` `(k, n, 3)` (absolute positions), named by `names` (default `target_0`, …).
#[pyfunction]
#[pyo3(signature = (path, v, f, targets, names=None))]
pub fn write_morphs(
    py: Python<'_>,
    path: PathBuf,
    v: &Bound<'_, PyAny>,
    f: &Bound<'_, PyAny>,
    targets: &Bound<'_, PyAny>,
    names: Option<Vec<String>>,
) -> PyResult<()> {
    let base = from_arrays("base", v, f)?;
    let targets = arrays::frames("targets", targets, Some(base.num_vertices()))?;
    let names = match names {
        Some(n) if n.len() != targets.len() => {
            return Err(crate::errors::new_err(
                Kind::Mesh,
                format!("names: {} names for {} targets", n.len(), targets.len()),
            ))
        }
        Some(n) => n,
        None => (0..targets.len()).map(|i| format!("target_{i}")).collect(),
    };
    let morphs = GltfMorphs {
        base,
        target_names: names,
        targets,
        weight_keys: Vec::new(),
    };
    py.detach(|| mio::write_gltf_morphs(&path, &morphs))
        .py(Kind::File)
}

/// Reads an animation and returns `(frames, F, names)`: `frames` `(k, n, 3)`. `path` is a
/// directory of OBJ frames, a glTF/GLB with a morph-weight animation (one frame per key), a
/// PC2 cache (needs `reference`, a mesh file giving the connectivity) or a single mesh.
#[pyfunction]
#[pyo3(signature = (path, reference=None))]
#[allow(clippy::type_complexity)]
pub fn read_animation<'py>(
    py: Python<'py>,
    path: PathBuf,
    reference: Option<PathBuf>,
) -> PyResult<(
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray2<i64>>,
    Vec<String>,
)> {
    let set = py
        .detach(|| mio::read_animation(&path, reference.as_deref()))
        .py(Kind::File)?;
    Ok((
        to_array3(py, set.all_positions(), set.num_vertices()),
        faces_to_array(py, set.triangles()),
        set.names().to_vec(),
    ))
}

/// Writes `frames` `(k, n, 3)` over the connectivity `F`: a directory of numbered OBJ frames
/// (a path without extension), a `.glb`/`.gltf` morph-weight animation at `fps`, or a `.pc2`
/// cache.
///
/// With `template` (a `.glb`/`.gltf`, written to a `.glb`/`.gltf` `path`), the frames are added
/// to that asset instead: one morph target per frame on its mesh (`mesh` chooses it by name)
/// and an animation `clip` (default `morphkit`) keying them at `times` (default `k / fps`
/// seconds; glTF keys are not negative and increase); its materials, skins, other meshes and
/// nodes are kept, and `F` is not needed
/// (the template's). `max_targets` (default 200; 0 for no limit) refuses a mesh that would get
/// more targets than WebGL2 viewers play.
///
/// Without a template, a `.glb`/`.gltf` animation of more frames than `max_targets` is a
/// compact clip (a few morph targets at per-frame weights, every vertex of every frame within
/// `clip_tolerance` of the bounding-box diagonal, default 1e-3), as the CLI writes it;
/// `clip_tolerance` asks for one at any length, `per_frame_targets=True` keeps one target per
/// frame (split into meshes of at most `max_targets`). `quantize=True` stores a `.glb`/`.gltf`
/// animation as 16-bit positions and deltas (`KHR_mesh_quantization`, within 2.7e-5 of the
/// diagonal), `meshopt=True` compresses it losslessly (`EXT_meshopt_compression`), as the
/// CLI's `--quantize` and `--meshopt`; with a template both are refused (the asset keeps its
/// own encoding).
///
/// >>> morphkit.write_animation("physical.glb", frames, template="face.glb", clip="talk-physical")
#[pyfunction]
#[pyo3(signature = (path, frames, f=None, fps=24.0, template=None, clip=None, times=None, mesh=None, max_targets=mio::SAFE_MORPH_TARGETS, clip_tolerance=None, per_frame_targets=false, quantize=false, meshopt=false))]
#[allow(clippy::too_many_arguments)]
pub fn write_animation(
    py: Python<'_>,
    path: PathBuf,
    frames: &Bound<'_, PyAny>,
    f: Option<&Bound<'_, PyAny>>,
    fps: f64,
    template: Option<PathBuf>,
    clip: Option<String>,
    times: Option<Vec<f64>>,
    mesh: Option<String>,
    max_targets: usize,
    clip_tolerance: Option<f64>,
    per_frame_targets: bool,
    quantize: bool,
    meshopt: bool,
) -> PyResult<()> {
    let layout = match (per_frame_targets, clip_tolerance) {
        (true, Some(_)) => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "give clip_tolerance or per_frame_targets, not both",
            ))
        }
        (true, None) => mio::FrameLayout::PerFrame,
        (false, Some(t)) if t.is_finite() && t > 0.0 => mio::FrameLayout::Compact(t),
        (false, Some(t)) => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "clip_tolerance must be a finite positive fraction of the diagonal, not {t}"
            )))
        }
        (false, None) => mio::FrameLayout::Auto,
    };
    let frames = arrays::frames("frames", frames, None)?;
    if template.is_some() && (quantize || meshopt) {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "quantize and meshopt apply to an animation written whole; a template asset keeps \
             its own encoding (leave them out)",
        ));
    }
    if let Some(t) = template {
        return crate::rig_io::write_animation_into(
            py,
            &path,
            &t,
            frames,
            fps,
            times,
            clip,
            mesh,
            max_targets,
        );
    }
    let Some(f) = f else {
        return Err(crate::errors::new_err(
            Kind::Mesh,
            "f: the faces are needed unless a template asset gives them",
        ));
    };
    let Some(first) = frames.first() else {
        return Err(crate::errors::new_err(Kind::Mesh, "frames: no frames"));
    };
    let n = first.len();
    let v0 = to_array(py, first);
    let base = from_arrays("frames[0]", v0.as_any(), f)?;
    let named = frames
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("frame_{i:04}"), p.clone()))
        .collect();
    let set = ShapeSet::new(base, named).py(Kind::Mesh)?;
    debug_assert_eq!(set.num_vertices(), n);
    let mut opts = FramesOptions {
        fps,
        ..FramesOptions::default()
    };
    opts.gltf.max_targets = max_targets;
    opts.gltf.layout = layout;
    opts.gltf.quantize = quantize;
    opts.gltf.meshopt = meshopt;
    py.detach(|| mio::write_frames(&path, &set, &opts))
        .py(Kind::File)
}
