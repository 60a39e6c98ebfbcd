//! Writing new positions into an artist's own PLY (the PLY counterpart of
//! [`super::ObjTemplate`]): every element and property the file has (vertex colours, `u`/`v` or
//! `s`/`t`, custom scalars and lists, face properties, other elements, comments) comes back
//! byte for byte, with the vertices' `x`, `y`, `z` replaced and `nx`, `ny`, `nz` recomputed
//! from the new positions.
//!
//! The file keeps its encoding (ascii, binary little or big endian). `x`, `y`, `z` become
//! `double` in the header whatever their type was, so that the positions are exact (as in every
//! PLY morphkit writes); in ascii the other values of a vertex line keep their text and the
//! spacing around them. A normal is the area-weighted mean of the normals of the faces using the
//! vertex (each polygon counted once, with its whole area), written in its property's type (`float` or `double`; integer normals are kept as they
//! are); a vertex no face with area uses keeps its normal. A morphkit result keeps the input's
//! vertex layout and order, so vertex `k` of a result is the file's `k`-th vertex.

use super::ply::{parse_header, parse_ply, Element, Header, Kind, PlyEncoding, Scalar};
use super::IoError;
use crate::mesh::{triangle_normal, Point, TriMesh};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What a vertex property is to the template.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    /// Position component 0, 1, 2.
    Position(usize),
    /// Normal component 0, 1, 2 (float or double, and all three present).
    Normal(usize),
    /// Kept as it is.
    Other,
}

/// A PLY file's bytes, kept to write other positions into; see the module docs.
#[derive(Clone, Debug)]
pub struct PlyTemplate {
    path: PathBuf,
    /// The file (without a byte-order mark).
    bytes: Vec<u8>,
    /// The header with `x`, `y`, `z` declared `double`.
    header: Vec<u8>,
    encoding: PlyEncoding,
    /// Byte offset of the body in `bytes`.
    body: usize,
    /// The elements (with their properties) in file order, and the vertex element's index.
    elements: Vec<Element>,
    vertex: usize,
    /// The role of each vertex property.
    roles: Vec<Role>,
    /// The template's mesh (faces for the normals).
    mesh: TriMesh,
}

impl PlyTemplate {
    /// Reads `path` as a template (it must read as a PLY mesh, see [`super::ply`]).
    pub fn read(path: &Path) -> Result<Self, IoError> {
        let raw = super::source::read_file(path)?;
        let bytes = super::strip_bom(&raw).to_vec();
        drop(raw);
        let mesh = parse_ply(path, &bytes)?;
        let Header {
            encoding,
            elements,
            body,
            ..
        } = parse_header(path, &bytes)?;
        let vertex = elements
            .iter()
            .position(|e| e.name == "vertex")
            .ok_or_else(|| IoError::content(path, "the file has no vertex element"))?;
        let index = |n: &str| elements[vertex].props.iter().position(|p| p.name == n);
        let is_float = |i: usize| {
            matches!(
                elements[vertex].props[i].kind,
                Kind::Scalar(Scalar::F32 | Scalar::F64)
            )
        };
        let mut roles = vec![Role::Other; elements[vertex].props.len()];
        for (c, n) in ["x", "y", "z"].iter().enumerate() {
            if let Some(i) = index(n) {
                roles[i] = Role::Position(c);
            }
        }
        let normals = ["nx", "ny", "nz"].map(index);
        if normals.iter().all(|i| i.is_some_and(is_float)) {
            for (c, i) in normals.iter().enumerate() {
                roles[i.expect("checked")] = Role::Normal(c);
            }
        }
        let header = double_positions(&bytes[..body]);
        Ok(Self {
            path: path.to_path_buf(),
            bytes,
            header,
            encoding,
            body,
            elements,
            vertex,
            roles,
            mesh,
        })
    }

