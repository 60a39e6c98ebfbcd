//! Rotation-aware blending of deformation gradients (Wang & Lee 2008, Sec. 3.2.2).
//!
//! A gradient is split by the polar decomposition $D = R S$ ([`crate::geom::polar_decomposition`]:
//! $R$ a rotation, $S$ symmetric). Two gradients $A = R_a S_a$, $B = R_b S_b$ blend at weight
//! $w \in [0, 1]$ as
//! $$\operatorname{blend}(A, B, w) = \operatorname{slerp}(R_a, R_b, w)\,\big((1 - w) S_a + w S_b\big),$$
//! the rotation by quaternion slerp on the shorter arc ([`crate::geom::slerp`]), the stretch
//! linearly. $w = 0$ returns $A$ and $w = 1$ returns $B$ exactly (no decomposition is done),
//! so fully selected and unselected triangles cost nothing.
//!
//! The decomposition is the hot loop of synthesis (two per blended triangle per frame), so
//! [`polar`] computes it by Higham's scaled Newton iteration
//! $X \leftarrow \tfrac12(\zeta X + \zeta^{-1} X^{-\top})$, $\zeta = (\|X^{-1}\|_F / \|X\|_F)^{1/2}$,
//! which converges quadratically to the same $R$ for $\det D > 0$ in a few 3 × 3 inverses;
//! reflections and (nearly) singular gradients fall back to the SVD of
//! [`crate::geom::polar_decomposition`], whose result it equals to round-off.
//!
//! The two modes of a layer with gradient $L$ at weight $w$ over the gradient $G$ below it:
//! - [`BlendMode::Blend`]: $G \leftarrow \operatorname{blend}(G, L, w)$;
//! - [`BlendMode::Compound`]: $G \leftarrow \operatorname{blend}(I, L, w)\, G$: the layer's
//!   deformation, faded in by $w$, applied after (left-multiplied onto) the one below, as the
//!   paper's Fig. 10 multiplies a run cycle onto a morph sequence.

use crate::geom::{polar_decomposition, slerp};
use nalgebra::Matrix3;

/// How a layer combines with the gradients below it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BlendMode {
    /// Interpolate from the gradient below to the layer's by the weight. Default.
    #[default]
    Blend,
    /// Interpolate the layer's gradient from the identity by the weight and multiply it onto
    /// the gradient below.
    Compound,
}

impl BlendMode {
    /// `"blend"` or `"compound"`.
    pub fn name(self) -> &'static str {
        match self {
            BlendMode::Blend => "blend",
            BlendMode::Compound => "compound",
        }
    }
}

/// Polar decomposition $D = R S$ ($R$ a rotation, $S$ symmetric): the scaled Newton
/// iteration of the module doc, or [`polar_decomposition`] (SVD) for a reflection or a nearly
/// singular $D$ ($\det D \le 10^{-8} \|D\|_F^3$) or when 30 iterations do not converge.
pub fn polar(d: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    if *d == Matrix3::identity() {
        return (*d, *d);
    }
    let n = d.norm();
    let det = d.determinant();
    if !(n.is_finite() && det > 1e-8 * n * n * n) {
        return polar_decomposition(d);
    }
    let mut x = *d;
    for _ in 0..30 {
        let Some(inv) = x.try_inverse() else {
            return polar_decomposition(d);
        };
        let zeta = (inv.norm() / x.norm()).sqrt();
        let next = (x * zeta + inv.transpose() / zeta) * 0.5;
        let change = (next - x).norm();
        x = next;
        // Quadratic convergence: the error after a step of size δ is O(δ²), so δ ≤ 1e-8
        // leaves X within round-off of R.
        if change <= 1e-8 {
            let s = x.transpose() * d;
            return (x, (s + s.transpose()) * 0.5);
        }
    }
    polar_decomposition(d)
}

/// $\operatorname{blend}(A, B, w)$ of the module doc; `w` is clamped to [0, 1].
pub fn blend_gradient(a: &Matrix3<f64>, b: &Matrix3<f64>, w: f64) -> Matrix3<f64> {
    if w <= 0.0 {
        return *a;
    }
    if w >= 1.0 {
        return *b;
    }
    let (ra, sa) = polar(a);
    let (rb, sb) = polar(b);
    slerp(&ra, &rb, w) * (sa * (1.0 - w) + sb * w)
}

