//! Issue 56, "a `blend`/`convert` GLB of a long sequence": a .glb/.gltf animation of more
//! frames than `--max-targets` is written as a compact clip (a few morph targets at per-frame
//! weights, every frame within `--clip-tolerance` as a reader plays it), not split into meshes
//! of one target per frame; `--per-frame-targets` keeps the exact layout, `--clip-tolerance`
//! asks for a compact clip of any length, and `--report` says which was written.

mod common;

use common::*;
use morphkit::geom::max_distance;
use morphkit::io::{read_animation, read_gltf_morphs};
use morphkit::mesh::{generate, Point, ShapeSet};
use std::path::Path;

/// `n` OBJ frames in `dir`: a tube bending back and forth while it swells at its own pace.
fn write_sequence(dir: &Path, n: usize) {
    let tube = generate::tube(0.3, 4.0, 12, 24, false);
    let shapes: Vec<(String, Vec<Point>)> = (0..n)
        .map(|i| {
            let t = i as f64 / (n - 1) as f64;
            let angle = 2.0 * (std::f64::consts::PI * 2.0 * t).sin();
            let mut p = generate::bend(&tube.positions, 1.0, 2.5, angle);
            let swell = 1.0 + 0.2 * (std::f64::consts::PI * 3.0 * t).sin().powi(2);
            for q in &mut p {
                q[0] *= swell;
            }
            (format!("frame_{i:04}"), p)
        })
        .collect();
    let set = ShapeSet::new(tube, shapes).unwrap();
    morphkit::io::write_frames(dir, &set, &Default::default()).unwrap();
}

/// The largest distance, relative to frame 0's diagonal, between the frames `path` plays at its
/// keys and `frames`.
fn played_error(path: &Path, frames: &ShapeSet) -> f64 {
    let rig = read_gltf_morphs(path).unwrap();
    assert_eq!(rig.weight_keys.len(), frames.len());
    let diag = frames.base().bbox_diagonal();
    (0..frames.len())
        .map(|k| max_distance(&rig.evaluate(&rig.weight_keys[k].1), frames.positions(k)))
        .fold(0.0, f64::max)
        / diag
}

