//! Checks made on the glTF JSON before the `gltf` crate sees it, for inputs on which that crate
//! panics instead of returning an error.
//!
//! `gltf-json` 1.4 validates a primitive's `POSITION` accessor by indexing the accessor array
//! before checking that the index is in range, so a `POSITION` naming a missing accessor
//! panics (found by `cargo fuzz`). This reads only the accessor count and the primitives'
//! `POSITION` indices (other values are skipped, not copied) and reports such an index as an
//! error naming the mesh and primitive. A document this cannot read is left to the `gltf`
//! crate, which reports it.

use crate::io::IoError;
use serde::de::IgnoredAny;
use serde::Deserialize;
use std::path::Path;

#[derive(Deserialize)]
struct Doc {
    #[serde(default)]
    accessors: Vec<IgnoredAny>,
    #[serde(default)]
    meshes: Vec<Mesh>,
}

#[derive(Deserialize)]
struct Mesh {
    #[serde(default)]
    primitives: Vec<Primitive>,
}

#[derive(Deserialize)]
struct Primitive {
    #[serde(default)]
    attributes: Attributes,
}

#[derive(Deserialize, Default)]
struct Attributes {
    #[serde(rename = "POSITION")]
    position: Option<serde_json::Value>,
}

/// The JSON text of a glTF file's bytes: the first GLB chunk (after
/// [`super::read`]'s container check), or the whole text.
fn json_of(bytes: &[u8]) -> Option<&[u8]> {
    if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        bytes.get(20..20usize.checked_add(len)?)
    } else {
        Some(bytes)
    }
}

/// Fails when a primitive's `POSITION` names an accessor the document does not have.
pub(crate) fn check_positions(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let Some(json) = json_of(bytes) else {
        return Ok(());
    };
    let Ok(doc) = serde_json::from_slice::<Doc>(json) else {
        return Ok(());
    };
    let n = doc.accessors.len();
    for (m, mesh) in doc.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let Some(v) = &prim.attributes.position else {
                continue;
            };
            if v.as_u64().is_some_and(|i| i >= n as u64) {
                return Err(IoError::content(
                    path,
                    format!(
                        "mesh {m}, primitive {p}: POSITION names accessor {v}, but the file has {n} accessors"
                    ),
                ));
            }
        }
    }
    Ok(())
}
