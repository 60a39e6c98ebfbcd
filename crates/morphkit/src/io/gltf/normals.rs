//! Vertex normals for glTF `NORMAL` attributes (glTF 2.0 §3.7.2.1: unit length, `f32` VEC3).
//!
//! A vertex normal is the area-weighted mean of its triangles' normals (the sum of the
//! unnormalised cross products), normalised. A vertex with no triangle of nonzero area gets
//! `+z`, so every written normal is unit length.

use crate::mesh::{triangle_normal, Point};

/// Unit vertex normals of `positions` over `triangles`, `#V`, in `f64`.
pub(super) fn vertex_normals(positions: &[Point], triangles: &[[u32; 3]]) -> Vec<Point> {
    let mut n = vec![[0.0; 3]; positions.len()];
    for &t in triangles {
        let f = triangle_normal(positions, t);
        for &v in &t {
            for k in 0..3 {
                n[v as usize][k] += f[k];
            }
        }
    }
    for q in &mut n {
        let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        *q = if len > 0.0 && len.is_finite() {
            [q[0] / len, q[1] / len, q[2] / len]
        } else {
            [0.0, 0.0, 1.0]
        };
    }
    n
}

/// `f32` copies of unit normals, renormalised after rounding so that the validator's unit
/// length check (|‖n‖ − 1| ≤ 5e-4) holds.
pub(super) fn to_f32_unit(n: &[Point]) -> Vec<[f32; 3]> {
    n.iter()
        .map(|q| {
            let f = q.map(|x| x as f32);
            let len = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            f.map(|x| x / len)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_unit_and_point_out_of_a_ccw_triangle() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [5.0, 5.0, 5.0],
        ];
        let n = vertex_normals(&p, &[[0, 1, 2]]);
        assert_eq!(n[0], [0.0, 0.0, 1.0]);
        assert_eq!(n[3], [0.0, 0.0, 1.0], "an isolated vertex gets +z");
        for q in to_f32_unit(&n) {
            let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-6);
        }
    }
}
