//! Shape sets and animations made of several meshes: reading frame sequences and rigs, writing
//! numbered OBJ frames, glTF morph animations, PC2 caches and USD layers.

use super::atomic::temp_sibling;
use super::format::Format;
use super::gltf::{
    choose_layout, read_gltf_morphs, write_compact_frames_with, write_gltf_with, GltfMorphs,
    GltfOptions, Layout,
};
use super::pc2::{parse_pc2, write_pc2, PointCache};
use super::staging::commit_dir;
use super::temporaries;
use super::usd::{read_usd_animation, write_usd_animation, UsdOptions};
use super::{check_not_input, obj, read_mesh, source::read_file, IoError};
use crate::mesh::{ShapeSet, ShapeSetError};
use std::path::{Path, PathBuf};

/// Options of [`write_frames`].
#[derive(Clone, Debug)]
pub struct FramesOptions {
    /// Frames per second of a glTF animation (frame `i` is keyed at `i / fps` seconds); must be
    /// positive. Default 24. Not stored in OBJ frames or PC2 caches.
    pub fps: f64,
    /// Input files; the output must not be one of them (nor a directory holding one).
    pub inputs: Vec<PathBuf>,
    /// How a `.glb` / `.gltf` output is written (names, normals, material, target limit,
    /// extras). Default [`GltfOptions::default`].
    pub gltf: GltfOptions,
    /// How a `.usda` output is written (prim name, up axis, units, custom data). Default
    /// [`UsdOptions::default`].
    pub usd: UsdOptions,
    /// The artist's own OBJ that a frame directory's frames are written into, every record
    /// kept ([`super::ObjTemplate`]); `None` (the default) or one of another vertex count
    /// writes plain `v`/`f` frames.
    pub obj_template: Option<super::ObjTemplate>,
}

impl Default for FramesOptions {
    fn default() -> Self {
        Self {
            fps: 24.0,
            inputs: Vec::new(),
            gltf: GltfOptions::default(),
            usd: UsdOptions::default(),
            obj_template: None,
        }
    }
}

/// A shape name without a mesh file extension (`.obj`, `.obj.gz`, `.ply`, `.off`, `.glb`,
/// `.gltf`, `.usda`, `.pc2`): `f00000.obj` → `f00000`. Other names are kept.
pub fn shape_name(name: &str) -> &str {
    let lower = name.to_ascii_lowercase();
    for ext in [
        ".obj.gz", ".obj", ".ply", ".off", ".glb", ".gltf", ".usda", ".pc2",
    ] {
        if lower.ends_with(ext) && name.len() > ext.len() {
            return &name[..name.len() - ext.len()];
        }
    }
    name
}

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Reads meshes that share one connectivity; shape names are the file names, shape 0 is the
/// first file. A mismatch is an [`IoError::ShapeSet`] naming the offending file's path and the
/// first differing triangle (or the differing counts).
pub fn read_shape_set(paths: &[PathBuf]) -> Result<ShapeSet, IoError> {
    read_shape_set_with(paths, |_, _| {})
}

/// Like [`read_shape_set`], calling `on_file(i, path)` after file `i` is read (for progress).
pub fn read_shape_set_with(
    paths: &[PathBuf],
    mut on_file: impl FnMut(usize, &Path),
) -> Result<ShapeSet, IoError> {
    let Some(first) = paths.first() else {
        return Err(IoError::ShapeSet {
            path: PathBuf::new(),
            cause: ShapeSetError::Empty,
        });
    };
    let base = read_mesh(first)?;
    on_file(0, first);
    let mut set = ShapeSet::from_meshes(vec![(file_name(first), base)]).map_err(|source| {
        IoError::ShapeSet {
            path: first.clone(),
            cause: source,
        }
    })?;
    for (i, p) in paths.iter().enumerate().skip(1) {
        let m = read_mesh(p)?;
        let wrap = |source| IoError::ShapeSet {
            path: p.clone(),
            cause: source,
        };
        set.check_connectivity(&p.display().to_string(), &m)
            .map_err(wrap)?;
        set.push(file_name(p), m.positions).map_err(wrap)?;
        on_file(i, p);
    }
    Ok(set)
}

/// The `.obj` and `.obj.gz` files of a directory, sorted by name with frame numbers compared
/// as numbers ([`super::sort_frame_paths`]: `anim2.obj` before `anim10.obj`): the frames a
/// directory argument stands for. An empty list is an [`IoError::Content`] error naming the directory.
pub fn obj_files(dir: &Path) -> Result<Vec<PathBuf>, IoError> {
    let entries = std::fs::read_dir(dir).map_err(|e| IoError::os(dir, "list the directory", e))?;
    let mut files = Vec::new();
    for e in entries {
        let p = e
            .map_err(|e| IoError::os(dir, "list the directory", e))?
            .path();
        if p.is_file() && matches!(Format::from_path(&p), Some(Format::Obj { .. })) {
            files.push(p);
        }
    }
    super::sort_frame_paths(&mut files);
    if files.is_empty() {
        return Err(IoError::content(
            dir,
            "the directory holds no .obj or .obj.gz files",
        ));
    }
    Ok(files)
}

