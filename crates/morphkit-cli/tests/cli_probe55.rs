//! Issue 55 (hardening, third probe): command lines the parser used to trip on, long output
//! names, flags that did nothing, and line endings of users' files.

mod common;
use common::*;

/// A command line with an argument that is not UTF-8 (a file name in Latin-1) ends in a clean
/// error, not a panic where the command line is recorded.
#[cfg(unix)]
#[test]
fn a_non_utf8_argument_is_a_clean_error() {
    use std::os::unix::ffi::OsStrExt;
    let d = tmp_dir("probe55-nonutf8");
    let mut name = d.clone().into_os_string();
    name.push(std::ffi::OsStr::from_bytes(b"/caf\xe9.obj"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .arg("info")
        .arg(&name)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(err.contains("caf\u{fffd}.obj"), "{err}");
}