    /// The number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.mesh.num_vertices()
    }

    /// The file the template was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The template's bytes with `positions` (one per vertex) written in and its normals
    /// recomputed; errors name `out`.
    pub fn fill(&self, out: &Path, positions: &[Point]) -> Result<Vec<u8>, IoError> {
        if positions.len() != self.num_vertices() {
            return Err(IoError::content(
                out,
                format!(
                    "{} positions for the {} vertices of {}",
                    positions.len(),
                    self.num_vertices(),
                    self.path.display()
                ),
            ));
        }
        super::atomic::check_finite(out, positions)?;
        let normals = area_normals(&self.mesh, positions);
        let mut w = Vec::with_capacity(self.bytes.len() + 12 * positions.len());
        w.extend_from_slice(&self.header);
        let bad = |m: String| IoError::content(&self.path, m);
        match self.encoding {
            PlyEncoding::Ascii => self.fill_ascii(&mut w, positions, &normals),
            e => self.fill_binary(
                &mut w,
                positions,
                &normals,
                e == PlyEncoding::BinaryBigEndian,
            ),
        }
        .map_err(bad)?;
        Ok(w)
    }

    /// Writes [`PlyTemplate::fill`] to `out` atomically.
    pub fn write(&self, out: &Path, positions: &[Point]) -> Result<(), IoError> {
        let bytes = self.fill(out, positions)?;
        super::atomic::write_atomic_with(out, |w| w.write_all(&bytes))
    }

    fn fill_binary(
        &self,
        w: &mut Vec<u8>,
        positions: &[Point],
        normals: &[Option<Point>],
        big: bool,
    ) -> Result<(), String> {
        let b = &self.bytes;
        let mut pos = self.body;
        for el in &self.elements[..self.vertex] {
            pos = skip_element(b, pos, el, big)?;
        }
        w.extend_from_slice(&b[self.body..pos]);
        let put = |w: &mut Vec<u8>, s: Scalar, x: f64| {
            let mut bytes = match s {
                Scalar::F32 => (x as f32).to_le_bytes().to_vec(),
                _ => x.to_le_bytes().to_vec(),
            };
            if big {
                bytes.reverse();
            }
            w.extend_from_slice(&bytes);
        };
        let el = &self.elements[self.vertex];
        for v in 0..el.count {
            for (prop, role) in el.props.iter().zip(&self.roles) {
                let start = pos;
                pos = skip_property(b, pos, &prop.kind, big)
                    .map_err(|m| format!("vertex {v}, property '{}': {m}", prop.name))?;
                match (*role, &prop.kind) {
                    (Role::Position(c), _) => put(w, Scalar::F64, positions[v][c]),
                    (Role::Normal(c), Kind::Scalar(s)) if normals[v].is_some() => {
                        put(w, *s, normals[v].expect("checked")[c])
                    }
                    _ => w.extend_from_slice(&b[start..pos]),
                }
            }
        }
        w.extend_from_slice(&b[pos..]);
        Ok(())
    }

    fn fill_ascii(
        &self,
        w: &mut Vec<u8>,
        positions: &[Point],
        normals: &[Option<Point>],
    ) -> Result<(), String> {
        // Non-empty lines are the element instances in order; the rest is copied.
        let (mut el, mut done) = (0usize, 0usize);
        let body = &self.bytes[self.body..];
        let mut lines = body.split(|&c| c == b'\n').peekable();
        while let Some(line) = lines.next() {
            let last = lines.peek().is_none();
            while el < self.elements.len() && done == self.elements[el].count {
                el += 1;
                done = 0;
            }
            let toks: Vec<&[u8]> = super::source::tokens(line).collect();
            if el == self.vertex && !toks.is_empty() {
                self.vertex_line(w, line, &toks, done, positions, normals)?;
            } else {
                w.extend_from_slice(line);
            }
            if !toks.is_empty() && el < self.elements.len() {
                done += 1;
            }
            if !last {
                w.push(b'\n');
            }
        }
        Ok(())
    }

    /// One ascii vertex line with its position and normal tokens replaced in place.
    fn vertex_line(
        &self,
        w: &mut Vec<u8>,
        line: &[u8],
        toks: &[&[u8]],
        v: usize,
        positions: &[Point],
        normals: &[Option<Point>],
    ) -> Result<(), String> {
        let offset = |t: &[u8]| t.as_ptr() as usize - line.as_ptr() as usize;
        let mut copied = 0;
        let mut t = 0;
        let el = &self.elements[self.vertex];
        for (prop, role) in el.props.iter().zip(&self.roles) {
            let missing = || format!("vertex {v}: no value for property '{}'", prop.name);
            let tok = *toks.get(t).ok_or_else(missing)?;
            t += match &prop.kind {
                Kind::Scalar(_) => 1,
                Kind::List { .. } => {
                    let n = super::source::parse_f64(tok).ok_or_else(missing)?;
                    1 + n as usize
                }
            };
            let text = match (*role, &prop.kind) {
                (Role::Position(c), _) => format!("{}", positions[v][c]),
                (Role::Normal(c), Kind::Scalar(Scalar::F32)) if normals[v].is_some() => {
                    format!("{}", normals[v].expect("checked")[c] as f32)
                }
                (Role::Normal(c), _) if normals[v].is_some() => {
                    format!("{}", normals[v].expect("checked")[c])
                }
                _ => continue,
            };
            let at = offset(tok);
            w.extend_from_slice(&line[copied..at]);
            w.extend_from_slice(text.as_bytes());
            copied = at + tok.len();
        }
        w.extend_from_slice(&line[copied..]);
        Ok(())
    }
}

