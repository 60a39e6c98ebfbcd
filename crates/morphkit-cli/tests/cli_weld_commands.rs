//! Issue 37 beyond `blend`: `transfer`, `rig`, `flex` and `blend --scene` solve on the welded
//! mesh (vertices split at seams and hard edges are one vertex) and write their results in the
//! input's own layout, equal to the unsplit mesh's; `info` counts the vertices to weld.

mod common;
use common::split::*;
use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Largest distance of a split result's vertex from its unsplit vertex, over the diagonal.
fn error(got: &Path, split: &Split, unsplit: &Path) -> f64 {
    let (g, u) = (read(got).0, read(unsplit).0);
    assert_eq!(g.len(), split.origin.len(), "the input's vertex count");
    let e = g
        .iter()
        .zip(&split.origin)
        .map(|(p, &o)| {
            let q = u[o];
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    e / diagonal(&u)
}

fn json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// A source tube with three bent frames, a target tube of another tessellation, markers.
struct Transfer {
    d: PathBuf,
    src: PathBuf,
    frames: Vec<PathBuf>,
    tgt: PathBuf,
    pairs: Vec<[usize; 2]>,
}

impl Transfer {
    fn new(name: &str) -> Self {
        let d = tmp_dir(name);
        let src = d.join("src.obj");
        write_tube(&src, 12, 7, 1.0, 0.0);
        let frames: Vec<PathBuf> = [0.3, 0.8, 1.4]
            .iter()
            .enumerate()
            .map(|(k, &b)| {
                let p = d.join(format!("frame-{k}.obj"));
                write_tube(&p, 12, 7, 1.0, b);
                p
            })
            .collect();
        let tgt = d.join("tgt.obj");
        write_tube(&tgt, 18, 10, 1.5, 0.0);
        let mut pairs = Vec::new();
        for (js, jt) in [(0, 0), (3, 9 / 2), (6, 9)] {
            for q in 0..4 {
                pairs.push([js * 12 + 3 * q, jt * 18 + (18 * q) / 4]);
            }
        }
        Self {
            d,
            src,
            frames,
            tgt,
            pairs,
        }
    }

    fn markers(&self, name: &str, map: impl Fn([usize; 2]) -> [usize; 2]) -> PathBuf {
        let p = self.d.join(name);
        let pairs: Vec<[usize; 2]> = self.pairs.iter().map(|&q| map(q)).collect();
        std::fs::write(&p, serde_json::json!({ "pairs": pairs }).to_string()).unwrap();
        p
    }

    /// The split source (reference and frames, one split) and target, in `tag`-named files.
    fn split(&self, tag: &str, shuffle: bool) -> (PathBuf, Vec<PathBuf>, PathBuf, Split, Split) {
        let src = self.d.join(format!("{tag}-src.obj"));
        let frames: Vec<PathBuf> = (0..self.frames.len())
            .map(|k| self.d.join(format!("{tag}-frame-{k}.obj")))
            .collect();
        let mut inputs = vec![self.src.clone()];
        inputs.extend(self.frames.iter().cloned());
        let mut outputs = vec![src.clone()];
        outputs.extend(frames.iter().cloned());
        let ss = Split::files(&inputs, &outputs, shuffle);
        let tgt = self.d.join(format!("{tag}-tgt.obj"));
        let ts = Split::files(
            std::slice::from_ref(&self.tgt),
            std::slice::from_ref(&tgt),
            shuffle,
        );
        (src, frames, tgt, ss, ts)
    }
}

fn transfer_args<'a>(
    src: &'a Path,
    frames: &'a [PathBuf],
    tgt: &'a Path,
    markers: &'a Path,
    out: &'a Path,
) -> Vec<&'a str> {
    let mut a = vec!["transfer", "--source-ref", s(src), "--source"];
    a.extend(frames.iter().map(|p| s(p)));
    a.extend(["--target", s(tgt), "--markers", s(markers), "--out", s(out)]);
    a
}

