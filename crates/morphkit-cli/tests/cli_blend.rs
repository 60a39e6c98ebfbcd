//! `morphkit demo` and `morphkit blend`, run as the built binary.

mod common;
use common::*;

use std::path::Path;

use common::obj_vertices as vertices;

#[test]
fn demo_writes_its_files_and_shows_the_linear_blend_shrinking() {
    let d = tmp_dir("blend-demo");
    let out = ok(&["demo", "--out", s(&d)]);
    assert!(out.contains("volume / interpolated volume"), "{out}");
    for f in [
        "base.obj",
        "target.obj",
        "linear-0.5.obj",
        "linear-0.5.glb",
        "physical-0.5.obj",
        "physical-0.5.glb",
        "physical-sequence.glb",
    ] {
        assert!(d.join(f).is_file(), "{f} missing");
    }
    // The physical blend keeps the bar's length; the linear one cuts the corner.
    let (b, l, p) = (
        vertices(&d.join("base.obj")),
        vertices(&d.join("linear-0.5.obj")),
        vertices(&d.join("physical-0.5.obj")),
    );
    let span = |v: &[[f64; 3]]| {
        let (a, z) = (v[v.len() - 2], v[v.len() - 1]); // the two cap centres
        ((a[0] - z[0]).powi(2) + (a[1] - z[1]).powi(2) + (a[2] - z[2]).powi(2)).sqrt()
    };
    assert!(
        span(&l) < span(&p),
        "linear end-to-end {} vs physical {}",
        span(&l),
        span(&p)
    );
    assert!(span(&p) < span(&b));
}

#[test]
fn blend_writes_frames_reports_and_refuses_bad_input() {
    let d = tmp_dir("blend-blend");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    // α = 0 gives the base back, α = 1 the target.
    for (alpha, want) in [("0", &base), ("1", &target)] {
        let out = d.join(format!("a{alpha}.obj"));
        ok(&blend_args(
            &base,
            &target,
            &["--alpha", alpha, "--out", s(&out)],
        ));
        let (got, want) = (vertices(&out), vertices(want));
        let err = got
            .iter()
            .zip(&want)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        assert!(err < 1e-5, "α = {alpha}: max error {err}");
    }
    let report = d.join("r.json");
    ok(&blend_args(
        &base,
        &target,
        &[
            "--frames",
            "5",
            "--out",
            s(&d.join("frames")),
            "--report",
            s(&report),
        ],
    ));
    assert!(d.join("frames/frame_0004.obj").is_file());
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let frames = r["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    // The sampled start's solves (each target's equilibria at ¼, ½, ¾) are reported.
    let samples = r["start_sample_solves"].as_u64().unwrap();
    assert!((1..=3).contains(&samples), "{samples} sample solves");
    for f in frames {
        assert_eq!(f["solver"]["converged"], true);
        let (p, l) = (
            f["physical"]["edge_length_rms"].as_f64().unwrap(),
            f["linear"]["edge_length_rms"].as_f64().unwrap(),
        );
        assert!(p <= l + 1e-9, "physical {p} vs linear {l}");
    }
    // Linear blend with a weights file (CSV with a header).
    std::fs::write(d.join("w.csv"), "w\n0.25\n0.75\n").unwrap();
    ok(&blend_args(
        &base,
        &target,
        &[
            "--weights-file",
            s(&d.join("w.csv")),
            "--linear",
            "--out",
            s(&d.join("lin.pc2")),
        ],
    ));
    assert!(d.join("lin.pc2").is_file());

    let e = fails(&blend_args(
        &base,
        &target,
        &["--alpha", "nan", "--out", s(&d.join("x.obj"))],
    ));
    assert!(e.contains("not finite"), "{e}");
    let e = fails(&blend_args(
        &base,
        &target,
        &[
            "--weights",
            "0.5,0.7",
            "--convex",
            "--out",
            s(&d.join("x.obj")),
        ],
    ));
    assert!(e.contains("sum to 1"), "{e}");
    let e = fails(&blend_args(
        &base,
        &target,
        &["--alpha", "0.5", "--out", s(&base)],
    ));
    assert!(e.contains("overwrite"), "{e}");
    let e = fails(&blend_args(
        &base,
        &target,
        &["--frames", "3", "--out", s(&d.join("one.obj"))],
    ));
    assert!(e.contains("one frame"), "{e}");
    let e = fails(&blend_args(
        &d,
        &target,
        &["--alpha", "0.5", "--out", s(&d.join("x.obj"))],
    ));
    assert!(e.contains("directory"), "{e}");
    std::fs::write(d.join("fixed.json"), "{\"fixed\": [0]}").unwrap();
    let e = fails(&blend_args(
        &base,
        &target,
        &[
            "--alpha",
            "0.5",
            "--fixed",
            s(&d.join("fixed.json")),
            "--out",
            s(&d.join("x.obj")),
        ],
    ));
    assert!(e.contains("rotate"), "{e}");
    // Another connectivity: a different generated mesh.
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = fails(&blend_args(
        &base,
        &d.join("tri.obj"),
        &["--alpha", "0.5", "--out", s(&d.join("x.obj"))],
    ));
    assert!(e.contains("vertices"), "{e}");
    assert!(!d.join("x.obj").exists(), "no partial output");
}

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// `--factor-precision double` and the default single-precision factor give the same
/// equilibrium to the gradient tolerance (the factor only preconditions), and a bad value is
/// refused by name.
#[test]
fn factor_precision_changes_the_speed_not_the_answer() {
    let d = tmp_dir("blend-precision");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let (single_out, double_out, bad_out) =
        (d.join("single.obj"), d.join("double.obj"), d.join("x.obj"));
    let args = |out: &std::path::PathBuf, precision: &'static str| -> Vec<String> {
        [
            "blend",
            "--base",
            s(&base),
            "--target",
            s(&target),
            "--alpha",
            "0.5",
            "--factor-precision",
            precision,
            "--out",
            s(out),
        ]
        .map(String::from)
        .to_vec()
    };
    ok(&refs(&args(&single_out, "single")));
    ok(&refs(&args(&double_out, "double")));
    let (single, double) = (vertices(&single_out), vertices(&double_out));
    let lin: Vec<[f64; 3]> = vertices(&base)
        .iter()
        .zip(vertices(&target))
        .map(|(p, q)| [0, 1, 2].map(|k| 0.5 * (p[k] + q[k])))
        .collect();
    let max = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max)
    };
    let moved = max(&double, &lin);
    assert!(moved > 1e-3, "the physical blend equals the linear blend");
    let diff = max(&single, &double);
    assert!(
        diff < 1e-4 * moved,
        "single vs double: {diff} (moved {moved})"
    );
    let e = fails(&refs(&args(&bad_out, "half")));
    assert!(e.contains("factor-precision"), "{e}");
}