/// The header with the vertex element's `x`, `y`, `z` declared `double` (line breaks kept).
fn double_positions(header: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(header.len() + 32);
    let mut element = String::new();
    for line in header.split_inclusive(|&c| c == b'\n') {
        let text = String::from_utf8_lossy(line);
        let t: Vec<&str> = text.split_ascii_whitespace().collect();
        if t.first() == Some(&"element") {
            element = t.get(1).unwrap_or(&"").to_string();
        }
        let position = element == "vertex"
            && t.len() == 3
            && t[0] == "property"
            && matches!(t[2], "x" | "y" | "z");
        if position && !matches!(t[1], "double" | "float64") {
            let end = &line[line.trim_ascii_end().len()..];
            write!(out, "property double {}", t[2]).expect("in memory");
            out.extend_from_slice(end);
        } else {
            out.extend_from_slice(line);
        }
    }
    out
}

/// A binary scalar at `pos` as `f64` (list counts).
fn scalar_at(b: &[u8], pos: usize, s: Scalar, big: bool) -> Result<f64, String> {
    let n = s.size();
    let bytes = b
        .get(pos..pos + n)
        .ok_or_else(|| format!("the file ends at byte {pos}"))?;
    Ok(s.decode(bytes, big))
}

/// The byte after the binary property value at `pos`.
fn skip_property(b: &[u8], pos: usize, kind: &Kind, big: bool) -> Result<usize, String> {
    let end = match kind {
        Kind::Scalar(s) => pos + s.size(),
        Kind::List { count, item } => {
            let n = scalar_at(b, pos, *count, big)?;
            if !(n >= 0.0 && n.fract() == 0.0) {
                return Err(format!("invalid list length {n}"));
            }
            (n as usize)
                .checked_mul(item.size())
                .and_then(|x| x.checked_add(pos + count.size()))
                .ok_or_else(|| format!("list length {n} is too large"))?
        }
    };
    if end > b.len() {
        return Err(format!("the file ends at byte {}", b.len()));
    }
    Ok(end)
}

/// The byte after the binary element `el` starting at `pos`.
fn skip_element(b: &[u8], mut pos: usize, el: &Element, big: bool) -> Result<usize, String> {
    for i in 0..el.count {
        for p in &el.props {
            pos = skip_property(b, pos, &p.kind, big)
                .map_err(|m| format!("{} {i}, property '{}': {m}", el.name, p.name))?;
        }
    }
    Ok(pos)
}

/// Unit area-weighted vertex normals of `positions` over `mesh`'s faces (a polygon counts with
/// its whole area vector at each corner, as in [`super::ObjTemplate`]); `None` where no face
/// with area uses the vertex.
fn area_normals(mesh: &TriMesh, positions: &[Point]) -> Vec<Option<Point>> {
    let mut n = vec![[0.0; 3]; positions.len()];
    let mut add = |face: &[u32]| {
        let mut area = [0.0; 3];
        for k in 1..face.len().saturating_sub(1) {
            let f = triangle_normal(positions, [face[0], face[k], face[k + 1]]);
            (0..3).for_each(|a| area[a] += f[a]);
        }
        for &v in face {
            (0..3).for_each(|a| n[v as usize][a] += area[a]);
        }
    };
    match &mesh.polygons {
        Some(p) => p.iter().for_each(&mut add),
        None => mesh.triangles.iter().for_each(|t| add(t)),
    }
    n.into_iter()
        .map(|q| {
            let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            (len > 0.0 && len.is_finite()).then(|| q.map(|x| x / len))
        })
        .collect()
}

#[cfg(test)]
#[path = "ply_template_tests.rs"]
mod tests;
