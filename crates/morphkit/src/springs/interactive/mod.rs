//! The interactive mode (issue 38): a space of the rig's own equilibria, prepared once, in
//! which a slider change is a small nonlinear solve.
//!
//! **Preparation** ([`PhysicalBlend::prepare_interactive`](super::PhysicalBlend::prepare_interactive)).
//! Canonical solves at *snapshot* weights ([`snapshot_coefficients`]): every target at
//! every eighth ([`SINGLES`]; ¼, ½, ¾ are the sampled start's own samples) and every pair of
//! targets at (½, ½) and (0.3, 0.3). Each gives a correction $d_j = x^*(c_j) - P(c_j)$ over
//! the free coordinates, with the set of targets it involves. A frame of one target uses all
//! seven of its snapshots; a frame of several uses each target's at ¼, ½, ¾ ([`COARSE`]) and
//! the pairs'. Every eighth, because the canonical solve of one target is not a smooth
//! function of its weight on real rigs: over some weight ranges a very soft direction or a
//! second minimum takes it where the snapshots around do not point (horse pose 1 from 0.55 to
//! 0.65, ICT eyeBlink_R near 0.6), and a space of ¼, ½, ¾ alone missed it there by up to 0.9 %
//! of the diagonal (docs/performance.md, "7 December").
//!
//! **A slider change** ([`Rig::solve_interactive`]). With the frame's energy $E$ exactly as in
//! the full solve ([`super::frame`]) and its affine start $x_0$ (the predictor plus each
//! target's own sampled correction; the full solve's start also adds the pairs' fields,
//! which the space holds as columns instead), the shape is $x(y) = x_0 + D_A T y$: $D_A$ holds the corrections of
//! the snapshots whose targets are all active in this frame (a frame depends only on its
//! nonzero weights, so the others do not belong), $T$ makes them orthonormal
//! (eigenvectors of their Gram matrix, directions under $10^{-10}$ of the largest dropped).
//! $y$ minimises $E$ by a quasi-Newton iteration: the first matrix is the projected Hessian
//! at $x_0$ reduced to the space, then BFGS updates, with an Armijo line search. Held
//! vertices stay at their holds. The cost per iteration is one full gradient and a few
//! products with $D_A$ (a few dozen columns), never a factorization.

mod cache;
#[cfg(test)]
mod cache_tests;
mod prepare;
mod solve;

pub(super) use cache::{decode, encode, is_cache_head};
pub use prepare::InteractiveCacheUse;

use super::reference::Factor;
use super::rig::Rig;
use super::solve::Start;
use super::workspace::Workspace;
use nalgebra::DMatrix;

/// One snapshot: a canonical equilibrium's correction to the predictor.
pub(super) struct Snapshot {
    /// Its shape coefficients.
    pub c: Vec<f64>,
    /// Targets with a nonzero coefficient (sorted shape indices, ≥ 1).
    pub active: Vec<usize>,
    /// $x^* - P$ over the free coordinates (`nf`).
    pub d: Vec<f64>,
    /// The interactive shape's distance from this equilibrium when the snapshot itself is
    /// left out of the space (fraction of the diagonal; the error estimate's data).
    pub left_out: f64,
    /// For a pair's snapshot: the interactive shape's distance from this equilibrium when
    /// every snapshot of the pair is left out (the space then holds the two targets apart,
    /// no interaction of them); 0 for a single target's. The error estimate's data for frames
    /// of three or more targets, whose own interactions the space never holds.
    pub apart: f64,
}

/// The weights of each target's single-target snapshots: every eighth. A frame of that target
/// alone uses them all; a frame of several targets only those at [`COARSE`] (with all of them,
/// a three-expression face change would take 27 columns instead of 15).
pub(super) const SINGLES: [f64; 7] = [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875];

/// The single-target snapshot weights that frames of several targets use.
pub(super) const COARSE: [f64; 3] = [0.25, 0.5, 0.75];

/// The single-target weights at which the preparation checks a target's frames against the
/// full solve (halfway between its snapshots, and between the ends and the nearest ones):
/// the error estimate of a frame of that target alone.
pub(super) const CHECKS: [f64; 8] = [
    0.0625, 0.1875, 0.3125, 0.4375, 0.5625, 0.6875, 0.8125, 0.9375,
];

/// The targets (shape indices ≥ 1) with a nonzero coefficient in `c`, ascending.
pub(super) fn active_targets(c: &[f64]) -> impl Iterator<Item = usize> + Clone + '_ {
    (1..c.len()).filter(|&s| c[s] != 0.0)
}

