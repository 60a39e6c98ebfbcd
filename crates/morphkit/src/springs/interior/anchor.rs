//! The rigid anchor (Ma et al. 2012, Sec. 3.4, steps 1, 2, 4 and 5): placement, springs, and
//! the blended rigid motion.
//!
//! The anchor is a cube of 8 vertices with edge `size` (step 1). Its 28 vertex pairs are
//! springs of stiffness [`AnchorOptions::stiffness`](super::AnchorOptions) $\cdot k_0$, so it
//! stays rigid when the reverse solve (step 3) places it in a target; each of its vertices is
//! tied at $k_0$ to its nearest body vertices (interior points where the component has any,
//! else surface vertices), through segments that stay inside the solid (step 2).
//!
//! [`AnchorMotion`] is step 4–5: per target the Kabsch motion of the anchor and, for blend
//! coefficients $c$, the motion $T(c) x = R(c)(x - a) + a + d(c)$ of the
//! [module docs](super), with $R(c) = \exp(\sum_s c_s \log R_s)$.

use super::lattice::Solid;
use super::options::{AnchorOptions, AnchorPlacement};
use super::InteriorError;
use crate::geom::{kabsch, RigidTransform};
use crate::mesh::{bbox_diagonal, norm, sub, Point};
use crate::springs::{Spring, SpringKind};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// A placed anchor.
#[derive(Clone, Debug, PartialEq)]
pub struct Anchor {
    /// Extended ids of its 8 vertices.
    pub vertices: Vec<u32>,
    /// Their base positions.
    pub points: Vec<Point>,
    /// Its own edges and its ties to the body, each with its stiffness multiplier.
    pub springs: Vec<(Spring, f64)>,
    /// Centre in the base.
    pub center: Point,
    /// Edge length.
    pub size: f64,
}

/// The deepest point of `s` on a 24³ grid over its bounding box (ties: nearest the centroid),
/// with its distance to the surface.
fn deepest(base: &[Point], s: &Solid) -> (Point, f64) {
    let pts: Vec<Point> = s.vertices.iter().map(|&v| base[v as usize]).collect();
    let (lo, hi) = crate::mesh::bounding_box(&pts);
    let n = 24;
    let mut best = (s.centroid, -1.0, f64::INFINITY);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let t = [i, j, k].map(|q| (q as f64 + 0.5) / n as f64);
                let p = [0, 1, 2].map(|a| lo[a] + t[a] * (hi[a] - lo[a]));
                let (inside, d) = s.query(p);
                let dc = norm(sub(p, s.centroid));
                if inside && (d > best.1 * (1.0 + 1e-9) || (d >= best.1 && dc < best.2)) {
                    best = (p, d, dc);
                }
            }
        }
    }
    (best.0, best.1.max(0.0))
}

