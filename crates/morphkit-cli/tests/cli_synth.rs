//! `morphkit flex` and `morphkit synth`, run as the built binary on a generated bending bar.

mod common;
use common::*;

use morphkit::io::{read_animation, read_mesh};
use std::path::{Path, PathBuf};

/// A bar, four bent frames and scribbles of its two halves ([`synth_bar`]).
fn setup(name: &str) -> PathBuf {
    let d = tmp_dir(name);
    synth_bar(&d);
    d
}

fn p(d: &Path, rel: &str) -> String {
    s(&d.join(rel)).to_string()
}

#[test]
fn help_shows_examples() {
    for cmd in ["flex", "synth"] {
        let h = ok(&[cmd, "--help"]);
        assert!(
            h.contains("Examples:") && h.contains(&format!("morphkit {cmd} ")),
            "{h}"
        );
    }
}

#[test]
fn flex_writes_colours_and_numbers() {
    let d = setup("flex");
    let (_, err) = run_ok(&[
        "flex",
        "--reference",
        &p(&d, "bar.obj"),
        "--frames",
        &p(&d, "frames/bend-*.obj"),
        "--out",
        &p(&d, "flex.ply"),
        "--json",
        &p(&d, "flex.json"),
    ]);
    assert!(err.contains("4 frames"), "{err}");
    let m = read_mesh(&d.join("flex.ply")).unwrap();
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("flex.json")).unwrap()).unwrap();
    let v = j["flexibility"].as_array().unwrap();
    assert_eq!(v.len(), m.num_triangles());
    assert!(j["stiff_partitions"].as_u64().unwrap() >= 2, "{j}");
    assert!(j["max"].as_f64().unwrap() > 0.1);
    // Writing over an input is refused with one line.
    let e = fails(&[
        "flex",
        "--reference",
        &p(&d, "bar.obj"),
        "--frames",
        &p(&d, "frames/bend-*.obj"),
        "--out",
        &p(&d, "bar.obj"),
    ]);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
}

#[test]
fn synth_writes_frames_selection_and_report() {
    let d = setup("synth");
    let (_, err) = run_ok(&[
        "synth",
        &p(&d, "recipe.toml"),
        "--out",
        &p(&d, "out.glb"),
        "--report",
        &p(&d, "report.json"),
    ]);
    assert!(err.contains("factorized"), "{err}");
    let set = read_animation(&d.join("out.glb"), None).unwrap();
    assert_eq!(set.len(), 4);
    let sel = read_mesh(&d.join("out.selection.ply")).unwrap();
    assert_eq!(sel.num_triangles(), set.triangles().len());
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["frames"], 4);
    assert!(
        r["layers"][0]["selected_triangles"].as_u64().unwrap() > 0,
        "{r}"
    );
    assert!(r["timings"]["factorization_s"].as_f64().unwrap() >= 0.0);
    // A frame directory and a PC2 cache work too.
    run_ok(&[
        "synth",
        &p(&d, "recipe.toml"),
        "--out",
        &p(&d, "frames-out"),
    ]);
    assert!(d.join("frames-out/frame_0003.obj").is_file());
    assert!(d.join("frames-out.selection.ply").is_file());
    run_ok(&["synth", &p(&d, "recipe.toml"), "--out", &p(&d, "out.pc2")]);
    assert!(d.join("out.pc2").is_file());
}

#[test]
fn synth_errors_are_one_line_naming_the_recipe_line() {
    let d = setup("synth-bad");
    std::fs::write(
        d.join("bad.toml"),
        "target = \"bar.obj\"\nframes = 4\n[[layer]]\nsource_frames = \"frames\"\nscribbel = \"far.json\"\n",
    )
    .unwrap();
    let e = fails(&["synth", &p(&d, "bad.toml"), "--out", &p(&d, "o.glb")]);
    assert!(e.contains("bad.toml:5: scribbel: unknown field"), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
}

#[test]
fn flex_and_synth_plan_their_outputs_before_any_work() {
    let d = setup("plan");
    let frames = p(&d, "frames");
    // flex: --out and --json the same file; an --out that is not .ply.
    let e = fails(&[
        "flex",
        "--reference",
        &p(&d, "bar.obj"),
        "--frames",
        &frames,
        "--out",
        &p(&d, "f.ply"),
        "--json",
        &p(&d, "f.ply"),
    ]);
    assert!(e.contains("f.ply"), "{e}");
    let e = fails(&[
        "flex",
        "--reference",
        &p(&d, "bar.obj"),
        "--frames",
        &frames,
        "--out",
        &p(&d, "f.obj"),
    ]);
    assert!(e.contains(".ply"), "{e}");
    assert!(!d.join("f.ply").exists() && !d.join("f.obj").exists());
    // synth: the report where the frames go; a report in a missing directory.
    let e = fails(&[
        "synth",
        &p(&d, "recipe.toml"),
        "--out",
        &p(&d, "o.pc2"),
        "--report",
        &p(&d, "o.pc2"),
    ]);
    assert!(e.contains("o.pc2"), "{e}");
    let e = fails(&[
        "synth",
        &p(&d, "recipe.toml"),
        "--out",
        &p(&d, "o.pc2"),
        "--report",
        &p(&d, "nodir/r.json"),
    ]);
    assert!(e.contains("nodir"), "{e}");
    assert!(!d.join("o.pc2").exists() && !d.join("o.selection.ply").exists());
}
