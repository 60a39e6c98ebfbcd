//! Issue 9: the quality metrics in `correspond --report` and `transfer --report`, and the
//! `--refine` / `--no-refine` / `--one-way` / `--combine` / `--local-stretch` flags, run as the built binary on
//! generated tubes.

mod common;
use common::*;

use std::path::Path;

/// An open tube (`nu` around, `nv` rings, scaled), bent by `bend` radians, as OBJ.
fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn reports_carry_quality_and_cycle_consistency() {
    let d = tmp_dir("quality");
    let src = d.join("src.obj");
    write_tube(&src, 12, 7, 1.0, 0.0);
    for (k, b) in [0.4, 1.0].iter().enumerate() {
        write_tube(&d.join(format!("frame-{k}.obj")), 12, 7, 1.0, *b);
    }
    let tgt = d.join("tgt.obj");
    write_tube(&tgt, 18, 10, 1.5, 0.0);
    let mut pairs = Vec::new();
    for (js, jt) in [(0, 0), (3, 9 / 2), (6, 9)] {
        for q in 0..4 {
            pairs.push(format!("[{}, {}]", js * 12 + 3 * q, jt * 18 + (18 * q) / 4));
        }
    }
    let markers = d.join("markers.json");
    std::fs::write(&markers, format!("{{\"pairs\": [{}]}}", pairs.join(", "))).unwrap();
    let corr = d.join("corr.json");
    // Refined by default since issue 40; `--refine` names the default.
    for (flags, refined) in [
        (vec![], true),
        (vec!["--refine"], true),
        (vec!["--no-refine"], false),
        (vec!["--one-way", "--no-refine"], false),
    ] {
        let rep = d.join("corr-report.json");
        let mut args = vec![
            "correspond",
            "--source",
            s(&src),
            "--target",
            s(&tgt),
            "--markers",
            s(&markers),
            "--out",
            s(&corr),
            "--report",
            s(&rep),
        ];
        args.extend(flags.iter().copied());
        ok(&args);
        let r = json(&rep);
        let q = &r["quality"];
        assert_eq!(r["refined"], refined, "{flags:?}");
        assert!(q["normal_pass_fraction"].as_f64().unwrap() > 0.99, "{r}");
        let coverage = q["source_coverage"].as_f64().unwrap();
        if !flags.contains(&"--one-way") {
            assert_eq!(
                coverage, 1.0,
                "{flags:?}: two-way matching reaches every source triangle"
            );
        }
        assert!(q["marker_residual_max"].as_f64().unwrap() < 1e-3);
    }
    // The correspondence report's cycle consistency, from the frames given.
    let rep = d.join("cycle.json");
    ok(&[
        "correspond",
        "--source",
        s(&src),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&corr),
        "--report",
        s(&rep),
        "--cycle-frames",
        &format!("{}/frame-*.obj", d.display()),
    ]);
    let cyc = &json(&rep)["cycle_consistency"];
    assert_eq!(cyc["frames"], 2);
    assert!(cyc["max_relative"].as_f64().unwrap() < 0.1, "{cyc}");
    let report = d.join("transfer.json");
    ok(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        &format!("{}/frame-*.obj", d.display()),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("out")),
        "--report",
        s(&report),
    ]);
    let r = json(&report);
    let c = &r["cycle_consistency"];
    let mean = c["mean_relative"].as_f64().unwrap();
    let max = c["max_relative"].as_f64().unwrap();
    assert!(mean > 0.0 && mean <= max && max < 0.1, "{c}");
    assert_eq!(c["frame_mean_relative"].as_array().unwrap().len(), 2);
    assert_eq!(r["sharp_folds_per_frame"].as_array().unwrap().len(), 2);
    // The local-stretch frame (with the refinement and area weights) runs and reports too.
    let local = d.join("transfer-local.json");
    ok(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        &format!("{}/frame-*.obj", d.display()),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("out-local")),
        "--report",
        s(&local),
        "--local-stretch",
        "--refine",
        "--area-weighted",
    ]);
    let c = &json(&local)["cycle_consistency"];
    let (lmean, lmax) = (
        c["mean_relative"].as_f64().unwrap(),
        c["max_relative"].as_f64().unwrap(),
    );
    assert!(lmean > 0.0 && lmean <= lmax && lmax < 0.1, "{c}");
    // The fold guard reports, per frame, the triangles it left unturned.
    let guarded = json(&local)["fold_guard_unturned_triangles_per_frame"].clone();
    assert_eq!(guarded.as_array().map(Vec::len), Some(2), "{guarded}");
    // The old defaults run: --no-refine --world-frame --uniform-weights, without the guard.
    let old = d.join("transfer-old.json");
    ok(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        &format!("{}/frame-*.obj", d.display()),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("out-old")),
        "--report",
        s(&old),
        "--no-refine",
        "--world-frame",
        "--uniform-weights",
    ]);
    let old = json(&old);
    assert_eq!(old["correspondence"]["refined"], false);
    // The world frame turns nothing, so the guard leaves nothing unturned.
    let unturned = &old["fold_guard_unturned_triangles_per_frame"];
    assert!(
        unturned
            .as_array()
            .is_some_and(|a| a.len() == 2 && a.iter().all(|x| x == 0)),
        "{unturned}"
    );
    assert!(old["cycle_consistency"]["mean_relative"].as_f64().unwrap() > 0.0);
    // --no-fold-guard does not go with --world-frame (the guard acts in the local frame).
    let e = fails(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        s(&d.join("frame-0.obj")),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("out3")),
        "--world-frame",
        "--no-fold-guard",
    ]);
    assert!(e.contains("--world-frame"), "{e}");
    let e = fails(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        s(&d.join("frame-0.obj")),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("out2")),
        "--combine",
        "median",
    ]);
    assert!(e.contains("median"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
