//! `morphkit correspond` and `morphkit transfer`, run as the built binary on generated tubes.

mod common;
use common::*;

use std::path::{Path, PathBuf};

/// Writes an open tube (`nu` around, `nv` rings, scaled by `scale`), bent by `bend` radians
/// over its height, as OBJ. `flip` reverses the first triangle (other connectivity).
fn write_tube(path: &Path, nu: usize, nv: usize, scale: f64, bend: f64, flip: bool) {
    let mut text = String::new();
    let h = 4.0;
    for j in 0..nv {
        let z = h * j as f64 / (nv - 1) as f64;
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            let (x, y) = (a.cos(), a.sin());
            let th = bend * z / h;
            let (px, pz) = if bend == 0.0 {
                (x, z)
            } else {
                let r = h / bend;
                (r - (r - x) * th.cos(), (r - x) * th.sin())
            };
            text += &format!("v {} {} {}\n", scale * px, scale * y, scale * pz);
        }
    }
    let id = |i: usize, j: usize| j * nu + i % nu + 1;
    let mut first = true;
    for j in 0..nv - 1 {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if first && flip {
                text += &format!("f {a} {c} {b}\n");
            } else {
                text += &format!("f {a} {b} {c}\n");
            }
            first = false;
            text += &format!("f {a} {c} {d}\n");
        }
    }
    std::fs::write(path, text).unwrap();
}

/// Source tube, three bent frames, a differently tessellated target and markers.
fn setup(name: &str) -> (PathBuf, PathBuf, Vec<PathBuf>, PathBuf, PathBuf) {
    let d = tmp_dir(name);
    let src = d.join("src.obj");
    write_tube(&src, 12, 7, 1.0, 0.0, false);
    let frames: Vec<PathBuf> = [0.3, 0.8, 1.4]
        .iter()
        .enumerate()
        .map(|(k, &b)| {
            let p = d.join(format!("frame-{k}.obj"));
            write_tube(&p, 12, 7, 1.0, b, false);
            p
        })
        .collect();
    let tgt = d.join("tgt.obj");
    write_tube(&tgt, 18, 10, 1.5, 0.0, false);
    let mut pairs = Vec::new();
    for (js, jt) in [(0, 0), (3, 9 / 2), (6, 9)] {
        for q in 0..4 {
            pairs.push(format!("[{}, {}]", js * 12 + 3 * q, jt * 18 + (18 * q) / 4));
        }
    }
    let markers = d.join("markers.json");
    std::fs::write(&markers, format!("{{\"pairs\": [{}]}}", pairs.join(", "))).unwrap();
    (d, src, frames, tgt, markers)
}

#[test]
fn correspond_then_transfer_to_obj_frames_and_pc2() {
    let (d, src, frames, tgt, markers) = setup("ok");
    let corr = d.join("corr.json");
    let correspond = [
        "correspond",
        "--source",
        s(&src),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
    ];
    let (_, err) = run_ok(
        &[
            &correspond[..],
            &[
                "--out",
                s(&corr),
                "--warped-source",
                s(&d.join("ws.obj")),
                "--report",
                s(&d.join("corr-report.json")),
                "--confidence",
                s(&d.join("confidence.ply")),
            ],
        ]
        .concat(),
    );
    assert!(
        err.contains("correspondence: 324 target triangles"),
        "{err}"
    );
    assert!(err.contains("match confidence: mean"), "{err}");
    let ply = std::fs::read(d.join("confidence.ply")).unwrap();
    let header = String::from_utf8_lossy(&ply[..ply.len().min(400)]).to_string();
    assert!(
        header.starts_with("ply") && header.contains("red"),
        "{header}"
    );
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&corr).unwrap()).unwrap();
    assert_eq!(c["offsets"].as_array().unwrap().len(), 18 * 9 * 2 + 1);
    assert!(d.join("ws.obj").is_file());
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("corr-report.json")).unwrap())
            .unwrap();
    assert_eq!(rep["marker_residuals"].as_array().unwrap().len(), 12);
    // A tube onto a wider tube with matching markers: its matches face its way almost
    // everywhere, and the doubtful triangles listed are the fraction given.
    let mc = &rep["match_confidence"];
    let mean = mc["mean"].as_f64().unwrap();
    assert!(mean > 0.8 && mean <= 1.0, "{mc}");
    let low = mc["low_triangles"].as_array().unwrap().len() as f64;
    assert!(
        (mc["low_fraction"].as_f64().unwrap() - low / 324.0).abs() < 1e-12,
        "{mc}"
    );
    let c2 = d.join("c2.json");
    let bad_ply = d.join("confidence.obj");
    let rest = ["--out", s(&c2), "--confidence", s(&bad_ply)];
    let e = fails(&[&correspond[..], &rest[..]].concat());
    assert!(e.contains("--confidence") && e.contains(".ply"), "{e}");

    let out = d.join("out");
    let report = d.join("report.json");
    let glob = format!("{}/frame-*.obj", d.display());
    ok(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        &glob,
        "--target",
        s(&tgt),
        "--correspondence",
        s(&corr),
        "--out",
        s(&out),
        "--report",
        s(&report),
    ]);
    for k in 0..3 {
        let f = out.join(format!("frame_{k:04}.obj"));
        let text = std::fs::read_to_string(&f).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 180);
        assert!(!text.contains("NaN"));
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    for key in ["correspondence_s", "factorization_s", "solve_per_frame_s"] {
        assert!(
            r["timings"][key].as_f64().is_some(),
            "report lacks {key}: {r}"
        );
    }
    assert_eq!(r["frames"], 3);

    // Markers instead of a correspondence, a point cache out.
    let pc2 = d.join("out.pc2");
    let mut args = vec!["transfer", "--source-ref", s(&src), "--source"];
    let fs: Vec<&str> = frames.iter().map(|p| s(p)).collect();
    args.extend(fs);
    args.extend([
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&pc2),
    ]);
    let rep2 = d.join("markers-report.json");
    args.extend(["--fixed-vertex", "--report", s(&rep2)]);
    let (_, err) = run_ok(&args);
    assert!(std::fs::metadata(&pc2).unwrap().len() > 3 * 180 * 12);
    // The correspondence computed from markers reports its match confidence too, the same as
    // `correspond` gives for the same meshes and markers.
    assert!(err.contains("match confidence: mean"), "{err}");
    let rep2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep2).unwrap()).unwrap();
    assert_eq!(rep2["correspondence"]["match_confidence"], *mc);
}

#[test]
fn bad_transfer_input_is_a_clear_error() {
    let (d, src, frames, tgt, _) = setup("bad");
    let bad = d.join("bad-markers.json");
    std::fs::write(
        &bad,
        r#"{"pairs": [[0, 0], [3, 4], [40, 9999], [80, 170]]}"#,
    )
    .unwrap();
    let err = fails(&[
        "correspond",
        "--source",
        s(&src),
        "--target",
        s(&tgt),
        "--markers",
        s(&bad),
        "--out",
        s(&d.join("c.json")),
    ]);
    assert!(
        err.contains("marker 2: target vertex 9999 is out of range"),
        "{err}"
    );

    let odd = d.join("odd.obj");
    write_tube(&odd, 12, 7, 1.0, 0.5, true);
    let markers = d.join("markers.json");
    let err = fails(&[
        "transfer",
        "--source-ref",
        s(&src),
        "--source",
        s(&frames[0]),
        s(&odd),
        "--target",
        s(&tgt),
        "--markers",
        s(&markers),
        "--out",
        s(&d.join("o")),
    ]);
    assert!(
        err.contains("odd.obj") && err.contains("triangle 0"),
        "{err}"
    );
}