/// Places the anchor (step 1) and builds its springs (step 2). `body` holds the base positions
/// of the surface (`0..n`) and interior vertices; the anchor's ids follow them.
pub fn place(
    body: &[Point],
    n: usize,
    solids: &[Solid],
    o: &AnchorOptions,
    k0: f64,
) -> Result<Option<Anchor>, InteriorError> {
    let surface = &body[..n];
    let diag = bbox_diagonal(surface);
    let (center, size, solid) = match &o.placement {
        AnchorPlacement::None => return Ok(None),
        AnchorPlacement::Auto => match solids.iter().max_by(|a, b| a.volume.total_cmp(&b.volume)) {
            Some(s) => {
                // The centroid when it is at least half as deep as the deepest point.
                let (inside, d) = s.query(s.centroid);
                let (p, depth) = deepest(body, s);
                let (c, d) = if inside && d >= 0.5 * depth {
                    (s.centroid, d)
                } else {
                    (p, depth)
                };
                (c, (0.5 * d).min(0.05 * diag), Some(s))
            }
            None => (centroid(surface), 0.02 * diag, None),
        },
        AnchorPlacement::At { center, size } => {
            let hit = solids.iter().find(|s| s.query(*center).0);
            match hit {
                Some(s) => {
                    let d = s.query(*center).1;
                    (*center, size.unwrap_or((0.5 * d).min(0.05 * diag)), Some(s))
                }
                None if solids.is_empty() => (*center, size.unwrap_or(0.02 * diag), None),
                None => return Err(InteriorError::AnchorOutside { position: *center }),
            }
        }
    };
    let size = if size > 0.0 { size } else { 0.01 * diag };
    let first = body.len() as u32;
    let points: Vec<Point> = (0..8)
        .map(|d| {
            let s = [d & 1, (d >> 1) & 1, d >> 2].map(|b| b as f64 - 0.5);
            [0, 1, 2].map(|a| center[a] + size * s[a])
        })
        .collect();
    let vertices: Vec<u32> = (0..8).map(|k| first + k).collect();
    let mut springs = Vec::new();
    for a in 0..8u32 {
        for b in a + 1..8 {
            let s = Spring {
                i: first + a,
                j: first + b,
                kind: SpringKind::Anchor,
            };
            springs.push((s, o.stiffness * k0));
        }
    }
    // Ties: interior points of the anchor's solid where there are any, else its surface.
    let in_solid = |v: usize| solid.is_none_or(|s| s.vertices.binary_search(&(v as u32)).is_ok());
    let interior: Vec<usize> = (n..body.len())
        .filter(|&v| solid.is_none_or(|s| s.query(body[v]).0))
        .collect();
    let candidates: Vec<usize> = if interior.is_empty() {
        (0..n).filter(|&v| in_solid(v)).collect()
    } else {
        interior
    };
    let tol = 1e-9 * diag;
    for (k, p) in points.iter().enumerate() {
        let mut cand: Vec<(f64, usize)> = candidates
            .iter()
            .map(|&v| (norm(sub(body[v], *p)), v))
            .collect();
        cand.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut taken = 0;
        for (_, v) in cand {
            if taken == o.ties_per_vertex {
                break;
            }
            if solid.is_none_or(|s| s.segment_inside(*p, body[v], tol)) {
                let s = Spring {
                    i: v as u32,
                    j: first + k as u32,
                    kind: SpringKind::Anchor,
                };
                springs.push((s, k0));
                taken += 1;
            }
        }
    }
    Ok(Some(Anchor {
        vertices,
        points,
        springs,
        center,
        size,
    }))
}

fn centroid(p: &[Point]) -> Point {
    let mut c = [0.0; 3];
    for q in p {
        for a in 0..3 {
            c[a] += q[a] / p.len() as f64;
        }
    }
    c
}

/// Steps 4–5: the anchor's rigid motion in every target and its blend.
#[derive(Clone, Debug, PartialEq)]
pub struct AnchorMotion {
    /// Base anchor centroid $a$.
    pub center: Point,
    /// $\log R_s$ (axis × angle) per shape; zero for the base.
    pub logs: Vec<Vector3<f64>>,
    /// $d_s$ per shape; zero for the base.
    pub displacements: Vec<Vector3<f64>>,
}

impl AnchorMotion {
    /// From the base anchor and the reverse-solved anchor of every shape (shape 0 = base).
    pub fn new(base: &[Point], per_shape: &[Vec<Point>]) -> Self {
        let center = centroid(base);
        let a = Vector3::from(center);
        let mut logs = Vec::new();
        let mut displacements = Vec::new();
        for (s, p) in per_shape.iter().enumerate() {
            if s == 0 {
                logs.push(Vector3::zeros());
                displacements.push(Vector3::zeros());
                continue;
            }
            let fit = kabsch(base, p, &[]);
            // Through the quaternion (Shepperd's method): the log map of the matrix itself takes
            // acos of its trace and gives NaN for a turn of nearly 180°.
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                fit.rotation,
            ));
            logs.push(q.scaled_axis());
            displacements.push(fit.rotation * a + fit.translation - a);
        }
        Self {
            center,
            logs,
            displacements,
        }
    }

    /// $T(c)$ for affine shape coefficients `c`.
    pub fn at(&self, c: &[f64]) -> RigidTransform {
        let mut w = Vector3::zeros();
        let mut d = Vector3::zeros();
        for (s, &cs) in c.iter().enumerate() {
            w += self.logs[s] * cs;
            d += self.displacements[s] * cs;
        }
        let r: Matrix3<f64> = Rotation3::new(w).into_inner();
        let a = Vector3::from(self.center);
        RigidTransform {
            rotation: r,
            translation: a + d - r * a,
        }
    }

    /// $T(e_s)$: the motion of shape `s`.
    pub fn shape(&self, s: usize) -> RigidTransform {
        let mut c = vec![0.0; self.logs.len()];
        c[s] = 1.0;
        self.at(&c)
    }
}