/// `--continuation K` solves each frame along its ray in K steps: on the demo (one
/// equilibrium) the same frame within the tolerance, with more Newton work in `--report`;
/// more than 64 steps are refused.
#[test]
fn continuation_solves_along_the_ray() {
    let d = tmp_dir("blend-continuation");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let run = |k: &str, name: &str| {
        let (out, report) = (
            d.join(format!("{name}.obj")),
            d.join(format!("{name}.json")),
        );
        ok(&blend_args(
            &base,
            &target,
            &[
                "--alpha",
                "0.6",
                "--continuation",
                k,
                "--out",
                s(&out),
                "--report",
                s(&report),
            ],
        ));
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let newton = r["frames"][0]["solver"]["newton_iterations"]
            .as_u64()
            .unwrap();
        (vertices(&out), newton)
    };
    let (plain, plain_newton) = run("0", "plain");
    let (along, along_newton) = run("4", "along");
    let diff = morphkit::geom::max_distance(&plain, &along);
    assert!(diff < 1e-4, "{diff}");
    assert!(
        along_newton > plain_newton,
        "{along_newton} vs {plain_newton}"
    );
    let e = fails(&blend_args(
        &base,
        &target,
        &[
            "--alpha",
            "0.6",
            "--continuation",
            "65",
            "--out",
            s(&d.join("x.obj")),
        ],
    ));
    assert!(e.contains("continuation"), "{e}");
}

/// Runs `blend` on `base` → `target` with the `extra` arguments and `--thin-band-rings rings`,
/// writing `out` and the report `report`; returns stderr and the report.
fn blend_rings(
    base: &Path,
    target: &Path,
    extra: &[&str],
    rings: &str,
    out: &Path,
    report: &Path,
) -> (String, serde_json::Value) {
    let mut args = extra.to_vec();
    args.extend([
        "--thin-band-rings",
        rings,
        "--out",
        s(out),
        "--report",
        s(report),
    ]);
    let (_, err) = run_ok(&blend_args(base, target, &args));
    let r = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    (err, r)
}

