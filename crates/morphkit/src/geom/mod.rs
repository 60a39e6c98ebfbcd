//! Small dense geometry on `nalgebra` 3×3 matrices: polar decomposition, quaternion slerp of
//! rotations, and the Kabsch best rigid fit.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// The largest distance between corresponding points of `a` and `b` (`#V` each; extra
/// points of the longer are ignored); 0 for empty sets.
pub fn max_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Polar decomposition $D = R S$ with $R$ a rotation ($\det R = +1$) and $S$ symmetric
/// (Shoemake & Duff 1992, used by Wang & Lee 2008 Sec. 3.2.2).
///
/// Computed through the SVD $D = U \Sigma V^\top$: $R = U V^\top$ and $S = V \Sigma V^\top$.
/// When $\det D < 0$ (a reflection), the singular vector of the smallest singular value is
/// flipped so that $R$ is a proper rotation; $S$ then has one negative eigenvalue and
/// $R S = D$ still holds exactly.
pub fn polar_decomposition(d: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let svd = d.svd(true, true);
    let mut u = svd.u.expect("svd computes U");
    let v_t = svd.v_t.expect("svd computes Vᵀ");
    let mut sigma = svd.singular_values;
    if (u * v_t).determinant() < 0.0 {
        let k = sigma.imin();
        u.set_column(k, &(-u.column(k)));
        sigma[k] = -sigma[k];
    }
    let r = u * v_t;
    let s = v_t.transpose() * Matrix3::from_diagonal(&sigma) * v_t;
    (r, s)
}

/// Spherical linear interpolation between rotations `a` (t = 0) and `b` (t = 1) along the
/// shorter arc (Shoemake 1985).
pub fn slerp(a: &Matrix3<f64>, b: &Matrix3<f64>, t: f64) -> Matrix3<f64> {
    let qa = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*a));
    let qb = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*b));
    // try_slerp fails only for antipodal quaternions (a 180° turn): any great circle is then
    // shortest; nlerp through a perturbed midpoint picks one deterministically.
    let q = qa.try_slerp(&qb, t, 1e-12).unwrap_or_else(|| {
        let axis = Vector3::x_axis();
        qa * UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI * t)
    });
    q.to_rotation_matrix().into_inner()
}

/// A rigid motion $x \mapsto R x + t$.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidTransform {
    /// Rotation, $\det R = +1$.
    pub rotation: Matrix3<f64>,
    /// Translation.
    pub translation: Vector3<f64>,
}

impl RigidTransform {
    /// The identity.
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }
    /// Applies the motion to a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let q = self.rotation * Vector3::from(p) + self.translation;
        [q.x, q.y, q.z]
    }
    /// The motion a fraction `alpha` of the way from the identity: rotation by slerp, translation
    /// linearly (Ma et al. 2012, Sec. 3.4 step 5).
    pub fn interpolate(&self, alpha: f64) -> Self {
        Self {
            rotation: slerp(&Matrix3::identity(), &self.rotation, alpha),
            translation: self.translation * alpha,
        }
    }
}

/// Best rigid motion taking `from[i]` to `to[i]` in the weighted least-squares sense
/// (Kabsch / orthogonal Procrustes, with the reflection fix $\det R = +1$).
///
/// `weights` may be empty (all ones). Fewer than three non-collinear points leave the rotation
/// partly undetermined; the SVD then picks one of the minimisers.
pub fn kabsch(from: &[[f64; 3]], to: &[[f64; 3]], weights: &[f64]) -> RigidTransform {
    let w = |i: usize| if weights.is_empty() { 1.0 } else { weights[i] };
    let n = from.len().min(to.len());
    let total: f64 = (0..n).map(w).sum();
    if n == 0 || total <= 0.0 {
        return RigidTransform::identity();
    }
    let mut ca = Vector3::zeros();
    let mut cb = Vector3::zeros();
    for i in 0..n {
        ca += Vector3::from(from[i]) * w(i);
        cb += Vector3::from(to[i]) * w(i);
    }
    ca /= total;
    cb /= total;
    let mut h = Matrix3::zeros();
    for i in 0..n {
        h += (Vector3::from(from[i]) - ca) * (Vector3::from(to[i]) - cb).transpose() * w(i);
    }
    let svd = h.svd(true, true);
    let u = svd.u.expect("U");
    let v = svd.v_t.expect("Vᵀ").transpose();
    let mut fix = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        fix[(2, 2)] = -1.0;
    }
    let rotation = v * fix * u.transpose();
    RigidTransform {
        rotation,
        translation: cb - rotation * ca,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(axis: [f64; 3], angle: f64) -> Matrix3<f64> {
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::from(axis)), angle)
            .into_inner()
    }

    #[test]
    fn polar_reconstructs_and_is_proper() {
        let d =
            rot([1.0, 2.0, 0.5], 1.1) * Matrix3::new(2.0, 0.3, 0.0, 0.3, 1.0, 0.1, 0.0, 0.1, 0.5);
        let (r, s) = polar_decomposition(&d);
        assert!((r * s - d).norm() < 1e-12);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!((s - s.transpose()).norm() < 1e-12);
        let refl = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)) * d;
        let (r, s) = polar_decomposition(&refl);
        assert!((r * s - refl).norm() < 1e-12);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn slerp_halves_the_angle() {
        let b = rot([0.0, 0.0, 1.0], 2.0);
        let m = slerp(&Matrix3::identity(), &b, 0.5);
        assert!((m - rot([0.0, 0.0, 1.0], 1.0)).norm() < 1e-12);
        assert!((slerp(&Matrix3::identity(), &b, 1.0) - b).norm() < 1e-12);
    }

    #[test]
    fn kabsch_recovers_a_rigid_motion() {
        let r = rot([0.3, -1.0, 0.2], 2.5);
        let t = Vector3::new(1.0, -2.0, 0.5);
        let from = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
            [1.0, 1.0, 1.0],
        ];
        let to: Vec<[f64; 3]> = from
            .iter()
            .map(|p| {
                let q = r * Vector3::from(*p) + t;
                [q.x, q.y, q.z]
            })
            .collect();
        let fit = kabsch(&from, &to, &[]);
        assert!((fit.rotation - r).norm() < 1e-12);
        assert!((fit.translation - t).norm() < 1e-12);
        assert!((fit.interpolate(1.0).rotation - r).norm() < 1e-12);
    }
}