/// $T^{-1} x$.
pub fn apply_inverse(t: &RigidTransform, p: Point) -> Point {
    let q = t.rotation.transpose() * (Vector3::from(p) - t.translation);
    [q.x, q.y, q.z]
}

/// Point targets given in the world, in the frame that `t` maps to the world (an anchored
/// blend solves in its anchor's frame).
pub fn targets_in_frame(
    t: Option<&RigidTransform>,
    targets: Vec<crate::springs::PointTarget>,
) -> Vec<crate::springs::PointTarget> {
    match t {
        None => targets,
        Some(t) => targets
            .into_iter()
            .map(|p| crate::springs::PointTarget {
                position: apply_inverse(t, p.position),
                ..p
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::slerp;

    /// The unit tetrahedron at the origin.
    fn corner_tetrahedron() -> Vec<Point> {
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    }

    #[test]
    fn two_shape_motion_is_the_papers_slerp_about_the_anchor() {
        let base = corner_tetrahedron();
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 2.0 * std::f64::consts::PI / 3.0)
            .into_inner();
        let t = Vector3::new(3.0, -1.0, 0.5);
        let moved: Vec<Point> = base
            .iter()
            .map(|p| {
                let q = r * Vector3::from(*p) + t;
                [q.x, q.y, q.z]
            })
            .collect();
        let m = AnchorMotion::new(&base, &[base.clone(), moved.clone()]);
        let end = m.shape(1);
        assert!((end.rotation - r).norm() < 1e-12);
        assert!((end.translation - t).norm() < 1e-12);
        let half = m.at(&[0.5, 0.5]);
        assert!((half.rotation - slerp(&Matrix3::identity(), &r, 0.5)).norm() < 1e-12);
        // The anchor centroid moves on the straight line between its two positions.
        let a = centroid(&base);
        let a1 = centroid(&moved);
        let h = half.apply(a);
        for k in 0..3 {
            assert!((h[k] - 0.5 * (a[k] + a1[k])).abs() < 1e-12);
        }
        let back = apply_inverse(&end, end.apply([0.3, 0.2, 0.1]));
        assert!(norm(sub(back, [0.3, 0.2, 0.1])) < 1e-12);
    }

    #[test]
    fn a_turn_of_nearly_half_a_circle_has_a_finite_log() {
        let base = corner_tetrahedron();
        for angle in [std::f64::consts::PI, std::f64::consts::PI - 1e-9] {
            let r = Rotation3::from_axis_angle(&Vector3::y_axis(), angle).into_inner();
            let moved: Vec<Point> = base
                .iter()
                .map(|p| {
                    let q = r * Vector3::from(*p);
                    [q.x, q.y, q.z]
                })
                .collect();
            let m = AnchorMotion::new(&base, &[base.clone(), moved]);
            assert!(m.logs[1].iter().all(|v| v.is_finite()), "{:?}", m.logs[1]);
            assert!(
                (m.logs[1].norm() - angle).abs() < 1e-6,
                "{}",
                m.logs[1].norm()
            );
            assert!((m.shape(1).rotation - r).norm() < 1e-6);
        }
    }
}
