//! `morphkit blend --interactive` (issue 38): frames from the prepared interactive space,
//! each within its reported error estimate of the full solve; the preparation kept in
//! `--interactive-cache` and read back by the next run, giving the same bytes.

mod common;
use common::*;

use std::path::Path;

use common::obj_vertices as vertices;

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn report(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn interactive_frames_are_within_their_estimate_and_the_cache_is_reused() {
    let d = tmp_dir("blend-interactive");
    ok(&["demo", "--out", s(&d)]);
    let (base, target) = (d.join("base.obj"), d.join("target.obj"));
    let (full, fast, cache) = (d.join("full"), d.join("fast"), d.join("rig.cache"));
    let (rf, ri) = (d.join("full.json"), d.join("fast.json"));
    ok(&blend_args(
        &base,
        &target,
        &["--frames", "5", "--out", s(&full), "--report", s(&rf)],
    ));
    let args = |out: &Path, rep: &Path| -> Vec<String> {
        let mut a: Vec<String> = blend_args(&base, &target, &[])
            .iter()
            .map(|x| x.to_string())
            .collect();
        for x in [
            "--frames",
            "5",
            "--interactive",
            "--interactive-cache",
            s(&cache),
            "--out",
            s(out),
            "--report",
            s(rep),
        ] {
            a.push(x.to_string());
        }
        a
    };
    ok(&refs(&args(&fast, &ri)));
    let r = report(&ri);
    assert_eq!(r["method"], "interactive");
    assert_eq!(r["interactive"]["loaded"], false);
    assert_eq!(r["interactive"]["snapshots"], 7);
    assert!(cache.is_file());
    let b = vertices(&base);
    let diag = {
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for p in &b {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    };
    for k in 0..5 {
        let name = format!("frame_{k:04}.obj");
        let (f, g) = (vertices(&full.join(&name)), vertices(&fast.join(&name)));
        let error = f
            .iter()
            .zip(&g)
            .map(|(p, q)| (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max)
            / diag;
        let estimate = r["frames"][k]["solver"]["error_estimate"].as_f64().unwrap();
        // (OBJ text keeps about 1e-6 of the coordinates.)
        assert!(
            error <= estimate + 1e-5,
            "frame {k}: {error:.2e} over {estimate:.2e}"
        );
        if k == 0 || k == 4 {
            assert_eq!(estimate, 0.0, "frame {k} is one-hot");
        }
    }
    // Interactive frames are judged by their estimate, not the gradient tolerance: no
    // unconverged region, and the frames named uncertain are those estimated over 1e-3.
    assert!(!d.join("fast-unconverged.ply").exists());
    assert_eq!(r["unconverged_frames"], serde_json::json!([]), "{r}");
    let over: Vec<usize> = (0..5)
        .filter(|&k| r["frames"][k]["solver"]["error_estimate"].as_f64().unwrap() > 1e-3)
        .collect();
    assert_eq!(
        r["interactive_uncertain_frames"],
        serde_json::json!(over),
        "{r}"
    );
    // Again with the cache: read, not prepared, and the same bytes.
    let (again, ra) = (d.join("again"), d.join("again.json"));
    ok(&refs(&args(&again, &ra)));
    assert_eq!(report(&ra)["interactive"]["loaded"], true);
    for k in 0..5 {
        let name = format!("frame_{k:04}.obj");
        assert_eq!(
            std::fs::read(fast.join(&name)).unwrap(),
            std::fs::read(again.join(&name)).unwrap(),
            "{name}"
        );
    }
    // --refine and --interactive-cache need --interactive; --linear excludes it; the cache
    // may not be an input.
    let x = d.join("x.obj");
    for (extra, says) in [
        (vec!["--refine", "1"], "--interactive"),
        (vec!["--interactive", "--linear"], "--linear"),
        (
            vec!["--interactive", "--interactive-cache", s(&target)],
            "--interactive-cache",
        ),
    ] {
        let mut rest = vec!["--alpha", "0.5", "--out", s(&x)];
        rest.extend(extra);
        let e = fails(&blend_args(&base, &target, &rest));
        assert!(e.contains(says), "{rest:?}: {e}");
    }
    assert!(!d.join("x.obj").exists());
}
