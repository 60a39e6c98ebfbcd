//! The numeric part of the two-level aggregation preconditioner (see
//! [`super::aggregation`]): the prolongation from each aggregate's rigid modes, the Galerkin
//! coarse matrix and its factor, and the V-cycle.

use super::aggregation::{gather_dot, symmetric_product, AggregationLevels, MODES};
use super::{Cholesky, SolveError};
use std::sync::Arc;

/// The numeric part of the two-level preconditioner for one matrix of an
/// [`AggregationLevels`] pattern (one per thread).
#[derive(Debug)]
pub struct AggregationPreconditioner {
    levels: Arc<AggregationLevels>,
    /// Fine lower-triangle values (a copy: the caller's buffer may change meanwhile).
    values: Vec<f64>,
    /// Row of the prolongation $T$ of each fine unknown (its aggregate's six columns).
    basis: Vec<[f64; MODES]>,
    coarse_values: Vec<f64>,
    coarse: Cholesky,
    x: Vec<f64>,
    scratch: Vec<f64>,
    coarse_rhs: Vec<f64>,
    ready: bool,
}

impl AggregationPreconditioner {
    /// Buffers for matrices of `levels`' pattern.
    pub fn new(levels: Arc<AggregationLevels>) -> Result<Self, SolveError> {
        let n = levels.pattern.n();
        let nc = MODES * levels.num_aggregates();
        let coarse = levels
            .coarse
            .share_symbolic_with(super::Precision::Double)?;
        Ok(Self {
            values: vec![0.0; levels.pattern.nnz()],
            basis: vec![[0.0; MODES]; n],
            coarse_values: vec![0.0; coarse.pattern().nnz()],
            coarse,
            x: vec![0.0; n],
            scratch: vec![0.0; n],
            coarse_rhs: vec![0.0; nc],
            levels,
            ready: false,
        })
    }

    /// Builds the preconditioner of the symmetric positive-definite matrix with lower-triangle
    /// `values` (the fine pattern's slots), the rigid modes taken at point positions
    /// `positions` (`[x, y, z]` per point, indexed by the points of the pattern's unknowns).
    /// The coarse matrix gets the smallest shift from a fixed ladder that makes it factor.
    pub fn refresh(&mut self, values: &[f64], positions: &[[f64; 3]]) -> Result<(), SolveError> {
        self.check(values, positions)?;
        self.values.clear();
        self.values.extend_from_slice(values);
        self.rebuild(positions)
    }

    /// [`refresh`](Self::refresh) without a copy: `values` (of the length of
    /// [`take_values`](Self::take_values)'s buffer) become the cycle's own, and `values` is left
    /// empty; on an error it keeps its values. With `take_values`, the caller and the cycle hold
    /// one array of the fine matrix between them instead of two (480 MB at a million vertices).
    pub fn refresh_from(
        &mut self,
        values: &mut Vec<f64>,
        positions: &[[f64; 3]],
    ) -> Result<(), SolveError> {
        self.check(values, positions)?;
        std::mem::swap(&mut self.values, values);
        *values = Vec::new();
        let result = self.rebuild(positions);
        if result.is_err() {
            *values = std::mem::take(&mut self.values);
        }
        result
    }

    /// The cycle's buffer of fine values, to be filled and handed back by
    /// [`refresh_from`](Self::refresh_from); the cycle is not ready until then.
    pub fn take_values(&mut self) -> Vec<f64> {
        self.ready = false;
        let mut v = std::mem::take(&mut self.values);
        v.resize(self.levels.pattern.nnz(), 0.0);
        v
    }

