//! Deformation gradients of triangles (Sumner & Popović 2004, Sec. 3; Wang & Lee 2008,
//! Sec. 3.1.1, math-notes §2).
//!
//! For a triangle $(v_1, v_2, v_3)$ a fourth vertex $v_4 = v_1 + n / \sqrt{\|n\|}$,
//! $n = (v_2 - v_1) \times (v_3 - v_1)$, is added along the scaled normal, so that the frame
//! $V = [v_2 - v_1,\; v_3 - v_1,\; v_4 - v_1]$ (3 × 3, columns) is invertible and its third
//! column scales like an edge length. With $\tilde V$ built the same way from the deformed
//! triangle, the deformation gradient is
//! $$D = \tilde V V^{-1} \quad (3 \times 3),$$
//! the affine map's linear part that takes the reference triangle (and its normal) to the
//! deformed one. A rigid motion gives $D = R$; a uniform scale $s$ gives $D = s I$.

use super::error::TransferError;
use crate::mesh::{cross, dot, norm, sub, Point, TriMesh};
use nalgebra::{Matrix3, Vector3};

/// Reference triangles whose doubled area is below this fraction of the squared
/// bounding-box diagonal are *degenerate*: they have no normal and no $V^{-1}$.
pub const DEGENERATE_AREA: f64 = 1e-14;

/// The frame $V = [e_1, e_2, n/\sqrt{\|n\|}]$ of a triangle, or `None` when $n = 0$.
pub fn triangle_frame(p: &[Point], t: [u32; 3]) -> Option<Matrix3<f64>> {
    let a = p[t[0] as usize];
    let e1 = sub(p[t[1] as usize], a);
    let e2 = sub(p[t[2] as usize], a);
    let n = cross(e1, e2);
    let len = norm(n);
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    let s = 1.0 / len.sqrt();
    Some(Matrix3::from_columns(&[
        Vector3::from(e1),
        Vector3::from(e2),
        Vector3::new(n[0] * s, n[1] * s, n[2] * s),
    ]))
}

/// The degeneracy tolerance of a reference mesh: [`DEGENERATE_AREA`] times its squared
/// bounding-box diagonal, compared with a triangle's doubled area $\|n\|$.
pub fn degeneracy_tolerance(reference: &TriMesh) -> f64 {
    let d = reference.bbox_diagonal();
    DEGENERATE_AREA * d * d
}

/// $V^{-1}$ of triangle `t` of a reference pose `p`, or `None` when the triangle is
/// *degenerate*: its doubled area $\|n\|$ is not above `tol` (from
/// [`degeneracy_tolerance`]) or its frame is not invertible. This is the one degeneracy test
/// of the transfer pipeline: degenerate source triangles get the identity gradient
/// ([`GradientOperator`]) and are never matched ([`super::correspond`]); degenerate target
/// triangles are skipped by the solve ([`super::TransferSolver`]).
pub fn reference_frame_inverse(p: &[Point], t: [u32; 3], tol: f64) -> Option<Matrix3<f64>> {
    let n = norm(crate::mesh::triangle_normal(p, t));
    if n > tol {
        triangle_frame(p, t).and_then(|v| v.try_inverse())
    } else {
        None
    }
}

/// Precomputed $V^{-1}$ of every triangle of a reference pose; gives the gradients of any
/// frame with the same connectivity in `O(#F)`.
#[derive(Clone, Debug)]
pub struct GradientOperator {
    triangles: Vec<[u32; 3]>,
    num_vertices: usize,
    inverse: Vec<Matrix3<f64>>,
    degenerate: Vec<usize>,
}

