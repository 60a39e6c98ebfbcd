//! Issue 37 ("the asset comes back whole"), PLY: a blend of an artist's PLY written as `.ply`
//! is that PLY with new positions and normals; colours, texture coordinates, custom scalars and
//! face properties come back exactly, in ascii and binary (little and big endian) files.

mod common;
use common::split::read;
use common::*;
use std::path::Path;

/// (format name, byte order, position type)
const FORMATS: [(&str, Option<bool>, &str); 3] = [
    ("ascii", None, "double"),
    ("binary_little_endian", Some(false), "double"),
    ("binary_big_endian", Some(true), "float"),
];

/// One property value in the file's encoding.
fn put(out: &mut Vec<u8>, ty: &str, x: f64, big: Option<bool>) {
    let Some(big) = big else {
        out.extend(format!("{x} ").bytes());
        return;
    };
    let mut b = match ty {
        "uchar" => vec![x as u8],
        "int" => (x as i32).to_le_bytes().to_vec(),
        "float" => (x as f32).to_le_bytes().to_vec(),
        _ => x.to_le_bytes().to_vec(),
    };
    if big {
        b.reverse();
    }
    out.extend(b);
}

/// The OBJ `obj` as a dressed PLY: per vertex position, normal, colour, u, v and a quality;
/// per face its indices and a material byte.
fn dress_ply(obj: &Path, ply: &Path, (format, big, xyz): (&str, Option<bool>, &str)) {
    let (v, f) = read(obj);
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment exported by a DCC\nelement vertex {}\n\
         property {xyz} x\nproperty {xyz} y\nproperty {xyz} z\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nproperty float u\nproperty float v\nproperty double quality\n\
         element face {}\nproperty list uchar int vertex_indices\nproperty uchar material\n\
         end_header\n",
        v.len(),
        f.len()
    )
    .into_bytes();
    let end = |out: &mut Vec<u8>| {
        if big.is_none() {
            out.pop();
            out.push(b'\n');
        }
    };
    for (i, p) in v.iter().enumerate() {
        let vals = [
            (xyz, p[0]),
            (xyz, p[1]),
            (xyz, p[2]),
            ("float", 0.0),
            ("float", 0.0),
            ("float", 1.0),
            ("uchar", (i * 37 % 256) as f64),
            ("uchar", 128.0),
            ("uchar", (255 - i % 256) as f64),
            ("float", (i % 16) as f64 / 16.0),
            ("float", 0.1 * (i / 16) as f64),
            ("double", 1.0 / (1.0 + i as f64)),
        ];
        for (ty, x) in vals {
            put(&mut out, ty, x, big);
        }
        end(&mut out);
    }
    for (k, face) in f.iter().enumerate() {
        put(&mut out, "uchar", face.len() as f64, big);
        for &i in face {
            put(&mut out, "int", i as f64, big);
        }
        put(&mut out, "uchar", (k % 5) as f64, big);
        end(&mut out);
    }
    std::fs::write(ply, out).unwrap();
}

/// The header's property lines and every value of every vertex and face (lists flattened
/// with their counts), decoded by the header's types.
fn decode(ply: &Path) -> (Vec<String>, Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let b = std::fs::read(ply).unwrap();
    let end = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8(b[..end].to_vec()).unwrap();
    let mut elements: Vec<(usize, Vec<Vec<String>>)> = Vec::new();
    let mut big = None;
    for l in header.lines() {
        let t: Vec<String> = l.split_whitespace().map(String::from).collect();
        match t[0].as_str() {
            "format" if t[1] != "ascii" => big = Some(t[1] == "binary_big_endian"),
            "element" => elements.push((t[2].parse().unwrap(), Vec::new())),
            "property" => elements.last_mut().unwrap().1.push(t[1..].to_vec()),
            _ => {}
        }
    }
    let text = String::from_utf8_lossy(&b[end..]).into_owned();
    let mut words = text.split_whitespace();
    let mut pos = end;
    let mut next = |ty: &str| -> f64 {
        let Some(big) = big else {
            return words.next().unwrap().parse().unwrap();
        };
        let n = match ty {
            "uchar" => 1,
            "int" | "float" => 4,
            _ => 8,
        };
        let mut a = b[pos..pos + n].to_vec();
        pos += n;
        if big {
            a.reverse();
        }
        match ty {
            "uchar" => a[0] as f64,
            "int" => i32::from_le_bytes(a.try_into().unwrap()) as f64,
            "float" => f32::from_le_bytes(a.try_into().unwrap()) as f64,
            _ => f64::from_le_bytes(a.try_into().unwrap()),
        }
    };
    let mut rows: Vec<Vec<Vec<f64>>> = Vec::new();
    for (count, props) in &elements {
        let mut el = Vec::new();
        for _ in 0..*count {
            let mut row = Vec::new();
            for p in props {
                if p[0] == "list" {
                    let n = next(&p[1]);
                    row.push(n);
                    for _ in 0..n as usize {
                        row.push(next(&p[2]));
                    }
                } else {
                    row.push(next(&p[0]));
                }
            }
            el.push(row);
        }
        rows.push(el);
    }
    let props = header
        .lines()
        .filter(|l| l.starts_with("property"))
        .map(String::from)
        .collect();
    (props, rows[0].clone(), rows[1].clone())
}

