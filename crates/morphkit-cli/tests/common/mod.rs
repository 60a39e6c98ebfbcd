//! Helpers shared by the CLI tests: run the built `morphkit` binary and check its outcome.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty temporary directory for one test.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `morphkit ARGS`.
pub fn morphkit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .args(args)
        .output()
        .expect("run morphkit")
}

/// Runs `morphkit ARGS`, asserts success, and returns `(stdout, stderr)`.
pub fn run_ok(args: &[&str]) -> (String, String) {
    let out = morphkit(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "morphkit {args:?} failed: {err}");
    (String::from_utf8_lossy(&out.stdout).into_owned(), err)
}

/// Runs `morphkit ARGS`, asserts success, and returns stdout.
pub fn ok(args: &[&str]) -> String {
    run_ok(args).0
}

/// Runs `morphkit ARGS`, asserts a failure reported as one `error: …` message without a
/// panic, and returns stderr.
pub fn fails(args: &[&str]) -> String {
    let out = morphkit(args);
    assert!(!out.status.success(), "morphkit {args:?} should fail");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// A path as `&str`.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