#[test]
fn a_sequence_longer_than_max_targets_is_written_as_a_compact_clip() {
    let d = tmp_dir("compact-frames");
    let seq = d.join("seq");
    write_sequence(&seq, 60);
    // Read back as the CLI reads it (OBJ rounds to f32).
    let frames = read_animation(&seq, None).unwrap();
    let compact = d.join("compact.glb");
    let (_, err) = run_ok(&["convert", s(&seq), "--max-targets", "20", s(&compact)]);
    assert!(err.contains("written as a compact clip"), "{err}");
    let rig = read_gltf_morphs(&compact).unwrap();
    let k = rig.targets.len();
    assert!((2..=20).contains(&k), "{k} targets");
    let e = played_error(&compact, &frames);
    assert!(e <= 1e-3, "compact clip {e:.3e} of the diagonal off");
    // The layout is recorded in the asset.
    let doc = glb_json(&compact);
    let clip = &doc["scenes"][0]["extras"]["morphkit"]["clip"];
    assert_eq!(clip["kind"], "compact", "{clip}");
    assert_eq!(clip["targets"], k);
    // One target per frame: exact, split into meshes of at most 20, and far larger.
    let split = d.join("split.glb");
    let (_, err) = run_ok(&[
        "convert",
        s(&seq),
        "--max-targets",
        "20",
        "--per-frame-targets",
        s(&split),
    ]);
    assert!(err.contains("meshes of at most 20 targets"), "{err}");
    assert!(played_error(&split, &frames) < 1e-6);
    let size = |p: &Path| std::fs::metadata(p).unwrap().len();
    assert!(
        size(&compact) * 3 < size(&split),
        "{} against {}",
        size(&compact),
        size(&split)
    );
    // Quantized: still within the tolerance as played (dequantized by the reader).
    let quantized = d.join("quantized.glb");
    run_ok(&[
        "convert",
        s(&seq),
        "--max-targets",
        "20",
        "--quantize",
        s(&quantized),
    ]);
    assert!(played_error(&quantized, &frames) <= 1e-3);
    assert!(size(&quantized) < size(&compact));
    // Within --max-targets, the frames stay exact unless a tolerance is asked for.
    let short = d.join("short.glb");
    let (_, err) = run_ok(&["convert", s(&seq), s(&short)]);
    assert!(!err.contains("compact clip"), "{err}");
    assert!(read_gltf_morphs(&short).unwrap().targets.len() >= 58);
    let asked = d.join("asked.glb");
    let (_, err) = run_ok(&["convert", s(&seq), "--clip-tolerance", "1e-4", s(&asked)]);
    assert!(err.contains("written as a compact clip"), "{err}");
    assert!(played_error(&asked, &frames) <= 1e-4);
    // A tolerance the budget cannot meet falls back to a target per frame, and says so.
    let tight = d.join("tight.glb");
    let (_, err) = run_ok(&[
        "convert",
        s(&seq),
        "--max-targets",
        "3",
        "--clip-tolerance",
        "1e-6",
        s(&tight),
    ]);
    assert!(
        err.contains("would need more than 3 morph targets"),
        "{err}"
    );
    assert!(played_error(&tight, &frames) < 1e-6);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn blend_reports_the_layout_of_its_animation_and_refuses_clip_flags_elsewhere() {
    let d = tmp_dir("compact-frames-blend");
    let (rest, bent) = (d.join("rest.obj"), d.join("bent.obj"));
    write_tube(&rest, 10, 12, 1.0, 0.0);
    write_tube(&bent, 10, 12, 1.0, 2.0);
    let out = d.join("b.glb");
    let report = d.join("b.json");
    run_ok(&blend_args(
        &rest,
        &bent,
        &[
            "--frames",
            "30",
            "--clip-tolerance",
            "1e-3",
            "--report",
            s(&report),
            "--out",
            s(&out),
        ],
    ));
    let frames_dir = d.join("frames");
    run_ok(&blend_args(
        &rest,
        &bent,
        &["--frames", "30", "--out", s(&frames_dir)],
    ));
    let frames = read_animation(&frames_dir, None).unwrap();
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let clip = &r["clip"];
    assert_eq!(clip["kind"], "compact", "{clip}");
    let reported = clip["played_error"].as_f64().unwrap();
    let e = played_error(&out, &frames);
    assert!(
        e <= 1e-3 && (e - reported).abs() < 1e-5,
        "{e} against {reported}"
    );
    // The same blend with one target per frame reports that.
    let exact = d.join("exact.glb");
    run_ok(&blend_args(
        &rest,
        &bent,
        &[
            "--frames",
            "30",
            "--per-frame-targets",
            "--report",
            s(&report),
            "--out",
            s(&exact),
        ],
    ));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(r["clip"]["kind"], "per_frame_targets");
    // Flags that would do nothing, or nonsense, are refused before any work.
    let e = fails(&blend_args(
        &rest,
        &bent,
        &[
            "--frames",
            "3",
            "--clip-tolerance",
            "1e-3",
            "--out",
            s(&d.join("dir")),
        ],
    ));
    assert!(
        e.contains("--clip-tolerance is used only with a .glb/.gltf output"),
        "{e}"
    );
    let e = fails(&[
        "convert",
        s(&frames_dir),
        "--per-frame-targets",
        s(&d.join("a.pc2")),
    ]);
    assert!(e.contains("--per-frame-targets is used only with"), "{e}");
    let o = morphkit(&[
        "convert",
        s(&frames_dir),
        "--clip-tolerance",
        "0",
        s(&d.join("z.glb")),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("finite positive"), "{e}");
    assert!(!d.join("dir").exists() && !d.join("a.pc2").exists() && !d.join("z.glb").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// The JSON chunk of a GLB.
fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}
