//! The Newton system over the free coordinates: index maps, the scalar lower-triangle pattern
//! built once from the terms' [`BlockPattern`], assembly of block values into it, and the
//! symmetric product used by the inner conjugate-gradient iterations.
//!
//! Coordinates are `3 #V` (`[x₀, y₀, z₀, x₁, …]`); fixed coordinates (boundary conditions,
//! gauge pins, kinematic vertices) are eliminated, so the matrix is `n_free × n_free`.

use super::terms::{BlockHessian, BlockPattern};
use crate::sparse::{
    AggregationLevels, Cholesky, Ordering, Precision, SolveError, SymmetricPattern,
};
use std::sync::Arc;

const NONE: u32 = u32::MAX;

/// Free-coordinate indexing and value maps of the Newton matrix.
#[derive(Debug)]
pub(crate) struct FreeSystem {
    /// Free index of each of the `3 #V` coordinates, [`u32::MAX`] when fixed.
    pub dof_index: Vec<u32>,
    /// Value slot of each entry `(a, c)` of each vertex's diagonal block (lower triangle only).
    diag_dest: Vec<[u32; 9]>,
    /// Value slot of each entry of each off-diagonal block.
    off_dest: Vec<[u32; 9]>,
    /// Diagonal slot of each free coordinate.
    pub diag_slots: Vec<u32>,
    pub pattern: Arc<SymmetricPattern>,
    /// The vertex-level pattern the scalar one was built from.
    pub block_pattern: Arc<BlockPattern>,
}

impl FreeSystem {
    /// Index maps and the scalar pattern for `fixed_dof` (`3 #V`).
    pub fn new(block_pattern: Arc<BlockPattern>, fixed_dof: &[bool]) -> Result<Self, SolveError> {
        let n = block_pattern.num_vertices();
        let mut dof_index = vec![NONE; 3 * n];
        let mut nfree = 0u32;
        for (k, fixed) in fixed_dof.iter().enumerate() {
            if !fixed {
                dof_index[k] = nfree;
                nfree += 1;
            }
        }
        let mut entries = Vec::new();
        let mut owner = Vec::new();
        for v in 0..n {
            for a in 0..3 {
                for c in 0..=a {
                    let (r, q) = (dof_index[3 * v + a], dof_index[3 * v + c]);
                    if r != NONE && q != NONE {
                        entries.push((r as usize, q as usize));
                        owner.push((0u8, v, 3 * a + c));
                    }
                }
            }
        }
        for i in 0..n {
            let start = block_pattern.row_start(i);
            for (k, &j) in block_pattern.row(i).iter().enumerate() {
                for a in 0..3 {
                    for c in 0..3 {
                        let (r, q) = (dof_index[3 * i + a], dof_index[3 * j as usize + c]);
                        if r != NONE && q != NONE {
                            entries.push((r as usize, q as usize));
                            owner.push((1u8, start + k, 3 * a + c));
                        }
                    }
                }
            }
        }
        let (pattern, slots) = SymmetricPattern::new(nfree as usize, &entries)?;
        let mut diag_dest = vec![[NONE; 9]; n];
        let mut off_dest = vec![[NONE; 9]; block_pattern.num_pairs()];
        for ((kind, b, e), s) in owner.into_iter().zip(slots) {
            if kind == 0 {
                diag_dest[b][e] = s as u32;
            } else {
                off_dest[b][e] = s as u32;
            }
        }
        let diag_slots = (0..nfree as usize)
            .map(|k| pattern.diag_slot(k) as u32)
            .collect();
        Ok(Self {
            dof_index,
            diag_dest,
            off_dest,
            diag_slots,
            pattern: Arc::new(pattern),
            block_pattern,
        })
    }

    /// Number of free coordinates.
    pub fn num_free(&self) -> usize {
        self.diag_slots.len()
    }

    /// Writes the block values into the scalar lower-triangle `values`.
    pub fn assemble(&self, h: &BlockHessian, values: &mut [f64]) {
        values.iter_mut().for_each(|v| *v = 0.0);
        for (b, dest) in h.diag.iter().zip(&self.diag_dest) {
            for (e, &s) in dest.iter().enumerate() {
                if s != NONE {
                    values[s as usize] += b[e / 3][e % 3];
                }
            }
        }
        for (b, dest) in h.off.iter().zip(&self.off_dest) {
            for (e, &s) in dest.iter().enumerate() {
                if s != NONE {
                    values[s as usize] += b[e / 3][e % 3];
                }
            }
        }
    }