/// A short open tube, 3 rings of 40 vertices, is a thin band: `--report` counts its moving
/// vertices (the bottom ring does not move and is fixed) as band vertices, and
/// `--thin-band-rings 0` solves it as springs instead.
#[test]
fn a_thin_band_follows_the_predictor_unless_turned_off() {
    let d = tmp_dir("blend-band");
    let (base, target) = (d.join("ring.obj"), d.join("bent.obj"));
    write_tube(&base, 40, 3, 1.0, 0.0);
    write_tube(&target, 40, 3, 1.0, 1.0);
    let bands = |rings: &str| {
        let (out, report) = (
            d.join(format!("out{rings}.obj")),
            d.join(format!("r{rings}.json")),
        );
        blend_rings(&base, &target, &["--alpha", "0.4"], rings, &out, &report).1["rig"]
            ["band_vertices"]
            .as_u64()
            .unwrap()
    };
    assert_eq!(bands("4"), 80);
    assert_eq!(bands("0"), 0);
}

/// A sequence in which a part snaps from one equilibrium to another is reported: a warning,
/// the pair of frames and the region in `--report`, and the region red in a PLY beside the
/// output. The squashed strip snaps when solved as springs (`--thin-band-rings 0`) and moves
/// smoothly as a thin band (the default), which then reports nothing.
#[test]
fn a_jump_between_frames_is_reported_with_its_region() {
    let d = tmp_dir("blend-jump");
    let (base, target) = (d.join("open.obj"), d.join("closed.obj"));
    write_annulus(&base, 1.0);
    write_annulus(&target, 0.05);
    let run = |rings: &str| {
        let (out, report) = (
            d.join(format!("seq{rings}.pc2")),
            d.join(format!("r{rings}.json")),
        );
        let (err, r) = blend_rings(&base, &target, &["--frames", "36"], rings, &out, &report);
        (err, r, d.join(format!("seq{rings}-jumps.ply")))
    };
    let (err, r, ply) = run("0");
    let c = &r["continuity"];
    let jumps = c["jumps"].as_array().unwrap();
    assert!(!jumps.is_empty(), "{c}");
    assert!(err.contains("jumped"), "{err}");
    assert!(c["worst_ratio"].as_f64().unwrap() > 4.0, "{c}");
    assert_eq!(c["bound"].as_f64(), Some(4.0));
    for j in jumps {
        let f = j["frames"].as_array().unwrap();
        assert_eq!(f[1].as_u64().unwrap(), f[0].as_u64().unwrap() + 1, "{j}");
        let v = j["vertices"].as_array().unwrap();
        assert!(!v.is_empty() && v.len() <= 480, "{j}");
        assert!(v.contains(&j["vertex"]), "{j}");
        assert!(j["ratio"].as_f64().unwrap() > 4.0, "{j}");
    }
    assert_eq!(r["jump_region"].as_str(), Some(s(&ply)));
    let text = std::fs::read(&ply).unwrap();
    assert!(text.starts_with(b"ply"), "not a PLY: {}", ply.display());
    let (err, r, ply) = run("4");
    let c = &r["continuity"];
    assert!(c["jumps"].as_array().unwrap().is_empty(), "{c}");
    assert!(c["worst_ratio"].as_f64().unwrap() < 2.0, "{c}");
    assert!(!err.contains("jumped"), "{err}");
    assert!(r["jump_region"].is_null());
    assert!(!ply.exists());
}

/// `blend` tells its jumps apart (issue 54): on cragl's cylinder, pose1-3 and pose1-4 move
/// smoothly faster than the bound (up to 5× the linear step: halving a step keeps its ratio),
/// and the warning says that none of them snaps. pose1-3 snapped near 0.57 (18× and 50×)
/// until the fold guard's trust was interpolated on a grid (docs/choices.md, "Continuity in
/// the weights"); the kinking tube's snaps, which the warning calls snaps, are checked in
/// `cli_compact_clip.rs`.
#[test]
fn blend_tells_a_snap_from_a_fast_step() {
    let Some(data) = std::env::var_os("MORPHKIT_DATA") else {
        eprintln!("SKIPPED: MORPHKIT_DATA is not set");
        return;
    };
    let cyl = std::path::Path::new(&data).join("cragl-bending-cylinder");
    let d = tmp_dir("blend-snaps");
    let base = cyl.join("cylinder-rest.obj");
    for target in ["pose1-3", "pose1-4"] {
        let t = cyl.join(format!("cylinder-{target}.obj"));
        assert!(base.exists() && t.exists(), "{} is missing", t.display());
        let (out, report) = (d.join(target), d.join(format!("{target}.json")));
        let (_, err) = run_ok(&blend_args(
            &base,
            &t,
            &["--frames", "41", "--out", s(&out), "--report", s(&report)],
        ));
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let jumps = r["continuity"]["jumps"].as_array().unwrap().len();
        let found = r["snaps"].as_array().unwrap().len();
        assert!(jumps >= 1, "{target}: {}", r["continuity"]);
        assert!(
            found == 0 && err.contains("none of them snaps"),
            "{target}: {} {err}",
            r["snaps"]
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}
