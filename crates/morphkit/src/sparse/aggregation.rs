//! A two-level aggregation preconditioner for the symmetric positive-definite systems of
//! mass–spring and elastic models, whose unknowns are the three coordinates of points.
//!
//! Unsmoothed aggregation (Vaněk, Mandel & Brezina, *Computing* 56, 1996, §3; Braess 1995)
//! with the rigid-body modes as the coarse space:
//! - *Set-up, once per pattern* ([`AggregationLevels::new`]): the points are grouped into
//!   aggregates by the greedy three-pass algorithm on the matrix graph (a point and all its
//!   neighbours; then leftovers join a neighbouring aggregate; then what remains forms new
//!   ones), the coarse pattern (6 × 6 blocks between neighbouring aggregates) is built and
//!   its Cholesky factor analysed.
//! - *Numeric, once per matrix* ([`AggregationPreconditioner::refresh`]): on each aggregate
//!   the three translations and three rotations about its centroid, at the current point
//!   positions, orthonormalized, form the prolongation $T$ (`n × 6 #aggregates`, one block
//!   per aggregate); the coarse matrix is the Galerkin product $A_c = T^\top A T$, factored.
//! - *Application* ([`AggregationPreconditioner::apply`]): one V-cycle, a forward
//!   Gauss–Seidel sweep from zero, the coarse correction $T A_c^{-1} T^\top r$, and a backward
//!   Gauss–Seidel sweep. Pre- and post-smoother are each other's transposes, so the cycle is
//!   a symmetric positive-definite operator, fit for preconditioned conjugate gradients and
//!   for defining a trust-region norm.
//!
//! On a volumetric system the translations and rotations are what the smoother cannot reduce
//! (the near null space of an elastic body), and a direct factor of the whole system fills
//! with the cross-sections of the body; here only the coarse matrix (about a fifth of the
//! unknowns' count divided by five) is factored. Everything is deterministic: no decision
//! depends on timing or thread count.

use super::{Cholesky, Ordering, Precision, SolveError, SymmetricPattern};
use std::sync::Arc;

/// Coarse unknowns per aggregate: three translations, three rotations.
const MODES: usize = 6;
const NONE: u32 = u32::MAX;

/// The aggregates, the coarse pattern and its symbolic factor of one fine pattern (shared by
/// every [`AggregationPreconditioner`] of that pattern).
#[derive(Debug)]
pub struct AggregationLevels {
    pattern: Arc<SymmetricPattern>,
    /// The pattern's column pointers and 32-bit row indices (a third less memory traffic in
    /// the cycle's sweeps and products than the pattern's own).
    col_ptr: Vec<usize>,
    rows: Vec<u32>,
    /// Point and axis (0, 1, 2) of each fine unknown.
    node_axis: Vec<(u32, u8)>,
    /// Aggregate of each fine unknown.
    agg_of_dof: Vec<u32>,
    /// Fine unknowns of each aggregate (ascending), CSR.
    agg_ptr: Vec<usize>,
    agg_dofs: Vec<u32>,
    /// Lower pairs `(I, J)`, `I ≥ J`, of neighbouring aggregates, grouped by `J`.
    pair_ptr: Vec<usize>,
    pair_row: Vec<u32>,
    /// Coarse value slot of entry `(6 I + a, 6 J + b)` of each pair (`NONE` above the diagonal
    /// of a diagonal block).
    pair_slots: Vec<[u32; MODES * MODES]>,
    coarse: Cholesky,
}