    /// `out = A p` for the symmetric matrix with lower-triangle `values`.
    pub fn mul(&self, values: &[f64], p: &[f64], out: &mut [f64]) {
        self.pattern.mul_vec_into(values, p, out);
    }

    /// The free entries of a full-length vector.
    pub fn gather(&self, full: &[f64], free: &mut [f64]) {
        for (k, &i) in self.dof_index.iter().enumerate() {
            if i != NONE {
                free[i as usize] = full[k];
            }
        }
    }

    /// `x[k] += t · step[free(k)]` over free coordinates.
    pub fn add_step(&self, x: &mut [f64], t: f64, step: &[f64]) {
        for (k, &i) in self.dof_index.iter().enumerate() {
            if i != NONE {
                x[k] += t * step[i as usize];
            }
        }
    }

    /// Max-norm of a full-length vector over the free coordinates.
    pub fn max_free(&self, g: &[f64]) -> f64 {
        g.iter()
            .zip(&self.dof_index)
            .filter(|(_, i)| **i != NONE)
            .fold(0.0, |m, (v, _)| m.max(v.abs()))
    }

    /// The aggregation cycle's set-up for this system's pattern, the free coordinates grouped
    /// by vertex.
    pub fn aggregation_levels(&self) -> Result<AggregationLevels, SolveError> {
        let node_axis: Vec<(u32, u8)> = (0..self.dof_index.len())
            .filter(|&k| self.dof_index[k] != NONE)
            .map(|k| ((k / 3) as u32, (k % 3) as u8))
            .collect();
        AggregationLevels::new(self.pattern.clone(), &node_axis)
    }

    /// Symbolic analysis of the scalar pattern with the cheapest of `orderings` (fewest
    /// multiply-adds per factorization, the first of equals), and its index; no numeric
    /// buffers yet ([`Cholesky::with_numeric`]), so that a blend preconditioned by the
    /// aggregation cycle never allocates the fine factor.
    pub fn analyze(
        &self,
        orderings: &[Ordering],
        precision: Precision,
    ) -> Result<(Cholesky, usize), SolveError> {
        Cholesky::analyze_cheapest_symbolic(Arc::clone(&self.pattern), orderings, precision)
    }
}

/// METIS nested dissection of the vertex graph of `pattern`.
pub(crate) fn vertex_nested_dissection(pattern: &BlockPattern) -> Result<Vec<usize>, SolveError> {
    let nv = pattern.num_vertices();
    let mut adj = vec![Vec::new(); nv];
    for i in 0..nv {
        for &j in pattern.row(i) {
            adj[i].push(j as usize);
            adj[j as usize].push(i);
        }
    }
    crate::sparse::metis::nested_dissection(&adj)
}

/// A vertex order expanded to the free coordinates (each vertex's free coordinates together).
pub(crate) fn expand_vertex_order(order: &[usize], dof_index: &[u32]) -> Vec<usize> {
    let mut out = Vec::with_capacity(dof_index.len());
    for &v in order {
        for a in 0..3 {
            if dof_index[3 * v + a] != NONE {
                out.push(dof_index[3 * v + a] as usize);
            }
        }
    }
    out
}

/// Bytes per vertex of what a blend holds besides the Newton system and its preconditioner:
/// springs and hinges with their rest data, topology, shapes, constraints and holds, the
/// rotation-aware predictor's Poisson factor, and the vectors of a solve. Measured, not
/// derived: the heap peak of one-frame blends of generated wavy sheets (docs/performance.md,
/// "Film scale") less the counted parts.
pub(crate) const RIG_BYTES_PER_VERTEX: u64 = 4096;

/// The parts of a blend's predicted memory for `nv` vertices and `pairs` coupled vertex
/// pairs, without the preconditioner: shared by every thread ([`Self::shared`]: the scalar
/// pattern and its index maps, [`RIG_BYTES_PER_VERTEX`]) and per solver workspace
/// ([`Self::workspace`]: the exact and projected Hessian values and blocks).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct SystemBytes {
    pub shared: u64,
    pub workspace: u64,
    /// The part of `workspace` that the aggregation cycle's workspaces do without: the exact
    /// Hessian's 3×3 blocks (both Hessians are assembled through one block buffer) and the
    /// projected Hessian's values (held by the cycle itself between refreshes).
    pub factor_only: u64,
}