#[test]
fn a_blend_of_an_artists_ply_keeps_every_property_and_updates_positions_and_normals() {
    let d = tmp_dir("assets-ply");
    let (a, b) = (d.join("a.obj"), d.join("b.obj"));
    write_tube(&a, 16, 10, 1.0, 0.0);
    write_tube(&b, 16, 10, 1.0, 2.0);
    for fmt in FORMATS {
        let da = d.join(format!("dressed-{}.ply", fmt.0));
        dress_ply(&a, &da, fmt);
        // The same positions without the dressing, blended to a plain PLY.
        let pa = d.join(format!("plain-{}.obj", fmt.0));
        ok(&["convert", s(&da), s(&pa)]);
        let plain = d.join(format!("plain-{}.ply", fmt.0));
        ok(&blend_args(
            &pa,
            &b,
            &["--alpha", "0.5", "--out", s(&plain)],
        ));
        let out = d.join(format!("blend-{}.ply", fmt.0));
        ok(&blend_args(&da, &b, &["--alpha", "0.5", "--out", s(&out)]));
        let copy = d.join(format!("copy-{}.ply", fmt.0));
        ok(&["convert", s(&da), s(&copy)]);
        let (props_in, v_in, f_in) = decode(&da);
        // Positions: the plain blend's exactly (compared through OBJ, written exactly).
        let (o1, o2) = (d.join("o1.obj"), d.join("o2.obj"));
        ok(&["convert", s(&out), s(&o1), "--force"]);
        ok(&["convert", s(&plain), s(&o2), "--force"]);
        assert_eq!(read(&o1).0, read(&o2).0, "{}", fmt.0);
        for (got, moved) in [(&out, true), (&copy, false)] {
            let (props, v, f) = decode(got);
            let want: Vec<String> = props_in
                .iter()
                .map(|p| {
                    p.replace("float x", "double x")
                        .replace("float y", "double y")
                        .replace("float z", "double z")
                })
                .collect();
            assert_eq!(props, want, "{}", got.display());
            // Faces with their material, and every vertex value but position and normal.
            assert_eq!(f, f_in, "{}", got.display());
            assert_eq!(v.len(), v_in.len());
            for (p, q) in v.iter().zip(&v_in) {
                assert_eq!(p[6..], q[6..], "{}", got.display());
            }
            // Normals: recomputed (the file's were all +z), unit, radial on the straight tube
            // (along z), leaning in z where the blend bends it.
            let leaning = v.iter().filter(|p| p[5].abs() > 0.1).count();
            for p in &v {
                let len = (p[3] * p[3] + p[4] * p[4] + p[5] * p[5]).sqrt();
                assert!((len - 1.0).abs() < 1e-6, "{}: {p:?}", got.display());
                assert!(p[5] < 0.99, "{}: {p:?}", got.display());
            }
            assert_eq!(leaning > v.len() / 4, moved, "{}: {leaning}", got.display());
            if !moved {
                assert_eq!(leaning, 0, "{}", got.display());
            }
        }
        // The copy's positions are the input's.
        let o3 = d.join("o3.obj");
        ok(&["convert", s(&copy), s(&o3), "--force"]);
        assert_eq!(read(&o3).0, read(&pa).0, "{}", fmt.0);
    }
    let _ = std::fs::remove_dir_all(&d);
}
