use super::*;

/// A dressed PLY: two quads with float positions and normals, uchar colours, `s`/`t`, a double
/// custom scalar and a short list per vertex; faces with an index list and a uchar material;
/// an `edge` element; comments.
const HEADER: &str = "ply\nformat {FORMAT} 1.0\ncomment made by an artist\nelement vertex 6\n\
property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n\
property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
property float s\nproperty float t\nproperty double quality\n\
property list uchar short tags\nelement face 2\nproperty list uchar int vertex_indices\n\
property uchar material\nelement edge 1\nproperty int vertex1\nproperty int vertex2\n\
end_header\n";

/// Per vertex: position, normal, colour, s, t, quality, tags.
fn vertices() -> Vec<Vec<f64>> {
    (0..6)
        .map(|i| {
            let (x, y) = ((i % 3) as f64 * 0.5, (i / 3) as f64);
            let mut v = vec![x, y, 0.25, 0.0, 0.0, 1.0];
            v.extend([10.0 * i as f64, 200.0, 7.0 + i as f64, x / 1.5, 0.125 * y]);
            v.push(0.1 + i as f64 / 3.0);
            v.extend((0..i % 3).map(|k| -(k as f64) - 1.0));
            v
        })
        .collect()
}

const FACES: [([u32; 4], u8); 2] = [([0, 1, 4, 3], 3), ([1, 2, 5, 4], 9)];

/// Scalar types in declaration order of the vertex element (a list: its count then items).
const VTYPES: [Scalar; 12] = [
    Scalar::F32,
    Scalar::F32,
    Scalar::F32,
    Scalar::F32,
    Scalar::F32,
    Scalar::F32,
    Scalar::U8,
    Scalar::U8,
    Scalar::U8,
    Scalar::F32,
    Scalar::F32,
    Scalar::F64,
];

fn put(out: &mut Vec<u8>, s: Scalar, x: f64, enc: PlyEncoding) {
    if enc == PlyEncoding::Ascii {
        write!(out, "{} ", x).unwrap();
        return;
    }
    let mut b = match s {
        Scalar::U8 => vec![x as u8],
        Scalar::I16 => (x as i16).to_le_bytes().to_vec(),
        Scalar::I32 => (x as i32).to_le_bytes().to_vec(),
        Scalar::F32 => (x as f32).to_le_bytes().to_vec(),
        Scalar::F64 => x.to_le_bytes().to_vec(),
        _ => unreachable!(),
    };
    if enc == PlyEncoding::BinaryBigEndian {
        b.reverse();
    }
    out.extend(b);
}

