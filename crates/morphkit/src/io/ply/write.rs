//! The PLY writer: ASCII or binary, polygons kept, optional per-vertex or per-face colours.

use super::{PlyEncoding, Scalar};
use crate::io::colors::Colors;
use crate::io::IoError;
use crate::mesh::{Polygons, TriMesh};
use std::io::Write;
use std::path::Path;

/// Writes `mesh` as PLY in the given encoding (polygons when present), atomically. A NaN or
/// infinite coordinate is an [`IoError::Content`] error naming the vertex, and nothing is written.
pub fn write_ply(path: &Path, mesh: &TriMesh, encoding: PlyEncoding) -> Result<(), IoError> {
    crate::io::atomic::check_finite(path, &mesh.positions)?;
    let faces = faces_of(mesh);
    crate::io::atomic::write_atomic_with(path, |w| write_ply_to(w, mesh, &faces, encoding, None))
}

/// Writes `mesh` as binary little-endian PLY with colours, atomically. Non-finite coordinates
/// are refused as in [`write_ply`].
///
/// [`Colors::PerVertex`] needs one colour per vertex. [`Colors::PerFace`] needs one colour
/// per triangle (the triangles are written) or, for a mesh with polygons, one per polygon (the
/// polygons are written); any other length is an [`IoError::Content`] error.
pub fn write_ply_colored(path: &Path, mesh: &TriMesh, colors: &Colors) -> Result<(), IoError> {
    crate::io::atomic::check_finite(path, &mesh.positions)?;
    let faces = match colors {
        Colors::PerVertex(c) if c.len() == mesh.num_vertices() => faces_of(mesh),
        Colors::PerFace(c) if c.len() == mesh.num_triangles() => triangles_as_polygons(mesh),
        Colors::PerFace(c) if mesh.polygons.as_ref().is_some_and(|p| p.len() == c.len()) => {
            faces_of(mesh)
        }
        Colors::PerVertex(c) => {
            return Err(IoError::content(
                path,
                format!(
                    "{} vertex colours given for {} vertices",
                    c.len(),
                    mesh.num_vertices()
                ),
            ))
        }
        Colors::PerFace(c) => {
            return Err(IoError::content(
                path,
                format!(
                    "{} face colours given for {} triangles",
                    c.len(),
                    mesh.num_triangles()
                ),
            ))
        }
    };
    crate::io::atomic::write_atomic_with(path, |w| {
        write_ply_to(
            w,
            mesh,
            &faces,
            PlyEncoding::BinaryLittleEndian,
            Some(colors),
        )
    })
}

fn triangles_as_polygons(mesh: &TriMesh) -> Polygons {
    Polygons {
        offsets: (0..=mesh.num_triangles() as u32).map(|t| 3 * t).collect(),
        indices: mesh.triangles.iter().flatten().copied().collect(),
    }
}

pub(super) fn faces_of(mesh: &TriMesh) -> Polygons {
    mesh.polygons
        .clone()
        .unwrap_or_else(|| triangles_as_polygons(mesh))
}

pub(super) fn write_ply_to(
    w: &mut dyn Write,
    mesh: &TriMesh,
    faces: &Polygons,
    encoding: PlyEncoding,
    colors: Option<&Colors>,
) -> std::io::Result<()> {
    let format = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    let max_len = faces.iter().map(<[u32]>::len).max().unwrap_or(3);
    let count_ty = if max_len <= 255 {
        Scalar::U8
    } else {
        Scalar::I32
    };
    let (vc, fc) = match colors {
        Some(Colors::PerVertex(c)) => (Some(c), None),
        Some(Colors::PerFace(c)) => (None, Some(c)),
        None => (None, None),
    };
    let rgb = "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    write!(
        w,
        "ply\nformat {format} 1.0\ncomment written by morphkit\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\n{}element face {}\n\
         property list {} int vertex_indices\n{}end_header\n",
        mesh.num_vertices(),
        if vc.is_some() { rgb } else { "" },
        faces.len(),
        if count_ty == Scalar::U8 {
            "uchar"
        } else {
            "int"
        },
        if fc.is_some() { rgb } else { "" },
    )?;
    let big = encoding == PlyEncoding::BinaryBigEndian;
    let f64b = |x: f64| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for (v, p) in mesh.positions.iter().enumerate() {
        if encoding == PlyEncoding::Ascii {
            write!(w, "{} {} {}", p[0], p[1], p[2])?;
            if let Some(c) = vc {
                write!(w, " {} {} {}", c[v][0], c[v][1], c[v][2])?;
            }
            writeln!(w)?;
        } else {
            for x in p {
                w.write_all(&f64b(*x))?;
            }
            if let Some(c) = vc {
                w.write_all(&c[v])?;
            }
        }
    }
    for (f, poly) in faces.iter().enumerate() {
        if encoding == PlyEncoding::Ascii {
            write!(w, "{}", poly.len())?;
            for i in poly {
                write!(w, " {i}")?;
            }
            if let Some(c) = fc {
                write!(w, " {} {} {}", c[f][0], c[f][1], c[f][2])?;
            }
            writeln!(w)?;
        } else {
            if count_ty == Scalar::U8 {
                w.write_all(&[poly.len() as u8])?;
            } else {
                w.write_all(&i32b(poly.len() as i32))?;
            }
            for &i in poly {
                w.write_all(&i32b(i as i32))?;
            }
            if let Some(c) = fc {
                w.write_all(&c[f])?;
            }
        }
    }
    Ok(())
}
