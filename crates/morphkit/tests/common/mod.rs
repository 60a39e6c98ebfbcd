//! Shared helpers for integration tests: access to the real meshes under `MORPHKIT_DATA`.
#![allow(dead_code)]

use std::path::PathBuf;

/// The data directory, or `None` when `MORPHKIT_DATA` is unset (real-data tests then skip).
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("MORPHKIT_DATA")?;
    let dir = PathBuf::from(dir);
    assert!(
        dir.is_dir(),
        "MORPHKIT_DATA={} is set but is not a directory",
        dir.display()
    );
    Some(dir)
}

/// A file under `MORPHKIT_DATA`: `None` when the variable is unset; a test failure when it is
/// set but the file is missing.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(rel);
    assert!(
        p.is_file(),
        "MORPHKIT_DATA is set but {} is missing",
        p.display()
    );
    Some(p)
}

/// Prints why a real-data test did nothing.
pub fn skip(test: &str) {
    eprintln!("{test}: MORPHKIT_DATA is unset; skipping the real-data test");
}
