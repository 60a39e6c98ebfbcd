//! Reference factors: frames near a sample weight of one target precondition their inner
//! conjugate gradients with a factor of the projected Hessian at that sample's equilibrium,
//! *turned* by each vertex's rotation from the sample to the current iterate, instead of
//! factorizing a Hessian of their own.
//!
//! For target $s$ the grid weights are $a_g \in \{0, ¼, ½, ¾, 1\}$: the two ends (the base
//! and the target shape, exact equilibria) and the three samples of the
//! [sampled start](super::sampled_start), whose equilibria are solved anyway. A frame with
//! coefficients $(1-a)\,e_0 + a\,e_s$, $0 < a < 1$, takes the grid weight nearest to $a$
//! (at most ⅛ away). Its preconditioner is
//!
//! $$M^{-1} = Q\, H_g^{-1}\, Q^\top, \qquad Q = \operatorname{diag}(Q_v),$$
//!
//! where $H_g$ is the projected Hessian at $y$, the iterate of the last factorization of that
//! grid weight's solve (for the samples, one Newton step or less from their equilibrium; for
//! the ends, the shape itself), and $Q_v$ the
//! rotation of the polar decomposition of $\sum_{w \sim v} (x_w - x_v)(y_w - y_v)^\top$ over
//! the vertices $w$ coupled to $v$ in the Hessian (identity where $v$ has fixed coordinates).
//! A spring's Hessian block $k\, d d^\top$ turns with its direction $d$, and in a bent body
//! that direction turns with the bend, so the plain $H_g^{-1}$ fits a frame ⅛ away badly while
//! $Q H_g^{-1} Q^\top$ follows the turn; $M$ stays symmetric positive definite, so it also
//! defines the trust-region norm. Measured on the 2.2k volumetric tube, at ⅛ from the sample:
//! PCG to a relative residual of 10⁻³ in 11 iterations with $H_g^{-1}$ and 5–6 with the
//! turned factor (1 with the frame's own factor).
//!
//! Each reference depends on the rig and its grid weight alone, whichever frame or thread
//! first asks for it, so every frame stays a deterministic function of its weights.

use super::system::FreeSystem;
use crate::geom::polar_decomposition;
use crate::sparse::{Cholesky, FrozenFactor};
use nalgebra::{Matrix3, Vector3};
use std::sync::{Arc, OnceLock};

/// A frozen factor of the projected Hessian and the iterate it was taken at.
pub(crate) struct Reference {
    pub factor: FrozenFactor,
    /// Solver coordinates, `3 #V`.
    pub x: Vec<f64>,
}

/// One grid cell: computed on first need (`None`: its solve did not converge or needed a
/// double-precision factor).
pub(crate) type Cell = OnceLock<Option<Arc<Reference>>>;

/// The grid weights of every target's references.
pub(crate) const GRID: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The weight of each target's probe: ⅛ from the ½ reference, as far as any frame.
pub(crate) const PROBE: f64 = 0.375;

/// Every target's references, shared by all threads.
pub(crate) struct References {
    /// The base (`a = 0`, shared by all targets).
    pub base: Cell,
    /// Index `s - 1`, then the grid weights ¼, ½, ¾, 1.
    pub cells: Vec<[Cell; 4]>,
    /// Index `s - 1`: whether the probe found that target's references to fit.
    pub fit: Vec<OnceLock<bool>>,
}

impl References {
    /// Room for the first `targets` targets (`0`: references off).
    pub fn new(targets: usize) -> Self {
        Self {
            base: OnceLock::new(),
            cells: (0..targets).map(|_| Default::default()).collect(),
            fit: (0..targets).map(|_| OnceLock::new()).collect(),
        }
    }

    /// How many targets (the first ones) get references within `budget` bytes: five
    /// factors of `chol`'s size each, the base's shared.
    pub fn targets(chol: &Cholesky, targets: usize, budget: u64) -> usize {
        let per = chol.factor_bytes().max(1);
        let fit = (budget / per).saturating_sub(1) / 4;
        targets.min(usize::try_from(fit).unwrap_or(usize::MAX))
    }

    /// The cell of target `s` at grid index `g`, if references cover that target.
    pub fn cell(&self, s: usize, g: usize) -> Option<&Cell> {
        let target = self.cells.get(s.checked_sub(1)?)?;
        match g {
            0 => Some(&self.base),
            _ => target.get(g - 1),
        }
    }

    /// `(s, g)` of the reference nearest to coefficients `c`: one target `s` with
    /// `0 < c[s] < 1`, `c[0] = 1 - c[s]` and every other coefficient zero.
    pub fn nearest(c: &[f64]) -> Option<(usize, usize)> {
        let mut active = c.iter().enumerate().skip(1).filter(|(_, &a)| a != 0.0);
        let (s, &a) = active.next()?;
        if active.next().is_some() || !(a > 0.0 && a < 1.0) || (c[0] - (1.0 - a)).abs() > 1e-12 {
            return None;
        }
        Some((s, (4.0 * a).round() as usize))
    }
}

/// The per-vertex rotations $Q_v$ from a reference's iterate to the current one.
pub(crate) struct Warp {
    rotations: Vec<Matrix3<f64>>,
}