/// The frames of a glTF rig: one per weight key (base + Σ wᵢ Δᵢ; named after the target when
/// the key is one-hot, else `frame_NNNN`), or, without an animation, the base (named `base`)
/// followed by each target.
pub fn gltf_to_frames(path: &Path, m: &GltfMorphs) -> Result<ShapeSet, IoError> {
    let shapes: Vec<(String, Vec<crate::mesh::Point>)> = if m.weight_keys.is_empty() {
        std::iter::once(("base".to_string(), m.base.positions.clone()))
            .chain(
                m.target_names
                    .iter()
                    .cloned()
                    .zip(m.targets.iter().cloned()),
            )
            .collect()
    } else {
        m.weight_keys
            .iter()
            .enumerate()
            .map(|(k, (_, w))| {
                let ones: Vec<usize> = (0..w.len()).filter(|&i| w[i] != 0.0).collect();
                let name = match ones.as_slice() {
                    [i] if w[*i] == 1.0 => m.target_names[*i].clone(),
                    _ => format!("frame_{k:04}"),
                };
                (name, m.evaluate(w))
            })
            .collect()
    };
    ShapeSet::new(m.base.clone(), shapes).map_err(|source| IoError::ShapeSet {
        path: path.to_path_buf(),
        cause: source,
    })
}

/// The glTF rig that plays `frames`: the base is frame 0 itself (its positions over shape 0's
/// connectivity), every later frame that differs from it is one morph target named after the
/// frame (without a mesh file extension, see [`shape_name`]), and key `i` at `i / fps` seconds
/// has one nonzero weight, 1 on frame `i`'s target (none for frame 0 and frames equal to it),
/// so playing the keys with `LINEAR` interpolation interpolates the frames' positions.
pub fn frames_to_gltf(frames: &ShapeSet, fps: f64) -> GltfMorphs {
    let n = frames.len();
    let first = frames.positions(0);
    let mut target_names = Vec::new();
    let mut targets = Vec::new();
    let mut target_of = vec![None; n];
    for i in 1..n {
        if frames.positions(i) != first {
            target_of[i] = Some(targets.len());
            target_names.push(shape_name(frames.name(i)).to_string());
            targets.push(frames.positions(i).to_vec());
        }
    }
    let nt = targets.len();
    let weight_keys = if nt == 0 {
        Vec::new()
    } else {
        (0..n)
            .map(|i| {
                let mut w = vec![0.0; nt];
                if let Some(t) = target_of[i] {
                    w[t] = 1.0;
                }
                (i as f64 / fps, w)
            })
            .collect()
    };
    GltfMorphs {
        base: frames.base().with_positions(first.to_vec()),
        target_names,
        targets,
        weight_keys,
    }
}

/// Reads an animation or a rig as a [`ShapeSet`]:
/// - a directory: its `*.obj` / `*.obj.gz` files in frame order ([`obj_files`]);
/// - `.glb` / `.gltf`: see [`gltf_to_frames`];
/// - `.usda`: one shape per `points` time sample (`frame_NNNN`), see [`read_usd_animation`];
/// - `.pc2`: one shape per sample (`frame_NNNN`) over `reference`'s connectivity, which is
///   required ([`IoError::NeedsReference`]) and must have as many vertices as the cache points;
/// - a single OBJ/PLY/OFF mesh: a set of one shape.
pub fn read_animation(path: &Path, reference: Option<&Path>) -> Result<ShapeSet, IoError> {
    if path.is_dir() {
        return read_shape_set(&obj_files(path)?);
    }
    match Format::from_path(path) {
        Some(Format::Gltf | Format::Glb) => gltf_to_frames(path, &read_gltf_morphs(path)?),
        Some(Format::Usda) => {
            let a = read_usd_animation(path)?;
            crate::mesh::validate(&a.mesh).map_err(|cause| IoError::InvalidMesh {
                path: path.to_path_buf(),
                cause,
            })?;
            let shapes = a
                .samples
                .into_iter()
                .enumerate()
                .map(|(i, (_, s))| (format!("frame_{i:04}"), s))
                .collect();
            ShapeSet::new(a.mesh, shapes).map_err(|source| IoError::ShapeSet {
                path: path.to_path_buf(),
                cause: source,
            })
        }
        Some(Format::Pc2) => {
            let reference = reference.ok_or_else(|| IoError::NeedsReference {
                path: path.to_path_buf(),
            })?;
            let mesh = read_mesh(reference)?;
            let cache = parse_pc2(path, &read_file(path)?)?;
            let np = cache.samples.first().map_or(0, Vec::len);
            if cache.samples.is_empty() {
                return Err(IoError::content(path, "the point cache has no samples"));
            }
            if np != mesh.num_vertices() {
                return Err(IoError::content(
                    path,
                    format!(
                        "the cache has {np} points, the reference {} has {} vertices",
                        reference.display(),
                        mesh.num_vertices()
                    ),
                ));
            }
            let shapes = cache
                .samples
                .into_iter()
                .enumerate()
                .map(|(i, s)| (format!("frame_{i:04}"), s))
                .collect();
            ShapeSet::new(mesh, shapes).map_err(|source| IoError::ShapeSet {
                path: path.to_path_buf(),
                cause: source,
            })
        }
        _ => read_shape_set(&[path.to_path_buf()]),
    }
}