impl GradientOperator {
    /// Inverts the frame of every triangle of `reference`. Degenerate triangles (see
    /// [`DEGENERATE_AREA`] and [`reference_frame_inverse`]) are listed in
    /// [`GradientOperator::degenerate`] and get the identity as their gradient in every frame.
    pub fn new(reference: &TriMesh) -> Self {
        let tol = degeneracy_tolerance(reference);
        let mut degenerate = Vec::new();
        let inverse = reference
            .triangles
            .iter()
            .enumerate()
            .map(|(t, &tri)| {
                reference_frame_inverse(&reference.positions, tri, tol).unwrap_or_else(|| {
                    degenerate.push(t);
                    Matrix3::zeros()
                })
            })
            .collect();
        Self {
            triangles: reference.triangles.clone(),
            num_vertices: reference.num_vertices(),
            inverse,
            degenerate,
        }
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Reference triangles without a gradient (zero area).
    pub fn degenerate(&self) -> &[usize] {
        &self.degenerate
    }

    /// $V^{-1}$ of triangle `t` (zero for a degenerate triangle).
    pub fn frame_inverse(&self, t: usize) -> &Matrix3<f64> {
        &self.inverse[t]
    }

    /// The deformation gradient $D_t = \tilde V_t V_t^{-1}$ of every triangle of `frame`
    /// (positions over the reference connectivity). A triangle that collapses in the frame gets
    /// $\tilde V$ with a zero third column (its deformed normal is zero), which is the limit
    /// of the formula, not NaN.
    /// Errors name frame 0; use [`GradientOperator::gradients_at`] to name another.
    pub fn gradients(&self, frame: &[Point]) -> Result<Vec<Matrix3<f64>>, TransferError> {
        self.gradients_at(0, frame)
    }

    /// [`GradientOperator::gradients`] of frame number `index` of an animation: errors name
    /// that frame.
    pub fn gradients_at(
        &self,
        index: usize,
        frame: &[Point],
    ) -> Result<Vec<Matrix3<f64>>, TransferError> {
        if frame.len() != self.num_vertices {
            return Err(TransferError::FrameVertexCount {
                frame: index,
                expected: self.num_vertices,
                found: frame.len(),
            });
        }
        if let Some(v) = frame.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(TransferError::NonFinite {
                what: "source frame vertex",
                index: v,
            });
        }
        let mut out = Vec::with_capacity(self.triangles.len());
        let mut degenerate = self.degenerate.iter().peekable();
        for (t, &tri) in self.triangles.iter().enumerate() {
            if degenerate.peek() == Some(&&t) {
                degenerate.next();
                out.push(Matrix3::identity());
                continue;
            }
            let vt = triangle_frame(frame, tri).unwrap_or_else(|| {
                let a = frame[tri[0] as usize];
                Matrix3::from_columns(&[
                    Vector3::from(sub(frame[tri[1] as usize], a)),
                    Vector3::from(sub(frame[tri[2] as usize], a)),
                    Vector3::zeros(),
                ])
            });
            out.push(vt * self.inverse[t]);
        }
        Ok(out)
    }
}

/// Deformation gradients of every triangle of `frame` relative to `reference` (same
/// connectivity): one-shot form of [`GradientOperator`].
pub fn deformation_gradients(
    reference: &TriMesh,
    frame: &[Point],
) -> Result<Vec<Matrix3<f64>>, TransferError> {
    GradientOperator::new(reference).gradients(frame)
}

/// Precomputed reference normals for [`FlipCheck::flipped`]: build once per reference mesh
/// and test every frame against it.
#[derive(Clone, Debug)]
pub struct FlipCheck {
    triangles: Vec<[u32; 3]>,
    /// Reference normal of every triangle (zero for a zero-area triangle).
    normals: Vec<Point>,
}

