//! Issue 55 (hardening, third probe): command lines the parser used to trip on, long output
//! names, flags that did nothing, and line endings of users' files.

mod common;
use common::*;
use std::path::{Path, PathBuf};

/// A directory with the demo's files: base.obj and target.obj (a bar straight and bent).
fn demo(name: &str) -> PathBuf {
    let d = tmp_dir(name);
    ok(&["demo", "--out", s(&d)]);
    d
}

fn blend_demo<'a>(d: &'a Path, rest: &[&'a str]) -> Vec<String> {
    let mut v = vec![
        "blend".to_string(),
        "--base".into(),
        d.join("base.obj").display().to_string(),
        "--target".into(),
        d.join("target.obj").display().to_string(),
    ];
    v.extend(rest.iter().map(|x| x.to_string()));
    v
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

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

/// Negative numbers are values of the options that take numbers, checked like any other value.
#[test]
fn negative_numbers_are_values() {
    let d = demo("probe55-negative");
    let out = d.join("minus.obj");
    ok(&strs(&blend_demo(
        &d,
        &["--alpha", "-0.5", "--linear", "--out", s(&out)],
    )));
    assert!(out.exists());
    let e = fails(&strs(&blend_demo(
        &d,
        &["--alpha", "-500", "--out", s(&out)],
    )));
    assert!(
        e.contains("--alpha: weight 0 is -500, expected at most 100"),
        "{e}"
    );
    let e = fails(&strs(&blend_demo(
        &d,
        &[
            "--frames",
            "3",
            "--fps",
            "-24",
            "--out",
            s(&d.join("a.glb")),
        ],
    )));
    assert!(e.contains("--fps -24: must be at least 0.001"), "{e}");
    let e = fails(&strs(&blend_demo(
        &d,
        &["--alpha", "0.5", "--k0", "-1", "--out", s(&out)],
    )));
    assert!(e.contains("--k0 -1: must be greater than 0"), "{e}");
    // A count is no negative number: clap says so, naming the flag.
    let out = morphkit(&strs(&blend_demo(
        &d,
        &["--frames", "-3", "--out", s(&d.join("b.glb"))],
    )));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("invalid value '-3' for '--frames"), "{err}");
}