/// Applies one layer to `below` in place: `below[t] ← mode(below[t], layer[t], weights[t])`.
/// The three slices have one entry per triangle.
pub fn apply_layer(
    below: &mut [Matrix3<f64>],
    layer: &[Matrix3<f64>],
    weights: &[f64],
    mode: BlendMode,
) {
    debug_assert_eq!(below.len(), layer.len());
    debug_assert_eq!(below.len(), weights.len());
    let id = Matrix3::identity();
    for ((g, l), &w) in below.iter_mut().zip(layer).zip(weights) {
        if w <= 0.0 {
            continue;
        }
        *g = match mode {
            BlendMode::Blend => blend_gradient(g, l, w),
            BlendMode::Compound => blend_gradient(&id, l, w) * *g,
        };
    }
}

/// One-shot: the gradients of `a` and `b` (per triangle) blended per triangle by `weights`.
pub fn blend_gradients(
    a: &[Matrix3<f64>],
    b: &[Matrix3<f64>],
    weights: &[f64],
    mode: BlendMode,
) -> Vec<Matrix3<f64>> {
    let mut out = a.to_vec();
    apply_layer(&mut out, b, weights, mode);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit, Vector3};
    use rand::{Rng, SeedableRng};

    fn rot(axis: [f64; 3], angle: f64) -> Matrix3<f64> {
        Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(axis)), angle).into_inner()
    }

    fn angle_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
        Rotation3::from_matrix_unchecked(a.transpose() * b).angle()
    }

    #[test]
    fn slerp_of_170_degrees_takes_the_short_arc() {
        let axis = [0.2, 1.0, -0.4];
        let a = rot(axis, 0.0);
        let b = rot(axis, 170f64.to_radians());
        let stretch = Matrix3::new(1.5, 0.1, 0.0, 0.1, 0.8, 0.0, 0.0, 0.0, 1.0);
        for w in [0.25, 0.5, 0.75] {
            let m = blend_gradient(&(a * stretch), &(b * stretch), w);
            let (r, s) = polar_decomposition(&m);
            assert!((s - stretch).norm() < 1e-9, "stretch kept");
            let want = rot(axis, w * 170f64.to_radians());
            assert!((r - want).norm() < 1e-9, "w = {w}");
        }
        // Going the other way round: from +95° to −95° is 170° through 180°, not 190° through 0.
        let a = rot(axis, 95f64.to_radians());
        let b = rot(axis, -95f64.to_radians());
        let mid = blend_gradient(&a, &b, 0.5);
        assert!((mid - rot(axis, 180f64.to_radians())).norm() < 1e-9);
        assert!(angle_between(&mid, &Matrix3::identity()) > 3.1);
    }

    #[test]
    fn newton_polar_equals_the_svd_one() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for k in 0..500 {
            let scale = 10f64.powi(k % 7 - 3);
            let d = (Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0))
                + Matrix3::identity() * (k % 3) as f64)
                * scale;
            let (r0, s0) = polar_decomposition(&d);
            let (r1, s1) = polar(&d);
            assert!((r1 * s1 - d).norm() < 1e-12 * d.norm(), "{d}");
            assert!((r1.determinant() - 1.0).abs() < 1e-12);
            let cond = d.svd(false, false).singular_values;
            if d.determinant() > 0.0 && cond.min() > 1e-3 * cond.max() {
                assert!((r1 - r0).norm() < 1e-9, "{d}: {r0} vs {r1}");
                assert!((s1 - s0).norm() < 1e-9 * d.norm());
            }
        }
        // A collapsed triangle's gradient (zero normal column) goes through the SVD.
        let flat = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        let (r, s) = polar(&flat);
        assert!((r * s - flat).norm() < 1e-12);
    }

    #[test]
    fn endpoints_are_exact_and_blending_with_itself_is_the_identity_map() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(10);
        for _ in 0..50 {
            let a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)) + Matrix3::identity();
            let b = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)) + Matrix3::identity();
            assert_eq!(blend_gradient(&a, &b, 0.0), a);
            assert_eq!(blend_gradient(&a, &b, 1.0), b);
            let w = rng.random_range(0.0..1.0);
            assert!((blend_gradient(&a, &a, w) - a).norm() < 1e-9 * a.norm());
            let id = vec![Matrix3::identity(); 1];
            let c = blend_gradients(&[a], &id, &[w], BlendMode::Compound);
            assert!((c[0] - a).norm() < 1e-12);
        }
    }
}
