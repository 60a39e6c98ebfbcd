//! Helpers shared by the CLI tests: run the built `morphkit` binary and check its outcome.
#![allow(dead_code)]

pub mod split;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty temporary directory for one test.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `morphkit ARGS`.
pub fn morphkit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .args(args)
        .output()
        .expect("run morphkit")
}

/// Runs `morphkit ARGS`, asserts success, and returns `(stdout, stderr)`.
pub fn run_ok(args: &[&str]) -> (String, String) {
    let out = morphkit(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "morphkit {args:?} failed: {err}");
    (String::from_utf8_lossy(&out.stdout).into_owned(), err)
}

/// Runs `morphkit ARGS`, asserts success, and returns stdout.
pub fn ok(args: &[&str]) -> String {
    run_ok(args).0
}

/// Runs `morphkit ARGS`, asserts a failure reported as one `error: …` message without a
/// panic, and returns stderr.
pub fn fails(args: &[&str]) -> String {
    let out = morphkit(args);
    assert!(!out.status.success(), "morphkit {args:?} should fail");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// A path as `&str`.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// An open tube of `nu` × `nv` vertices along z (height 4), bent by `bend` radians about the
/// y axis and scaled by `scale`, written as OBJ.
pub fn write_tube(path: &std::path::Path, nu: usize, nv: usize, scale: f64, bend: f64) {
    let h = 4.0;
    let mut text = String::new();
    for j in 0..nv {
        let z = h * j as f64 / (nv - 1) as f64;
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            let (x, y) = (a.cos(), a.sin());
            let (px, pz) = if bend == 0.0 {
                (x, z)
            } else {
                let r = h / bend;
                let th = bend * z / h;
                (r - (r - x) * th.cos(), (r - x) * th.sin())
            };
            text += &format!("v {} {} {}\n", scale * px, scale * y, scale * pz);
        }
    }
    ring_faces(&mut text, nv, nu);
    std::fs::write(path, text).unwrap();
}

/// Appends the OBJ faces joining `rings` consecutive rings of `around` vertices each (ring `j`
/// holds vertices `j · around …`, each ring closed), two triangles per quad.
fn ring_faces(text: &mut String, rings: usize, around: usize) {
    let id = |i: usize, j: usize| j * around + i % around + 1;
    for j in 0..rings - 1 {
        for i in 0..around {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            *text += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
}

/// An annulus of 3 rings of 160 vertices (radii 0.85…1.15) lying on a sphere of radius 1.5,
/// squashed in y by `squash` (1: as made), as an eye-occlusion strip over an eyeball that
/// closes (the library's `tests/springs_bands.rs` case, without its bar).
pub fn write_annulus(path: &std::path::Path, squash: f64) {
    let cap = |x: f64, y: f64| (2.25 - x * x - y * y).sqrt();
    let (rows, around) = (3usize, 160usize);
    let mut text = String::new();
    for i in 0..rows {
        let r = 0.85 + 0.3 * i as f64 / (rows - 1) as f64;
        for j in 0..around {
            let t = std::f64::consts::TAU * j as f64 / around as f64;
            let (x, y) = (r * t.cos(), squash * r * t.sin());
            text += &format!("v {x} {y} {}\n", cap(x, y));
        }
    }
    ring_faces(&mut text, rows, around);
    std::fs::write(path, text).unwrap();
}

/// `blend --base BASE --target TARGET` followed by `rest`.
pub fn blend_args<'a>(base: &'a Path, target: &'a Path, rest: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["blend", "--base", s(base), "--target", s(target)];
    v.extend_from_slice(rest);
    v
}

/// A bar, four bent frames, a scribble of its far half and a recipe, in `d`.
pub fn synth_bar(d: &Path) {
    std::fs::create_dir_all(d.join("frames")).unwrap();
    let bar = morphkit::mesh::generate::bar(4.0, 0.5, 2, 32);
    morphkit::io::write_mesh(&d.join("bar.obj"), &bar).unwrap();
    for k in 0..4 {
        let a = (k as f64 + 1.0) * 30f64.to_radians();
        let bent = bar.with_positions(morphkit::mesh::generate::bend(&bar.positions, 1.9, 0.25, a));
        morphkit::io::write_mesh(&d.join(format!("frames/bend-{k}.obj")), &bent).unwrap();
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

/// The `v` lines of an OBJ file.
pub fn obj_vertices(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}