/// An output name of 250 bytes (the file system allows 255) is written: its temporaries
/// stand under a short name, and none is left behind.
#[test]
fn an_output_name_of_250_bytes_is_written() {
    let d = demo("probe55-long");
    let long = |ext: &str| d.join(format!("{}.{ext}", "x".repeat(249 - ext.len())));
    let (obj, glb, report) = (long("obj"), long("glb"), long("json"));
    assert_eq!(obj.file_name().unwrap().len(), 250);
    let args = ["--alpha", "0.5", "--out", s(&obj), "--report", s(&report)];
    ok(&strs(&blend_demo(&d, &args)));
    ok(&strs(&blend_demo(&d, &["--frames", "3", "--out", s(&glb)])));
    let frames = d.join("f".repeat(250));
    ok(&["convert", s(&glb), s(&frames)]);
    assert!(obj.is_file() && glb.is_file() && report.is_file());
    assert!(frames.join("frame_0002.obj").is_file());
    let left: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// Flags that act only with another one are refused without it, instead of being ignored.
#[test]
fn flags_that_would_do_nothing_are_refused() {
    let d = demo("probe55-idle");
    let out = d.join("x.obj");
    for (flag, value, needed) in [
        ("--mesh", "Face", "--rig"),
        ("--animation", "Talk", "--rig"),
        ("--refine", "2", "--interactive"),
        ("--interactive-cache", "c.json", "--interactive"),
    ] {
        let args = ["--alpha", "0.5", "--linear", flag, value, "--out", s(&out)];
        let e = fails(&strs(&blend_demo(&d, &args)));
        assert!(
            e.contains(&format!("{flag} is used only with {needed}")),
            "{flag}: {e}"
        );
        assert!(!out.exists());
    }
    // An edit of a user's asset keeps its accessors: the encoding flags would be ignored.
    let glb = d.join("anim.glb");
    ok(&strs(&blend_demo(&d, &["--frames", "3", "--out", s(&glb)])));
    let copy = d.join("copy.glb");
    for flag in ["--quantize", "--sparse-targets", "--no-normals"] {
        let e = fails(&["convert", s(&glb), s(&copy), flag]);
        assert!(
            e.contains(&format!(
                "{flag} not applied to an edit of the user's asset"
            )),
            "{e}"
        );
    }
    // --quantize applies to a compact clip's correctives, not to one target per frame.
    let per_frame = ["--per-frame-targets", "--quantize", "--out", s(&copy)];
    let e = fails(&[&["blend", "--rig", s(&glb)][..], &per_frame[..]].concat());
    assert!(e.contains("--quantize not applied"), "{e}");
    let e = fails(&[
        "blend",
        "--rig",
        s(&glb),
        "--sparse-targets",
        "--out",
        s(&copy),
    ]);
    assert!(e.contains("--sparse-targets not applied"), "{e}");
    assert!(!copy.exists());
    ok(&["convert", s(&glb), s(&copy)]);
}

/// OBJ files of old Mac tools (CR line breaks) are read, and an OBJ written back through the
/// input's own file keeps its line breaks (CRLF here).
#[test]
fn obj_line_breaks_are_read_and_kept() {
    let d = demo("probe55-eol");
    let text = std::fs::read_to_string(d.join("base.obj")).unwrap();
    let mac = d.join("mac.obj");
    std::fs::write(&mac, text.replace('\n', "\r")).unwrap();
    let info = ok(&["info", "--json", s(&mac)]);
    let want = ok(&["info", "--json", s(&d.join("base.obj"))]);
    let triangles =
        |j: &str| serde_json::from_str::<serde_json::Value>(j).unwrap()[0]["triangles"].clone();
    assert_eq!(triangles(&info), triangles(&want));
    let dos = d.join("dos.obj");
    std::fs::write(&dos, text.replace('\n', "\r\n")).unwrap();
    let out = d.join("back.obj");
    ok(&["convert", s(&dos), s(&out)]);
    let back = std::fs::read_to_string(&out).unwrap();
    assert!(back.contains("\r\n"));
    assert_eq!(back.matches('\n').count(), back.matches("\r\n").count());
}

/// A 450-frame `.glb` that `blend` wrote with one target per frame (split into meshes of 200
/// targets; by default it would be a compact clip, `cli_compact_frames.rs`) is read by
/// `blend --rig` as what it is: 449 targets and one key per frame, so a blend of it to frames
/// works; into the `.glb` itself (an edit of the split rig) it is refused, naming the file and
/// saying it is a split frame sequence, before any solve.
#[test]
fn a_split_frame_sequence_is_read_whole_by_blend_rig() {
    let d = demo("probe55-split");
    let long = d.join("long.glb");
    ok(&strs(&blend_demo(
        &d,
        &[
            "--frames",
            "450",
            "--linear",
            "--per-frame-targets",
            "--out",
            s(&long),
        ],
    )));
    let pc2 = d.join("again.pc2");
    ok(&["blend", "--rig", s(&long), "--linear", "--out", s(&pc2)]);
    let back = morphkit::io::read_animation(&pc2, Some(&d.join("base.obj"))).unwrap();
    let sequence = morphkit::io::read_animation(&long, None).unwrap();
    assert_eq!(back.len(), 450, "one frame per key");
    let tol = 1e-6 * sequence.base().bbox_diagonal();
    for k in 0..450 {
        let e = back
            .positions(k)
            .iter()
            .zip(sequence.positions(k))
            .flat_map(|(p, q)| (0..3).map(move |i| (p[i] - q[i]).abs()))
            .fold(0.0, f64::max);
        assert!(e < tol, "frame {k}: {e}");
    }
    let e = fails(&[
        "blend",
        "--rig",
        s(&long),
        "--linear",
        "--out",
        s(&d.join("x.glb")),
    ]);
    assert!(
        e.contains("long.glb") && e.contains("frame sequence morphkit split into 3 meshes"),
        "{e}"
    );
    assert!(!d.join("x.glb").exists());
}
