//! Issue 39 (hardening, second probe): interrupted and repeated runs leave nothing behind,
//! values a format cannot hold or a solver cannot scale are refused with the file named, and
//! animations too large for memory are refused before any solve.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Names in `d` starting with a dot: what staging and atomic writes leave when interrupted.
fn hidden(d: &Path) -> Vec<String> {
    std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// A base and a bent target tube of 64 × 64 vertices in `d`.
fn tubes(d: &Path) -> (PathBuf, PathBuf) {
    let (a, b) = (d.join("a.obj"), d.join("b.obj"));
    write_tube(&a, 64, 64, 1.0, 0.0);
    write_tube(&b, 64, 64, 1.0, 1.5);
    (a, b)
}

/// Starts a long linear blend into `out`, waits until its staged output appears in `d`, sends
/// `signal`, and returns the exit status's code.
fn interrupt_while_writing(d: &Path, out: &Path, signal: &str) -> Option<i32> {
    let (a, b) = tubes(d);
    let mut child = Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .args(blend_args(&a, &b, &["--frames", "4000", "--linear"]))
        .args(["--out", s(out), "--force"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while !hidden(d).iter().any(|n| n.starts_with(".stage-")) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it staged anything"
        );
        assert!(t.elapsed() < Duration::from_secs(120), "nothing was staged");
        std::thread::sleep(Duration::from_millis(2));
    }
    let pid = child.id().to_string();
    let sent = Command::new("kill").args([signal, &pid]).status().unwrap();
    assert!(sent.success());
    child.wait().unwrap().code()
}

#[test]
fn sigint_and_sigterm_while_writing_leave_no_temporaries() {
    for (name, signal, code) in [("frames", "-INT", 130), ("anim.glb", "-TERM", 143)] {
        let d = tmp_dir(&format!("interrupt-{code}"));
        let out = d.join(name);
        let got = interrupt_while_writing(&d, &out, signal);
        assert_eq!(got, Some(code), "{name}");
        assert!(hidden(&d).is_empty(), "{name}: left {:?}", hidden(&d));
        assert!(
            !out.exists(),
            "{name}: a partial output was moved into place"
        );
        let _ = std::fs::remove_dir_all(&d);
    }
}

#[test]
fn a_rerun_removes_what_a_killed_run_left_for_the_same_output_only() {
    let d = tmp_dir("interrupt-kill");
    let out = d.join("frames");
    assert_eq!(interrupt_while_writing(&d, &out, "-KILL"), None);
    let left = hidden(&d);
    assert!(
        !left.is_empty(),
        "SIGKILL cannot clean up, yet nothing was left"
    );
    // Another output's temporary, of a process that cannot be ours (pid 1 is alive).
    let other = d.join(".stage-1-0-other");
    std::fs::write(&other, "x").unwrap();
    let (a, b) = (d.join("a.obj"), d.join("b.obj"));
    ok(&blend_args(
        &a,
        &b,
        &["--frames", "3", "--linear", "--out", s(&out), "--force"],
    ));
    assert_eq!(hidden(&d), [".stage-1-0-other"]);
    assert_eq!(io_frames(&out), 3);
    let _ = std::fs::remove_dir_all(&d);
}

fn io_frames(d: &Path) -> usize {
    std::fs::read_dir(d).unwrap().count()
}

#[test]
fn an_earlier_runs_unconverged_region_is_not_left_beside_a_converged_result() {
    let d = tmp_dir("stale-region");
    let (a, b) = tubes(&d);
    let out = d.join("half.obj");
    let stale = d.join("half-unconverged.ply");
    let jumps = d.join("half-jumps.ply");
    std::fs::write(&stale, "from an earlier run").unwrap();
    std::fs::write(&jumps, "from an earlier run").unwrap();
    ok(&blend_args(&a, &b, &["--alpha", "0.5", "--out", s(&out)]));
    assert!(out.exists());
    assert!(!stale.exists(), "the earlier run's region is still there");
    assert!(!jumps.exists(), "the earlier run's jumps are still there");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn values_a_format_or_the_solver_cannot_hold_are_refused_naming_the_file() {
    let d = tmp_dir("scale");
    for (name, scale, word) in [("huge", 1e150, "overflow"), ("tiny", 1e-310, "underflow")] {
        let (a, b) = (
            d.join(format!("{name}-a.obj")),
            d.join(format!("{name}-b.obj")),
        );
        write_tube(&a, 12, 8, scale, 0.0);
        write_tube(&b, 12, 8, scale, 1.0);
        let e = fails(&blend_args(
            &a,
            &b,
            &["--alpha", "0.5", "--out", s(&d.join("x.obj"))],
        ));
        assert!(e.contains(&format!("{name}-a.obj")), "{e}");
        assert!(e.contains(word) && e.contains("rescale"), "{e}");
        // `info` shows the size instead of 0.000000.
        let info = ok(&["info", s(&a)]);
        assert!(!info.contains("diagonal  0.000000"), "{info}");
    }
    let pc2 = d.join("huge.pc2");
    let e = fails(&[
        "convert",
        s(&d.join("huge-a.obj")),
        s(&d.join("huge-b.obj")),
        s(&pc2),
    ]);
    assert!(
        e.contains("huge.pc2") && e.contains("not representable as f32"),
        "{e}"
    );
    assert!(!pc2.exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn animations_too_large_for_memory_are_refused_before_any_solve() {
    let d = tmp_dir("frames-memory");
    let (a, b) = tubes(&d);
    // 100 000 frames of 4 096 vertices hold 9.2 GiB as f64 positions alone.
    let t = Instant::now();
    let e = fails(&blend_args(
        &a,
        &b,
        &["--frames", "100000", "--out", s(&d.join("x.glb"))],
    ));
    assert!(
        e.contains("GiB in memory") && e.contains("--max-memory"),
        "{e}"
    );
    assert!(t.elapsed() < Duration::from_secs(30));
    // A weights file is held to the same limits as --frames.
    let rows = d.join("w.csv");
    std::fs::write(&rows, "0.5\n".repeat(100_001)).unwrap();
    let e = fails(&blend_args(
        &a,
        &b,
        &[
            "--weights-file",
            s(&rows),
            "--linear",
            "--out",
            s(&d.join("y.pc2")),
        ],
    ));
    assert!(
        e.contains("100001 rows") && e.contains("split the file"),
        "{e}"
    );
    std::fs::write(&rows, "0.5\n".repeat(300)).unwrap();
    let e = fails(&blend_args(
        &a,
        &b,
        &[
            "--weights-file",
            s(&rows),
            "--linear",
            "--max-memory",
            "0.01",
            "--out",
            s(&d.join("y.glb")),
        ],
    ));
    assert!(e.contains("300 frames of 4096 vertices"), "{e}");
    // A .pc2 is written frame by frame as the frames are made and holds none of them whole:
    // the same limit lets it through.
    let pc2 = d.join("y.pc2");
    ok(&blend_args(
        &a,
        &b,
        &[
            "--weights-file",
            s(&rows),
            "--linear",
            "--max-memory",
            "0.01",
            "--out",
            s(&pc2),
        ],
    ));
    let len = std::fs::metadata(&pc2).unwrap().len();
    assert_eq!(len, 32 + 300 * 4096 * 12);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_compressed_stream_without_line_breaks_is_stopped_early() {
    let d = tmp_dir("gz-bomb");
    let p = d.join("zeros.obj.gz");
    // 64 MiB of zeros compress to about 300 KiB (the system's gzip: the CLI crate has no
    // compressor of its own).
    let made = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "head -c 67108864 /dev/zero | gzip -1 > '{}'",
            s(&p)
        ))
        .status()
        .unwrap();
    assert!(made.success());
    let e = fails(&["info", s(&p)]);
    assert!(
        e.contains("zeros.obj.gz:1") && e.contains("longer than"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
