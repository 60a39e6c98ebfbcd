//! Issue 37 ("the asset comes back whole"): a blend of an artist's OBJ is that OBJ with new
//! positions and normals; texture coordinates, normal indices, materials, groups, smoothing
//! groups and comments come back as they were.

mod common;
use common::split::*;
use common::*;
use std::path::Path;

/// `plain` with a material library, a group, smoothing, a texture coordinate and a normal per
/// vertex, and faces that use them (`v/vt/vn`).
fn dress(plain: &Path, dressed: &Path) {
    let (v, f) = read(plain);
    let mut s = String::from("# exported by a DCC tool\nmtllib tube.mtl\no Tube\n");
    for p in &v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for (k, _) in v.iter().enumerate() {
        s += &format!("vt {} 0.5\n", k as f64 / v.len() as f64);
    }
    for _ in &v {
        s += "vn 0 0 1\n";
    }
    s += "g body\nusemtl skin\ns 1\n";
    for t in &f {
        s += "f";
        for &i in t {
            s += &format!(" {0}/{0}/{0}", i + 1);
        }
        s += "\n";
    }
    std::fs::write(dressed, s).unwrap();
}

fn records(p: &Path, keep: impl Fn(&str) -> bool) -> Vec<String> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter(|l| keep(l))
        .map(String::from)
        .collect()
}

#[test]
fn a_blend_of_an_artists_obj_keeps_every_record_and_updates_positions_and_normals() {
    let d = tmp_dir("assets-obj");
    let (a, b) = (d.join("a.obj"), d.join("b.obj"));
    write_tube(&a, 16, 10, 1.0, 0.0);
    write_tube(&b, 16, 10, 1.0, 2.0);
    let plain = d.join("plain.obj");
    ok(&blend_args(&a, &b, &["--alpha", "0.5", "--out", s(&plain)]));
    let (da, db) = (d.join("da.obj"), d.join("db.obj"));
    dress(&a, &da);
    dress(&b, &db);
    let out = d.join("dressed.obj");
    ok(&blend_args(&da, &db, &["--alpha", "0.5", "--out", s(&out)]));
    let frames = d.join("frames");
    ok(&blend_args(
        &da,
        &db,
        &["--frames", "3", "--out", s(&frames)],
    ));
    let not_v = |l: &str| !l.starts_with("v ") && !l.starts_with("vn ");
    for got in [out.clone(), frames.join("frame_0001.obj")] {
        // Everything but positions and normals is the input's, line for line.
        assert_eq!(
            records(&got, not_v),
            records(&da, not_v),
            "{}",
            got.display()
        );
        // Positions are the blend's (the same solve as the plain file's).
        assert_eq!(read(&got).0, read(&plain).0);
        // Normals are recomputed: unit length, no longer all (0, 0, 1) on a bent tube.
        let normals = records(&got, |l| l.starts_with("vn "));
        assert_eq!(normals.len(), read(&a).0.len());
        let n: Vec<[f64; 3]> = normals
            .iter()
            .map(|l| {
                let t: Vec<f64> = l[3..]
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                [t[0], t[1], t[2]]
            })
            .collect();
        assert!(n
            .iter()
            .all(|q| ((q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() - 1.0).abs() < 1e-12));
        assert!(n.iter().filter(|q| q[2].abs() < 0.9).count() > n.len() / 2);
    }
    let _ = std::fs::remove_dir_all(&d);
}
