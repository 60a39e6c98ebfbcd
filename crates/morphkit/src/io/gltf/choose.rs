//! Choosing one element of a glTF document (a mesh, a weights animation) by the name or the
//! index a user gives: the one rule behind [`super::GltfReadOptions::mesh`] and
//! [`super::GltfAsset::weight_animation`].
//!
//! A key is first a name: the element of that name when exactly one has it. Names are not
//! unique in glTF, and when several elements share the key as their name the choice is refused,
//! naming the file, the name and the indices that share it (taking the first, as before, left
//! the others unreachable). A key that no element has as its name and that is a number is an
//! index in the document's array (`"1"` is `meshes[1]`), so every element can be chosen.

use crate::io::IoError;
use std::path::Path;

/// One element a key may choose: its index in the document's array and its name.
pub(super) struct Named<'a> {
    /// The index in the document's array (`meshes`, `animations`).
    pub index: usize,
    /// Its name, when it has one.
    pub name: Option<&'a str>,
}

/// The position in `items` of the element `key` chooses (see the [module
/// documentation](self)). `what` names the kind in messages (`mesh`, `animation`), `scope` says
/// which elements were looked at (`""`, or ` driving the morph weights of mesh 1`), and
/// `missing` is the message for a key that chooses none.
///
/// Errors: several elements named `key`; no element named `key` and no element at that index.
pub(super) fn choose(
    path: &Path,
    what: &str,
    scope: &str,
    items: &[Named],
    key: &str,
    missing: impl FnOnce() -> String,
) -> Result<usize, IoError> {
    let named: Vec<usize> = (0..items.len())
        .filter(|&i| items[i].name == Some(key))
        .collect();
    match named.as_slice() {
        [one] => return Ok(*one),
        [] => {}
        several => {
            let indices: Vec<String> = several
                .iter()
                .map(|&i| items[i].index.to_string())
                .collect();
            return Err(IoError::content(
                path,
                format!(
                    "{} {}{scope} are named '{key}' ({what} {}); a name cannot tell them \
                     apart: choose one by its index ({})",
                    several.len(),
                    plural(what),
                    indices.join(format!(", {what} ").as_str()),
                    indices
                        .iter()
                        .map(|i| format!("'{i}'"))
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
    }
    if let Ok(index) = key.parse::<usize>() {
        if let Some(i) = items.iter().position(|m| m.index == index) {
            return Ok(i);
        }
    }
    Err(IoError::content(path, missing()))
}

/// `meshes`, `animations`.
fn plural(what: &str) -> String {
    if what.ends_with("sh") {
        format!("{what}es")
    } else {
        format!("{what}s")
    }
}

/// True when two of `items` share a name (messages then ask to choose by index).
pub(super) fn shared_names(items: &[Named]) -> bool {
    items
        .iter()
        .enumerate()
        .any(|(i, a)| a.name.is_some() && items[..i].iter().any(|b| b.name == a.name))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn items() -> Vec<Named<'static>> {
        vec![
            Named {
                index: 0,
                name: Some("Prop"),
            },
            Named {
                index: 1,
                name: Some("Face"),
            },
            Named {
                index: 2,
                name: Some("Face"),
            },
            Named {
                index: 3,
                name: None,
            },
        ]
    }

    fn pick(key: &str) -> Result<usize, String> {
        choose(Path::new("a.glb"), "mesh", "", &items(), key, || {
            format!("no mesh is named '{key}' or has that index")
        })
        .map_err(|e| e.to_string())
    }

    /// Issue 55: `--mesh Face` took the first of two meshes named `Face`, and the second could
    /// not be chosen.
    #[test]
    fn a_shared_name_is_refused_and_an_index_chooses() {
        assert_eq!(pick("Prop"), Ok(0));
        let e = pick("Face").unwrap_err();
        assert!(
            e.starts_with("a.glb: 2 meshes are named 'Face' (mesh 1, mesh 2)"),
            "{e}"
        );
        assert!(e.contains("choose one by its index ('1' or '2')"), "{e}");
        assert_eq!(pick("1"), Ok(1));
        assert_eq!(pick("2"), Ok(2));
        assert_eq!(pick("3"), Ok(3));
        let e = pick("7").unwrap_err();
        assert!(e.contains("no mesh is named '7' or has that index"), "{e}");
        assert!(shared_names(&items()));
        assert!(!shared_names(&items()[..2]));
    }
}
