//! `V, F` arrays into the library's [`TriMesh`], validated by the library.

use crate::arrays;
use crate::errors::{new_err, Kind};
use morphkit::mesh::{validate, TriMesh};
use pyo3::prelude::*;

/// Builds and validates a mesh from `V` `(n, 3)` and `F` `(m, 3)`; `what` names the mesh in
/// errors (`"source"`, `"base"`, …).
pub fn from_arrays(what: &str, v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let positions = arrays::points(&format!("{what} V"), v)?;
    let triangles = arrays::faces(&format!("{what} F"), f, Some(positions.len()))?;
    let mesh = TriMesh::new(positions, triangles);
    validate(&mesh).map_err(|e| new_err(Kind::Mesh, format!("{what}: {e}")))?;
    Ok(mesh)
}