#[test]
fn transfer_welds_split_source_and_target() {
    let t = Transfer::new("weld-transfer");
    let m = t.markers("m.json", |q| q);
    let reference = t.d.join("ref");
    ok(&transfer_args(&t.src, &t.frames, &t.tgt, &m, &reference));
    for (tag, shuffle) in [("appended", false), ("shuffled", true)] {
        let (src, frames, tgt, ss, ts) = t.split(tag, shuffle);
        let m = t.markers(&format!("{tag}-m.json"), |[a, b]| [ss.id(a), ts.id(b)]);
        let out = t.d.join(format!("{tag}-out"));
        let report = t.d.join(format!("{tag}-r.json"));
        let mut args = transfer_args(&src, &frames, &tgt, &m, &out);
        args.extend(["--report", s(&report)]);
        let (_, err) = run_ok(&args);
        for n in [ss.copies(), ts.copies()] {
            assert!(err.contains(&format!("welded {n} split vertices")), "{err}");
        }
        let r = json(&report);
        assert_eq!(r["welded_vertices"]["source"], ss.copies());
        assert_eq!(r["welded_vertices"]["target"], ts.copies());
        for k in 0..t.frames.len() {
            let name = format!("frame_{k:04}.obj");
            let got = read(&out.join(&name));
            assert_eq!(got.1, ts.meshes[0].1, "the output keeps the target's faces");
            let e = error(&out.join(&name), &ts, &reference.join(&name));
            assert!(e < 1e-9, "{tag} frame {k}: {e}");
        }
    }
    let _ = std::fs::remove_dir_all(&t.d);
}

/// Issue 37: an OBJ target comes back as the artist's file, with the transferred positions.
#[test]
fn transfer_writes_into_the_targets_own_obj() {
    let t = Transfer::new("assets-transfer");
    let m = t.markers("m.json", |q| q);
    let reference = t.d.join("ref");
    ok(&transfer_args(&t.src, &t.frames, &t.tgt, &m, &reference));
    let dressed = t.d.join("dressed-target.obj");
    dress(&t.tgt, &dressed);
    let out = t.d.join("dressed-out");
    ok(&transfer_args(&t.src, &t.frames, &dressed, &m, &out));
    let not_v = |l: &str| !l.starts_with("v ") && !l.starts_with("vn ");
    for k in 0..t.frames.len() {
        let name = format!("frame_{k:04}.obj");
        assert_eq!(records(&out.join(&name), not_v), records(&dressed, not_v));
        assert_eq!(read(&out.join(&name)).0, read(&reference.join(&name)).0);
    }
    let _ = std::fs::remove_dir_all(&t.d);
}

#[test]
fn correspond_welds_and_writes_for_the_input_meshes() {
    let t = Transfer::new("weld-correspond");
    let m = t.markers("m.json", |q| q);
    let reference = t.d.join("ref");
    ok(&transfer_args(&t.src, &t.frames, &t.tgt, &m, &reference));
    let (src, frames, tgt, ss, ts) = t.split("shuffled", true);
    let m = t.markers("split-m.json", |[a, b]| [ss.id(a), ts.id(b)]);
    let (corr, report) = (t.d.join("corr.json"), t.d.join("corr-report.json"));
    let (_, err) = run_ok(&[
        "correspond",
        "--source",
        s(&src),
        "--target",
        s(&tgt),
        "--markers",
        s(&m),
        "--out",
        s(&corr),
        "--report",
        s(&report),
    ]);
    for n in [ss.copies(), ts.copies()] {
        assert!(err.contains(&format!("welded {n} split vertices")), "{err}");
    }
    assert_eq!(json(&report)["welded_vertices"]["target"], ts.copies());
    let c = json(&corr);
    assert_eq!(c["source_vertices"], ss.origin.len(), "input numbering");
    assert_eq!(c["target_vertices"], ts.origin.len(), "input numbering");
    let out = t.d.join("out");
    let mut args = vec!["transfer", "--source-ref", s(&src), "--source"];
    args.extend(frames.iter().map(|p| s(p)));
    args.extend([
        "--target",
        s(&tgt),
        "--correspondence",
        s(&corr),
        "--out",
        s(&out),
    ]);
    ok(&args);
    for k in 0..t.frames.len() {
        let name = format!("frame_{k:04}.obj");
        let e = error(&out.join(&name), &ts, &reference.join(&name));
        assert!(e < 1e-9, "frame {k}: {e}");
    }
    let _ = std::fs::remove_dir_all(&t.d);
}