impl SystemBytes {
    pub fn new(nv: u64, pairs: u64) -> Self {
        let scalar_nnz = 9 * pairs + 6 * nv;
        let blocks = nv + pairs;
        Self {
            // Row indices and column starts; value slots of every block entry; free indices.
            shared: 8 * scalar_nnz + 8 * 3 * nv + 36 * blocks + 12 * nv + RIG_BYTES_PER_VERTEX * nv,
            // Two value arrays (exact and projected), two sets of 3×3 blocks.
            workspace: 16 * scalar_nnz + 2 * 72 * blocks,
            factor_only: 72 * blocks + 8 * scalar_nnz,
        }
    }
}

/// A fine factor's numeric memory from a vertex-level factor of `l_vertex` entries, before
/// the scalar analysis: every vertex pair is a 3×3 block, in `precision`; a single-precision
/// factor also keeps the matrix rounded to `f32`; the factorization's scratch, about a fifth
/// of the factor on sheets (measured 22 % at 40k vertices, 17 % at 250k).
fn factor_bytes(nv: u64, pairs: u64, l_vertex: u64, precision: Precision) -> u64 {
    let factor = 9 * l_vertex;
    let (per_value, rounded) = match precision {
        Precision::Double => (8, 0),
        Precision::Single => (4, 4 * (9 * pairs + 6 * nv)),
    };
    let values = per_value * factor;
    values + values / 5 + rounded
}

/// Predicted bytes of a blend over `block_pattern` before the scalar system is built: the
/// [`SystemBytes`] and, unless `without_factor`, the fill of a vertex-level symbolic analysis
/// (see [`factor_bytes`]). `without_factor` is the aggregation cycle's lower bound (its
/// coarse levels are counted once they are built).
pub(crate) fn predicted_bytes(
    block_pattern: &BlockPattern,
    ordering_vertices: Option<&[usize]>,
    precision: Precision,
    without_factor: bool,
) -> Result<u64, SolveError> {
    let n = block_pattern.num_vertices();
    let (nv, pairs) = (n as u64, block_pattern.num_pairs() as u64);
    let s = SystemBytes::new(nv, pairs);
    if without_factor {
        return Ok(s.shared + s.workspace - s.factor_only);
    }
    let mut entries = Vec::with_capacity(block_pattern.num_pairs());
    for i in 0..n {
        for &j in block_pattern.row(i) {
            entries.push((j as usize, i));
        }
    }
    let (vp, _) = SymmetricPattern::new(n, &entries)?;
    let ordering = match ordering_vertices {
        Some(p) => Ordering::Custom(p.to_vec()),
        None => Ordering::Amd,
    };
    let l_vertex = Cholesky::predicted_factor_nnz(&vp, ordering)? as u64;
    Ok(s.shared + s.workspace + factor_bytes(nv, pairs, l_vertex, precision))
}

/// A lower bound of [`predicted_bytes`] from the triangles alone, before any connectivity is
/// built: every distinct triangle edge is a coupled pair (counted by one sort), and the factor
/// (unless `without_factor`) holds at least the matrix's lower triangle. A mesh over the limit
/// by this bound is refused in the time it took to read it (issue 39: a 2M-vertex sheet took
/// 35 s and 3.6 GB of set-up to be refused).
pub(crate) fn predicted_bytes_lower_bound(
    vertices: usize,
    triangles: &[[u32; 3]],
    precision: Precision,
    without_factor: bool,
) -> u64 {
    let mut edges: Vec<u64> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (u64::from(a.min(b)) << 32) | u64::from(a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let n = vertices as u64;
    let pairs = edges.len() as u64;
    let s = SystemBytes::new(n, pairs);
    if without_factor {
        // The aggregation cycle's workspaces (see SystemBytes::factor_only).
        return s.shared + s.workspace - s.factor_only;
    }
    s.shared + s.workspace + factor_bytes(n, pairs, n + pairs, precision)
}
