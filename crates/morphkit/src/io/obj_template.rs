//! Writing new positions into an artist's own OBJ: every record the file has (`vt`, `vn`,
//! `usemtl`, `mtllib`, `g`/`o` groups, `s` smoothing groups, comments, polygons with their
//! texture and normal indices) comes back as it was, with the `v` positions replaced and the
//! `vn` normals recomputed from them.
//!
//! A morphkit result keeps the input's vertex layout and order (split seams are welded only
//! for the solve, see [`crate::mesh::Weld`]), so vertex `k` of a result is the file's `k`-th
//! `v` record. Extra components of a `v` record (`w`, vertex colours) are kept. A normal is
//! the area-weighted sum of the normals of the faces whose corners use it, so hard edges and
//! smoothing stay as the artist split them; a normal no face uses is kept. Lines keep their
//! own breaks (`\n`, `\r\n`, or `\r` from old Mac tools).

use super::source::{lines, lines_with_ends, parse_i64, tokens};
use super::IoError;
use crate::mesh::{cross, sub, Point};
use std::io::Write;
use std::path::{Path, PathBuf};

/// An OBJ file's text, kept to write other positions into; see the module docs.
#[derive(Clone, Debug)]
pub struct ObjTemplate {
    path: PathBuf,
    text: Vec<u8>,
    vertices: usize,
}

impl ObjTemplate {
    /// Reads `path` (`.obj` or `.obj.gz`) as a template.
    pub fn read(path: &Path) -> Result<Self, IoError> {
        let text = super::source::read_file(path)?;
        let text = super::strip_bom(&text).to_vec();
        let vertices = lines(&text)
            .filter(|(_, l)| tokens(l).next() == Some(b"v".as_slice()))
            .count();
        Ok(Self {
            path: path.to_path_buf(),
            text,
            vertices,
        })
    }

    /// The number of `v` records.
    pub fn num_vertices(&self) -> usize {
        self.vertices
    }

    /// The file the template was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The template's text with `positions` (one per `v` record) written in, and its normals
    /// recomputed; errors name `out`.
    pub fn fill(&self, out: &Path, positions: &[Point]) -> Result<Vec<u8>, IoError> {
        if positions.len() != self.vertices {
            return Err(IoError::content(
                out,
                format!(
                    "{} positions for the {} vertices of {}",
                    positions.len(),
                    self.vertices,
                    self.path.display()
                ),
            ));
        }
        super::atomic::check_finite(out, positions)?;
        let normals = self.normals(positions);
        let mut w = Vec::with_capacity(self.text.len() + self.text.len() / 4);
        let (mut v, mut n) = (0usize, 0usize);
        for (_, line, end) in lines_with_ends(&self.text) {
            let mut toks = tokens(line);
            match toks.next() {
                Some(b"v") => {
                    let p = positions[v];
                    v += 1;
                    write!(w, "v {} {} {}", p[0], p[1], p[2]).expect("in memory");
                    for extra in toks.skip(3) {
                        w.push(b' ');
                        w.extend_from_slice(extra);
                    }
                }
                Some(b"vn") => {
                    match normals.get(n).copied().flatten() {
                        Some(q) => write!(w, "vn {} {} {}", q[0], q[1], q[2]).expect("in memory"),
                        None => w.extend_from_slice(line),
                    }
                    n += 1;
                }
                _ => w.extend_from_slice(line),
            }
            // Each line keeps its own break (`\n`, `\r\n` or `\r`), the last none.
            w.extend_from_slice(end);
        }
        Ok(w)
    }

    /// Writes [`ObjTemplate::fill`] to `out` atomically (gzip-compressed when `gzip`).
    pub fn write(&self, out: &Path, positions: &[Point], gzip: bool) -> Result<(), IoError> {
        let bytes = self.fill(out, positions)?;
        super::atomic::write_atomic_with(out, |w| {
            if gzip {
                let mut gz = flate2::write::GzEncoder::new(w, flate2::Compression::default());
                gz.write_all(&bytes)?;
                gz.finish()?;
                Ok(())
            } else {
                w.write_all(&bytes)
            }
        })
    }

