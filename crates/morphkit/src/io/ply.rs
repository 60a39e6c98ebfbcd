//! Stanford PLY: ascii, `binary_little_endian` and `binary_big_endian`.
//!
//! Reading takes the `vertex` element's `x`, `y`, `z` (any scalar type) and the `face`
//! element's `vertex_indices` or `vertex_index` list (any count and item type); other elements
//! and properties are parsed only to be skipped. This is a small parser of our own rather than
//! `ply-rs`, so that a truncated binary body gives an error naming the byte offset, the element
//! and the property instead of a generic end-of-file, and so that no per-element allocation
//! (a property map per vertex) is needed.
//!
//! Writing uses `double` coordinates (lossless) and `int` indices, binary little endian by
//! default; [`write_ply_colored`] adds `uchar red, green, blue` per vertex or per face.

use super::source::{parse_f64, show, tokens};
use super::IoError;
use crate::mesh::{Point, Polygons, TriMesh};
use std::path::Path;

/// How the body of a PLY file is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    /// Text.
    Ascii,
    /// Binary, little endian (the default: compact and what most tools write).
    #[default]
    BinaryLittleEndian,
    /// Binary, big endian.
    BinaryBigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The value of `bytes` (exactly [`Scalar::size`] of them) in this type, little endian
    /// unless `big`.
    pub(super) fn decode(self, bytes: &[u8], big: bool) -> f64 {
        let n = self.size();
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(&bytes[..n]);
        if big {
            a[..n].reverse();
        }
        match self {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        }
    }

    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<Property>,
}

pub(super) struct Header {
    pub(super) encoding: PlyEncoding,
    pub(super) elements: Vec<Element>,
    /// Byte offset of the body.
    pub(super) body: usize,
    /// Number of header lines (body line numbers follow).
    lines: usize,
}

pub(super) fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, IoError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let rest = &bytes[pos..];
        let end = rest.iter().position(|&b| b == b'\n').ok_or_else(|| {
            IoError::parse(path, line_no + 1, "the header ends before 'end_header'")
        })?;
        line_no += 1;
        let line = String::from_utf8_lossy(&rest[..end]);
        let line = line.trim();
        pos += end + 1;
        let mut t = line.split_ascii_whitespace();
        let key = t.next().unwrap_or("");
        let err = |m: String| IoError::parse(path, line_no, m);
        if line_no == 1 {
            if line != "ply" {
                return Err(err("not a PLY file: the first line is not 'ply'".into()));
            }
            continue;
        }
        match key {
            "format" => {
                encoding = Some(match t.next() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some("binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    other => return Err(err(format!("unknown format {other:?}"))),
                })
            }
            "element" => {
                let name = t
                    .next()
                    .ok_or_else(|| err("element without a name".into()))?;
                let count = t
                    .next()
                    .and_then(|c| c.parse().ok())
                    .ok_or_else(|| err(format!("element '{name}' without a valid count")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err("property before any element".into()))?;
                let ty = t.next().unwrap_or("");
                let scalar = |s: Option<&str>| {
                    s.and_then(Scalar::parse)
                        .ok_or_else(|| err(format!("unknown property type {:?}", s.unwrap_or(""))))
                };
                let kind = if ty == "list" {
                    let count = scalar(t.next())?;
                    let item = scalar(t.next())?;
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(scalar(Some(ty))?)
                };
                let name = t
                    .next()
                    .ok_or_else(|| err("property without a name".into()))?;
                // A list would be read as one number (its count is skipped): every vertex
                // would sit at 0 along that axis.
                if el.name == "vertex"
                    && matches!(name, "x" | "y" | "z")
                    && matches!(kind, Kind::List { .. })
                {
                    return Err(err(format!(
                        "the vertex coordinate '{name}' is declared as a list ('{line}'); a \
                         coordinate must be one number (property float {name})"
                    )));
                }
                el.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => break,
            "comment" | "obj_info" | "" => {}
            other => return Err(err(format!("unknown header keyword '{other}'"))),
        }
    }
    let encoding =
        encoding.ok_or_else(|| IoError::parse(path, 2, "the header has no 'format' line"))?;
    Ok(Header {
        encoding,
        elements,
        body: pos,
        lines: line_no,
    })
}

/// Numbered lines of an ascii body.
type AsciiLines<'a> = std::iter::Enumerate<std::slice::Split<'a, u8, fn(&u8) -> bool>>;

/// Where the values come from: a binary cursor or ascii lines.
enum Body<'a> {
    Binary {
        data: &'a [u8],
        pos: usize,
        big: bool,
    },
    Ascii {
        lines: AsciiLines<'a>,
        first_line: usize,
    },
}

