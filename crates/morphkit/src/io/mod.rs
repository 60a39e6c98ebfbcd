//! Mesh and animation files: OBJ (also `.obj.gz`), PLY, OFF, glTF/GLB, PC2 and USD text.
//!
//! | format | read | write | notes |
//! |---|---|---|---|
//! | OBJ | [`obj`] | [`obj`] | `v`/`f` only, polygons kept, full `f64` precision; `.obj.gz` both ways |
//! | PLY | [`ply`] | [`ply`] | ascii and binary; written binary little endian, optionally coloured; results of a PLY input written into it ([`PlyTemplate`]) |
//! | OFF | [`off`] | [`off`] | |
//! | glTF / GLB | [`gltf`] | [`gltf`] | the mesh with morph targets (or the first; choose by name with [`GltfReadOptions`]); quantized, meshopt and sparse accessors; morph-weight animations; a user's whole asset edited in place with [`GltfAsset`] |
//! | PC2 | [`pc2`] | [`pc2`] | positions only; connectivity from a reference mesh |
//! | USD (`.usda`) | [`usd`] (minimal) | [`usd`] | time-sampled `points`; `UsdSkel` blend shapes |
//! | weights | [`weights`] | | per-frame blend weights, JSON or CSV |
//!
//! Every read is validated once, on entry, with [`crate::mesh::validate`]: what it calls an
//! error becomes [`IoError::InvalidMesh`] naming the file, its warnings are returned by
//! [`read_mesh_with_report`]. Every write is atomic ([`write_atomic`]) and sequence writers never
//! overwrite an input ([`check_not_input`]); several outputs of one command are written all or
//! none ([`Staging`]). Text formats accept a UTF-8 byte-order mark ([`strip_bom`]). Every error
//! names the file.

mod atomic;
pub mod colors;
mod error;
mod format;
pub mod frame_order;
mod frame_stream;
pub mod gltf;
pub mod obj;
mod obj_template;
pub mod off;
pub mod pc2;
pub mod ply;
mod ply_template;
mod sequence;
mod source;
mod staging;
pub mod temporaries;
pub mod usd;
pub mod weights;

pub use atomic::{canonical_path, check_not_input, write_atomic};
pub use colors::{diverging, scalar_colors, viridis, Colors, NAN_GREY};
pub use error::IoError;
pub use format::Format;
pub use frame_order::{natural_cmp, sort_frame_paths};
pub use frame_stream::FrameStream;
pub use gltf::is_valid_target_name;
pub use gltf::{
    choose_layout, compact_frames, parse_gltf_morphs, parse_gltf_morphs_with, read_gltf_morphs,
    read_gltf_morphs_with, write_compact_frames_with, write_gltf_morphs, write_gltf_scene,
    write_gltf_scene_with, write_gltf_with, CompactEncoding, CompactFrames, FrameLayout, GltfAsset,
    GltfAssetOptions, GltfMorphs, GltfOptions, GltfReadOptions, GltfRigidMesh, GltfSummary,
    GltfWeightAnimation, Layout, MESHOPT_EXTENSION, SAFE_MORPH_TARGETS,
};
pub use obj_template::ObjTemplate;
pub use ply::{write_ply_colored, PlyEncoding};
pub use ply_template::PlyTemplate;
pub use sequence::{
    frames_to_gltf, gltf_to_frames, obj_files, read_animation, read_shape_set, read_shape_set_with,
    shape_name, write_frames, write_frames_with, FramesOptions,
};
pub use source::{strip_bom, strip_bom_str};
pub use staging::{frame_files, is_frame_file_name, Staging};
pub use temporaries::{remove_stale_for, remove_temporaries_then};
pub use usd::{
    read_usd_animation, write_usd_animation, write_usd_blendshape_rig, write_usd_blendshapes,
    UpAxis, UsdAnimation, UsdBlendShape, UsdOptions,
};
pub use weights::{
    parse_named_weights, parse_weights, read_named_weights, read_weights, WeightRow,
};

use crate::mesh::{validate, Point, TriMesh, ValidationReport};
use std::path::Path;

/// An input's own file that results are written into, every other record kept: an OBJ
/// ([`ObjTemplate`]) or a PLY ([`PlyTemplate`]).
#[derive(Clone, Debug)]
pub enum MeshTemplate {
    /// An `.obj` / `.obj.gz`.
    Obj(ObjTemplate),
    /// A `.ply` (boxed: it holds the file's parsed header beside its bytes).
    Ply(Box<PlyTemplate>),
}

impl MeshTemplate {
    /// `path` as a template when it is an OBJ or a PLY (by extension), else `None`.
    pub fn read(path: &Path) -> Result<Option<Self>, IoError> {
        Ok(match Format::from_path(path) {
            Some(Format::Obj { .. }) => Some(Self::Obj(ObjTemplate::read(path)?)),
            Some(Format::Ply) => Some(Self::Ply(Box::new(PlyTemplate::read(path)?))),
            _ => None,
        })
    }