impl Warp {
    /// $Q_v$ at iterate `x` for every vertex with three free coordinates (identity
    /// otherwise).
    pub fn new(system: &FreeSystem, reference: &[f64], x: &[f64]) -> Self {
        let n = x.len() / 3;
        let mut m = vec![Matrix3::<f64>::zeros(); n];
        let bp = &system.block_pattern;
        let p = |v: &[f64], i: usize| Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        for i in 0..n {
            for &j in bp.row(i) {
                let j = j as usize;
                let outer = (p(x, j) - p(x, i)) * (p(reference, j) - p(reference, i)).transpose();
                m[i] += outer;
                m[j] += outer;
            }
        }
        let dof = &system.dof_index;
        let rotations = m
            .iter()
            .enumerate()
            .map(|(v, mv)| {
                let free = (0..3).all(|a| dof[3 * v + a] != u32::MAX);
                if free && mv.iter().all(|e| e.is_finite()) && mv.norm() > 0.0 {
                    polar_decomposition(mv).0
                } else {
                    Matrix3::identity()
                }
            })
            .collect();
        Self { rotations }
    }

    /// `r ← Qᵀ r` (`transpose`) or `r ← Q r` over free coordinates.
    pub fn apply(&self, system: &FreeSystem, r: &mut [f64], transpose: bool) {
        let dof = &system.dof_index;
        for (v, q) in self.rotations.iter().enumerate() {
            let k = [dof[3 * v], dof[3 * v + 1], dof[3 * v + 2]];
            if k.contains(&u32::MAX) {
                continue;
            }
            let a = Vector3::new(r[k[0] as usize], r[k[1] as usize], r[k[2] as usize]);
            let b = if transpose { q.transpose() * a } else { q * a };
            for (t, &kk) in k.iter().enumerate() {
                r[kk as usize] = b[t];
            }
        }
    }
}

/// Which factor a solve's inner iterations start with.
pub(crate) enum Factor<'a> {
    /// Its own factorizations.
    Fresh,
    /// The [reference](super::reference) nearest to its weights, when there is one and
    /// its target passed the probe.
    Reference,
    /// The nearest reference without the probe (the probe itself).
    Probe,
    /// Its own factorizations, and the reference at its equilibrium written here.
    Produce(&'a mut Option<Reference>),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::springs::terms::BlockPattern;
    use nalgebra::Rotation3;

    #[test]
    fn nearest_takes_one_targets_frames_strictly_between_the_ends() {
        assert_eq!(References::nearest(&[0.9, 0.1]), Some((1, 0)));
        assert_eq!(References::nearest(&[0.6, 0.4]), Some((1, 2)));
        assert_eq!(References::nearest(&[0.625, 0.0, 0.375]), Some((2, 2)));
        assert_eq!(References::nearest(&[0.1, 0.0, 0.9]), Some((2, 4)));
        // Ends, extrapolation, several targets, and weights that do not sum to one.
        for c in [
            &[1.0, 0.0][..],
            &[0.0, 1.0],
            &[-0.2, 1.2],
            &[0.5, 0.25, 0.25],
            &[0.5, 0.4],
        ] {
            assert_eq!(References::nearest(c), None, "{c:?}");
        }
        let r = References::new(2);
        assert!(r.cell(1, 0).is_some() && r.cell(2, 4).is_some() && r.cell(3, 1).is_none());
        // A target past the budget has no cell, not even the shared base's.
        assert!(r.cell(3, 0).is_none() && r.cell(0, 0).is_none());
        assert!(std::ptr::eq(r.cell(1, 0).unwrap(), r.cell(2, 0).unwrap()));
        assert!(References::new(0).cell(1, 0).is_none());
    }

    /// Four vertices of a tetrahedron, all coupled, the last with one fixed coordinate.
    fn tetrahedron() -> (FreeSystem, Vec<f64>) {
        let pairs = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];
        let bp = std::sync::Arc::new(BlockPattern::new(4, &pairs));
        let mut fixed = vec![false; 12];
        fixed[11] = true;
        let x = vec![0.0, 0.0, 0.0, 1.0, 0.1, 0.0, 0.2, 1.0, 0.0, 0.3, 0.2, 1.0];
        (FreeSystem::new(bp, &fixed).unwrap(), x)
    }

    #[test]
    fn warp_of_a_rigid_motion_is_its_rotation_and_orthogonal() {
        let (sys, y) = tetrahedron();
        let q = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 0.5)),
            0.7,
        );
        let x: Vec<f64> = y
            .chunks(3)
            .flat_map(|p| {
                let v = q * Vector3::new(p[0], p[1], p[2]) + Vector3::new(3.0, -1.0, 2.0);
                [v.x, v.y, v.z]
            })
            .collect();
        let w = Warp::new(&sys, &y, &x);
        for v in 0..3 {
            assert!((w.rotations[v] - q.matrix()).norm() < 1e-12, "vertex {v}");
        }
        // The vertex with a fixed coordinate keeps the identity.
        assert_eq!(w.rotations[3], Matrix3::identity());
        let r0: Vec<f64> = (0..sys.num_free()).map(|k| (k as f64).sin()).collect();
        let mut r = r0.clone();
        w.apply(&sys, &mut r, true);
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        assert!((norm(&r) - norm(&r0)).abs() < 1e-12);
        w.apply(&sys, &mut r, false);
        let back = r
            .iter()
            .zip(&r0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(back < 1e-12, "Q Qᵀ r differs from r by {back:e}");
    }
}
