//! Issue 37 (artists' own assets): vertices split at seams and hard edges are one vertex for
//! the solve, and the result comes back in the input's own layout, equal to the unsplit one.

mod common;
use common::split::*;
use common::*;
use std::path::{Path, PathBuf};

/// The split meshes and, for each split vertex, its unsplit vertex.
fn split(shapes: &[Mesh], shuffle: bool) -> (Vec<Mesh>, Vec<usize>) {
    let s = Split::new(shapes, shuffle);
    (s.meshes, s.origin)
}

/// Blends `base` → `target` at α = ½, unsplit and split (appended and shuffled copies), and
/// returns the largest distance of a split result's vertex from its unsplit vertex, over the
/// diagonal, for (appended, shuffled); also checks the report's welded count.
fn split_against_unsplit(d: &Path, base: &Path, target: &Path) -> (f64, f64) {
    let reference = d.join("ref.obj");
    ok(&blend_args(
        base,
        target,
        &["--alpha", "0.5", "--out", s(&reference)],
    ));
    let unsplit = read(&reference).0;
    let diag = diagonal(&read(base).0);
    let mut errs = Vec::new();
    for shuffle in [false, true] {
        let (meshes, origin) = split(&[read(base), read(target)], shuffle);
        let (b, t): (PathBuf, PathBuf) = (d.join("b.obj"), d.join("t.obj"));
        write(&b, &meshes[0]);
        write(&t, &meshes[1]);
        let out = d.join("split.obj");
        let report = d.join("r.json");
        let (_, err) = run_ok(&blend_args(
            &b,
            &t,
            &["--alpha", "0.5", "--out", s(&out), "--report", s(&report)],
        ));
        let welded = origin.len() - unsplit.len();
        assert!(
            err.contains(&format!("welded {welded} split vertices")),
            "{err}"
        );
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(r["welded_vertices"], welded);
        let got = read(&out);
        assert_eq!(got.1, meshes[0].1, "the output keeps the input's faces");
        let e = got
            .0
            .iter()
            .zip(&origin)
            .map(|(p, &o)| {
                let q = unsplit[o];
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max);
        errs.push(e / diag);
    }
    (errs[0], errs[1])
}

#[test]
fn a_seam_split_tube_blends_as_the_unsplit_one() {
    let d = tmp_dir("weld-tube");
    let (a, b) = (d.join("a.obj"), d.join("bent.obj"));
    write_tube(&a, 24, 16, 1.0, 0.0);
    write_tube(&b, 24, 16, 1.0, 2.0);
    let (appended, shuffled) = split_against_unsplit(&d, &a, &b);
    assert_eq!(
        appended, 0.0,
        "copies after their originals weld to the same mesh"
    );
    assert!(shuffled < 1e-9, "{shuffled}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn vertices_that_part_in_a_target_are_not_welded() {
    let d = tmp_dir("weld-part");
    let (a, b) = (d.join("a.obj"), d.join("bent.obj"));
    write_tube(&a, 24, 16, 1.0, 0.0);
    write_tube(&b, 24, 16, 1.0, 2.0);
    let (mut meshes, _) = split(&[read(&a), read(&b)], false);
    // Move every copy in the target: the seam opens there, so nothing is welded.
    let n = read(&a).0.len();
    for p in &mut meshes[1].0[n..] {
        p[0] += 0.05;
    }
    let (sb, st) = (d.join("sb.obj"), d.join("st.obj"));
    write(&sb, &meshes[0]);
    write(&st, &meshes[1]);
    let report = d.join("r.json");
    let (_, err) = run_ok(&blend_args(
        &sb,
        &st,
        &[
            "--alpha",
            "0.5",
            "--out",
            s(&d.join("o.obj")),
            "--report",
            s(&report),
        ],
    ));
    assert!(!err.contains("welded"), "{err}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["welded_vertices"], 0);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_seam_split_real_cylinder_blends_as_the_unsplit_one() {
    let Some(data) = std::env::var_os("MORPHKIT_DATA") else {
        eprintln!("SKIPPED: MORPHKIT_DATA is not set");
        return;
    };
    let cyl = Path::new(&data).join("cragl-bending-cylinder");
    let (base, target) = (
        cyl.join("cylinder-rest.obj"),
        cyl.join("cylinder-bend-4.obj"),
    );
    assert!(
        base.exists() && target.exists(),
        "{} is missing",
        cyl.display()
    );
    let d = tmp_dir("weld-cylinder");
    let (appended, shuffled) = split_against_unsplit(&d, &base, &target);
    assert_eq!(appended, 0.0);
    assert!(shuffled < 1e-9, "{shuffled}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue 37: a triangle that uses a vertex twice and a vertex no triangle uses are carried,
/// not refused: warned about once, left out of the solve, and written back.
#[test]
fn degenerate_elements_are_carried_through_a_blend_and_read_back() {
    let d = tmp_dir("weld-degenerate");
    let (a, b) = (d.join("a.obj"), d.join("bent.obj"));
    write_tube(&a, 24, 16, 1.0, 0.0);
    write_tube(&b, 24, 16, 1.0, 2.0);
    let reference = d.join("ref.obj");
    ok(&blend_args(
        &a,
        &b,
        &["--alpha", "0.5", "--out", s(&reference)],
    ));
    for p in [&a, &b] {
        let mut m = read(p);
        m.1.push(vec![0, 0, 1]);
        write(p, &m);
    }
    let info = ok(&["info", s(&a)]);
    assert!(info.contains("1 triangles use a vertex twice"), "{info}");
    let out = d.join("out.obj");
    let (_, err) = run_ok(&blend_args(&a, &b, &["--alpha", "0.5", "--out", s(&out)]));
    assert!(
        err.contains("1 triangles use a vertex twice") && err.contains(": 720"),
        "{err}"
    );
    let got = read(&out);
    assert_eq!(
        got.1.last(),
        Some(&vec![0, 0, 1]),
        "the triangle is written back"
    );
    assert_eq!(
        got.0,
        read(&reference).0,
        "and changes nothing in the solve"
    );
    // morphkit reads what it wrote.
    ok(&["info", s(&out)]);
    let _ = std::fs::remove_dir_all(&d);
}