    /// The recomputed normal of each `vn` record (`None`: no face corner uses it).
    fn normals(&self, positions: &[Point]) -> Vec<Option<Point>> {
        let mut sums: Vec<Option<Point>> = Vec::new();
        let (mut nv, mut nn) = (0i64, 0i64);
        let mut corners: Vec<(usize, Option<usize>)> = Vec::new();
        for (_, line) in lines(&self.text) {
            let mut toks = tokens(line);
            match toks.next() {
                Some(b"v") => nv += 1,
                Some(b"vn") => {
                    nn += 1;
                    sums.push(None);
                }
                Some(b"f") => {
                    corners.clear();
                    for tok in toks {
                        if tok.starts_with(b"#") {
                            break;
                        }
                        let mut parts = tok.split(|&b| b == b'/');
                        let resolve = |x: Option<&[u8]>, count: i64| {
                            let i = parse_i64(x.filter(|s| !s.is_empty())?)?;
                            let abs = if i > 0 { i - 1 } else { count + i };
                            (0..count).contains(&abs).then_some(abs as usize)
                        };
                        let Some(pv) = resolve(parts.next(), nv) else {
                            corners.clear();
                            break;
                        };
                        let _texture = parts.next();
                        corners.push((pv, resolve(parts.next(), nn)));
                    }
                    if corners.len() < 3 {
                        continue;
                    }
                    // The polygon's area vector (Newell's fan from its first corner).
                    let p0 = positions[corners[0].0];
                    let mut area = [0.0; 3];
                    for k in 1..corners.len() - 1 {
                        let c = cross(
                            sub(positions[corners[k].0], p0),
                            sub(positions[corners[k + 1].0], p0),
                        );
                        for a in 0..3 {
                            area[a] += c[a];
                        }
                    }
                    for &(_, n) in &corners {
                        if let Some(n) = n {
                            let s = sums[n].get_or_insert([0.0; 3]);
                            for a in 0..3 {
                                s[a] += area[a];
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        sums.into_iter()
            .map(|s| {
                let s = s?;
                let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
                (len > 0.0 && len.is_finite()).then(|| s.map(|x| x / len))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE_FACE: &str = "# an artist's file\nmtllib look.mtl\no Plate\nv 0 0 0 0.5 0.5 0.5\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nvn 1 0 0\ng front\nusemtl red\ns 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";

    #[test]
    fn every_record_comes_back_with_new_positions_and_normals() {
        let d = std::env::temp_dir().join(format!("morphkit-objt-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("plate.obj");
        std::fs::write(&p, CUBE_FACE).unwrap();
        let t = ObjTemplate::read(&p).unwrap();
        assert_eq!(t.num_vertices(), 4);
        // Turned to face +x: x = 0 for all, y and z from the old x and y.
        let turned = [
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
            [0.0, 0.0, 1.0],
        ];
        let text = String::from_utf8(t.fill(&d.join("o.obj"), &turned).unwrap()).unwrap();
        // The first vertex stays at the origin with its colour.
        let want = CUBE_FACE
            .replace("v 1 0 0\n", "v 0 1 0\n")
            .replace("v 1 1 0\nv 0 1 0\n", "v 0 1 1\nv 0 0 1\n")
            .replace("vn 0 0 1", "vn 1 0 0");
        assert_eq!(text, want);
        // The unused normal is kept; a wrong count is an error naming the template.
        assert!(text.contains("vn 1 0 0\ng front"));
        let e = t
            .fill(&d.join("o.obj"), &turned[..3])
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 positions for the 4 vertices of"), "{e}");
        // CRLF and CR-only files come back with their own line breaks.
        for eol in ["\r\n", "\r"] {
            let p = d.join("eol.obj");
            std::fs::write(&p, CUBE_FACE.replace('\n', eol)).unwrap();
            let t = ObjTemplate::read(&p).unwrap();
            assert_eq!(t.num_vertices(), 4);
            let text = String::from_utf8(t.fill(&d.join("o.obj"), &turned).unwrap()).unwrap();
            assert_eq!(text, want.replace('\n', eol), "{eol:?}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
