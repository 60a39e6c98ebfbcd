//! Atomic writes and the never-overwrite-an-input rule.
//!
//! A file is written to a temporary file in the destination directory, flushed to disk
//! (`fsync`) and renamed over the destination, so readers see either the old or the complete
//! new file, and a failed write leaves nothing behind.

use super::temporaries::{name_in_temporary, SIBLING_NAME_BUDGET};
use super::IoError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically: temporary file in the same directory, `fsync`, rename.
///
/// Fails with [`IoError::IsDirectory`] when `path` is a directory and with [`IoError::Os`] when
/// the directory does not exist or is not writable; the temporary file is removed on failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], with the content produced by `fill` into a buffered writer.
pub(crate) fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    if path.file_name().is_none() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = temp_sibling(path, "tmp");
    super::temporaries::record(&tmp, false);
    let file = match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
    {
        Ok(f) => f,
        Err(e) => {
            super::temporaries::forget(&tmp);
            return Err(IoError::os(path, "create the output file", e));
        }
    };
    let result = (|| {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        super::temporaries::forget(&tmp);
        return Err(IoError::os(path, "write the output file", e));
    }
    let renamed = std::fs::rename(&tmp, path);
    if renamed.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    super::temporaries::forget(&tmp);
    if let Err(e) = renamed {
        return Err(IoError::os(path, "move the finished file into place", e));
    }
    // Make the rename itself durable where the platform allows opening directories.
    if let Ok(d) = std::fs::File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// A fresh, unused path next to `path` (same directory, so a rename into place stays on one
/// file system): `.NAME.PID-N.SUFFIX`, with a long NAME shortened as
/// [`super::temporaries`] says.
pub(crate) fn temp_sibling(path: &Path, suffix: &str) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    dir.join(format!(
        ".{}.{}-{}.{suffix}",
        name_in_temporary(&name, SIBLING_NAME_BUDGET),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ))
}

/// Fails with an [`IoError::Content`] error naming the first vertex of `positions` with a NaN
/// or infinite coordinate: writers refuse to store such values.
pub(crate) fn check_finite(path: &Path, positions: &[[f64; 3]]) -> Result<(), IoError> {
    match positions
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        Some(v) => Err(IoError::content(
            path,
            format!(
                "vertex {v} has a non-finite coordinate {:?}; refusing to write it",
                positions[v]
            ),
        )),
        None => Ok(()),
    }
}

/// Fails with an [`IoError::Content`] error naming `what` and the first vertex of `positions`
/// that single precision cannot hold (NaN, infinite, or beyond ±3.4e38, which `as f32` would
/// turn into ±inf): the check of every writer that stores `f32` (PC2, glTF, USD).
pub(crate) fn check_fits_f32(
    path: &Path,
    what: &str,
    positions: &[[f64; 3]],
) -> Result<(), IoError> {
    match positions
        .iter()
        .position(|p| p.iter().any(|&x| !(x as f32).is_finite()))
    {
        Some(v) => Err(IoError::content(
            path,
            format!(
                "{what}: vertex {v} is {:?}, not representable as f32 (the format stores single \
                 precision, up to ±3.4e38); rescale the mesh or write .obj or .ply",
                positions[v]
            ),
        )),
        None => {
            // A mesh whose every coordinate is below single precision's normal range (a
            // denormal 1e-310 mesh) would be stored as one point.
            let largest = positions
                .iter()
                .flatten()
                .fold(0.0f64, |m, x| m.max(x.abs()));
            if largest > 0.0 && largest < F32_SMALLEST_SIZE {
                return Err(IoError::content(
                    path,
                    format!(
                        "{what}: every coordinate is below {F32_SMALLEST_SIZE:e} in size (the \
                         largest is {largest:e}), which single precision would store as one \
                         point; rescale the mesh or write .obj or .ply"
                    ),
                ));
            }
            Ok(())
        }
    }
}

/// The smallest largest-coordinate a mesh may have in an `f32` format: about 2²³ times `f32`'s
/// smallest normal number, so that the mesh keeps its 24 bits of precision.
const F32_SMALLEST_SIZE: f64 = 1e-30;

/// Canonical form of a path that may not exist yet: its existing parent canonicalized, plus
/// the file name.
pub fn canonical_path(path: &Path) -> PathBuf {
    canonical(path)
}

fn canonical(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => {
            let parent = if parent.as_os_str().is_empty() {
                Path::new(".")
            } else {
                parent
            };
            canonical(parent).join(name)
        }
        _ => path.to_path_buf(),
    }
}

/// Fails with [`IoError::WouldOverwriteInput`] when `out` is one of `inputs` (compared after
/// canonicalization, so `./a.obj` and `a.obj` or a symlink are the same file; this includes an
/// output directory that is itself an input directory), or when `out` is an existing directory
/// that directly holds one of the inputs (frame directories are written into, and a frame file
/// could replace an input).
pub fn check_not_input(out: &Path, inputs: &[PathBuf]) -> Result<(), IoError> {
    let out_c = canonical(out);
    let out_is_dir = out.is_dir();
    for input in inputs {
        let in_c = canonical(input);
        let inside = out_is_dir && in_c.parent() == Some(out_c.as_path()) && !in_c.is_dir();
        if in_c == out_c || inside {
            return Err(IoError::WouldOverwriteInput {
                path: out.to_path_buf(),
                input: input.clone(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("morphkit-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn writes_and_replaces_leaving_no_temporary_files() {
        let d = tmp_dir("replace");
        let p = d.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn directory_and_missing_parent_are_errors() {
        let d = tmp_dir("errors");
        let e = write_atomic(&d, b"x").unwrap_err();
        assert!(matches!(e, IoError::IsDirectory { .. }), "{e}");
        let bad = d.join("missing").join("a.txt");
        let e = write_atomic(&bad, b"x").unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn refuses_inputs_and_directories_holding_them() {
        let d = tmp_dir("inputs");
        let a = d.join("a.obj");
        std::fs::write(&a, "x").unwrap();
        let dotted = d.join(".").join("a.obj");
        assert!(check_not_input(&dotted, std::slice::from_ref(&a)).is_err());
        assert!(check_not_input(&d, std::slice::from_ref(&a)).is_err());
        assert!(check_not_input(&d.join("b.obj"), &[a]).is_ok());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn refuses_an_output_directory_that_is_an_input_directory() {
        let d = tmp_dir("same-dir");
        let e = check_not_input(&d, std::slice::from_ref(&d)).unwrap_err();
        assert!(matches!(e, IoError::WouldOverwriteInput { .. }), "{e}");
        let dotted = d.join(".");
        assert!(check_not_input(&dotted, std::slice::from_ref(&d)).is_err());
        let other = d.join("sub");
        std::fs::create_dir_all(&other).unwrap();
        assert!(check_not_input(&other, std::slice::from_ref(&d)).is_ok());
        let _ = std::fs::remove_dir_all(&d);
    }
}
