//! Object File Format (OFF): `OFF`, the counts `#V #F #E`, then vertices and faces
//! (`n i0 … i(n−1)`, trailing per-face colour values ignored). `#` starts a comment.
//! The header keyword may share its line with the counts (`OFF 8 6 0`); `COFF`/`NOFF` style
//! prefixes are accepted and their extra per-vertex values ignored.

use super::source::{lines, parse_f64, parse_i64, show, tokens};
use super::IoError;
use crate::mesh::{Point, Polygons, TriMesh};
use std::io::Write;
use std::path::Path;

/// Parses OFF text. `path` only names the file in errors, which name the line.
pub fn parse_off(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    let bytes = super::strip_bom(bytes);
    // Non-empty, comment-stripped lines.
    let mut it = lines(bytes).filter_map(|(n, l)| {
        let l = match l.iter().position(|&b| b == b'#') {
            Some(i) => &l[..i],
            None => l,
        };
        (tokens(l).next().is_some()).then_some((n, l))
    });
    let (n0, first) = it
        .next()
        .ok_or_else(|| IoError::parse(path, 1, "no 'OFF' header"))?;
    let mut toks = tokens(first);
    let key = toks.next().unwrap_or(b"");
    if !key.ends_with(b"OFF") {
        return Err(IoError::parse(
            path,
            n0,
            format!("expected 'OFF', found '{}'", show(key)),
        ));
    }
    let mut count_toks: Vec<&[u8]> = toks.collect();
    let mut count_line = n0;
    if count_toks.is_empty() {
        let (n, l) = it
            .next()
            .ok_or_else(|| IoError::parse(path, n0 + 1, "missing the vertex and face counts"))?;
        count_toks = tokens(l).collect();
        count_line = n;
    }
    let count = |k: usize| -> Result<usize, IoError> {
        let t = count_toks.get(k).copied().unwrap_or(b"");
        parse_i64(t)
            .filter(|&c| c >= 0)
            .map(|c| c as usize)
            .ok_or_else(|| {
                IoError::parse(path, count_line, format!("malformed count '{}'", show(t)))
            })
    };
    let (nv, nf) = (count(0)?, count(1)?);
    let mut positions: Vec<Point> = Vec::with_capacity(nv.min(1 << 24));
    for v in 0..nv {
        let (n, l) = it.next().ok_or_else(|| {
            IoError::parse(
                path,
                count_line,
                format!("the file ends before vertex {v} of {nv}"),
            )
        })?;
        let mut p = [0.0; 3];
        let mut t = tokens(l);
        for c in &mut p {
            let tok = t
                .next()
                .ok_or_else(|| IoError::parse(path, n, "vertex has fewer than 3 coordinates"))?;
            *c = parse_f64(tok).ok_or_else(|| {
                IoError::parse(path, n, format!("malformed number '{}'", show(tok)))
            })?;
            if !c.is_finite() {
                return Err(IoError::parse(
                    path,
                    n,
                    format!("non-finite coordinate '{}'", show(tok)),
                ));
            }
        }
        positions.push(p);
    }
    let mut polys = Polygons {
        offsets: Vec::with_capacity(nf.min(1 << 24) + 1),
        indices: Vec::new(),
    };
    polys.offsets.push(0);
    for f in 0..nf {
        let (n, l) = it.next().ok_or_else(|| {
            IoError::parse(
                path,
                count_line,
                format!("the file ends before face {f} of {nf}"),
            )
        })?;
        let mut t = tokens(l);
        let int = |tok: Option<&[u8]>| -> Result<i64, IoError> {
            let tok = tok.unwrap_or(b"");
            parse_i64(tok).ok_or_else(|| {
                IoError::parse(path, n, format!("malformed integer '{}'", show(tok)))
            })
        };
        let k = int(t.next())?;
        if k < 3 {
            return Err(IoError::parse(
                path,
                n,
                format!("face has {k} vertices, needs at least 3"),
            ));
        }
        for _ in 0..k {
            let i = int(t.next())?;
            if i < 0 || i as usize >= nv {
                return Err(IoError::parse(
                    path,
                    n,
                    format!("face index {i} is out of range: the file has {nv} vertices"),
                ));
            }
            polys.indices.push(i as u32);
        }
        polys.offsets.push(polys.indices.len() as u32);
    }
    Ok(TriMesh::from_polygons(positions, polys))
}

/// Writes `mesh` as OFF text (polygons when present, full `f64` precision).
pub fn write_off_to(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    let nf = mesh
        .polygons
        .as_ref()
        .map_or(mesh.num_triangles(), |p| p.len());
    writeln!(w, "OFF\n{} {} 0", mesh.num_vertices(), nf)?;
    for p in &mesh.positions {
        writeln!(w, "{} {} {}", p[0], p[1], p[2])?;
    }
    match &mesh.polygons {
        Some(polys) => {
            for poly in polys.iter() {
                write!(w, "{}", poly.len())?;
                for i in poly {
                    write!(w, " {i}")?;
                }
                writeln!(w)?;
            }
        }
        None => {
            for t in &mesh.triangles {
                writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
            }
        }
    }
    Ok(())
}

/// Writes `mesh` as OFF to `path` atomically. A NaN or infinite coordinate is an
/// [`IoError::Content`] error naming the vertex, and nothing is written.
pub fn write_off(path: &Path, mesh: &TriMesh) -> Result<(), IoError> {
    super::atomic::check_finite(path, &mesh.positions)?;
    super::atomic::write_atomic_with(path, |w| write_off_to(w, mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_with_comments_and_inline_counts() {
        let m = parse_off(
            Path::new("t.off"),
            b"# c\nOFF 4 1 0\n0 0 0\n1 0 0\n1 1 0 # x\n0 1 0\n4 0 1 2 3 255 0 0\n",
        )
        .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let mut buf = Vec::new();
        write_off_to(&mut buf, &m).unwrap();
        assert_eq!(parse_off(Path::new("b.off"), &buf).unwrap(), m);
    }

    #[test]
    fn out_of_range_names_line() {
        let e = parse_off(
            Path::new("t.off"),
            b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("t.off:6: face index 3 is out of range"),
            "{e}"
        );
    }
}
