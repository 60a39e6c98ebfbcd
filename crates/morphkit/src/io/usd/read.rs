//! A minimal `.usda` reader for baked mesh animation: the first `Mesh` prim's faces and its
//! `points` (default value and time samples), and the layer's `timeCodesPerSecond`. It reads
//! what [`super::write_usd_animation`] writes (and hand-written layers of the same shape); it
//! is not a USD implementation (no composition, no references, no binary `.usdc`).

use crate::io::{source::read_file, IoError};
use crate::mesh::{Point, Polygons, TriMesh};
use std::path::Path;

/// A baked animation read from `.usda`.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdAnimation {
    /// The mesh (faces fan-triangulated, polygons kept) at the first sample.
    pub mesh: TriMesh,
    /// `(time code, points)` in time order: the time samples, or the default value at time 0.
    pub samples: Vec<(f64, Vec<Point>)>,
    /// `timeCodesPerSecond` (24 when the layer does not say).
    pub time_codes_per_second: f64,
}

/// Reads `path` (see [`parse_usd_animation`]).
pub fn read_usd_animation(path: &Path) -> Result<UsdAnimation, IoError> {
    let bytes = read_file(path)?;
    let text = std::str::from_utf8(crate::io::strip_bom(&bytes))
        .map_err(|e| IoError::binary(path, e.valid_up_to() as u64, "not UTF-8 text"))?;
    parse_usd_animation(path, text)
}

struct Cursor<'a> {
    path: &'a Path,
    text: &'a str,
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn err(&self, msg: impl Into<String>) -> IoError {
        let line = self.text[..self.pos.min(self.text.len())]
            .matches('\n')
            .count()
            + 1;
        IoError::parse(self.path, line, msg)
    }
    fn skip_ws(&mut self) {
        let b = self.text.as_bytes();
        while self.pos < b.len() && (b[self.pos].is_ascii_whitespace() || b[self.pos] == b',') {
            self.pos += 1;
        }
    }
    fn expect(&mut self, c: u8) -> Result<(), IoError> {
        self.skip_ws();
        if self.text.as_bytes().get(self.pos) == Some(&c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err(format!("expected '{}'", c as char)))
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.text.as_bytes().get(self.pos).copied()
    }
    fn number(&mut self) -> Result<f64, IoError> {
        self.skip_ws();
        let b = self.text.as_bytes();
        let start = self.pos;
        while self.pos < b.len()
            && (b[self.pos].is_ascii_alphanumeric() || matches!(b[self.pos], b'.' | b'-' | b'+'))
        {
            self.pos += 1;
        }
        let s = &self.text[start..self.pos];
        match s.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => {
                self.pos = start;
                Err(self.err(format!("'{s}' is not a finite number")))
            }
        }
    }
    /// `[a, b, …]`.
    fn scalars(&mut self) -> Result<Vec<f64>, IoError> {
        self.expect(b'[')?;
        let mut v = Vec::new();
        while self.peek() != Some(b']') {
            v.push(self.number()?);
        }
        self.pos += 1;
        Ok(v)
    }
    /// `[(x, y, z), …]`.
    fn points(&mut self) -> Result<Vec<Point>, IoError> {
        self.expect(b'[')?;
        let mut v = Vec::new();
        while self.peek() != Some(b']') {
            self.expect(b'(')?;
            let p = [self.number()?, self.number()?, self.number()?];
            self.expect(b')')?;
            v.push(p);
        }
        self.pos += 1;
        Ok(v)
    }
    /// Moves just past the next `needle` at or after the cursor; false when there is none.
    fn find(&mut self, needle: &str) -> bool {
        match self.text[self.pos..].find(needle) {
            Some(i) => {
                self.pos += i + needle.len();
                true
            }
            None => false,
        }
    }
}

/// Parses a baked animation from `.usda` text; `path` names the file in errors (which give
/// the 1-based line).
///
/// Errors: no `Mesh` prim, missing faces or points, malformed arrays, face indices out of
/// range, samples with another point count than the faces need.
pub fn parse_usd_animation(path: &Path, text: &str) -> Result<UsdAnimation, IoError> {
    if !text.starts_with("#usda") {
        return Err(IoError::parse(
            path,
            1,
            "not a USD text layer (no '#usda' header)",
        ));
    }
    let mut c = Cursor { path, text, pos: 0 };
    let mut tcps = 24.0;
    if let Some(i) = text.find("timeCodesPerSecond") {
        c.pos = i + "timeCodesPerSecond".len();
        c.expect(b'=')?;
        tcps = c.number()?;
    }
    c.pos = 0;
    if !c.find("def Mesh") {
        return Err(IoError::content(path, "no Mesh prim"));
    }
    let mesh_start = c.pos;
    let field = |c: &mut Cursor, name: &str| -> Result<bool, IoError> {
        c.pos = mesh_start;
        while c.find(name) {
            let rest = &c.text[c.pos..];
            let t = rest.trim_start();
            if t.starts_with('=') {
                c.pos += rest.len() - t.len() + 1;
                return Ok(true);
            }
        }
        Ok(false)
    };
    if !field(&mut c, "faceVertexCounts")? {
        return Err(IoError::content(path, "the Mesh has no faceVertexCounts"));
    }
    let counts = c.scalars()?;
    if !field(&mut c, "faceVertexIndices")? {
        return Err(IoError::content(path, "the Mesh has no faceVertexIndices"));
    }
    let indices = c.scalars()?;
    let mut samples = Vec::new();
    if field(&mut c, "points.timeSamples")? {
        c.expect(b'{')?;
        while c.peek() != Some(b'}') {
            let t = c.number()?;
            c.expect(b':')?;
            samples.push((t, c.points()?));
        }
    } else if field(&mut c, "points")? {
        samples.push((0.0, c.points()?));
    } else {
        return Err(IoError::content(path, "the Mesh has no points"));
    }
    if samples.is_empty() {
        return Err(IoError::content(path, "points.timeSamples is empty"));
    }
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nv = samples[0].1.len();
    let mut polys = Polygons {
        offsets: vec![0],
        indices: Vec::with_capacity(indices.len()),
    };
    let mut next = 0usize;
    for (f, &n) in counts.iter().enumerate() {
        let n = n as usize;
        if n < 3 || n > indices.len() - next {
            return Err(IoError::content(
                path,
                format!(
                    "face {f}: {n} vertices, but faceVertexIndices has {} left",
                    indices.len() - next
                ),
            ));
        }
        for &i in &indices[next..next + n] {
            if i < 0.0 || i as usize >= nv || i.fract() != 0.0 {
                return Err(IoError::content(
                    path,
                    format!(
                        "face {f}: vertex index {i} is out of range (the mesh has {nv} points)"
                    ),
                ));
            }
            polys.indices.push(i as u32);
        }
        next += n;
        polys.offsets.push(polys.indices.len() as u32);
    }
    if let Some((t, s)) = samples.iter().find(|(_, s)| s.len() != nv) {
        return Err(IoError::content(
            path,
            format!(
                "the points at time {t} are {}, the first sample has {nv}",
                s.len()
            ),
        ));
    }
    let mesh = TriMesh::from_polygons(samples[0].1.clone(), polys);
    Ok(UsdAnimation {
        mesh,
        samples,
        time_codes_per_second: tcps,
    })
}
