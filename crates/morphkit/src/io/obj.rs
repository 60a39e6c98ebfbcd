//! Wavefront OBJ: `v` and `f` records (other records ignored), also gzip-compressed.
//!
//! Reading accepts the face forms `a`, `a/b`, `a//c` and `a/b/c`, 1-based or negative
//! (relative to the vertices read so far) indices, extra `v` components (`w`, vertex colours),
//! and trailing `#` comments. Polygons are fan-triangulated by [`TriMesh::from_polygons`].
//! The parser allocates nothing per line; a file is read whole, or, gzip-compressed, as a
//! stream ([`read_obj`]).
//!
//! Writing uses Rust's shortest round-trip formatting of `f64`, so `write` then `read` gives
//! back the same bits, and emits the original polygons when the mesh has them.

use super::source::{lines, parse_f64, parse_i64, show, tokens};
use super::IoError;
use crate::mesh::{Point, Polygons, TriMesh};
use std::io::Write;
use std::path::Path;

/// Parses OBJ text. `path` only names the file in errors.
///
/// Errors name the line: malformed numbers, `v` with fewer than three coordinates, non-finite
/// coordinates, index 0, a relative index before the first vertex, a face with fewer than
/// three vertices, and a face index beyond the file's vertex count.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    let mut p = ObjParser::default();
    for (line_no, line) in lines(super::strip_bom(bytes)) {
        p.line(path, line_no, line)?;
    }
    p.finish(path)
}

/// Reads the OBJ file `path` (gzip-compressed or not) as [`parse_obj`] parses its text; a
/// compressed file is decompressed as a stream ([`super::source::for_each_line`]), so memory
/// is that of the mesh, not of the decompressed text.
pub fn read_obj(path: &Path) -> Result<TriMesh, IoError> {
    let mut p = ObjParser::default();
    super::source::for_each_line(path, |line_no, line| p.line(path, line_no, line))?;
    p.finish(path)
}

/// The state of an OBJ parse: what the lines so far gave.
struct ObjParser {
    positions: Vec<Point>,
    polys: Polygons,
    /// The largest absolute index seen and the line where it was seen, checked at the end so
    /// that (rare, but legal) forward references work.
    max_index: (u64, usize),
}

impl Default for ObjParser {
    fn default() -> Self {
        Self {
            positions: Vec::new(),
            polys: Polygons {
                offsets: vec![0],
                indices: Vec::new(),
            },
            max_index: (0, 0),
        }
    }
}

impl ObjParser {
    fn line(&mut self, path: &Path, line_no: usize, line: &[u8]) -> Result<(), IoError> {
        let (positions, polys, max_index) =
            (&mut self.positions, &mut self.polys, &mut self.max_index);
        let mut toks = tokens(line);
        let Some(key) = toks.next() else {
            return Ok(());
        };
        match key {
            b"v" => {
                let mut p = [0.0; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let tok = toks.next().ok_or_else(|| {
                        IoError::parse(
                            path,
                            line_no,
                            format!("vertex has {k} coordinates, needs 3"),
                        )
                    })?;
                    *c = parse_f64(tok).ok_or_else(|| {
                        IoError::parse(path, line_no, format!("malformed number '{}'", show(tok)))
                    })?;
                    if !c.is_finite() {
                        return Err(IoError::parse(
                            path,
                            line_no,
                            format!("non-finite coordinate '{}'", show(tok)),
                        ));
                    }
                }
                positions.push(p);
            }
            b"f" => {
                let start = polys.indices.len();
                for tok in toks {
                    if tok.starts_with(b"#") {
                        break;
                    }
                    let head = tok.split(|&b| b == b'/').next().unwrap_or(tok);
                    let i = parse_i64(head).ok_or_else(|| {
                        IoError::parse(
                            path,
                            line_no,
                            format!("malformed face index '{}'", show(tok)),
                        )
                    })?;
                    let n = positions.len() as i64;
                    let abs = match i {
                        0 => return Err(IoError::parse(path, line_no, "face index 0 (OBJ indices start at 1)")),
                        i if i > 0 => i - 1,
                        i if n + i >= 0 => n + i,
                        i => {
                            return Err(IoError::parse(
                                path,
                                line_no,
                                format!("relative face index {i} points before the first vertex ({n} read so far)"),
                            ))
                        }
                    };
                    let abs = abs as u64;
                    if abs > u32::MAX as u64 - 1 {
                        return Err(IoError::parse(
                            path,
                            line_no,
                            format!("face index {i} is too large"),
                        ));
                    }
                    if abs >= max_index.0 {
                        *max_index = (abs, line_no);
                    }
                    polys.indices.push(abs as u32);
                }
                let count = polys.indices.len() - start;
                if count < 3 {
                    return Err(IoError::parse(
                        path,
                        line_no,
                        format!("face has {count} vertices, needs at least 3"),
                    ));
                }
                polys.offsets.push(polys.indices.len() as u32);
            }
            _ => {}
        }
        Ok(())
    }

