//! [`FrozenFactor`]: a read-only copy of a [`Cholesky`] factor that solvers sharing its
//! symbolic analysis solve with, on any thread.

use super::{solve_one_stored, Aligned, Cholesky, Precision, SymbolicCholesky};
use crate::sparse::SolveError;
use faer::dyn_stack::MemStack;
use std::sync::Arc;

/// A read-only copy of a [`Cholesky`] factor ([`Cholesky::freeze`]): `Send + Sync`, shared
/// by the threads that precondition with it through [`Cholesky::solve_one_with`].
pub struct FrozenFactor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    precision: Precision,
    l_values: Aligned<f64>,
    l_single: Aligned<f32>,
}

impl FrozenFactor {
    /// The factor's arithmetic.
    pub fn precision(&self) -> Precision {
        self.precision
    }
    /// Bytes of the stored factor.
    pub fn bytes(&self) -> usize {
        8 * self.l_values.len + 4 * self.l_single.len
    }
}

impl std::fmt::Debug for FrozenFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrozenFactor")
            .field("precision", &self.precision)
            .field("bytes", &self.bytes())
            .finish()
    }
}

impl Cholesky {
    /// A read-only copy of the current factor, to precondition solves on other threads
    /// through [`solve_one_with`](Self::solve_one_with) of any solver sharing this one's
    /// symbolic analysis. `Err` before a successful factorization or without memory.
    pub fn freeze(&self) -> Result<FrozenFactor, SolveError> {
        if !self.factored {
            return Err(SolveError::Backend(
                "freeze called before a successful factorization".into(),
            ));
        }
        let oom = || SolveError::Backend("out of memory for a frozen factor".into());
        let mut l_values = Aligned::new(self.l_values.len).ok_or_else(oom)?;
        l_values
            .as_mut_slice()
            .copy_from_slice(self.l_values.as_slice());
        let mut l_single = Aligned::new(self.l_single.len).ok_or_else(oom)?;
        l_single
            .as_mut_slice()
            .copy_from_slice(self.l_single.as_slice());
        Ok(FrozenFactor {
            symbolic: self.symbolic.clone(),
            precision: self.precision,
            l_values,
            l_single,
        })
    }

    /// Solves $A x = b$ in place for one right-hand side with the frozen factor `f` (of a
    /// solver sharing this one's symbolic analysis, in its precision) and this solver's
    /// buffers, with no allocation. This solver's own factor is untouched; it need not be
    /// factored.
    pub fn solve_one_with(&mut self, f: &FrozenFactor, rhs: &mut [f64]) -> Result<(), SolveError> {
        if !Arc::ptr_eq(&self.symbolic, &f.symbolic) {
            return Err(SolveError::Backend(
                "the frozen factor belongs to another symbolic analysis".into(),
            ));
        }
        self.check_values(rhs, 1)?;
        if f.precision != self.precision {
            return Err(SolveError::Backend(
                "the frozen factor's precision differs from the solver's".into(),
            ));
        }
        let stack = MemStack::new(&mut self.solve_scratch);
        let factor = (f.l_single.as_slice(), f.l_values.as_slice());
        let work = (
            self.rhs_single.as_mut_slice(),
            self.rhs_scratch.as_mut_slice(),
        );
        solve_one_stored(&f.symbolic, f.precision, factor, work, rhs, stack);
        Ok(())
    }
}
