//! Issue 37: `morphkit synth` welds a seam-split (and reordered) target like every solving
//! command: the frames equal the unsplit synthesis within 1e-9 of the diagonal, in the split
//! mesh's own layout and order, and `--report` gives `welded_vertices`.

mod common;
use common::split::{diagonal, read, Split};
use common::*;

use morphkit::io::write_mesh;
use morphkit::mesh::generate;
use std::path::Path;

/// A bar, four bent frames, a scribble of its far half and a recipe, in `d`.
fn setup(d: &Path) {
    std::fs::create_dir_all(d.join("frames")).unwrap();
    let bar = generate::bar(4.0, 0.5, 2, 32);
    write_mesh(&d.join("bar.obj"), &bar).unwrap();
    for k in 0..4 {
        let a = (k as f64 + 1.0) * 30f64.to_radians();
        let bent = bar.with_positions(generate::bend(&bar.positions, 1.9, 0.25, a));
        write_mesh(&d.join(format!("frames/bend-{k}.obj")), &bent).unwrap();
    }
    let x = |t: usize| {
        (0..3)
            .map(|k| bar.positions[bar.triangles[t][k] as usize][0])
            .sum::<f64>()
            / 3.0
    };
    let far: Vec<usize> = (0..bar.num_triangles()).filter(|&t| x(t) > 2.3).collect();
    std::fs::write(
        d.join("far.json"),
        serde_json::json!({ "triangles": far }).to_string(),
    )
    .unwrap();
    std::fs::write(
        d.join("recipe.toml"),
        "target = \"bar.obj\"\nframes = 4\n[[layer]]\nsource_frames = \"frames\"\nscribble = \"far.json\"\n",
    )
    .unwrap();
}

#[test]
fn synth_of_a_split_target_equals_the_unsplit_one_in_its_own_layout() {
    let (du, ds) = (tmp_dir("synth-weld-u"), tmp_dir("synth-weld-s"));
    setup(&du);
    setup(&ds);
    // The split target and frames (faces keep their order, so the scribble holds), shuffled.
    let names: Vec<String> = std::iter::once("bar.obj".to_string())
        .chain((0..4).map(|k| format!("frames/bend-{k}.obj")))
        .collect();
    let inputs: Vec<_> = names.iter().map(|n| du.join(n)).collect();
    let outputs: Vec<_> = names.iter().map(|n| ds.join(n)).collect();
    let split = Split::files(&inputs, &outputs, true);
    let run = |d: &Path| {
        let (_, err) = run_ok(&[
            "synth",
            s(&d.join("recipe.toml")),
            "--out",
            s(&d.join("out")),
            "--report",
            s(&d.join("r.json")),
        ]);
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("r.json")).unwrap()).unwrap();
        (err, r)
    };
    let (err_u, ru) = run(&du);
    let (err_s, rs) = run(&ds);
    assert!(!err_u.contains("welded"), "{err_u}");
    assert!(
        err_s.contains("welded") && err_s.contains("the target"),
        "{err_s}"
    );
    assert_eq!(ru["welded_vertices"]["target"], 0);
    assert_eq!(rs["welded_vertices"]["target"], split.copies());
    assert_eq!(rs["welded_vertices"]["sources"][0], split.copies());
    assert_eq!(rs["target_vertices"], split.origin.len());
    let diag = diagonal(&read(&du.join("bar.obj")).0);
    for k in 0..4 {
        let f = format!("frame_{k:04}.obj");
        let (a, b) = (
            read(&du.join("out").join(&f)).0,
            read(&ds.join("out").join(&f)).0,
        );
        assert_eq!(b.len(), split.origin.len());
        for (v, &o) in split.origin.iter().enumerate() {
            let d = (0..3)
                .map(|i| (a[o][i] - b[v][i]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d <= 1e-9 * diag, "{f}, vertex {v}: {d:e}");
        }
    }
    let _ = std::fs::remove_dir_all(&du);
    let _ = std::fs::remove_dir_all(&ds);
}