    /// The argument checks of [`refresh`](Self::refresh).
    fn check(&mut self, values: &[f64], positions: &[[f64; 3]]) -> Result<(), SolveError> {
        self.ready = false;
        let lv = &self.levels;
        let n = lv.pattern.n();
        if values.len() != lv.pattern.nnz() {
            return Err(SolveError::Dimension {
                what: "matrix values",
                expected: lv.pattern.nnz(),
                found: values.len(),
            });
        }
        if let Some(&(v, _)) = lv
            .node_axis
            .iter()
            .find(|&&(v, _)| v as usize >= positions.len())
        {
            return Err(SolveError::Dimension {
                what: "point positions",
                expected: v as usize + 1,
                found: positions.len(),
            });
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "matrix values",
            });
        }
        for k in 0..n {
            if values[lv.pattern.diag_slot(k)] <= 0.0 {
                return Err(SolveError::NotPositiveDefinite { column: k, size: n });
            }
        }
        Ok(())
    }

    /// The coarse level of the current fine values.
    fn rebuild(&mut self, positions: &[[f64; 3]]) -> Result<(), SolveError> {
        let dead = self.build_basis(positions);
        self.assemble_coarse();
        let diag: Vec<usize> = (0..self.coarse_rhs.len())
            .map(|k| self.coarse.pattern().diag_slot(k))
            .collect();
        let mean =
            diag.iter().map(|&d| self.coarse_values[d]).sum::<f64>() / diag.len().max(1) as f64;
        for &d in &dead {
            self.coarse_values[diag[d]] = mean.max(f64::MIN_POSITIVE);
        }
        let mut shift = 0.0;
        loop {
            match self.coarse.factorize(&self.coarse_values) {
                Ok(()) => break,
                Err(SolveError::NotPositiveDefinite { .. }) if shift < 1e-2 * mean => {
                    let next = if shift == 0.0 {
                        1e-10 * mean
                    } else {
                        100.0 * shift
                    };
                    for &d in &diag {
                        self.coarse_values[d] += next - shift;
                    }
                    shift = next;
                }
                Err(e) => return Err(e),
            }
        }
        self.ready = true;
        Ok(())
    }

    /// Orthonormal rigid modes of every aggregate; returns the coarse unknowns whose mode is
    /// dependent on the others (a point or a line of points has fewer than six).
    fn build_basis(&mut self, positions: &[[f64; 3]]) -> Vec<usize> {
        let lv = &self.levels;
        let mut dead = Vec::new();
        for a in 0..lv.num_aggregates() {
            let dofs = &lv.agg_dofs[lv.agg_ptr[a]..lv.agg_ptr[a + 1]];
            let mut c = [0.0; 3];
            for &k in dofs {
                let p = positions[lv.node_axis[k as usize].0 as usize];
                (0..3).for_each(|i| c[i] += p[i]);
            }
            c.iter_mut().for_each(|v| *v /= dofs.len().max(1) as f64);
            for &k in dofs {
                let (v, axis) = lv.node_axis[k as usize];
                let p = positions[v as usize];
                let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                // e_b × d for b = x, y, z, component `axis`.
                let rot = [[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]];
                let mut row = [0.0; MODES];
                row[axis as usize] = 1.0;
                for b in 0..3 {
                    row[3 + b] = rot[b][axis as usize];
                }
                self.basis[k as usize] = row;
            }
            // Modified Gram–Schmidt over the aggregate's unknowns.
            for m in 0..MODES {
                let before: f64 = dofs
                    .iter()
                    .map(|&k| self.basis[k as usize][m].powi(2))
                    .sum();
                for q in 0..m {
                    let dot: f64 = dofs
                        .iter()
                        .map(|&k| self.basis[k as usize][m] * self.basis[k as usize][q])
                        .sum();
                    for &k in dofs {
                        let b = &mut self.basis[k as usize];
                        b[m] -= dot * b[q];
                    }
                }
                let after: f64 = dofs
                    .iter()
                    .map(|&k| self.basis[k as usize][m].powi(2))
                    .sum();
                if before == 0.0 || after <= 1e-12 * before {
                    dofs.iter().for_each(|&k| self.basis[k as usize][m] = 0.0);
                    dead.push(MODES * a + m);
                } else {
                    let s = 1.0 / after.sqrt();
                    dofs.iter().for_each(|&k| self.basis[k as usize][m] *= s);
                }
            }
        }
        dead
    }

    /// $A_c = T^\top A T$ into the coarse lower-triangle values.
    fn assemble_coarse(&mut self) {
        let lv = &self.levels;
        let (col_ptr, row_idx) = lv.pattern.columns();
        self.coarse_values.iter_mut().for_each(|v| *v = 0.0);
        let mut acc: Vec<(u32, [f64; MODES])> = Vec::new();
        for c in 0..lv.pattern.n() {
            let j = lv.agg_of_dof[c];
            let tc = self.basis[c];
            acc.clear();
            let start = col_ptr[c];
            // The diagonal entry first: A_cc t_c t_cᵀ, counted once.
            let vcc = self.values[start];
            let mut same = tc.map(|t| 0.5 * vcc * t);
            for (&r, &v) in row_idx[start + 1..col_ptr[c + 1]]
                .iter()
                .zip(&self.values[start + 1..col_ptr[c + 1]])
            {
                let i = lv.agg_of_dof[r];
                let tr = &self.basis[r];
                if i == j {
                    (0..MODES).for_each(|m| same[m] += v * tr[m]);
                    continue;
                }
                let slot = match acc.iter_mut().find(|s| s.0 == i) {
                    Some(s) => s,
                    None => {
                        acc.push((i, [0.0; MODES]));
                        acc.last_mut().expect("just pushed")
                    }
                };
                (0..MODES).for_each(|m| slot.1[m] += v * tr[m]);
            }
            // Diagonal block: (w t_cᵀ + t_c wᵀ), lower part.
            let slots = &lv.pair_slots[lv.pair(j, j)];
            for a in 0..MODES {
                for b in 0..=a {
                    let s = slots[MODES * a + b] as usize;
                    self.coarse_values[s] += same[a] * tc[b] + tc[a] * same[b];
                }
            }
            for &(i, u) in &acc {
                let (hi, lo) = if i > j { (i, j) } else { (j, i) };
                let slots = &lv.pair_slots[lv.pair(hi, lo)];
                for a in 0..MODES {
                    for b in 0..MODES {
                        let s = slots[MODES * a + b] as usize;
                        // Entry (6 hi + a, 6 lo + b) of Σ t_r A_rc t_cᵀ and its mirror.
                        self.coarse_values[s] += if i > j { u[a] * tc[b] } else { tc[a] * u[b] };
                    }
                }
            }
        }
    }

    /// Overwrites `r` with one V-cycle applied to it (see the module docs). Fails when the
    /// preconditioner was not built, or on a size mismatch.
    pub fn apply(&mut self, r: &mut [f64]) -> Result<(), SolveError> {
        let lv = self.levels.clone();
        let n = lv.pattern.n();
        if !self.ready {
            return Err(SolveError::Backend(
                "the aggregation preconditioner was not built".into(),
            ));
        }
        if r.len() != n {
            return Err(SolveError::Dimension {
                what: "right-hand side",
                expected: n,
                found: r.len(),
            });
        }
        let (col_ptr, rows) = (&lv.col_ptr, &lv.rows);
        let vals = &self.values;
        let column = |c: usize| {
            let (a, b) = (col_ptr[c] + 1, col_ptr[c + 1]);
            rows[a..b].iter().zip(&vals[a..b])
        };
        let below = |c: usize, x: &[f64]| {
            let (a, b) = (col_ptr[c] + 1, col_ptr[c + 1]);
            gather_dot(&rows[a..b], &vals[a..b], x)
        };
        // Forward Gauss–Seidel from zero, (D + L) x = r, by columns.
        let x = &mut self.x;
        let s = &mut self.scratch;
        s.copy_from_slice(r);
        for c in 0..n {
            let xc = s[c] / vals[col_ptr[c]];
            x[c] = xc;
            for (&row, &v) in column(c) {
                s[row as usize] -= v * xc;
            }
        }
        // Its residual r − A x = −U x (since (D + L) x = r), restricted.
        self.coarse_rhs.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..n {
            let res = -below(c, x);
            let base = MODES * lv.agg_of_dof[c] as usize;
            let t = &self.basis[c];
            (0..MODES).for_each(|m| self.coarse_rhs[base + m] += t[m] * res);
        }
        self.coarse.solve_one(&mut self.coarse_rhs)?;
        for k in 0..n {
            let base = MODES * lv.agg_of_dof[k] as usize;
            let t = &self.basis[k];
            x[k] += (0..MODES)
                .map(|m| t[m] * self.coarse_rhs[base + m])
                .sum::<f64>();
        }
        // Backward Gauss–Seidel: x += (D + U)⁻¹ (r − A x), the correction by rows from the
        // last (row c of U is column c of the stored lower triangle).
        symmetric_product(col_ptr, rows, vals, x, s);
        for k in 0..n {
            s[k] = r[k] - s[k];
        }
        for c in (0..n).rev() {
            let d = (s[c] - below(c, s)) / vals[col_ptr[c]];
            s[c] = d;
        }
        for k in 0..n {
            r[k] = x[k] + s[k];
        }
        Ok(())
    }

    /// The pattern's aggregates (shared).
    pub fn levels(&self) -> &Arc<AggregationLevels> {
        &self.levels
    }
}

#[cfg(test)]
#[path = "aggregation_tests.rs"]
mod tests;
