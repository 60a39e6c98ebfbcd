//! Per-thread buffers of a solve (issue 38): the preconditioner (the fine factor, or the
//! aggregation cycle that holds the projected Hessian's values between its refreshes), the
//! Hessians as 3×3 blocks and as scalar values. On the cycle's path a workspace holds no fine
//! symbolic analysis, one block buffer, and one array of values besides the cycle's: on a
//! million-vertex sheet that cut the blend's peak resident from 9.05 to 7.70 GB on one thread
//! (docs/performance.md, "Evening of 6 December").

use super::terms::BlockHessian;
use crate::sparse::{AggregationPreconditioner, Cholesky, SolveError};

/// Per-thread buffers of a solve: numeric factor, block values, scalar values.
pub(crate) struct Workspace {
    /// The factor in the rig's [`Precision`](crate::sparse::Precision); `None` when the
    /// aggregation cycle preconditions ([`Self::aggregation`]): the fine symbolic analysis is
    /// then dropped once the preconditioner is chosen (no solve reads it).
    pub chol: Option<Cholesky>,
    /// A double-precision factor for the matrices whose single-precision factorization fails
    /// (allocated on first need; used until the end of that solve only, so that every solve
    /// starts alike).
    pub double: Option<Cholesky>,
    /// Whether the current solve factors with [`Self::double`].
    pub use_double: bool,
    pub blocks: BlockHessian,
    /// Exact-Hessian blocks when both Hessians are assembled in one pass
    /// ([`EnergyTerm::add_hessians`]); unallocated with the aggregation cycle, whose solves
    /// assemble the two Hessians in two passes over one block buffer (one copy of the
    /// `72 · (#V + pairs)` bytes fewer, where memory is what limits the mesh size).
    pub blocks_exact: BlockHessian,
    /// Scalar values of the exact Hessian (the CG operator).
    pub exact: Vec<f64>,
    /// Scalar values of the projected Hessian (the factorization input).
    pub projected: Vec<f64>,
    /// The aggregation cycle that preconditions instead of [`Self::chol`]
    /// ([`Preconditioner::Aggregation`](super::Preconditioner::Aggregation)).
    pub aggregation: Option<AggregationPreconditioner>,
    /// Vertex positions of the current iterate (the aggregation cycle's rigid modes).
    pub points: Vec<[f64; 3]>,
    /// The iterate of the last factorization of [`Self::chol`] in the current solve.
    pub factored_at: Option<Vec<f64>>,
    /// The interactive mode's reduced-space buffers (`m · nf` values each), kept between
    /// slider changes: fresh ones cost page faults and zeroing on every change.
    pub reduced: [Vec<f64>; 2],
}

impl Workspace {
    /// New buffers around the preconditioner: the factor `chol`, or the aggregation cycle
    /// `aggregation` (then `chol` is `None`, and the projected Hessian's values live in the
    /// cycle between refreshes, [`AggregationPreconditioner::take_values`]).
    pub fn new(
        chol: Option<Cholesky>,
        aggregation: Option<AggregationPreconditioner>,
        blocks: BlockHessian,
        nnz: usize,
    ) -> Self {
        let (blocks_exact, projected) = match chol {
            Some(_) => (blocks.clone(), vec![0.0; nnz]),
            None => (
                BlockHessian::unallocated(blocks.pattern_arc().clone()),
                Vec::new(),
            ),
        };
        Self {
            chol,
            double: None,
            use_double: false,
            blocks_exact,
            blocks,
            exact: vec![0.0; nnz],
            projected,
            aggregation,
            points: Vec::new(),
            factored_at: None,
            reduced: Default::default(),
        }
    }

    /// Allocates the buffer of the projected Hessian's values, or takes it back from the
    /// aggregation cycle when it holds them (see [`Self::new`]).
    pub fn ensure_projected(&mut self) {
        if self.projected.is_empty() {
            self.projected = match self.aggregation.as_mut() {
                Some(agg) => agg.take_values(),
                None => vec![0.0; self.exact.len()],
            };
        }
    }

    /// The factor the current solve uses; an error when the aggregation cycle preconditions.
    pub fn factor(&mut self) -> Result<&mut Cholesky, SolveError> {
        Ok(self.parts()?.0)
    }

    /// The factor the current solve uses, beside the projected and exact Hessian values.
    pub fn parts(&mut self) -> Result<(&mut Cholesky, &mut Vec<f64>, &Vec<f64>), SolveError> {
        let chol = match (&mut self.double, self.use_double, &mut self.chol) {
            (Some(d), true, _) => d,
            (_, _, Some(c)) => c,
            (_, _, None) => return Err(no_factor()),
        };
        Ok((chol, &mut self.projected, &self.exact))
    }

    /// The rig's factor (not the double-precision fallback).
    pub fn rig_factor(&self) -> Result<&Cholesky, SolveError> {
        self.chol.as_ref().ok_or_else(no_factor)
    }
}

/// The error of a factor asked for where the aggregation cycle preconditions.
fn no_factor() -> SolveError {
    SolveError::Backend("internal: no fine factor where the aggregation cycle preconditions".into())
}
