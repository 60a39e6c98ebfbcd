//! Issue 8 (hardening): outputs checked before any work and written all or none, animations
//! never cut silently, and errors that name the flag, the file row and what was expected.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A directory with the demo's files: base.obj, target.obj, physical-sequence.glb (36 frames).
fn demo(name: &str) -> PathBuf {
    let d = tmp_dir(name);
    ok(&["demo", "--out", s(&d)]);
    d
}

fn blend<'a>(d: &'a Path, rest: &[&'a str]) -> Vec<String> {
    let mut v: Vec<String> = ["blend", "--base"].iter().map(|x| x.to_string()).collect();
    v.push(d.join("base.obj").display().to_string());
    v.push("--target".into());
    v.push(d.join("target.obj").display().to_string());
    v.extend(rest.iter().map(|x| x.to_string()));
    v
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn outputs_of_one_command_must_be_distinct_and_not_inputs() {
    let d = demo("hard-distinct");
    let x = d.join("x.json");
    let xo = d.join("x.obj");
    let e = fails(&strs(&blend(
        &d,
        &[
            "--alpha",
            "0.5",
            "--out",
            s(&xo),
            "--report",
            s(&d.join(".").join("x.obj")),
        ],
    )));
    assert!(e.contains("--out and --report are the same file"), "{e}");
    assert!(!xo.exists());
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let markers = d.join("m.json");
    std::fs::write(&markers, r#"{"pairs": [[0, 0], [5, 5], [9, 9]]}"#).unwrap();
    let corr = |extra: &[&str]| {
        let mut v = vec![
            "correspond",
            "--source",
            s(&base),
            "--target",
            s(&target),
            "--markers",
            s(&markers),
        ];
        v.extend_from_slice(extra);
        fails(&v)
    };
    let w = d.join("w.obj");
    let e = corr(&[
        "--out",
        s(&x),
        "--warped-source",
        s(&w),
        "--warped-target",
        s(&w),
    ]);
    assert!(
        e.contains("--warped-source and --warped-target are the same file"),
        "{e}"
    );
    let cw = d.join("cw.obj");
    let e = corr(&["--out", s(&cw), "--warped-source", s(&cw)]);
    assert!(
        e.contains("--out and --warped-source are the same file"),
        "{e}"
    );
    let e = corr(&["--out", s(&x), "--report", s(&markers)]);
    assert!(
        e.contains("--report") && e.contains("refusing to overwrite"),
        "{e}"
    );
    let e = corr(&["--out", s(&x), "--warped-target", s(&d.join("w.pc2"))]);
    assert!(
        e.contains("--warped-target") && e.contains("unsupported format"),
        "{e}"
    );
    assert!(!x.exists() && !w.exists() && !cw.exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn output_locations_are_checked_before_any_work() {
    let d = demo("hard-early");
    let out = d.join("half.obj");
    let t0 = Instant::now();
    let e = fails(&strs(&blend(
        &d,
        &["--frames", "30", "--out", s(&d.join("nodir/x.glb"))],
    )));
    assert!(e.contains("--out") && e.contains("does not exist"), "{e}");
    if Path::new("/proc/self").exists() {
        let e = fails(&strs(&blend(
            &d,
            &[
                "--alpha",
                "0.5",
                "--out",
                s(&out),
                "--report",
                "/proc/x.json",
            ],
        )));
        assert!(e.contains("--report /proc/x.json: cannot write"), "{e}");
        assert!(
            !out.exists(),
            "the main output was written although the report cannot be"
        );
        let e = fails(&["bench", "--suite", "springs", "--report", "/proc/x.json"]);
        assert!(e.contains("--report /proc/x.json: cannot write"), "{e}");
    }
    // Each of these fails before solving: together well under the time of one solve set-up.
    assert!(t0.elapsed().as_secs_f64() < 5.0);
    let e = fails(&[
        "transfer",
        "--source-ref",
        s(&d.join("base.obj")),
        "--source",
        s(&d.join("physical-sequence.glb")),
        "--target",
        s(&d.join("target.obj")),
        "--markers",
        s(&d.join("missing-markers.json")),
        "--out",
        s(&d.join("t.ply")),
    ]);
    assert!(e.contains("--out") && e.contains("holds one mesh"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bench_steps_are_bounded() {
    let e = fails(&["bench", "--steps", "0"]);
    assert!(e.contains("--steps 0: must be between 1 and 1000"), "{e}");
    let e = fails(&["bench", "--steps", "1000000000"]);
    assert!(e.contains("between 1 and 1000"), "{e}");
}

#[test]
fn converting_an_animation_to_one_mesh_needs_a_frame() {
    let d = demo("hard-frame");
    let glb = d.join("physical-sequence.glb");
    let one = d.join("one.obj");
    let e = fails(&["convert", s(&glb), s(&one)]);
    assert!(
        e.contains("holds 36 frames") && e.contains("--frame"),
        "{e}"
    );
    assert!(!one.exists());
    ok(&["convert", s(&glb), "--frame", "35", s(&one)]);
    let frames = d.join("frames");
    ok(&["convert", s(&glb), s(&frames)]);
    assert_eq!(
        std::fs::read(&one).unwrap(),
        std::fs::read(frames.join("frame_0035.obj")).unwrap()
    );
    let e = fails(&["convert", s(&glb), "--frame", "36", s(&d.join("two.ply"))]);
    assert!(e.contains("--frame 36") && e.contains("0 to 35"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn existing_frames_in_an_output_directory_need_force() {
    let d = demo("hard-force");
    let out = d.join("dir");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("frame_0005.obj"), "from another sequence").unwrap();
    std::fs::write(out.join("notes.txt"), "keep").unwrap();
    let glb = d.join("linear-sequence.glb");
    let e = fails(&["convert", s(&glb), s(&out)]);
    assert!(e.contains("frame_0005.obj") && e.contains("--force"), "{e}");
    assert_eq!(names(&out), ["frame_0005.obj", "notes.txt"]);
    ok(&["convert", s(&glb), "--force", s(&out)]);
    let n = names(&out);
    assert_eq!(n.len(), 37, "{n:?}");
    assert!(n.contains(&"notes.txt".to_string()));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn weight_errors_say_what_was_expected_and_found() {
    let d = demo("hard-weights");
    let out = d.join("o.obj");
    let e = fails(&strs(&blend(
        &d,
        &["--weights", "0.5,0.2", "--out", s(&out)],
    )));
    assert!(
        e.contains("--weights: expected 1 delta weight (one per --target), found 2"),
        "{e}"
    );
    let e = fails(&strs(&blend(
        &d,
        &["--weights", "0.5,0.4", "--convex", "--out", s(&out)],
    )));
    assert!(e.contains("sum to 0.9, expected 1"), "{e}");
    let e = fails(&strs(&blend(&d, &["--alpha", "1e6", "--out", s(&out)])));
    assert!(
        e.contains("--alpha: weight 0 is 1e6, expected at most 100"),
        "{e}"
    );
    for (text, want) in [
        (
            "0.25\n0,5\n",
            "w.csv:2 (frame 1, '0,5'): expected 1 delta weight",
        ),
        (
            "0.5;0.7\n",
            "w.csv:1 (frame 0, '0.5;0.7'): expected 1 delta weight",
        ),
        ("0.5\n1e300\n", "weight 0 is 1e300, expected at most 100"),
        ("0.5\nnan\n", "weight 0 is NaN, not finite"),
    ] {
        let w = d.join("w.csv");
        std::fs::write(&w, text).unwrap();
        let e = fails(&strs(&blend(
            &d,
            &["--weights-file", s(&w), "--out", s(&d.join("o.glb"))],
        )));
        assert!(e.contains(want), "{text:?}: {e}");
        assert!(!e.contains("invalid weights"), "{e}");
    }
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn non_finite_flags_are_named() {
    let d = demo("hard-flags");
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let o = d.join("o.glb");
    for (flag, val) in [
        ("--fps", "inf"),
        ("--k0", "inf"),
        ("--tolerance", "inf"),
        ("--fps", "1e-300"),
    ] {
        let e = fails(&strs(&blend(
            &d,
            &["--alpha", "0.5", flag, val, "--out", s(&o)],
        )));
        assert!(e.contains(&format!("{flag} {val}")), "{e}");
        if val == "inf" {
            assert!(e.contains("not finite"), "{e}");
        }
        assert!(
            !e.contains("gradient_tolerance") && !e.contains("000000000000"),
            "{e}"
        );
    }
    // An unreachable tolerance is allowed, but every message prints it compactly.
    let r = morphkit(&strs(&blend(
        &d,
        &[
            "--alpha",
            "0.5",
            "--tolerance",
            "1e-300",
            "--out",
            s(&d.join("t.obj")),
        ],
    )));
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(!e.contains("000000000000"), "{e}");
    for flag in ["--omega", "--radius"] {
        let e = fails(&[
            "correspond",
            "--source",
            s(&base),
            "--target",
            s(&target),
            "--markers",
            s(&d.join("m.json")),
            "--out",
            s(&d.join("c.json")),
            flag,
            "inf",
        ]);
        assert!(e.contains(&format!("{flag} inf: not finite")), "{e}");
    }
    let transfer = |extra: &[&str]| {
        let mut v = vec![
            "transfer",
            "--source-ref",
            s(&base),
            "--source",
            s(&target),
            "--target",
            s(&target),
            "--out",
            s(&o),
        ];
        v.extend_from_slice(extra);
        fails(&v)
    };
    let m = d.join("m.json");
    let e = transfer(&["--markers", s(&m), "--source-scale", "inf"]);
    assert!(e.contains("--source-scale inf: not finite"), "{e}");
    let e = transfer(&[]);
    assert!(
        e.contains("--markers") && e.contains("--correspondence"),
        "{e}"
    );
    let e = transfer(&["--markers", s(&m), "--fixed-vertex=-1"]);
    assert!(e.contains("--fixed-vertex -1"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
