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

pub use super::aggregation_cycle::AggregationPreconditioner;
use super::{Cholesky, Ordering, Precision, SolveError, SymmetricPattern};
use std::sync::Arc;

/// Coarse unknowns per aggregate: three translations, three rotations.
pub(super) const MODES: usize = 6;
const NONE: u32 = u32::MAX;

/// The aggregates, the coarse pattern and its symbolic factor of one fine pattern (shared by
/// every [`AggregationPreconditioner`] of that pattern).
#[derive(Debug)]
pub struct AggregationLevels {
    pub(super) pattern: Arc<SymmetricPattern>,
    /// The pattern's column pointers and 32-bit row indices (a third less memory traffic in
    /// the cycle's sweeps and products than the pattern's own).
    pub(super) col_ptr: Vec<usize>,
    pub(super) rows: Vec<u32>,
    /// Point and axis (0, 1, 2) of each fine unknown.
    pub(super) node_axis: Vec<(u32, u8)>,
    /// Aggregate of each fine unknown.
    pub(super) agg_of_dof: Vec<u32>,
    /// Fine unknowns of each aggregate (ascending), CSR.
    pub(super) agg_ptr: Vec<usize>,
    pub(super) agg_dofs: Vec<u32>,
    /// Lower pairs `(I, J)`, `I ≥ J`, of neighbouring aggregates, grouped by `J`.
    pub(super) pair_ptr: Vec<usize>,
    pub(super) pair_row: Vec<u32>,
    /// Coarse value slot of entry `(6 I + a, 6 J + b)` of each pair (`NONE` above the diagonal
    /// of a diagonal block).
    pub(super) pair_slots: Vec<[u32; MODES * MODES]>,
    pub(super) coarse: Cholesky,
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
        // Symbolic only: each cycle factors in buffers of its own.
        let coarse = Cholesky::analyze_symbolic_only(
            Arc::new(coarse_pattern),
            Ordering::Amd,
            Precision::Double,
        )?;
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

    /// Bytes of these levels (shared by every cycle) and of each
    /// [`AggregationPreconditioner`] over them (its copy of the matrix, the rigid modes, the
    /// coarse matrix, factor and scratch).
    pub fn bytes(&self) -> (u64, u64) {
        let n = self.pattern.n() as u64;
        let nnz = self.rows.len() as u64;
        let aggs = self.num_aggregates() as u64;
        let pairs = self.pair_row.len() as u64;
        let shared = 8 * (n + 1)
            + 4 * nnz
            + 8 * n
            + 4 * n
            + 8 * (aggs + 1)
            + 4 * n
            + 8 * (aggs + 1)
            + 4 * pairs
            + 4 * (MODES * MODES) as u64 * pairs;
        let coarse = self.coarse.pattern().nnz() as u64;
        let cycle = 8 * nnz
            + 8 * MODES as u64 * n
            + 16 * n
            + 8 * coarse
            + 8 * MODES as u64 * aggs
            + self.coarse.numeric_bytes();
        (shared, cycle)
    }

    /// Multiply-adds of one coarse factorization.
    pub fn coarse_flops(&self) -> f64 {
        self.coarse.factor_flops()
    }

    /// The pair index of lower aggregate pair `(hi, lo)`, `hi ≥ lo`.
    pub(super) fn pair(&self, hi: u32, lo: u32) -> usize {
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

/// `y = A x` for a symmetric matrix stored as its lower triangle by columns (diagonal first).
pub(super) fn symmetric_product<V: Copy + Into<f64>>(
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
pub(super) fn gather_dot<V: Copy + Into<f64>>(rows: &[u32], values: &[V], x: &[f64]) -> f64 {
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
