//! The blend energy as a sum of terms, $E(x) = \sum_t E_t(x; w)$.
//!
//! Every physical ingredient of the blend (distance springs, signed hinges, and later internal
//! springs, anchor springs, soft pulls, contacts) is one [`EnergyTerm`]. A term declares once,
//! at set-up, which vertex pairs its Hessian couples ([`EnergyTerm::couplings`]); the solver
//! builds one sparsity pattern from all terms and runs the symbolic analysis once. Per weight
//! vector a term computes its parameters ([`EnergyTerm::prepare`]: interpolated rest lengths,
//! dihedral angles, …), then the Newton loop only asks for energy, gradient and Hessian blocks.
//! The Newton loop never knows which terms exist.
//!
//! Conventions: positions are flattened, `x = [x₀, y₀, z₀, x₁, …]` (length `3 #V`); gradients
//! have the same layout; Hessian blocks are 3×3, row-major, added with
//! [`BlockHessian::add`]`(i, j, B)` meaning $\partial^2 E / \partial x_i \partial x_j \mathrel{+}= B$
//! (and, by symmetry, $B^\top$ at `(j, i)`).

mod hinge;
mod orientation;
mod points;
mod spring;
mod volume;

pub use hinge::{HingeOptions, HingeTerm};
pub(crate) use orientation::OrientationTerm;
pub use orientation::{AGREE_COS, GUARD_FROM};
pub use points::PointTarget;
pub(crate) use points::{Held, PointTerm};
pub use spring::SpringTerm;
pub use volume::VolumeTerm;

/// A 3×3 block, row-major.
pub type Block = [[f64; 3]; 3];

/// Which Hessian the Newton loop asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HessianKind {
    /// Positive semi-definite everywhere (compressed springs clamped, Gauss–Newton for
    /// least-squares terms): safe to factorize with Cholesky.
    Projected,
    /// The true Hessian where the term can give it (it may be indefinite); terms whose exact
    /// Hessian is not worth its cost may return their projected one.
    Exact,
}

/// Per-frame parameters of one term, computed from the shape coefficients by
/// [`EnergyTerm::prepare`]. The layout is private to the term.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TermParameters {
    /// The term's numbers (rest lengths, angles, stiffnesses…).
    pub values: Vec<f64>,
    /// Elements whose interpolated parameter had to be clamped (extrapolated weights).
    pub clamped: usize,
}

/// One additive piece of the blend energy.
pub trait EnergyTerm: Send + Sync {
    /// A short name for reports (`"springs"`, `"hinges"`).
    fn name(&self) -> &'static str;
    /// Every vertex pair `(i, j)`, `i ≠ j`, whose Hessian block this term may write. Called
    /// once, at set-up.
    fn couplings(&self, out: &mut Vec<[u32; 2]>);
    /// Called once with the pattern that the solver built from every term's couplings, before
    /// any Hessian is asked for: a term may look up where its blocks go ([`PairSlots`]) instead
    /// of searching the pattern for every block of every Hessian. Default: nothing.
    fn bind(&mut self, _pattern: &std::sync::Arc<BlockPattern>) {}
    /// The parameters for affine shape coefficients `c` (`Σ c = 1`, one per shape). Must
    /// depend on `c` alone.
    fn prepare(&self, c: &[f64]) -> TermParameters;
    /// Adds $\nabla E_t(x)$ to `g` and returns $E_t(x)$.
    fn add_gradient(&self, p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64;
    /// $E_t(x)$ alone.
    fn energy(&self, p: &TermParameters, x: &[f64]) -> f64;
    /// Adds the term's Hessian blocks at `x`.
    fn add_hessian(&self, p: &TermParameters, x: &[f64], kind: HessianKind, h: &mut BlockHessian);
    /// Adds both Hessians at one `x`: the [`HessianKind::Projected`] blocks to `projected`
    /// and the [`HessianKind::Exact`] ones to `exact`, with the same values as two calls of
    /// [`Self::add_hessian`]. A term overrides it to share the work of the two (the Newton
    /// loop asks for both whenever it refreshes its factor).
    fn add_hessians(
        &self,
        p: &TermParameters,
        x: &[f64],
        projected: &mut BlockHessian,
        exact: &mut BlockHessian,
    ) {
        self.add_hessian(p, x, HessianKind::Projected, projected);
        self.add_hessian(p, x, HessianKind::Exact, exact);
    }
}

/// Vertex-level block sparsity: for each vertex, its sorted coupled neighbours of larger index.
#[derive(Clone, Debug)]
pub struct BlockPattern {
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
}

impl BlockPattern {
    /// The pattern holding every pair of `pairs` (either order) on `n` vertices.
    pub fn new(n: usize, pairs: &[[u32; 2]]) -> Self {
        let mut count = vec![0usize; n + 1];
        for &[a, b] in pairs {
            if a != b {
                count[a.min(b) as usize + 1] += 1;
            }
        }
        for k in 0..n {
            count[k + 1] += count[k];
        }
        let mut fill = count.clone();
        let mut cols = vec![0u32; count[n]];
        for &[a, b] in pairs {
            if a != b {
                let r = a.min(b) as usize;
                cols[fill[r]] = a.max(b);
                fill[r] += 1;
            }
        }
        // Sort and deduplicate each row, compacting in place.
        let mut row_ptr = vec![0usize; n + 1];
        let mut out = 0;
        for r in 0..n {
            let row = &mut cols[count[r]..count[r + 1]];
            row.sort_unstable();
            let mut last = u32::MAX;
            for k in count[r]..count[r + 1] {
                let c = cols[k];
                if c != last {
                    cols[out] = c;
                    out += 1;
                    last = c;
                }
            }
            row_ptr[r + 1] = out;
        }
        cols.truncate(out);
        Self { row_ptr, cols }
    }
    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.row_ptr.len() - 1
    }
    /// Number of off-diagonal (upper) blocks.
    pub fn num_pairs(&self) -> usize {
        self.cols.len()
    }
    /// Neighbours `j > i` of vertex `i`, sorted.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.cols[self.row_ptr[i]..self.row_ptr[i + 1]]
    }
    /// Index of the block of pair `(i, j)`, `i < j`.
    #[inline]
    pub fn pair_index(&self, i: usize, j: usize) -> Option<usize> {
        let row = self.row(i);
        row.binary_search(&(j as u32))
            .ok()
            .map(|k| self.row_ptr[i] + k)
    }
    /// Offset of row `i` in the pair list.
    pub(crate) fn row_start(&self, i: usize) -> usize {
        self.row_ptr[i]
    }
}

