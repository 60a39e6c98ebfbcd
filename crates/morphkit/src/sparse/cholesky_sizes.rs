//! What a [`Cholesky`] analysis costs: the factor's entries, bytes and multiply-adds, and
//! the numeric buffers a solver holds, all from the symbolic structure.

use super::{Cholesky, Precision};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::Par;

/// Multiply-adds of one numeric factorization with `symbolic` (see [`Cholesky::factor_flops`]).
pub(super) fn symbolic_flops(symbolic: &SymbolicCholesky<usize>) -> f64 {
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => {
            let (begin, end) = (s.supernode_begin(), s.supernode_end());
            let rows = s.col_ptr_for_row_idx();
            (0..s.n_supernodes())
                .map(|k| {
                    let w = (end[k] - begin[k]) as f64;
                    let r = (rows[k + 1] - rows[k]) as f64;
                    w * w * w / 3.0 + w * w * r + w * r * r
                })
                .sum::<f64>()
                + 0.0 // an empty sum is -0.0
        }
        SymbolicCholeskyRaw::Simplicial(s) => {
            s.col_ptr()
                .windows(2)
                .map(|c| ((c[1] - c[0]) as f64).powi(2))
                .sum::<f64>()
                + 0.0
        }
    }
}

impl Cholesky {
    /// Number of stored entries of the factor $L$ (a measure of fill and memory).
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Bytes of the stored factor in its precision (of a [`FrozenFactor`] copy, too).
    pub fn factor_bytes(&self) -> u64 {
        let width = match self.precision {
            Precision::Single => 4,
            Precision::Double => 8,
        };
        width * self.factor_nnz() as u64
    }

    /// Bytes of the numeric buffers a solver of this analysis holds (or would hold, before
    /// [`Self::with_numeric`]): the factor in its precision, the matrix rounded to `f32` for
    /// a single-precision factor, and the factorization's and a solve's scratch.
    pub fn numeric_bytes(&self) -> u64 {
        let n = self.pattern.n() as u64;
        let (scratch, rounded, rhs) = match self.precision {
            Precision::Single => (
                self.symbolic
                    .factorize_numeric_llt_scratch::<f32>(Par::Seq, Default::default())
                    .or(self.symbolic.solve_in_place_scratch::<f32>(1, Par::Seq)),
                4 * self.pattern.nnz() as u64,
                12 * n,
            ),
            Precision::Double => (
                self.symbolic
                    .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                    .or(self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq)),
                0,
                8 * n,
            ),
        };
        self.factor_bytes() + rounded + rhs + scratch.size_bytes() as u64
    }

    /// Multiply-adds of one numeric factorization, from the symbolic structure: per
    /// supernode of $w$ columns with $r$ rows below its diagonal block, $w^3/3$ for the
    /// diagonal block, $w^2 r$ for the panel below it and $w r^2$ for its update of the rest
    /// (per column $c^2$ for a simplicial factor, $c$ its entries). An ordering's cost,
    /// independent of the machine and its load.
    pub fn factor_flops(&self) -> f64 {
        symbolic_flops(&self.symbolic)
    }
}