#[test]
fn transfer_does_not_weld_a_source_seam_that_opens_in_a_frame() {
    let t = Transfer::new("weld-transfer-part");
    let (src, frames, tgt, ss, ts) = t.split("split", false);
    // Move every copy in the last frame: the source's seam opens there.
    let mut last = read(frames.last().unwrap());
    let n = ss.origin.len() - ss.copies();
    for p in &mut last.0[n..] {
        p[0] += 0.05;
    }
    write(frames.last().unwrap(), &last);
    let m = t.markers("m.json", |[a, b]| [ss.id(a), ts.id(b)]);
    let (out, report) = (t.d.join("out"), t.d.join("r.json"));
    let mut args = transfer_args(&src, &frames, &tgt, &m, &out);
    args.extend(["--report", s(&report)]);
    let (_, err) = run_ok(&args);
    assert!(!err.contains("hard edges) of the source"), "{err}");
    let r = json(&report);
    assert_eq!(r["welded_vertices"]["source"], 0);
    assert_eq!(r["welded_vertices"]["target"], ts.copies());
    let _ = std::fs::remove_dir_all(&t.d);
}

#[test]
fn rig_welds_split_source_and_target() {
    let t = Transfer::new("weld-rig");
    let m = t.markers("m.json", |q| q);
    let run = |src: &Path, frames: &[PathBuf], tgt: &Path, m: &Path, dir: &Path| {
        let glb = dir.with_extension("glb");
        let report = dir.with_extension("json");
        let mut a = vec!["rig", "--source-neutral", s(src), "--source-shapes"];
        a.extend(frames.iter().map(|p| s(p)));
        a.extend(["--target", s(tgt), "--markers", s(m), "--out", s(&glb)]);
        a.extend(["--shapes-dir", s(dir), "--report", s(&report)]);
        let (_, err) = run_ok(&a);
        (err, json(&report))
    };
    let reference = t.d.join("ref");
    run(&t.src, &t.frames, &t.tgt, &m, &reference);
    for (tag, shuffle) in [("appended", false), ("shuffled", true)] {
        let (src, frames, tgt, ss, ts) = t.split(tag, shuffle);
        let m = t.markers(&format!("{tag}-m.json"), |[a, b]| [ss.id(a), ts.id(b)]);
        let dir = t.d.join(format!("{tag}-shapes"));
        let (err, r) = run(&src, &frames, &tgt, &m, &dir);
        for n in [ss.copies(), ts.copies()] {
            assert!(err.contains(&format!("welded {n} split vertices")), "{err}");
        }
        assert_eq!(r["welded_vertices"]["source"], ss.copies());
        assert_eq!(r["welded_vertices"]["target"], ts.copies());
        for k in 0..t.frames.len() {
            // Shapes are named by the source files' stems.
            let (a, b) = (
                dir.join(format!("{tag}-frame-{k}.obj")),
                reference.join(format!("frame-{k}.obj")),
            );
            let e = error(&a, &ts, &b);
            assert!(e < 1e-9, "{tag} shape {k}: {e}");
        }
    }
    let _ = std::fs::remove_dir_all(&t.d);
}

#[test]
fn flex_welds_a_split_reference() {
    let t = Transfer::new("weld-flex");
    let run = |src: &Path, frames: &[PathBuf], tag: &str| {
        let (ply, j) = (
            t.d.join(format!("{tag}.ply")),
            t.d.join(format!("{tag}.json")),
        );
        let mut a = vec!["flex", "--reference", s(src), "--frames"];
        a.extend(frames.iter().map(|p| s(p)));
        a.extend(["--out", s(&ply), "--json", s(&j)]);
        let (_, err) = run_ok(&a);
        (err, json(&j))
    };
    let (_, want) = run(&t.src, &t.frames, "ref");
    let want: Vec<f64> = serde_json::from_value(want["flexibility"].clone()).unwrap();
    assert!(want.iter().any(|&f| f > 0.0));
    for (tag, shuffle) in [("appended", false), ("shuffled", true)] {
        let (src, frames, _, ss, _) = t.split(tag, shuffle);
        let (err, r) = run(&src, &frames, tag);
        assert!(
            err.contains(&format!("welded {} split vertices", ss.copies())),
            "{err}"
        );
        assert_eq!(r["welded_vertices"]["reference"], ss.copies());
        let got: Vec<f64> = serde_json::from_value(r["flexibility"].clone()).unwrap();
        assert_eq!(got.len(), want.len(), "one value per input triangle");
        let e = got
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(e < 1e-9, "{tag}: {e}");
    }
    let _ = std::fs::remove_dir_all(&t.d);
}