/// Where a term's off-diagonal blocks go in one [`BlockPattern`], looked up once
/// ([`EnergyTerm::bind`]): per pair of the term, in the term's own order, the index of its
/// block. Valid only for Hessians on that pattern ([`Self::get`] checks).
#[derive(Clone, Debug, Default)]
pub struct PairSlots {
    pattern: Option<std::sync::Arc<BlockPattern>>,
    slots: Vec<u32>,
}

impl PairSlots {
    /// The blocks of `pairs` in `pattern`; every pair must be in it (declared by the term).
    pub fn new(
        pattern: &std::sync::Arc<BlockPattern>,
        pairs: impl Iterator<Item = [u32; 2]>,
    ) -> Self {
        let slots = pairs
            .map(|[a, b]| {
                let (r, c) = (a.min(b) as usize, a.max(b) as usize);
                pattern.pair_index(r, c).map_or(u32::MAX, |k| k as u32)
            })
            .collect();
        Self {
            pattern: Some(std::sync::Arc::clone(pattern)),
            slots,
        }
    }

    /// The slots, when `h` is on the pattern they were looked up in.
    #[inline]
    pub fn get(&self, h: &BlockHessian) -> Option<&[u32]> {
        match &self.pattern {
            Some(p) if std::sync::Arc::ptr_eq(p, &h.pattern) => Some(&self.slots),
            _ => None,
        }
    }
}

/// Hessian values on a [`BlockPattern`]: one full 3×3 block per vertex (diagonal) and one per
/// coupled pair `(i, j)`, `i < j`, holding $\partial^2 E/\partial x_i \partial x_j$.
#[derive(Clone, Debug)]
pub struct BlockHessian {
    pattern: std::sync::Arc<BlockPattern>,
    /// Diagonal blocks, `#V`.
    pub diag: Vec<Block>,
    /// Off-diagonal blocks in pattern order.
    pub off: Vec<Block>,
}

impl BlockHessian {
    /// Zero values for `pattern`.
    pub fn zeros(pattern: std::sync::Arc<BlockPattern>) -> Self {
        Self {
            diag: vec![[[0.0; 3]; 3]; pattern.num_vertices()],
            off: vec![[[0.0; 3]; 3]; pattern.num_pairs()],
            pattern,
        }
    }
    /// No values (empty `diag` and `off`) for `pattern`: a placeholder that is never
    /// assembled into.
    pub fn unallocated(pattern: std::sync::Arc<BlockPattern>) -> Self {
        Self {
            diag: Vec::new(),
            off: Vec::new(),
            pattern,
        }
    }
    /// The pattern.
    pub fn pattern(&self) -> &BlockPattern {
        &self.pattern
    }
    /// The shared pattern.
    pub(crate) fn pattern_arc(&self) -> &std::sync::Arc<BlockPattern> {
        &self.pattern
    }
    /// Sets every value to zero.
    pub fn clear(&mut self) {
        self.diag.iter_mut().for_each(|b| *b = [[0.0; 3]; 3]);
        self.off.iter_mut().for_each(|b| *b = [[0.0; 3]; 3]);
    }
    /// $H_{ij} \mathrel{+}= B$ (and $H_{ji} \mathrel{+}= B^\top$). A pair missing from the
    /// pattern is a programming error of the term (it did not declare it) and panics in debug
    /// builds; release builds drop it.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, b: &Block) {
        if i == j {
            add_block(&mut self.diag[i], b, false);
            return;
        }
        let (r, c, transpose) = if i < j { (i, j, false) } else { (j, i, true) };
        match self.pattern.pair_index(r, c) {
            Some(k) => add_block(&mut self.off[k], b, transpose),
            None => debug_assert!(false, "pair ({i}, {j}) was not declared"),
        }
    }
}

