//! Inexact Newton steps by conjugate gradients preconditioned with a lagged Cholesky factor.
//!
//! Along an animation the Hessian changes little from one Newton step, or one frame, to the
//! next. Instead of refactorizing at every step, the last factorization serves as a
//! preconditioner for CG on the current Hessian (applied matrix-free, spring by spring). A
//! triangular solve costs a small fraction of a factorization, so a handful of CG iterations is
//! much cheaper than a new factor; when CG stalls, the caller refactorizes. This is the
//! "previous factorization as a preconditioner" strategy named in the project issue.

use super::energy::Block;
use super::SpringSet;
use crate::sparse::Cholesky;

/// Outcome of [`pcg`].
pub(crate) enum PcgOutcome {
    /// Converged to the requested relative residual.
    Converged(Vec<f64>),
    /// A direction of non-positive curvature was met: the operator is not positive definite.
    NegativeCurvature,
    /// The iteration budget ran out; the last iterate and its relative residual.
    Stalled(Vec<f64>, f64),
}

/// Matrix-free product with the Hessian given by per-spring `blocks` over free coordinates.
pub(crate) struct HessianOperator<'a> {
    pub springs: &'a SpringSet,
    pub blocks: &'a [Block],
    pub dof_index: &'a [u32],
    pub mu: f64,
}

impl HessianOperator<'_> {
    /// `out = (H + mu I) p`; `full` is scratch of length `3 #V`.
    pub(crate) fn apply(&self, p: &[f64], full: &mut [f64], out: &mut [f64]) {
        for (k, &i) in self.dof_index.iter().enumerate() {
            full[k] = if i == u32::MAX { 0.0 } else { p[i as usize] };
        }
        out.iter_mut().zip(p).for_each(|(o, v)| *o = self.mu * v);
        for (s, b) in self.springs.springs().iter().zip(self.blocks) {
            let (i, j) = (3 * s.i as usize, 3 * s.j as usize);
            let d = [
                full[i] - full[j],
                full[i + 1] - full[j + 1],
                full[i + 2] - full[j + 2],
            ];
            for a in 0..3 {
                let t = b[a][0] * d[0] + b[a][1] * d[1] + b[a][2] * d[2];
                let (fi, fj) = (self.dof_index[i + a], self.dof_index[j + a]);
                if fi != u32::MAX {
                    out[fi as usize] += t;
                }
                if fj != u32::MAX {
                    out[fj as usize] -= t;
                }
            }
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `H x = b` to relative residual `rtol` in at most `max_iter` iterations.
pub(crate) fn pcg(
    op: &HessianOperator<'_>,
    precond: &Cholesky,
    b: &[f64],
    rtol: f64,
    max_iter: usize,
    iterations: &mut usize,
) -> PcgOutcome {
    let n = b.len();
    let mut full = vec![0.0; op.dof_index.len()];
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let bnorm = dot(b, b).sqrt();
    if bnorm == 0.0 {
        return PcgOutcome::Converged(x);
    }
    let Ok(mut z) = precond.solve(&r) else {
        return PcgOutcome::Stalled(x, 1.0);
    };
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut hp = vec![0.0; n];
    for _ in 0..max_iter {
        *iterations += 1;
        op.apply(&p, &mut full, &mut hp);
        let php = dot(&p, &hp);
        if php <= 0.0 || !php.is_finite() {
            return PcgOutcome::NegativeCurvature;
        }
        let alpha = rz / php;
        for k in 0..n {
            x[k] += alpha * p[k];
            r[k] -= alpha * hp[k];
        }
        if dot(&r, &r).sqrt() <= rtol * bnorm {
            return PcgOutcome::Converged(x);
        }
        z = match precond.solve(&r) {
            Ok(z) => z,
            Err(_) => return PcgOutcome::Stalled(x, 1.0),
        };
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for k in 0..n {
            p[k] = z[k] + beta * p[k];
        }
    }
    let rel = dot(&r, &r).sqrt() / bnorm;
    PcgOutcome::Stalled(x, rel)
}