/// The target of coefficients `c` when they are a single target's off the [`COARSE`] weights
/// (a snapshot that only frames of that target alone use).
pub(super) fn fine_target(c: &[f64]) -> Option<usize> {
    let mut active = active_targets(c);
    match (active.next(), active.next()) {
        (Some(t), None) if !COARSE.contains(&c[t]) => Some(t),
        _ => None,
    }
}

impl Snapshot {
    /// Whether this is a single target's snapshot off the [`COARSE`] weights (only frames of
    /// that target alone use it).
    pub(super) fn fine(&self) -> bool {
        fine_target(&self.c).is_some()
    }
}

/// The least error estimate of a frame that is not exact (fraction of the diagonal): the
/// accuracy to which the canonical equilibrium itself is defined (its gradient tolerance moves
/// it by about this much; the continuity check's floor). Below it the checks measure the full
/// solves' round-off: with every eighth a snapshot, a generated rig's frame at 0.6 was 1.6e-7
/// from its full solve against checks of 1.1e-7.
pub(super) const CANONICAL_ACCURACY: f64 = 1e-6;

/// A rig's prepared interactive space (see the [module docs](self)).
pub struct InteractiveSpace {
    pub(super) snapshots: Vec<Snapshot>,
    /// Per target (index `s - 1`): the largest error of the interactive shape against the
    /// full solve at the [`CHECKS`] weights (fraction of the diagonal); the estimate of a
    /// frame of that target alone.
    pub(super) checked: Vec<f64>,
    /// Per target: the largest error at its snapshots off [`COARSE`] with only its
    /// [`COARSE`] snapshots in the space, as in a frame of several targets; such a frame's
    /// estimate counts it for each active target.
    pub(super) checked_many: Vec<f64>,
    /// Snapshot solves that did not converge (left out of the space).
    pub unconverged: usize,
    /// The base shape's bounding-box diagonal.
    pub diagonal: f64,
    /// Seconds the preparation took (reported only).
    pub prepare_seconds: f64,
    /// The snapshots' Gram matrix $d_i \cdot d_j$ (`len × len`), so that a slider change
    /// takes its columns' entries from it instead of a pass over the coordinates per pair
    /// (ICT: about 6 ms per change).
    pub(super) gram: DMatrix<f64>,
}

/// The snapshot coefficient vectors of an `n`-shape rig: every target at each of [`SINGLES`],
/// every pair at (½, ½) and (0.3, 0.3); the base takes the rest.
pub(super) fn snapshot_coefficients(n: usize) -> Vec<Vec<f64>> {
    let coeffs = |pairs: &[(usize, f64)]| {
        let mut c = vec![0.0; n];
        c[0] = 1.0 - pairs.iter().map(|p| p.1).sum::<f64>();
        for &(s, a) in pairs {
            c[s] = a;
        }
        c
    };
    let mut out = Vec::new();
    for s in 1..n {
        for a in SINGLES {
            out.push(coeffs(&[(s, a)]));
        }
    }
    for s in 1..n {
        for t in s + 1..n {
            out.push(coeffs(&[(s, 0.5), (t, 0.5)]));
            out.push(coeffs(&[(s, 0.3), (t, 0.3)]));
        }
    }
    out
}

/// $d_i \cdot d_j$ over all snapshots, a block of coordinates at a time (one matrix product
/// per block; the sums' order depends only on the sizes).
fn gram(snapshots: &[Snapshot]) -> DMatrix<f64> {
    const BLOCK: usize = 1024;
    let s = snapshots.len();
    let nf = snapshots.first().map_or(0, |d| d.d.len());
    let mut g = DMatrix::zeros(s, s);
    for start in (0..nf).step_by(BLOCK) {
        let len = BLOCK.min(nf - start);
        let block = DMatrix::from_fn(len, s, |r, j| snapshots[j].d[start + r]);
        g += block.tr_mul(&block);
    }
    g
}

impl std::fmt::Debug for InteractiveSpace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("InteractiveSpace")
            .field("snapshots", &self.snapshots.len())
            .field("checked", &self.checked)
            .field("checked_many", &self.checked_many)
            .field("unconverged", &self.unconverged)
            .field("diagonal", &self.diagonal)
            .field("prepare_seconds", &self.prepare_seconds)
            .finish()
    }
}

impl InteractiveSpace {
    /// The space of `snapshots` with the error estimate's data `[checked, checked_many]` (see
    /// the fields).
    pub(super) fn new(
        snapshots: Vec<Snapshot>,
        [checked, checked_many]: [Vec<f64>; 2],
        unconverged: usize,
        diagonal: f64,
        prepare_seconds: f64,
    ) -> Self {
        let gram = gram(&snapshots);
        Self {
            snapshots,
            checked,
            checked_many,
            unconverged,
            diagonal,
            prepare_seconds,
            gram,
        }
    }

