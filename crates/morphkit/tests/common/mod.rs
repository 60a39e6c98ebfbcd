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

/// Asserts that two solves of the same frame are the same bits. (They once differed in the
/// last bits: METIS orderings computed on two threads at once interleaved the draws of its
/// process-wide random generator; METIS calls are now serialized.)
pub fn assert_same_frame(a: &[[f64; 3]], b: &[[f64; 3]], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: vertex counts differ");
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in b {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
    let worst = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    assert!(
        worst == 0.0 && a == b,
        "{what}: frames differ by {worst:e} (diagonal {diag:e})"
    );
}

/// A closed bar (4 × 0.6 × 0.6, 16 segments) and the same bar bent by 90° over its second
/// half: its first half moves in no shape, so `FixedVertices::Auto` fixes it.
pub fn bent_bar() -> morphkit::mesh::ShapeSet {
    use morphkit::mesh::{generate, ShapeSet};
    let bar = generate::bar(4.0, 0.6, 2, 16);
    let bent = generate::bend(&bar.positions, 2.0, 2.0, std::f64::consts::FRAC_PI_2);
    ShapeSet::new(
        bar.clone(),
        vec![
            ("straight".into(), bar.positions.clone()),
            ("bent".into(), bent),
        ],
    )
    .unwrap()
}