    /// The number of vertices the template holds.
    pub fn num_vertices(&self) -> usize {
        match self {
            Self::Obj(t) => t.num_vertices(),
            Self::Ply(t) => t.num_vertices(),
        }
    }

    /// The OBJ template (what frame directories, made of OBJ files, are written into).
    pub fn into_obj(self) -> Option<ObjTemplate> {
        match self {
            Self::Obj(t) => Some(t),
            Self::Ply(_) => None,
        }
    }

    /// Whether an output at `out` is written into the template: it has the template's format
    /// (`.obj`/`.obj.gz` for an OBJ, `.ply` for a PLY).
    pub fn fits(&self, out: &Path) -> bool {
        matches!(
            (self, Format::from_path(out)),
            (Self::Obj(_), Some(Format::Obj { .. })) | (Self::Ply(_), Some(Format::Ply))
        )
    }

    /// Writes `positions` into the template at `out`, atomically; an `out` the template does
    /// not [fit](MeshTemplate::fits) is an [`IoError::UnknownFormat`] error.
    pub fn write(&self, out: &Path, positions: &[Point]) -> Result<(), IoError> {
        match (self, Format::from_path(out)) {
            (Self::Obj(t), Some(Format::Obj { gzip })) => t.write(out, positions, gzip),
            (Self::Ply(t), Some(Format::Ply)) => t.write(out, positions),
            (Self::Obj(_), _) => Err(IoError::UnknownFormat {
                path: out.to_path_buf(),
                expected: ".obj or .obj.gz, the template's format",
            }),
            (Self::Ply(_), _) => Err(IoError::UnknownFormat {
                path: out.to_path_buf(),
                expected: ".ply, the template's format",
            }),
        }
    }
}

const MESH_FORMATS: &str = ".obj, .obj.gz, .ply, .off, .gltf, .glb or .usda";

/// Reads one mesh, choosing the format by extension (`.obj`, `.obj.gz`, `.ply`, `.off`,
/// `.gltf`, `.glb`, `.usda`; for glTF the first mesh's base positions, for USD the first
/// sample), and validates it. Validation
/// warnings are dropped; see [`read_mesh_with_report`].
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    read_mesh_with_report(path).map(|(m, _)| m)
}

/// Like [`read_mesh`], also returning the validation warnings (degenerate or duplicate
/// triangles, coincident or isolated vertices).
pub fn read_mesh_with_report(path: &Path) -> Result<(TriMesh, ValidationReport), IoError> {
    read_mesh_with(path, &GltfReadOptions::default())
}

/// [`read_mesh_with_report`] choosing the mesh of a glTF file with `gltf`
/// ([`GltfReadOptions::mesh`]); other formats ignore it.
pub fn read_mesh_with(
    path: &Path,
    gltf: &GltfReadOptions,
) -> Result<(TriMesh, ValidationReport), IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let mesh = match format::mesh_format(path, MESH_FORMATS)? {
        Format::Obj { .. } => obj::read_obj(path)?,
        Format::Ply => ply::parse_ply(path, &source::read_file(path)?)?,
        Format::Off => off::parse_off(path, &source::read_file(path)?)?,
        Format::Gltf | Format::Glb => read_gltf_morphs_with(path, gltf)?.base,
        Format::Usda => read_usd_animation(path)?.mesh,
        Format::Pc2 => {
            return Err(IoError::NeedsReference {
                path: path.to_path_buf(),
            })
        }
    };
    let report = validate(&mesh).map_err(|source| IoError::InvalidMesh {
        path: path.to_path_buf(),
        cause: source,
    })?;
    Ok((mesh, report))
}

/// Writes one mesh atomically, choosing the format by extension: `.obj` / `.obj.gz` and `.off`
/// (original polygons when the mesh has them), `.ply` (binary little endian), `.glb` / `.gltf`
/// (triangles, no morph targets), `.usda` (a static `Mesh`).
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), IoError> {
    match format::mesh_format(path, MESH_FORMATS)? {
        Format::Obj { gzip } => obj::write_obj(path, mesh, gzip),
        Format::Ply => ply::write_ply(path, mesh, PlyEncoding::default()),
        Format::Off => off::write_off(path, mesh),
        Format::Gltf | Format::Glb => write_gltf_morphs(
            path,
            &GltfMorphs {
                base: mesh.clone(),
                ..GltfMorphs::default()
            },
        ),
        Format::Usda => write_usd_animation(
            path,
            mesh,
            std::slice::from_ref(&mesh.positions),
            24.0,
            &UsdOptions::default(),
        ),
        Format::Pc2 => Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
            expected: MESH_FORMATS,
        }),
    }
}