impl AggregationLevels {
    /// Aggregates the points of a fine `pattern` whose unknown `k` is coordinate
    /// `node_axis[k].1` of point `node_axis[k].0` (a point may have fewer than three free
    /// coordinates), and analyses the coarse system.
    pub fn new(
        pattern: Arc<SymmetricPattern>,
        node_axis: &[(u32, u8)],
    ) -> Result<Self, SolveError> {
        let n = pattern.n();
        if node_axis.len() != n {
            return Err(SolveError::Dimension {
                what: "point of each unknown",
                expected: n,
                found: node_axis.len(),
            });
        }
        if let Some(&(_, a)) = node_axis.iter().find(|&&(_, a)| a > 2) {
            return Err(SolveError::Dimension {
                what: "axis of an unknown",
                expected: 3,
                found: a as usize,
            });
        }
        let num_nodes = node_axis
            .iter()
            .map(|&(v, _)| v as usize + 1)
            .max()
            .unwrap_or(0);
        let node_of = |k: usize| node_axis[k].0 as usize;
        // The point graph of the matrix.
        let (col_ptr, row_idx) = pattern.columns();
        let mut has_dof = vec![false; num_nodes];
        let mut adj: Vec<Vec<u32>> = vec![Vec::new(); num_nodes];
        for c in 0..n {
            has_dof[node_of(c)] = true;
            for &r in &row_idx[col_ptr[c] + 1..col_ptr[c + 1]] {
                let (a, b) = (node_of(r), node_of(c));
                if a != b {
                    adj[a].push(b as u32);
                    adj[b].push(a as u32);
                }
            }
        }
        for l in &mut adj {
            l.sort_unstable();
            l.dedup();
        }
        let agg_of_node = aggregate(&adj, &has_dof);
        let num_aggs = agg_of_node
            .iter()
            .filter(|&&a| a != NONE)
            .map(|&a| a as usize + 1)
            .max()
            .unwrap_or(0);
        let agg_of_dof: Vec<u32> = (0..n).map(|k| agg_of_node[node_of(k)]).collect();
        let mut agg_ptr = vec![0usize; num_aggs + 1];
        for &a in &agg_of_dof {
            agg_ptr[a as usize + 1] += 1;
        }
        for i in 0..num_aggs {
            agg_ptr[i + 1] += agg_ptr[i];
        }
        let mut fill = agg_ptr.clone();
        let mut agg_dofs = vec![0u32; n];
        for (k, &a) in agg_of_dof.iter().enumerate() {
            agg_dofs[fill[a as usize]] = k as u32;
            fill[a as usize] += 1;
        }
        // Coarse pairs.
        let mut pairs: Vec<Vec<u32>> = (0..num_aggs).map(|j| vec![j as u32]).collect();
        for c in 0..n {
            for &r in &row_idx[col_ptr[c] + 1..col_ptr[c + 1]] {
                let (i, j) = (agg_of_dof[r], agg_of_dof[c]);
                let (hi, lo) = if i >= j { (i, j) } else { (j, i) };
                pairs[lo as usize].push(hi);
            }
        }
        let mut pair_ptr = vec![0usize];
        let mut pair_row = Vec::new();
        for l in &mut pairs {
            l.sort_unstable();
            l.dedup();
            pair_row.extend_from_slice(l);
            pair_ptr.push(pair_row.len());
        }
        let mut entries = Vec::with_capacity(pair_row.len() * MODES * MODES);
        for j in 0..num_aggs {
            for &i in &pair_row[pair_ptr[j]..pair_ptr[j + 1]] {
                for a in 0..MODES {
                    for b in 0..MODES {
                        if i as usize != j || a >= b {
                            entries.push((MODES * i as usize + a, MODES * j + b));
                        }
                    }
                }
            }
        }
        let (coarse_pattern, slots) = SymmetricPattern::new(MODES * num_aggs, &entries)?;
        let mut pair_slots = vec![[NONE; MODES * MODES]; pair_row.len()];
        let mut s = slots.into_iter();
        for j in 0..num_aggs {
            for p in pair_ptr[j]..pair_ptr[j + 1] {
                let diagonal = pair_row[p] as usize == j;
                for a in 0..MODES {
                    for b in 0..MODES {
                        if !diagonal || a >= b {
                            pair_slots[p][MODES * a + b] =
                                s.next().expect("one slot per entry") as u32;
                        }
                    }
                }
            }
        }
        let coarse = Cholesky::analyze_with(coarse_pattern, Ordering::Amd, Precision::Double)?;
        if row_idx.len() > u32::MAX as usize {
            return Err(SolveError::Backend(
                "too many matrix entries for the aggregation cycle".into(),
            ));
        }
        let (col_ptr, rows) = (
            col_ptr.to_vec(),
            row_idx.iter().map(|&r| r as u32).collect(),
        );
        Ok(Self {
            pattern,
            col_ptr,
            rows,
            node_axis: node_axis.to_vec(),
            agg_of_dof,
            agg_ptr,
            agg_dofs,
            pair_ptr,
            pair_row,
            pair_slots,
            coarse,
        })
    }

    /// `out = A p` for the symmetric matrix with lower-triangle `values` of this pattern (the
    /// same as [`SymmetricPattern::mul_vec_into`], with the cycle's 32-bit indices).
    pub fn mul(&self, values: &[f64], p: &[f64], out: &mut [f64]) {
        symmetric_product(&self.col_ptr, &self.rows, values, p, out);
    }