    /// Number of snapshots.
    pub fn len(&self) -> usize {
        self.snapshots.len()
    }

    /// Whether there is no snapshot.
    pub fn is_empty(&self) -> bool {
        self.snapshots.is_empty()
    }

    /// The snapshots whose targets are all active in coefficients `c`, but those in
    /// `exclude`; with several active targets, of their single-target snapshots only those at
    /// [`COARSE`] weights.
    fn columns(&self, c: &[f64], exclude: &[usize]) -> Vec<usize> {
        let many = active_targets(c).nth(1).is_some();
        (0..self.snapshots.len())
            .filter(|k| !exclude.contains(k))
            .filter(|&k| self.snapshots[k].active.iter().all(|&s| c[s] != 0.0))
            .filter(|&k| !many || !self.snapshots[k].fine())
            .collect()
    }

    /// The error estimate of a frame with coefficients `c` whose space is snapshots `cols`:
    /// the largest checked error of its active targets (of frames of one target or of
    /// several, as this one) and leave-one-out error of its
    /// combinations; with three or more active targets, also the largest error of its pairs
    /// held apart ([`Snapshot::apart`]), scaled by the pair's weights' product over ¼ where
    /// that is larger than 1: the space holds no interaction of more than two targets, and a
    /// pair without its own snapshots is the measured case of an interaction the space lacks;
    /// never under [`CANONICAL_ACCURACY`] (`None` without snapshots).
    fn estimate(&self, c: &[f64], cols: &[usize]) -> Option<f64> {
        if cols.is_empty() {
            return None;
        }
        let many = active_targets(c).count() >= 3;
        let combos = cols
            .iter()
            .filter(|&&k| self.snapshots[k].active.len() > 1)
            .map(|&k| {
                let s = &self.snapshots[k];
                if many {
                    // An interaction of two targets grows with the product of their weights
                    // (the second-order term of the equilibrium in the weights): held apart
                    // at (½, ½), scaled to this frame's, never below the measured value.
                    let w: f64 = s.active.iter().map(|&t| c[t].abs()).product();
                    s.left_out.max(s.apart * (4.0 * w).max(1.0))
                } else {
                    s.left_out
                }
            });
        let active = active_targets(c);
        let checked = match active.clone().count() {
            1 => &self.checked,
            _ => &self.checked_many,
        };
        let singles = active.map(|s| checked.get(s - 1).copied().unwrap_or(f64::INFINITY));
        combos
            .chain(singles)
            .reduce(f64::max)
            .map(|e| e.max(CANONICAL_ACCURACY))
    }
}

impl Rig {
    /// The snapshot at coefficients `c`: its canonical solve, or `None` where it did not
    /// converge.
    pub(super) fn snapshot(&self, ws: &mut Workspace, c: &[f64]) -> Option<Snapshot> {
        let (r, x) = self
            .solve_state(ws, c, &[], Start::Canonical, Factor::Fresh)
            .ok()?;
        if !r.stats.converged {
            return None;
        }
        let p = self.frame_energy(c, &[], true, true).predicted?;
        let diff: Vec<f64> = x.iter().zip(&p).map(|(a, b)| a - b).collect();
        let mut d = vec![0.0; self.system.num_free()];
        self.system.gather(&diff, &mut d);
        let active = active_targets(c).collect();
        Some(Snapshot {
            c: c.to_vec(),
            active,
            d,
            left_out: 0.0,
            apart: 0.0,
        })
    }

    /// The interactive shape's distance from the equilibrium `truth` (a snapshot's data),
    /// with the snapshots `exclude` left out of the space (fraction of the diagonal; infinite
    /// where a solve fails).
    pub(super) fn interactive_error(
        &self,
        ws: &mut Workspace,
        space: &InteractiveSpace,
        truth: &Snapshot,
        exclude: &[usize],
    ) -> f64 {
        let Ok((_, x)) = self.interactive_state(ws, space, &truth.c, 0, exclude) else {
            return f64::INFINITY;
        };
        let Some(p) = self.frame_energy(&truth.c, &[], true, true).predicted else {
            return f64::INFINITY;
        };
        let diff: Vec<f64> = x.iter().zip(&p).map(|(a, b)| a - b).collect();
        let mut d = vec![0.0; self.system.num_free()];
        self.system.gather(&diff, &mut d);
        d.iter_mut().zip(&truth.d).for_each(|(a, b)| *a -= b);
        solve::max_vertex(&self.system, &d) / space.diagonal
    }
}