impl FlipCheck {
    /// Computes the normals of `reference`'s triangles.
    pub fn new(reference: &TriMesh) -> Self {
        Self {
            triangles: reference.triangles.clone(),
            normals: reference
                .triangles
                .iter()
                .map(|&t| crate::mesh::triangle_normal(&reference.positions, t))
                .collect(),
        }
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Triangles of `frame` (over the reference's connectivity) that face against the
    /// orientation their intended gradient gives them: triangle `t` is flipped when its frame
    /// normal $\tilde n_t$ satisfies $\tilde n_t \cdot (\operatorname{cof} M_t)\, n_t \le 0$,
    /// with $n_t$ the reference normal and $\operatorname{cof} M = \det(M) M^{-\top}$ the
    /// cofactor matrix, which maps normals the way $M$ maps the surface. Zero-area triangles
    /// (in the reference or the frame) are skipped.
    pub fn flipped(&self, frame: &[Point], intended: &[Matrix3<f64>]) -> Vec<usize> {
        let mut out = Vec::new();
        for (t, (&tri, &n0)) in self.triangles.iter().zip(&self.normals).enumerate() {
            let n1 = crate::mesh::triangle_normal(frame, tri);
            if norm(n0) == 0.0 || norm(n1) == 0.0 {
                continue;
            }
            let m = &intended[t];
            // Columns of the cofactor matrix: cross products of M's columns.
            let c = |i: usize, j: usize| {
                let a = m.column(i);
                let b = m.column(j);
                Vector3::new(
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                )
            };
            let cof = Matrix3::from_columns(&[c(1, 2), c(2, 0), c(0, 1)]);
            let mapped = cof * Vector3::from(n0);
            if dot(n1, [mapped.x, mapped.y, mapped.z]) <= 0.0 {
                out.push(t);
            }
        }
        out
    }
}

/// One-shot [`FlipCheck::flipped`]: triangles of `frame` (over `reference`'s connectivity)
/// that face against the orientation their intended gradient gives them. For many frames
/// build a [`FlipCheck`] (or use [`super::AnimationTransfer::flipped_triangles`]) once.
pub fn flipped_triangles(
    reference: &TriMesh,
    frame: &[Point],
    intended: &[Matrix3<f64>],
) -> Vec<usize> {
    FlipCheck::new(reference).flipped(frame, intended)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn tet() -> TriMesh {
        TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.1, 0.0],
                [0.2, 1.0, 0.1],
                [0.3, 0.2, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
    }

    #[test]
    fn affine_and_rigid_maps_are_recovered() {
        let m = tet();
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let t = Vector3::new(1.0, -2.0, 0.5);
        let moved: Vec<Point> = m
            .positions
            .iter()
            .map(|p| (r * Vector3::from(*p) + t).into())
            .collect();
        for d in deformation_gradients(&m, &moved).unwrap() {
            assert!((d - r).norm() < 1e-12, "rigid: {d}");
        }
        let scaled: Vec<Point> = m.positions.iter().map(|p| p.map(|x| 2.5 * x)).collect();
        for d in deformation_gradients(&m, &scaled).unwrap() {
            assert!((d - Matrix3::identity() * 2.5).norm() < 1e-12);
        }
        // A general affine map is reproduced on the surface directions.
        let a = Matrix3::new(1.2, 0.3, 0.0, -0.1, 0.9, 0.2, 0.0, 0.4, 1.1);
        let sheared: Vec<Point> = m
            .positions
            .iter()
            .map(|p| (a * Vector3::from(*p)).into())
            .collect();
        let op = GradientOperator::new(&m);
        for (k, d) in op.gradients(&sheared).unwrap().iter().enumerate() {
            let tri = m.triangles[k];
            let e = Vector3::from(sub(
                m.positions[tri[1] as usize],
                m.positions[tri[0] as usize],
            ));
            assert!((d * e - a * e).norm() < 1e-12);
        }
        assert!(flipped_triangles(&m, &sheared, &vec![a; 4]).is_empty());
    }

    #[test]
    fn degenerate_triangles_get_the_identity_and_a_mirror_flips() {
        let mut m = tet();
        m.positions.push([2.0, 0.0, 0.0]);
        m.triangles.push([0, 1, 4]); // nearly collinear, but not exactly
        m.positions[4] = [2.0, 0.3, 0.0];
        m.positions.push([4.0, 0.7, 0.0]);
        m.triangles.push([1, 4, 5]); // exactly collinear
        let op = GradientOperator::new(&m);
        assert_eq!(op.degenerate(), &[5]);
        let g = op.gradients(&m.positions).unwrap();
        for d in &g {
            assert!((d - Matrix3::identity()).norm() < 1e-12);
        }
        // Mirror in x: consistent with a mirror as the intended gradient, and against the
        // identity exactly where the normal's x part is the smaller one.
        let mirror = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0));
        let mirrored: Vec<Point> = m.positions.iter().map(|p| [-p[0], p[1], p[2]]).collect();
        assert!(flipped_triangles(&m, &mirrored, &vec![mirror; 6]).is_empty());
        let flips = flipped_triangles(&m, &mirrored, &vec![Matrix3::identity(); 6]);
        let want: Vec<usize> = (0..5)
            .filter(|&t| {
                let n = m.triangle_normal(t);
                n[0] * n[0] < n[1] * n[1] + n[2] * n[2]
            })
            .collect();
        assert!(!want.is_empty());
        assert_eq!(flips, want);
        assert!(matches!(
            op.gradients(&m.positions[..3]),
            Err(TransferError::FrameVertexCount { .. })
        ));
    }
}