#[test]
fn flex_on_a_split_target_is_the_unsplit_one() {
    let t = Transfer::new("weld-flex-target");
    let run = |src: &Path, frames: &[PathBuf], tgt: &Path, m: &Path, tag: &str| {
        let (ply, j) = (
            t.d.join(format!("{tag}.ply")),
            t.d.join(format!("{tag}.json")),
        );
        let mut a = vec!["flex", "--reference", s(src), "--frames"];
        a.extend(frames.iter().map(|p| s(p)));
        a.extend(["--target", s(tgt), "--markers", s(m)]);
        a.extend(["--out", s(&ply), "--json", s(&j)]);
        ok(&a);
        json(&j)
    };
    let m = t.markers("m.json", |q| q);
    let want = run(&t.src, &t.frames, &t.tgt, &m, "ref");
    let want: Vec<f64> = serde_json::from_value(want["flexibility"].clone()).unwrap();
    let (src, frames, tgt, ss, ts) = t.split("shuffled", true);
    let m = t.markers("split-m.json", |[a, b]| [ss.id(a), ts.id(b)]);
    let r = run(&src, &frames, &tgt, &m, "split");
    assert_eq!(r["welded_vertices"]["target"], ts.copies());
    let got: Vec<f64> = serde_json::from_value(r["flexibility"].clone()).unwrap();
    assert_eq!(got.len(), want.len(), "one value per target triangle");
    let e = got
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(e < 1e-9, "{e}");
    let _ = std::fs::remove_dir_all(&t.d);
}

const SCENE: &str = r#"
base = "BASE"
targets = ["TARGET"]
[weights]
frames = 3
[[pull]]
vertex = PULLED
[[pull.key]]
frame = 0
position = START
[[pull.key]]
frame = 2
position = END
"#;

#[test]
fn a_scene_welds_its_split_rig_and_maps_pulled_vertices() {
    let d = tmp_dir("weld-scene");
    let (a, b) = (d.join("a.obj"), d.join("b.obj"));
    write_tube(&a, 16, 12, 1.0, 0.0);
    write_tube(&b, 16, 12, 1.0, 1.5);
    // A vertex on the seam of the top ring (y = 0), pulled outwards.
    let pulled = 11 * 16;
    let start = read(&b).0[pulled];
    let end = [start[0] + 0.3, start[1], start[2]];
    let scene = |base: &Path, target: &Path, v: usize, name: &str| {
        let text = SCENE
            .replace("BASE", s(base))
            .replace("TARGET", s(target))
            .replace("PULLED", &v.to_string())
            .replace("START", &format!("{start:?}"))
            .replace("END", &format!("{end:?}"));
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let reference = d.join("ref");
    let sc = scene(&a, &b, pulled, "ref.toml");
    ok(&["blend", "--scene", s(&sc), "--out", s(&reference)]);
    for (tag, shuffle) in [("appended", false), ("shuffled", true)] {
        let (sa, sb) = (
            d.join(format!("{tag}-a.obj")),
            d.join(format!("{tag}-b.obj")),
        );
        let split = Split::files(&[a.clone(), b.clone()], &[sa.clone(), sb.clone()], shuffle);
        let sc = scene(&sa, &sb, split.id(pulled), &format!("{tag}.toml"));
        let (out, report) = (d.join(format!("{tag}-out")), d.join(format!("{tag}.json")));
        let (_, err) = run_ok(&[
            "blend",
            "--scene",
            s(&sc),
            "--out",
            s(&out),
            "--report",
            s(&report),
        ]);
        assert!(
            err.contains(&format!("welded {} split vertices", split.copies())),
            "{err}"
        );
        assert_eq!(json(&report)["welded_vertices"], split.copies());
        for k in 0..3 {
            let name = format!("frame_{k:04}.obj");
            let e = error(&out.join(&name), &split, &reference.join(&name));
            assert!(e < 1e-9, "{tag} frame {k}: {e}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn info_counts_the_vertices_to_weld() {
    let d = tmp_dir("weld-info");
    let a = d.join("a.obj");
    write_tube(&a, 12, 7, 1.0, 0.0);
    let sa = d.join("split.obj");
    let split = Split::files(std::slice::from_ref(&a), std::slice::from_ref(&sa), true);
    let doc: Value = serde_json::from_str(&ok(&["info", "--json", s(&a), s(&sa)])).unwrap();
    assert_eq!(doc["files"][0]["welded_vertices"], 0);
    assert_eq!(doc["files"][1]["welded_vertices"], split.copies());
    let text = ok(&["info", s(&sa)]);
    assert!(
        text.contains(&format!("welded vertices        {}", split.copies())),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
