//! The minimal gauge of a component with no fixed vertex (Ma et al. 2012, Sec. 3.4): three
//! pinned vertices and the frame the solver holds the component in; see the docs of
//! [`super::constraints`].

use crate::mesh::{cross, norm, sub, Point};

/// True when the points are not all within `tol` of one line.
pub(super) fn spans_plane(p: &[Point], tol: f64) -> bool {
    if p.len() < 3 {
        return false;
    }
    let a = p[0];
    let Some(b) = p
        .iter()
        .copied()
        .max_by(|x, y| norm(sub(*x, a)).total_cmp(&norm(sub(*y, a))))
    else {
        return false;
    };
    let d = sub(b, a);
    let ld = norm(d);
    if ld <= tol {
        return false;
    }
    p.iter().any(|&c| norm(cross(d, sub(c, a))) / ld > tol)
}

/// The minimal gauge of one component: vertices `a` (nearest the centroid), `b` (farthest
/// from `a`) and `c` (farthest from the line `ab`), and the rotation `frame` (rows
/// $e_1 = \widehat{b - a}$, $e_3 = \widehat{e_1 \times (c - a)}$, $e_2 = e_3 \times e_1$) in which
/// the solver holds the component. In that frame the pins are `a`: x, y, z; `b`: y, z; `c`: z.
/// Every configuration of the component can be moved rigidly onto these pins (put `b − a`
/// along x, then turn about x until `c` lies in the plane), so they remove exactly the rigid
/// motions, whatever the blend does to the component's size and shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Gauge {
    /// The component's vertices.
    pub vertices: Vec<u32>,
    /// The pinned vertices `[a, b, c]`.
    pub pinned: [u32; 3],
    /// Rotation from world to solver coordinates (row-major, rows `e1, e2, e3`).
    pub frame: [[f64; 3]; 3],
}

impl Gauge {
    pub(super) fn new(p: &[Point], verts: &[u32]) -> Self {
        let inv = 1.0 / verts.len() as f64;
        let mut centroid = [0.0; 3];
        for &v in verts {
            for k in 0..3 {
                centroid[k] += p[v as usize][k] * inv;
            }
        }
        let dist = |v: u32, q: Point| norm(sub(p[v as usize], q));
        let pick = |key: &dyn Fn(u32) -> f64| {
            verts
                .iter()
                .copied()
                .fold((verts[0], f64::NEG_INFINITY), |best, v| {
                    let k = key(v);
                    if k > best.1 {
                        (v, k)
                    } else {
                        best
                    }
                })
        };
        let (a, _) = pick(&|v| -dist(v, centroid));
        let pa = p[a as usize];
        let (b, _) = pick(&|v| dist(v, pa));
        let d = sub(p[b as usize], pa);
        let (c, _) = pick(&|v| norm(cross(d, sub(p[v as usize], pa))));
        let unit = |v: Point| {
            let n = norm(v);
            if n > 0.0 {
                [v[0] / n, v[1] / n, v[2] / n]
            } else {
                v
            }
        };
        let e1 = if norm(d) > 0.0 {
            unit(d)
        } else {
            [1.0, 0.0, 0.0]
        };
        let mut e3 = unit(cross(e1, sub(p[c as usize], pa)));
        if norm(e3) == 0.0 {
            // All on one line: any plane through it will do.
            let helper = if e1[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            e3 = unit(cross(e1, helper));
        }
        let e2 = cross(e3, e1);
        Self {
            vertices: verts.to_vec(),
            pinned: [a, b, c],
            frame: [e1, e2, e3],
        }
    }

    /// The solver frame for positions `p` of the component: rows $\widehat{b - a}$,
    /// $e_2$, $\widehat{e_1 \times (c - a)}$ as in the type's doc, or the base frame when
    /// `a`, `b`, `c` are (nearly) collinear in `p`.
    pub fn frame_for(&self, p: &[Point]) -> [[f64; 3]; 3] {
        let [a, b, c] = self.pinned.map(|v| p[v as usize]);
        let d = sub(b, a);
        let ld = norm(d);
        let n = cross(d, sub(c, a));
        let ln = norm(n);
        if ld <= 0.0 || ln <= 1e-9 * ld * ld {
            return self.frame;
        }
        let e1 = [d[0] / ld, d[1] / ld, d[2] / ld];
        let e3 = [n[0] / ln, n[1] / ln, n[2] / ln];
        [e1, cross(e3, e1), e3]
    }

    /// The pinned `(vertex, axis)` pairs, axes in solver coordinates.
    pub fn pins(&self) -> [(u32, usize); 6] {
        let [a, b, c] = self.pinned;
        [(a, 0), (a, 1), (a, 2), (b, 1), (b, 2), (c, 2)]
    }

    /// World → solver coordinates in the base frame.
    pub fn to_solver(&self, q: Point) -> Point {
        rotate_into(&self.frame, q)
    }
}

/// `f q` for a frame `f` given by its rows.
pub fn rotate_into(f: &[[f64; 3]; 3], q: Point) -> Point {
    [
        crate::mesh::dot(f[0], q),
        crate::mesh::dot(f[1], q),
        crate::mesh::dot(f[2], q),
    ]
}
