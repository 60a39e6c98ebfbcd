//! Synthetic meshes for the transfer unit tests, in the parameterisation those tests use
//! (built by [`crate::mesh::generate`]).

use crate::mesh::{generate, TriMesh};

/// A planar `nx × ny` grid of squares of side `h` in the z = 0 plane, two triangles each.
pub fn grid(nx: usize, ny: usize, h: f64) -> TriMesh {
    generate::grid(nx, ny, nx as f64 * h, ny as f64 * h)
}

/// A closed UV sphere of radius `r`: `nu` segments around, `nv` bands, outward normals.
pub fn sphere(nu: usize, nv: usize, r: f64) -> TriMesh {
    generate::uv_sphere(r, nv, nu)
}