impl BlockHessian {
    /// $H_{ij} \mathrel{+}= B$ for `i ≠ j` whose block is `slot` (from [`PairSlots`]; a
    /// pair missing from the pattern, [`u32::MAX`], is dropped like in [`Self::add`]).
    #[inline]
    pub fn add_at(&mut self, slot: u32, i: usize, j: usize, b: &Block) {
        match self.off.get_mut(slot as usize) {
            Some(dst) => add_block(dst, b, i > j),
            None => debug_assert!(false, "pair ({i}, {j}) was not declared"),
        }
    }

    /// `add_at` with the slot when there is one, else [`Self::add`].
    #[inline]
    pub(crate) fn add_pair(&mut self, slot: Option<u32>, i: usize, j: usize, b: &Block) {
        match slot {
            Some(k) => self.add_at(k, i, j, b),
            None => self.add(i, j, b),
        }
    }
}

#[inline]
fn add_block(dst: &mut Block, b: &Block, transpose: bool) {
    for a in 0..3 {
        for c in 0..3 {
            dst[a][c] += if transpose { b[c][a] } else { b[a][c] };
        }
    }
}

/// Total energy of `terms`.
pub fn total_energy(terms: &[&dyn EnergyTerm], params: &[TermParameters], x: &[f64]) -> f64 {
    terms.iter().zip(params).map(|(t, p)| t.energy(p, x)).sum()
}

/// Writes the total gradient into `g` and returns the total energy.
pub fn total_gradient(
    terms: &[&dyn EnergyTerm],
    params: &[TermParameters],
    x: &[f64],
    g: &mut [f64],
) -> f64 {
    g.iter_mut().for_each(|v| *v = 0.0);
    terms
        .iter()
        .zip(params)
        .map(|(t, p)| t.add_gradient(p, x, g))
        .sum()
}

#[cfg(test)]
pub(crate) mod check {
    //! Finite-difference checks shared by the term tests.
    use super::*;

    /// Asserts that the term's projected Hessian at `x` is symmetric positive semi-definite
    /// (the Gauss–Newton part of a least-squares term).
    pub fn assert_projected_psd(t: &dyn EnergyTerm, p: &TermParameters, x: &[f64]) {
        let hm = dense_hessian(t, p, x, HessianKind::Projected);
        let n = x.len();
        let dm = nalgebra::DMatrix::from_fn(n, n, |r, c| hm[r][c]);
        assert!((&dm - dm.transpose()).norm() < 1e-12 * dm.norm());
        let eig = dm.symmetric_eigenvalues();
        assert!(
            eig.min() > -1e-9 * eig.max(),
            "min eigenvalue {}",
            eig.min()
        );
    }

    /// Max abs difference between the analytic gradient and central differences.
    pub fn gradient_error(t: &dyn EnergyTerm, p: &TermParameters, x: &[f64]) -> (f64, f64) {
        let mut g = vec![0.0; x.len()];
        let e = t.add_gradient(p, x, &mut g);
        assert!((e - t.energy(p, x)).abs() <= 1e-12 * e.abs().max(1e-300));
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for k in 0..x.len() {
            let mut xp = x.to_vec();
            let mut xm = x.to_vec();
            xp[k] += h;
            xm[k] -= h;
            let fd = (t.energy(p, &xp) - t.energy(p, &xm)) / (2.0 * h);
            worst = worst.max((fd - g[k]).abs());
        }
        (worst, g.iter().fold(0.0f64, |m, v| m.max(v.abs())))
    }

