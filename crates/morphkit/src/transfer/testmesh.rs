//! Synthetic meshes for unit tests.

use crate::mesh::{Point, TriMesh};

/// A planar `nx × ny` grid of squares of side `h` in the z = 0 plane, two triangles each.
pub fn grid(nx: usize, ny: usize, h: f64) -> TriMesh {
    let mut p = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            p.push([i as f64 * h, j as f64 * h, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut t = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(p, t)
}

/// A closed UV sphere of radius `r`: `nu` segments around, `nv` bands, outward normals.
pub fn sphere(nu: usize, nv: usize, r: f64) -> TriMesh {
    use std::f64::consts::PI;
    let mut p: Vec<Point> = vec![[0.0, 0.0, r]];
    for j in 1..nv {
        let th = PI * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = 2.0 * PI * i as f64 / nu as f64;
            p.push([
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ]);
        }
    }
    p.push([0.0, 0.0, -r]);
    let south = (p.len() - 1) as u32;
    let ring = |j: usize, i: usize| (1 + (j - 1) * nu + i % nu) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        t.push([0, ring(1, i), ring(1, i + 1)]);
        t.push([south, ring(nv - 1, i + 1), ring(nv - 1, i)]);
    }
    for j in 1..nv - 1 {
        for i in 0..nu {
            t.push([ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)]);
            t.push([ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)]);
        }
    }
    TriMesh::new(p, t)
}
