//! Issue 37: `morphkit synth` welds a seam-split (and reordered) target like every solving
//! command: the frames equal the unsplit synthesis within 1e-9 of the diagonal, in the split
//! mesh's own layout and order, and `--report` gives `welded_vertices`.

mod common;
use common::split::{diagonal, read, Split};
use common::*;

use std::path::Path;

#[test]
fn synth_of_a_split_target_equals_the_unsplit_one_in_its_own_layout() {
    let (du, ds) = (tmp_dir("synth-weld-u"), tmp_dir("synth-weld-s"));
    synth_bar(&du);
    synth_bar(&ds);
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