    /// Max abs difference between `hessian` (dense) and central differences of the gradient.
    pub fn hessian_error(
        t: &dyn EnergyTerm,
        p: &TermParameters,
        x: &[f64],
        hessian: &[Vec<f64>],
    ) -> f64 {
        let n = x.len();
        let (mut gp, mut gm) = (vec![0.0; n], vec![0.0; n]);
        let mut worst: f64 = 0.0;
        for k in 0..n {
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[k] += 1e-6;
            xm[k] -= 1e-6;
            gp.iter_mut().for_each(|v| *v = 0.0);
            gm.iter_mut().for_each(|v| *v = 0.0);
            t.add_gradient(p, &xp, &mut gp);
            t.add_gradient(p, &xm, &mut gm);
            for r in 0..n {
                let d = ((gp[r] - gm[r]) / 2e-6 - hessian[r][k]).abs();
                if d.is_nan() {
                    return f64::INFINITY; // f64::max would skip a NaN entry
                }
                worst = worst.max(d);
            }
        }
        worst
    }

    /// Whether [`EnergyTerm::add_hessians`] writes exactly (bit for bit) the blocks of two
    /// [`EnergyTerm::add_hessian`] calls.
    pub fn fused_hessians_match(t: &dyn EnergyTerm, p: &TermParameters, x: &[f64]) -> bool {
        let mut pairs = Vec::new();
        t.couplings(&mut pairs);
        let pattern = std::sync::Arc::new(BlockPattern::new(x.len() / 3, &pairs));
        let zeros = || BlockHessian::zeros(pattern.clone());
        let (mut fp, mut fe, mut sp, mut se) = (zeros(), zeros(), zeros(), zeros());
        t.add_hessians(p, x, &mut fp, &mut fe);
        t.add_hessian(p, x, HessianKind::Projected, &mut sp);
        t.add_hessian(p, x, HessianKind::Exact, &mut se);
        let same = |a: &BlockHessian, b: &BlockHessian| {
            let bits = |h: &BlockHessian| -> Vec<u64> {
                h.diag
                    .iter()
                    .chain(&h.off)
                    .flatten()
                    .flatten()
                    .map(|v| v.to_bits())
                    .collect()
            };
            bits(a) == bits(b)
        };
        let nonzero = fe.off.iter().flatten().flatten().any(|v| *v != 0.0);
        nonzero && same(&fp, &sp) && same(&fe, &se)
    }

    /// Whether the Hessians of `t` after [`EnergyTerm::bind`] to a pattern are, bit for bit,
    /// those it writes without (by searching the pattern), both kinds and fused.
    pub fn bound_hessians_match(t: &mut dyn EnergyTerm, p: &TermParameters, x: &[f64]) -> bool {
        let mut pairs = Vec::new();
        t.couplings(&mut pairs);
        // Another term's pair too, so that the term's blocks are not the whole pattern.
        pairs.push([0, (x.len() / 3 - 1) as u32]);
        let pattern = std::sync::Arc::new(BlockPattern::new(x.len() / 3, &pairs));
        let all = |t: &dyn EnergyTerm| {
            let zeros = || BlockHessian::zeros(pattern.clone());
            let (mut a, mut b, mut fp, mut fe) = (zeros(), zeros(), zeros(), zeros());
            t.add_hessian(p, x, HessianKind::Projected, &mut a);
            t.add_hessian(p, x, HessianKind::Exact, &mut b);
            t.add_hessians(p, x, &mut fp, &mut fe);
            [a, b, fp, fe]
                .iter()
                .flat_map(|h| h.diag.iter().chain(&h.off).flatten().flatten())
                .map(|v| v.to_bits())
                .collect::<Vec<u64>>()
        };
        let unbound = all(t);
        t.bind(&pattern);
        let bound = all(t);
        unbound.iter().any(|&v| v != 0) && unbound == bound
    }

    /// Dense Hessian of `t` from its blocks.
    pub fn dense_hessian(
        t: &dyn EnergyTerm,
        p: &TermParameters,
        x: &[f64],
        kind: HessianKind,
    ) -> Vec<Vec<f64>> {
        let n = x.len() / 3;
        let mut pairs = Vec::new();
        t.couplings(&mut pairs);
        let pattern = std::sync::Arc::new(BlockPattern::new(n, &pairs));
        let mut h = BlockHessian::zeros(pattern.clone());
        t.add_hessian(p, x, kind, &mut h);
        let mut m = vec![vec![0.0; 3 * n]; 3 * n];
        for i in 0..n {
            for a in 0..3 {
                for c in 0..3 {
                    m[3 * i + a][3 * i + c] += h.diag[i][a][c];
                }
            }
            for (k, &j) in pattern.row(i).iter().enumerate() {
                let b = &h.off[pattern.row_start(i) + k];
                let j = j as usize;
                for a in 0..3 {
                    for c in 0..3 {
                        m[3 * i + a][3 * j + c] += b[a][c];
                        m[3 * j + c][3 * i + a] += b[a][c];
                    }
                }
            }
        }
        m
    }
}