/// True when `out` names a frame directory: an existing directory, or a path without extension.
fn is_frame_dir(out: &Path) -> bool {
    out.is_dir() || (!out.exists() && out.extension().is_none())
}

/// Writes an animation; see [`write_frames_with`].
pub fn write_frames(out: &Path, frames: &ShapeSet, opts: &FramesOptions) -> Result<(), IoError> {
    write_frames_with(out, frames, opts, |_| {})
}

/// Writes `frames` to `out`, calling `on_frame(i)` after each OBJ frame file:
/// - a directory (existing, or a path without extension, created): `frame_0000.obj`, … one
///   per shape. All frames are first written into a fresh temporary sibling directory
///   (`.NAME.PID-N.frames.tmp`); only when every frame succeeded are they moved into `out`
///   (a new `out` is the renamed temporary directory), and `frame_*.obj` files left in `out`
///   by an earlier, longer sequence are then removed. Other files in `out` are never touched.
///   A failure while writing removes only the temporary directory: no file that existed before
///   the call is changed or deleted;
/// - `.glb` / `.gltf`: laid out as `opts.gltf.layout` chooses ([`choose_layout`]): one target
///   per frame ([`frames_to_gltf`] at `opts.fps`, written with [`write_gltf_with`]) or a
///   compact clip ([`write_compact_frames_with`]), with `opts.gltf`;
/// - `.pc2`: one sample per shape, start frame 0, one frame per sample;
/// - `.usda`: [`write_usd_animation`] at `opts.fps` with `opts.usd`.
///
/// Fails before writing anything when `out` is an input ([`check_not_input`]) or `fps` is not
/// positive.
pub fn write_frames_with(
    out: &Path,
    frames: &ShapeSet,
    opts: &FramesOptions,
    mut on_frame: impl FnMut(usize),
) -> Result<(), IoError> {
    check_not_input(out, &opts.inputs)?;
    if !(opts.fps.is_finite() && opts.fps > 0.0) {
        return Err(IoError::content(
            out,
            format!("frame rate {} is not positive", opts.fps),
        ));
    }
    if is_frame_dir(out) {
        let template = opts
            .obj_template
            .as_ref()
            .filter(|t| t.num_vertices() == frames.num_vertices());
        return write_frame_dir(out, frames, template, &mut on_frame);
    }
    match Format::from_path(out) {
        Some(Format::Glb | Format::Gltf) => match choose_layout(frames, opts.fps, &opts.gltf) {
            Layout::Compact(c, _) => write_compact_frames_with(out, &c, &opts.gltf).map(|_| ()),
            Layout::PerFrame(_) => {
                write_gltf_with(out, &frames_to_gltf(frames, opts.fps), &opts.gltf).map(|_| ())
            }
        },
        Some(Format::Usda) => write_usd_animation(
            out,
            frames.base(),
            frames.all_positions(),
            opts.fps,
            &opts.usd,
        ),
        Some(Format::Pc2) => write_pc2(
            out,
            &PointCache {
                start_frame: 0.0,
                sample_rate: 1.0,
                samples: frames.all_positions().to_vec(),
            },
        ),
        _ => Err(IoError::UnknownFormat {
            path: out.to_path_buf(),
            expected: "a directory, .glb, .gltf, .pc2 or .usda for an animation",
        }),
    }
}

/// The directory case of [`write_frames_with`].
fn write_frame_dir(
    out: &Path,
    frames: &ShapeSet,
    template: Option<&super::ObjTemplate>,
    on_frame: &mut dyn FnMut(usize),
) -> Result<(), IoError> {
    let existed = out.exists();
    if !existed {
        if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)
                .map_err(|e| IoError::os(out, "create the parent directory", e))?;
        }
    }
    let tmp = temp_sibling(out, "frames.tmp");
    temporaries::record(&tmp, true);
    if let Err(e) = std::fs::create_dir(&tmp) {
        temporaries::forget(&tmp);
        return Err(IoError::os(
            out,
            "create a temporary directory next to it",
            e,
        ));
    }
    let names: Vec<String> = (0..frames.len())
        .map(|i| format!("frame_{i:04}.obj"))
        .collect();
    for (i, name) in names.iter().enumerate() {
        let written = match template {
            Some(t) => t.write(&tmp.join(name), frames.positions(i), false),
            None => obj::write_obj(&tmp.join(name), &frames.mesh(i), false),
        };
        if let Err(e) = written {
            let _ = std::fs::remove_dir_all(&tmp);
            temporaries::forget(&tmp);
            return Err(match e {
                // Name the destination frame, not the temporary file.
                IoError::Content { message, .. } => IoError::content(&out.join(name), message),
                e => e,
            });
        }
        on_frame(i);
    }
    // A new `out` is the renamed temporary directory; an existing one receives its frames.
    let r = commit_dir(&tmp, out);
    temporaries::forget(&tmp);
    r
}
