//! Issue 37 ("the asset comes back whole"): a blend of an artist's OBJ is that OBJ with new
//! positions and normals; texture coordinates, normal indices, materials, groups, smoothing
//! groups and comments come back as they were.

mod common;
use common::split::*;
use common::*;

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
    // `convert` of an OBJ to an OBJ keeps the records too.
    let copy = d.join("copy.obj.gz");
    ok(&["convert", s(&da), s(&copy)]);
    let plain_copy = d.join("copy.obj");
    ok(&["convert", s(&copy), s(&plain_copy)]);
    assert_eq!(records(&plain_copy, not_v), records(&da, not_v));
    assert_eq!(read(&plain_copy).0, read(&da).0);
    let _ = std::fs::remove_dir_all(&d);
}
