//! Elimination of fixed (Dirichlet) unknowns from a symmetric system.
//!
//! Partition the unknowns into free $f$ and fixed $c$. Then
//! $A_{ff} x_f = b_f - A_{fc} x_c$: the reduced matrix $A_{ff}$ stays symmetric positive definite,
//! unlike the "identity rows" of the paper's Sec. 3.4, and is smaller.

use super::SolveError;

/// A symmetric system with some unknowns fixed, reduced to its free unknowns.
#[derive(Clone, Debug)]
pub struct Dirichlet {
    n: usize,
    free: Vec<usize>,
    index: Vec<usize>,
    reduced: Vec<(usize, usize, f64)>,
    coupling: Vec<(usize, usize, f64)>,
}

impl Dirichlet {
    /// Splits the `n × n` symmetric matrix given by lower-triangle triplets `(i, j, v)`, `i ≥ j`
    /// (duplicates allowed), by the mask `fixed` (length `n`).
    pub fn new(
        n: usize,
        fixed: &[bool],
        lower: &[(usize, usize, f64)],
    ) -> Result<Self, SolveError> {
        if fixed.len() != n {
            return Err(SolveError::Dimension {
                what: "fixed mask",
                expected: n,
                found: fixed.len(),
            });
        }
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        let mut index = vec![usize::MAX; n];
        for (k, &i) in free.iter().enumerate() {
            index[i] = k;
        }
        let mut reduced = Vec::with_capacity(lower.len());
        let mut coupling = Vec::new();
        for &(i, j, v) in lower {
            if i >= n || j >= n {
                return Err(SolveError::Dimension {
                    what: "triplet index",
                    expected: n,
                    found: i.max(j),
                });
            }
            match (fixed[i], fixed[j]) {
                (false, false) => {
                    let (a, b) = (index[i], index[j]);
                    reduced.push((a.max(b), a.min(b), v));
                }
                (false, true) => coupling.push((index[i], j, v)),
                (true, false) => coupling.push((index[j], i, v)),
                (true, true) => {}
            }
        }
        Ok(Self {
            n,
            free,
            index,
            reduced,
            coupling,
        })
    }

    /// Number of free unknowns.
    pub fn num_free(&self) -> usize {
        self.free.len()
    }
    /// Free unknowns, in reduced order.
    pub fn free(&self) -> &[usize] {
        &self.free
    }
    /// Reduced index of unknown `i`, `None` if it is fixed.
    pub fn reduced_index(&self, i: usize) -> Option<usize> {
        (self.index[i] != usize::MAX).then_some(self.index[i])
    }
    /// Lower-triangle triplets of $A_{ff}$ in reduced indices.
    pub fn reduced_triplets(&self) -> &[(usize, usize, f64)] {
        &self.reduced
    }
    /// Reduced right-hand side $b_f - A_{fc} x_c$; `b` and `x` are full-length, and only the
    /// fixed entries of `x` are read.
    pub fn rhs(&self, b: &[f64], x: &[f64]) -> Vec<f64> {
        let mut r: Vec<f64> = self.free.iter().map(|&i| b[i]).collect();
        for &(fi, c, v) in &self.coupling {
            r[fi] -= v * x[c];
        }
        r
    }
    /// Writes the free solution into the full vector `x` (fixed entries untouched).
    pub fn expand_into(&self, x_free: &[f64], x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n);
        for (k, &i) in self.free.iter().enumerate() {
            x[i] = x_free[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::cholesky::tests::random_spd;
    use crate::sparse::{Cholesky, Ordering, SymmetricPattern};

    /// Dense Gaussian elimination with partial pivoting, the reference.
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
                .unwrap();
            a.swap(k, p);
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            x[k] = (b[k] - (k + 1..n).map(|j| a[k][j] * x[j]).sum::<f64>()) / a[k][k];
        }
        x
    }

    #[test]
    fn elimination_matches_a_dense_reference() {
        let n = 40;
        let t = random_spd(n, 11);
        let mut dense = vec![vec![0.0; n]; n];
        for &(i, j, v) in &t {
            dense[i][j] += v;
            if i != j {
                dense[j][i] += v;
            }
        }
        let fixed: Vec<bool> = (0..n).map(|i| i % 5 == 0).collect();
        let xc: Vec<f64> = (0..n)
            .map(|i| if fixed[i] { (i as f64).sqrt() } else { 0.0 })
            .collect();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.7).sin()).collect();

        let d = Dirichlet::new(n, &fixed, &t).unwrap();
        let (p, v) = SymmetricPattern::from_triplets(d.num_free(), d.reduced_triplets()).unwrap();
        let mut c = Cholesky::analyze(p, Ordering::Amd).unwrap();
        c.factorize(&v).unwrap();
        let xf = c.solve(&d.rhs(&b, &xc)).unwrap();
        let mut x = xc.clone();
        d.expand_into(&xf, &mut x);

        // Dense reference: rows of fixed unknowns replaced by identity rows.
        let mut a2 = dense.clone();
        let mut b2 = b.clone();
        for i in 0..n {
            if fixed[i] {
                a2[i] = vec![0.0; n];
                a2[i][i] = 1.0;
                b2[i] = xc[i];
            }
        }
        let xr = dense_solve(a2, b2);
        let err = x
            .iter()
            .zip(&xr)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-10, "max difference {err}");
        for i in 0..n {
            if fixed[i] {
                assert_eq!(x[i], xc[i]);
            }
        }
    }
}