    fn finish(self, path: &Path) -> Result<TriMesh, IoError> {
        let (positions, polys, max_index) = (self.positions, self.polys, self.max_index);
        if !polys.indices.is_empty() && max_index.0 >= positions.len() as u64 {
            return Err(IoError::parse(
                path,
                max_index.1,
                format!(
                    "face index {} is out of range: the file has {} vertices",
                    max_index.0 + 1,
                    positions.len()
                ),
            ));
        }
        Ok(TriMesh::from_polygons(positions, polys))
    }
}

/// Writes `mesh` as OBJ text (1-based indices, full `f64` precision, polygons when present).
pub fn write_obj_to(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(w, "# written by morphkit")?;
    writeln!(
        w,
        "# {} vertices, {} faces",
        mesh.num_vertices(),
        mesh.polygons
            .as_ref()
            .map_or(mesh.num_triangles(), |p| p.len())
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    match &mesh.polygons {
        Some(polys) => {
            for poly in polys.iter() {
                w.write_all(b"f")?;
                for &i in poly {
                    write!(w, " {}", i + 1)?;
                }
                w.write_all(b"\n")?;
            }
        }
        None => {
            for t in &mesh.triangles {
                writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
            }
        }
    }
    Ok(())
}

/// Writes `mesh` as OBJ to `path` atomically; gzip-compressed when `gzip`. A NaN or infinite
/// coordinate is an [`IoError::Content`] error naming the vertex, and nothing is written.
pub fn write_obj(path: &Path, mesh: &TriMesh, gzip: bool) -> Result<(), IoError> {
    super::atomic::check_finite(path, &mesh.positions)?;
    super::atomic::write_atomic_with(path, |w| {
        if gzip {
            let mut gz = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            write_obj_to(&mut gz, mesh)?;
            gz.finish()?;
            Ok(())
        } else {
            write_obj_to(w, mesh)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<TriMesh, IoError> {
        parse_obj(Path::new("t.obj"), s.as_bytes())
    }

    #[test]
    fn face_forms_and_relative_indices() {
        let m = parse(
            "v 0 0 0\nv 1 0 0\r\nv 1 1 0 1.0\nv 0 1 0\nvt 0 0\nvn 0 0 1\ng x\nusemtl m\n\
             f 1/1 2/1/1 3//1 4 # quad\nf -4 -2 -1\n",
        )
        .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert_eq!(m.face_origin, vec![0, 0, 1]);
        assert_eq!(m.polygons.as_ref().unwrap().len(), 2);
    }

    #[test]
    fn cr_only_line_endings_are_lines() {
        let text = "v 0 0 0\rv 1 0 0\rv 0 1 0\rv 1 1 0\rf 1 2 3\rf 2 4 3\r";
        assert_eq!(parse(text).unwrap().triangles, vec![[0, 1, 2], [1, 3, 2]]);
        let e = parse("v 0 0 0\rv 1 x 0\r").unwrap_err().to_string();
        assert!(e.contains("t.obj:2"), "{e}");
        // The same read from a file, plain and gzip-compressed (a stream split into lines).
        let d = std::env::temp_dir().join(format!("morphkit-obj-cr-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let plain = d.join("mac.obj");
        std::fs::write(&plain, text).unwrap();
        let gz = d.join("mac.obj.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        enc.write_all(text.as_bytes()).unwrap();
        std::fs::write(&gz, enc.finish().unwrap()).unwrap();
        for p in [&plain, &gz] {
            assert_eq!(read_obj(p).unwrap().triangles.len(), 2, "{}", p.display());
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 x 0\n").unwrap_err().to_string();
        assert!(
            e.contains("t.obj:2") && e.contains("malformed number 'x'"),
            "{e}"
        );
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.obj:4") && e.contains("out of range"), "{e}");
        let e = parse("v 0 0 nan\n").unwrap_err().to_string();
        assert!(e.contains("t.obj:1") && e.contains("non-finite"), "{e}");
        let e = parse("v 0 0\n").unwrap_err().to_string();
        assert!(e.contains("needs 3"), "{e}");
        let e = parse("v 0 0 0\nf 0 1 1\n").unwrap_err().to_string();
        assert!(e.contains("index 0"), "{e}");
    }

    #[test]
    fn write_read_is_bit_exact() {
        let m = TriMesh::new(
            vec![
                [0.1, 1.0 / 3.0, -2e-9],
                [1e10, 0.0, 5.5],
                [std::f64::consts::PI, 2.0, 1e-300],
            ],
            vec![[0, 1, 2]],
        );
        let mut buf = Vec::new();
        write_obj_to(&mut buf, &m).unwrap();
        let back = parse_obj(Path::new("x"), &buf).unwrap();
        assert_eq!(back, m);
    }
}