    /// Number of aggregates (coarse unknowns: six per aggregate).
    pub fn num_aggregates(&self) -> usize {
        self.agg_ptr.len() - 1
    }

    /// Multiply-adds of one coarse factorization.
    pub fn coarse_flops(&self) -> f64 {
        self.coarse.factor_flops()
    }

    /// The pair index of lower aggregate pair `(hi, lo)`, `hi ≥ lo`.
    fn pair(&self, hi: u32, lo: u32) -> usize {
        let (s, e) = (self.pair_ptr[lo as usize], self.pair_ptr[lo as usize + 1]);
        s + self.pair_row[s..e]
            .binary_search(&hi)
            .expect("every coupled pair of aggregates is in the coarse pattern")
    }
}

/// Greedy aggregation of the points with unknowns (Vaněk et al. 1996, §3, three passes):
/// returns each point's aggregate (`NONE` for points without unknowns).
fn aggregate(adj: &[Vec<u32>], has_dof: &[bool]) -> Vec<u32> {
    let mut agg = vec![NONE; adj.len()];
    let mut count = 0u32;
    // 1: a point whose neighbours are all free starts an aggregate with them.
    for v in 0..adj.len() {
        if has_dof[v] && agg[v] == NONE && adj[v].iter().all(|&u| agg[u as usize] == NONE) {
            agg[v] = count;
            for &u in &adj[v] {
                agg[u as usize] = count;
            }
            count += 1;
        }
    }
    // 2: leftovers join the aggregate of pass 1 they share most neighbours with (the lowest
    // of equals).
    let first = agg.clone();
    for v in 0..adj.len() {
        if has_dof[v] && agg[v] == NONE {
            let mut best: Option<(usize, u32)> = None;
            let mut seen: Vec<(u32, usize)> = Vec::new();
            for &u in &adj[v] {
                let a = first[u as usize];
                if a == NONE {
                    continue;
                }
                match seen.iter_mut().find(|s| s.0 == a) {
                    Some(s) => s.1 += 1,
                    None => seen.push((a, 1)),
                }
            }
            for &(a, c) in &seen {
                if best.is_none_or(|(bc, ba)| c > bc || (c == bc && a < ba)) {
                    best = Some((c, a));
                }
            }
            if let Some((_, a)) = best {
                agg[v] = a;
            }
        }
    }
    // 3: what remains (isolated groups) forms aggregates with its unaggregated neighbours.
    for v in 0..adj.len() {
        if has_dof[v] && agg[v] == NONE {
            agg[v] = count;
            for &u in &adj[v] {
                if agg[u as usize] == NONE {
                    agg[u as usize] = count;
                }
            }
            count += 1;
        }
    }
    agg
}

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
        let coarse = levels.coarse.share_symbolic()?;
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
        let lv = self.levels.clone();
        let n = lv.pattern.n();
        self.ready = false;
        if values.len() != self.values.len() {
            return Err(SolveError::Dimension {
                what: "matrix values",
                expected: self.values.len(),
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
        self.values.copy_from_slice(values);
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

/// `y = A x` for a symmetric matrix stored as its lower triangle by columns (diagonal first).
fn symmetric_product<V: Copy + Into<f64>>(
    col_ptr: &[usize],
    rows: &[u32],
    values: &[V],
    x: &[f64],
    y: &mut [f64],
) {
    y.iter_mut().for_each(|v| *v = 0.0);
    for c in 0..x.len() {
        let (start, end) = (col_ptr[c], col_ptr[c + 1]);
        let xc = x[c];
        let (rs, vs) = (&rows[start + 1..end], &values[start + 1..end]);
        for (&r, &v) in rs.iter().zip(vs) {
            y[r as usize] += v.into() * xc;
        }
        y[c] += values[start].into() * xc + gather_dot(rs, vs, x);
    }
}

/// `Σ_k values[k] x[rows[k]]`, in four interleaved partial sums (independent additions
/// instead of one chain; the same order, hence the same bits, on every run).
fn gather_dot<V: Copy + Into<f64>>(rows: &[u32], values: &[V], x: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (rc, vc) = (rows.chunks_exact(4), values.chunks_exact(4));
    let (rr, vr) = (rc.remainder(), vc.remainder());
    for (r, v) in rc.zip(vc) {
        for k in 0..4 {
            acc[k] += v[k].into() * x[r[k] as usize];
        }
    }
    for (k, (&r, &v)) in rr.iter().zip(vr).enumerate() {
        acc[k] += v.into() * x[r as usize];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

#[cfg(test)]
#[path = "aggregation_tests.rs"]
mod tests;
