//! A thin layer over faer's sparse Cholesky factorization.
//!
//! The layer keeps faer's split between the *symbolic* phase (fill-reducing ordering, elimination
//! tree, supernode structure: depends only on the sparsity pattern) and the *numeric* phase
//! (the values of $L$ in $A = L L^\top$). A [`SymmetricPattern`] fixes the pattern of a symmetric
//! matrix once; a [`Cholesky`] analyses it once and then refactorizes numerically as often as
//! the values change, with every buffer allocated up front. Everything runs with `Par::Seq`:
//! the callers (per-frame solves, Newton steps) are already the unit of parallelism.
//!
//! - [`SparseMatrix`]: a general compressed-column matrix assembled from triplets (duplicates
//!   summed), with products and the normal-equation matrix $A^\top A$.
//! - [`SymmetricPattern`]: lower-triangle pattern of a symmetric matrix plus, for each entry
//!   given at construction, the slot its value goes to, so hot loops assemble without sorting.
//! - [`Cholesky`]: symmetric positive-definite solver with symbolic reuse and multiple
//!   right-hand sides.
//! - [`Dirichlet`]: eliminates fixed unknowns, moving their columns to the right-hand side.
//! - [`AggregationLevels`] / [`AggregationPreconditioner`]: a two-level preconditioner for
//!   systems over point coordinates (rigid modes of point aggregates as the coarse space),
//!   for volumetric systems whose direct factor fills too much.

mod aggregation;
mod aggregation_cycle;
mod cholesky;
mod dirichlet;
mod matrix;
pub mod metis;
mod pattern;

pub use aggregation::{AggregationLevels, AggregationPreconditioner};
pub use cholesky::{Cholesky, FrozenFactor, Ordering, Precision};
pub use dirichlet::Dirichlet;
pub use matrix::SparseMatrix;
pub use pattern::SymmetricPattern;

/// Why a sparse solve failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SolveError {
    /// The matrix is not numerically positive definite (singular, or indefinite).
    #[error("the matrix is not positive definite (non-positive pivot at permuted column {column} of {size}); the system is singular or under-constrained")]
    NotPositiveDefinite {
        /// Permuted column of the failing pivot.
        column: usize,
        /// Matrix size.
        size: usize,
    },
    /// Values or right-hand sides contain NaN or infinity.
    #[error("non-finite value in {what}")]
    NonFinite {
        /// Which input had it.
        what: &'static str,
    },
    /// Sizes do not agree.
    #[error("size mismatch: {what} has {found}, expected {expected}")]
    Dimension {
        /// What was checked.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Found size.
        found: usize,
    },
    /// faer failed for another reason (out of memory, index overflow).
    #[error("sparse factorization failed: {0}")]
    Backend(String),
}