fn encode(enc: PlyEncoding) -> Vec<u8> {
    let name = match enc {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    let mut out = HEADER.replace("{FORMAT}", name).into_bytes();
    let nl = |out: &mut Vec<u8>| {
        if enc == PlyEncoding::Ascii {
            out.pop();
            out.push(b'\n');
        }
    };
    for v in vertices() {
        for (k, &s) in VTYPES.iter().enumerate() {
            put(&mut out, s, v[k], enc);
        }
        put(&mut out, Scalar::U8, (v.len() - 12) as f64, enc);
        for &x in &v[12..] {
            put(&mut out, Scalar::I16, x, enc);
        }
        nl(&mut out);
    }
    for (f, m) in FACES {
        put(&mut out, Scalar::U8, 4.0, enc);
        for i in f {
            put(&mut out, Scalar::I32, i as f64, enc);
        }
        put(&mut out, Scalar::U8, m as f64, enc);
        nl(&mut out);
    }
    put(&mut out, Scalar::I32, 0.0, enc);
    put(&mut out, Scalar::I32, 5.0, enc);
    nl(&mut out);
    out
}

/// Every value of every element instance of a PLY, lists flattened with their counts.
fn decode(bytes: &[u8]) -> (Vec<u8>, Vec<Vec<Vec<f64>>>) {
    let p = Path::new("d.ply");
    let h = parse_header(p, bytes).unwrap();
    let big = h.encoding == PlyEncoding::BinaryBigEndian;
    let mut pos = h.body;
    let text = String::from_utf8_lossy(&bytes[h.body..]).into_owned();
    let mut words = text.split_ascii_whitespace();
    let mut next = |s: Scalar| -> f64 {
        if h.encoding == PlyEncoding::Ascii {
            return words.next().unwrap().parse().unwrap();
        }
        let x = scalar_at(bytes, pos, s, big).unwrap();
        pos += s.size();
        x
    };
    let mut all = Vec::new();
    for el in &h.elements {
        let mut rows = Vec::new();
        for _ in 0..el.count {
            let mut row = Vec::new();
            for prop in &el.props {
                match prop.kind {
                    Kind::Scalar(s) => row.push(next(s)),
                    Kind::List { count, item } => {
                        let n = next(count);
                        row.push(n);
                        for _ in 0..n as usize {
                            row.push(next(item));
                        }
                    }
                }
            }
            rows.push(row);
        }
        all.push(rows);
    }
    (bytes[..h.body].to_vec(), all)
}

#[test]
fn every_property_comes_back_with_new_positions_and_normals() {
    let d = std::env::temp_dir().join(format!("morphkit-plyt-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    // The quads folded along x = 0.5: a ridge whose normals are no longer +z.
    let new: Vec<Point> = (0..6)
        .map(|i| {
            let (x, y) = ((i % 3) as f64 * 0.5, (i / 3) as f64);
            [x, y + 1.0 / 3.0, 0.25 + (0.5 - (x - 0.5).abs()) * 0.7]
        })
        .collect();
    for enc in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let p = d.join(format!("dressed-{enc:?}.ply"));
        let original = encode(enc);
        std::fs::write(&p, &original).unwrap();
        let t = PlyTemplate::read(&p).unwrap();
        assert_eq!(t.num_vertices(), 6);
        let out = d.join(format!("out-{enc:?}.ply"));
        t.write(&out, &new).unwrap();
        let bytes = std::fs::read(&out).unwrap();
        // morphkit reads the positions back exactly, with the same faces.
        let m = parse_ply(&out, &bytes).unwrap();
        assert_eq!(m.positions, new, "{enc:?}");
        assert_eq!(m.polygons, parse_ply(&p, &original).unwrap().polygons);
        let (header, got) = decode(&bytes);
        let (old_header, want) = decode(&original);
        let header = String::from_utf8(header).unwrap();
        assert_eq!(
            header,
            String::from_utf8(old_header)
                .unwrap()
                .replace("float x\n", "double x\n")
                .replace("float y\n", "double y\n")
                .replace("float z\n", "double z\n"),
        );
        // Faces and edges byte for byte the same values; vertices too but for x..nz.
        assert_eq!(got[1..], want[1..], "{enc:?}");
        let normals = area_normals(&m, &new);
        for v in 0..6 {
            assert_eq!(got[0][v][6..], want[0][v][6..], "{enc:?} vertex {v}");
            assert_eq!(got[0][v][..3], new[v], "{enc:?} vertex {v}");
            let n = normals[v].unwrap();
            for k in 0..3 {
                assert_eq!(got[0][v][3 + k] as f32, n[k] as f32, "{enc:?} vertex {v}");
            }
        }
        // The middle column's normals point up, the others lean outwards.
        let n = |v: usize| got[0][v][3..6].to_vec();
        assert!(
            n(1)[2] > 0.99 && n(0)[0] < -0.5 && n(2)[0] > 0.5,
            "{:?}",
            [n(0), n(1), n(2)]
        );
        // Writing the template's own positions gives its values back.
        let same = t.fill(&out, &m.positions).unwrap();
        assert_eq!(decode(&same).1[1..], want[1..]);
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_wrong_vertex_count_names_the_template() {
    let d = std::env::temp_dir().join(format!("morphkit-plyt-n-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("t.ply");
    std::fs::write(&p, encode(PlyEncoding::BinaryLittleEndian)).unwrap();
    let t = PlyTemplate::read(&p).unwrap();
    let e = t
        .fill(&d.join("o.ply"), &[[0.0; 3]; 5])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("5 positions for the 6 vertices of") && e.contains("t.ply"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
