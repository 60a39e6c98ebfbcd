//! File formats, recognised by extension (case-insensitive; `.gz` only after `.obj`).

use super::IoError;
use std::path::Path;

/// A file format morphkit reads or writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ; `gzip` for `.obj.gz`.
    Obj {
        /// True for `.obj.gz`.
        gzip: bool,
    },
    /// Stanford PLY (ascii or binary).
    Ply,
    /// Object File Format.
    Off,
    /// glTF 2.0 JSON.
    Gltf,
    /// Binary glTF 2.0.
    Glb,
    /// Point cache (Blender's Mesh Cache modifier, 3ds Max).
    Pc2,
    /// USD text layer (`.usda`): a mesh with time-sampled points.
    Usda,
}

impl Format {
    /// The format named by `path`'s extension, if any.
    pub fn from_path(path: &Path) -> Option<Format> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let (stem, ext) = name.rsplit_once('.')?;
        Some(match ext {
            "obj" => Format::Obj { gzip: false },
            "gz" if stem.ends_with(".obj") => Format::Obj { gzip: true },
            "ply" => Format::Ply,
            "off" => Format::Off,
            "gltf" => Format::Gltf,
            "glb" => Format::Glb,
            "pc2" => Format::Pc2,
            "usda" => Format::Usda,
            _ => return None,
        })
    }

    /// True for formats that hold one mesh (OBJ, PLY, OFF).
    pub fn is_single_mesh(self) -> bool {
        matches!(self, Format::Obj { .. } | Format::Ply | Format::Off)
    }

    /// True for formats that hold a whole animation (glTF, GLB, PC2, USDA).
    pub fn is_animation(self) -> bool {
        matches!(
            self,
            Format::Gltf | Format::Glb | Format::Pc2 | Format::Usda
        )
    }
}

/// The mesh format of `path`, or an error naming the accepted extensions.
pub(crate) fn mesh_format(path: &Path, expected: &'static str) -> Result<Format, IoError> {
    match Format::from_path(path) {
        Some(f) if f != Format::Pc2 => Ok(f),
        _ => Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
            expected,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognises_extensions() {
        let f = |s: &str| Format::from_path(Path::new(s));
        assert_eq!(f("a/b.OBJ"), Some(Format::Obj { gzip: false }));
        assert_eq!(f("b.obj.gz"), Some(Format::Obj { gzip: true }));
        assert_eq!(f("b.tar.gz"), None);
        assert_eq!(f("x.glb"), Some(Format::Glb));
        assert_eq!(f("x.pc2"), Some(Format::Pc2));
        assert_eq!(f("x.USDA"), Some(Format::Usda));
        assert_eq!(f("frames"), None);
    }
}