/// A reader of one element instance's values.
struct Values<'a, 'b> {
    body: &'b mut Body<'a>,
    /// Tokens of the current ascii line and its number.
    toks: Vec<&'a [u8]>,
    next_tok: usize,
    line: usize,
}

impl<'a> Values<'a, '_> {
    fn read(&mut self, path: &Path, s: Scalar, what: &dyn Fn() -> String) -> Result<f64, IoError> {
        match &mut *self.body {
            Body::Binary { data, pos, big } => {
                let n = s.size();
                let Some(b) = data.get(*pos..*pos + n) else {
                    return Err(IoError::binary(
                        path,
                        *pos as u64,
                        format!(
                            "the file ends while reading {}: needs {n} bytes, {} left (truncated?)",
                            what(),
                            data.len() - *pos
                        ),
                    ));
                };
                *pos += n;
                Ok(s.decode(b, *big))
            }
            Body::Ascii { .. } => {
                let Some(tok) = self.toks.get(self.next_tok) else {
                    return Err(IoError::parse(
                        path,
                        self.line,
                        format!("missing value for {}", what()),
                    ));
                };
                self.next_tok += 1;
                parse_f64(tok).ok_or_else(|| {
                    IoError::parse(
                        path,
                        self.line,
                        format!("malformed number '{}' for {}", show(tok), what()),
                    )
                })
            }
        }
    }

    /// An upper bound on the bytes left to read (caps reservations driven by header counts).
    fn remaining(&self, total: usize) -> usize {
        match &*self.body {
            Body::Binary { data, pos, .. } => data.len().saturating_sub(*pos),
            Body::Ascii { .. } => total,
        }
    }

    /// Starts an element instance: for ascii, moves to the next non-empty line.
    fn start(&mut self, path: &Path, what: &dyn Fn() -> String) -> Result<(), IoError> {
        if let Body::Ascii { lines, first_line } = &mut *self.body {
            loop {
                let Some((i, l)) = lines.next() else {
                    return Err(IoError::parse(
                        path,
                        self.line + 1,
                        format!("the file ends before {}", what()),
                    ));
                };
                self.line = *first_line + i;
                let l = l.strip_suffix(b"\r").unwrap_or(l);
                self.toks.clear();
                self.toks.extend(tokens(l));
                self.next_tok = 0;
                if !self.toks.is_empty() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }
}

/// Parses a PLY file's bytes. `path` only names the file in errors.
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    let bytes = super::strip_bom(bytes);
    let h = parse_header(path, bytes)?;
    let body_bytes = &bytes[h.body..];
    let is_nl: fn(&u8) -> bool = |&b| b == b'\n';
    let mut body = match h.encoding {
        PlyEncoding::Ascii => Body::Ascii {
            lines: body_bytes.split(is_nl).enumerate(),
            first_line: h.lines + 1,
        },
        e => Body::Binary {
            data: bytes,
            pos: h.body,
            big: e == PlyEncoding::BinaryBigEndian,
        },
    };
    let mut vals = Values {
        body: &mut body,
        toks: Vec::new(),
        next_tok: 0,
        line: h.lines,
    };
    let mut positions: Vec<Point> = Vec::new();
    let mut polys = Polygons {
        offsets: vec![0],
        indices: Vec::new(),
    };
    let mut saw_vertex = false;
    for el in &h.elements {
        if h.encoding != PlyEncoding::Ascii && el.count > 0 && el.props.is_empty() {
            return Err(IoError::content(
                path,
                format!(
                    "binary element '{}' has {} instances but no properties",
                    el.name, el.count
                ),
            ));
        }
        // Every instance takes at least one byte, so no element can hold more instances than
        // bytes are left: reservations never exceed what the file could fill.
        let room = vals.remaining(body_bytes.len());
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        let coord = |n: &str| el.props.iter().position(|p| p.name == n);
        let xyz = if is_vertex {
            saw_vertex = true;
            let idx = [coord("x"), coord("y"), coord("z")];
            if idx.iter().any(Option::is_none) {
                return Err(IoError::content(
                    path,
                    "the vertex element lacks an x, y or z property",
                ));
            }
            positions.reserve(el.count.min(room));
            idx.map(|i| i.unwrap_or(usize::MAX))
        } else {
            [usize::MAX; 3]
        };
        let face_prop = if is_face {
            let p = el
                .props
                .iter()
                .position(|p| {
                    matches!(p.kind, Kind::List { .. })
                        && (p.name == "vertex_indices" || p.name == "vertex_index")
                })
                .ok_or_else(|| {
                    IoError::content(
                        path,
                        "the face element has no 'vertex_indices' or 'vertex_index' list",
                    )
                })?;
            polys.indices.reserve(el.count.saturating_mul(3).min(room));
            Some(p)
        } else {
            None
        };
        for i in 0..el.count {
            vals.start(path, &|| format!("{} {i}", el.name))?;
            let mut p = [0.0; 3];
            for (k, prop) in el.props.iter().enumerate() {
                let what = || format!("{} {i}, property '{}'", el.name, prop.name);
                match prop.kind {
                    Kind::Scalar(s) => {
                        let v = vals.read(path, s, &what)?;
                        if let Some(c) = xyz.iter().position(|&j| j == k) {
                            p[c] = v;
                        }
                    }
                    Kind::List { count, item } => {
                        let n = vals.read(path, count, &what)?;
                        if !(n >= 0.0 && n.fract() == 0.0) {
                            return Err(IoError::content(
                                path,
                                format!("{}: invalid list length {n}", what()),
                            ));
                        }
                        let n = n as usize;
                        let keep = face_prop == Some(k);
                        if keep && n < 3 {
                            return Err(IoError::content(
                                path,
                                format!("face {i} has {n} vertices, needs at least 3"),
                            ));
                        }
                        for _ in 0..n {
                            let v = vals.read(path, item, &what)?;
                            if keep {
                                if !(v >= 0.0 && v.fract() == 0.0 && v < u32::MAX as f64) {
                                    return Err(IoError::content(
                                        path,
                                        format!("face {i} has an invalid vertex index {v}"),
                                    ));
                                }
                                polys.indices.push(v as u32);
                            }
                        }
                        if keep {
                            polys.offsets.push(polys.indices.len() as u32);
                        }
                    }
                }
            }
            if is_vertex {
                positions.push(p);
            }
        }
    }
    if !saw_vertex {
        return Err(IoError::content(path, "the file has no vertex element"));
    }
    let nv = positions.len();
    for (f, poly) in polys.iter().enumerate() {
        if let Some(&bad) = poly.iter().find(|&&v| v as usize >= nv) {
            return Err(IoError::content(
                path,
                format!("face {f} refers to vertex {bad}, but the file has only {nv} vertices"),
            ));
        }
    }
    Ok(TriMesh::from_polygons(positions, polys))
}

