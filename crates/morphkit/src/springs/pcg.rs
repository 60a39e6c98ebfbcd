//! The spring Hessian as a matrix-free operator over the free coordinates, applied spring by
//! spring from per-spring 3×3 blocks. The trust-region Newton–CG step ([`super::steihaug`])
//! runs conjugate gradients with it, preconditioned by the last Cholesky factor, so that a
//! handful of cheap triangular solves replaces most refactorizations along an animation (the
//! "previous factorization as a preconditioner" strategy named in the project issue).

use super::energy::Block;
use super::SpringSet;

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