mod write;
pub use write::{write_ply, write_ply_colored};

#[cfg(test)]
mod tests {
    use super::write::{faces_of, write_ply_to};
    use super::*;

    fn quad_mesh() -> TriMesh {
        TriMesh::from_polygons(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.1],
                [0.0, 1.0, 1.0 / 3.0],
                [2.0, 0.5, 0.0],
            ],
            Polygons {
                offsets: vec![0, 4, 7],
                indices: vec![0, 1, 2, 3, 1, 4, 2],
            },
        )
    }

    #[test]
    fn round_trips_in_every_encoding() {
        let m = quad_mesh();
        let faces = faces_of(&m);
        for enc in [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ] {
            let mut buf = Vec::new();
            write_ply_to(&mut buf, &m, &faces, enc, None).unwrap();
            let back = parse_ply(Path::new("m.ply"), &buf).unwrap();
            assert_eq!(back, m, "{enc:?}");
        }
    }

    #[test]
    fn reads_other_types_and_skips_unknown_properties() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty uchar q\n\
                    property float y\nproperty float z\nelement face 1\nproperty uchar flags\n\
                    property list uint short vertex_index\nelement edge 1\nproperty int a\nend_header\n\
                    0 7 0 0\n1 7 0 0\n0 7 1 0\n\n9 3 0 1 2\n5\n";
        let m = parse_ply(Path::new("t.ply"), text.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn a_coordinate_declared_as_a_list_is_refused() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n\
                    1 1 0 0\n1 2 0 0\n1 3 1 0\n3 0 1 2\n";
        let e = parse_ply(Path::new("listed.ply"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("listed.ply:4: the vertex coordinate 'x' is declared as a list"),
            "{e}"
        );
        // Lists elsewhere, and of other names, are read and skipped as before.
        let ok = text
            .replace("list uchar float x", "float x")
            .replace("1 1 0 0\n1 2 0 0\n1 3 1 0", "1 0 0\n2 0 0\n3 1 0");
        let m = parse_ply(Path::new("ok.ply"), ok.as_bytes()).unwrap();
        assert_eq!(m.positions[2], [3.0, 1.0, 0.0]);
    }

    #[test]
    fn truncated_binary_names_the_offset() {
        let m = quad_mesh();
        let mut buf = Vec::new();
        write_ply_to(
            &mut buf,
            &m,
            &faces_of(&m),
            PlyEncoding::BinaryLittleEndian,
            None,
        )
        .unwrap();
        buf.truncate(buf.len() - 5);
        let e = parse_ply(Path::new("t.ply"), &buf).unwrap_err();
        assert!(matches!(e, IoError::Binary { .. }), "{e}");
        let s = e.to_string();
        assert!(s.contains("t.ply: at byte") && s.contains("face 1"), "{s}");
    }
}
