//! Symmetric positive-definite solves with the symbolic analysis computed once per pattern.

use super::{SolveError, SymmetricPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError as DenseLltError;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};
use std::sync::Arc;

#[path = "cholesky_frozen.rs"]
mod frozen;
pub use frozen::FrozenFactor;
#[path = "cholesky_sizes.rs"]
mod sizes;
use sizes::symbolic_flops;

/// A zeroed buffer whose first element is 64-byte aligned, whatever the allocator returns.
/// faer's SIMD kernels take different head/tail paths for different alignments, and so round
/// differently: with every buffer aligned the same way, a factorization and a solve give the
/// same bits in every process, thread and allocation state.
#[derive(Debug)]
struct Aligned<T> {
    storage: Vec<T>,
    offset: usize,
    len: usize,
}

impl<T: Copy + Default> Aligned<T> {
    fn new(len: usize) -> Option<Self> {
        let size = std::mem::size_of::<T>();
        let pad = 64 / size;
        let mut storage = Vec::new();
        storage.try_reserve_exact(len + pad).ok()?;
        storage.resize(len + pad, T::default());
        let addr = storage.as_ptr() as usize;
        let offset = ((64 - addr % 64) % 64) / size;
        Some(Self {
            storage,
            offset,
            len,
        })
    }
    fn empty() -> Self {
        Self {
            storage: Vec::new(),
            offset: 0,
            len: 0,
        }
    }
    fn as_slice(&self) -> &[T] {
        &self.storage[self.offset..self.offset + self.len]
    }
    fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.storage[self.offset..self.offset + self.len]
    }
}

/// Arithmetic of the stored factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Precision {
    /// `f64` factor: solves accurate to the matrix's conditioning. The default.
    #[default]
    Double,
    /// `f32` factor of the `f64` matrix, with `f64` right-hand sides: half the memory and
    /// about twice the factorization speed, for uses where the factor only preconditions an
    /// `f64` iteration (conjugate gradients), whose answer it does not change.
    Single,
}

/// Fill-reducing ordering for the symbolic analysis.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Ordering {
    /// Approximate minimum degree (faer's AMD). The default, and good for surface meshes.
    #[default]
    Amd,
    /// No reordering: factor in the given order.
    Identity,
    /// A caller-supplied permutation: `perm[k]` is the original index of the `k`-th pivot
    /// (a nested-dissection ordering from METIS, say).
    Custom(Vec<usize>),
}

/// Sparse Cholesky $A = L L^\top$ of a symmetric positive-definite matrix whose pattern is a
/// [`SymmetricPattern`]. [`Cholesky::analyze`] runs the symbolic phase once;
/// [`Cholesky::factorize`] may then be called any number of times with new values of the same
/// pattern, and [`Cholesky::solve_in_place`] solves for any number of right-hand sides.
pub struct Cholesky {
    pattern: Arc<SymmetricPattern>,
    symbolic: Arc<SymbolicCholesky<usize>>,
    precision: Precision,
    /// The factor ([`Precision::Double`]; empty otherwise).
    l_values: Aligned<f64>,
    /// The factor ([`Precision::Single`]; empty otherwise).
    l_single: Aligned<f32>,
    /// The matrix values rounded to `f32` ([`Precision::Single`]; empty otherwise).
    a_single: Vec<f32>,
    /// Right-hand side of [`Cholesky::solve_one`], copied here so that its alignment is fixed.
    rhs_scratch: Aligned<f64>,
    rhs_single: Aligned<f32>,
    factor_scratch: MemBuffer,
    /// Scratch of single right-hand-side solves ([`Cholesky::solve_one`]).
    solve_scratch: MemBuffer,
    /// Whether the numeric buffers above exist (`false`: a symbolic analysis only, see
    /// [`Cholesky::analyze_cheapest_symbolic`]).
    numeric: bool,
    factored: bool,
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("n", &self.pattern.n())
            .field("factor_nnz", &self.factor_nnz())
            .field("precision", &self.precision)
            .finish()
    }
}

impl Cholesky {
    /// Symbolic analysis of `pattern`.
    pub fn analyze(pattern: SymmetricPattern, ordering: Ordering) -> Result<Self, SolveError> {
        Self::analyze_with(pattern, ordering, Precision::Double)
    }

    /// Symbolic analysis of `pattern`, for numeric factors of the given precision.
    pub fn analyze_with(
        pattern: SymmetricPattern,
        ordering: Ordering,
        precision: Precision,
    ) -> Result<Self, SolveError> {
        Self::analyze_shared(Arc::new(pattern), ordering, precision)
    }

    /// Like [`analyze_with`](Self::analyze_with) for a pattern its owner keeps using too
    /// (shared, not copied).
    pub fn analyze_shared(
        pattern: Arc<SymmetricPattern>,
        ordering: Ordering,
        precision: Precision,
    ) -> Result<Self, SolveError> {
        let symbolic = Self::analyze_symbolic(&pattern, ordering)?;
        Self::with_buffers(pattern, Arc::new(symbolic), precision)
    }

    /// Like [`analyze_shared`](Self::analyze_shared) with the cheapest of `orderings`: the one
    /// whose factorization takes the fewest multiply-adds ([`Self::factor_flops`]; the first
    /// of equals) among those whose factor has no more entries than the first ordering's. The
    /// first ordering is the memory reference: a caller that estimated its memory with it
    /// (as the physical blend's `--max-memory` check does) is never handed a larger factor.
    /// Returns the solver and the index of the ordering. Only the chosen one gets numeric
    /// buffers.
    pub fn analyze_cheapest(
        pattern: Arc<SymmetricPattern>,
        orderings: &[Ordering],
        precision: Precision,
    ) -> Result<(Self, usize), SolveError> {
        let (symbolic, k) = Self::analyze_cheapest_symbolic(pattern, orderings, precision)?;
        Ok((symbolic.with_numeric()?, k))
    }

    /// Like [`analyze_cheapest`](Self::analyze_cheapest), without numeric buffers: the
    /// analysis's counts ([`Self::factor_nnz`], [`Self::factor_flops`],
    /// [`Self::factor_bytes`]) before deciding whether to factor at all. Give it buffers with
    /// [`Self::with_numeric`]; until then it cannot factor or solve.
    pub fn analyze_cheapest_symbolic(
        pattern: Arc<SymmetricPattern>,
        orderings: &[Ordering],
        precision: Precision,
    ) -> Result<(Self, usize), SolveError> {
        let mut best: Option<(SymbolicCholesky<usize>, f64, usize)> = None;
        let mut reference_entries = usize::MAX;
        for (k, ordering) in orderings.iter().enumerate() {
            let symbolic = Self::analyze_symbolic(&pattern, ordering.clone())?;
            let flops = symbolic_flops(&symbolic);
            let entries = symbolic.len_val();
            if k == 0 {
                reference_entries = entries;
            }
            if entries <= reference_entries && best.as_ref().is_none_or(|b| flops < b.1) {
                best = Some((symbolic, flops, k));
            }
        }
        let (symbolic, _, k) = best
            .ok_or_else(|| SolveError::Backend("no ordering to analyse the pattern with".into()))?;
        Ok((
            Self::symbolic_only(pattern, Arc::new(symbolic), precision),
            k,
        ))
    }

    /// Symbolic analysis of `pattern` without numeric buffers (see
    /// [`analyze_cheapest_symbolic`](Self::analyze_cheapest_symbolic)).
    pub fn analyze_symbolic_only(
        pattern: Arc<SymmetricPattern>,
        ordering: Ordering,
        precision: Precision,
    ) -> Result<Self, SolveError> {
        let symbolic = Self::analyze_symbolic(&pattern, ordering)?;
        Ok(Self::symbolic_only(pattern, Arc::new(symbolic), precision))
    }

    /// This analysis with numeric buffers (itself if it has them).
    pub fn with_numeric(self) -> Result<Self, SolveError> {
        if self.numeric {
            return Ok(self);
        }
        Self::with_buffers(self.pattern, self.symbolic, self.precision)
    }

    /// Whether this solver has numeric buffers (can factor and solve).
    pub fn is_numeric(&self) -> bool {
        self.numeric
    }

    fn symbolic_only(
        pattern: Arc<SymmetricPattern>,
        symbolic: Arc<SymbolicCholesky<usize>>,
        precision: Precision,
    ) -> Self {
        let empty = || MemBuffer::new(faer::dyn_stack::StackReq::EMPTY);
        Self {
            pattern,
            symbolic,
            precision,
            l_values: Aligned::empty(),
            l_single: Aligned::empty(),
            a_single: Vec::new(),
            rhs_scratch: Aligned::empty(),
            rhs_single: Aligned::empty(),
            factor_scratch: empty(),
            solve_scratch: empty(),
            numeric: false,
            factored: false,
        }
    }

    fn analyze_symbolic(
        pattern: &SymmetricPattern,
        ordering: Ordering,
    ) -> Result<SymbolicCholesky<usize>, SolveError> {
        let n = pattern.n();
        let (fwd, inv);
        // faer 0.24's `SymmetricOrdering::Identity` analyses a lower-triangle input as if it
        // were upper; an explicit identity permutation takes the well-trodden path instead.
        let identity: Vec<usize>;
        let ordering_perm = match &ordering {
            Ordering::Identity => {
                identity = (0..n).collect();
                Some(&identity)
            }
            Ordering::Custom(p) => Some(p),
            Ordering::Amd => None,
        };
        let ord = match ordering_perm {
            None => SymmetricOrdering::Amd,
            Some(p) => {
                if p.len() != n {
                    return Err(SolveError::Dimension {
                        what: "ordering",
                        expected: n,
                        found: p.len(),
                    });
                }
                let mut seen = vec![usize::MAX; n];
                for (k, &i) in p.iter().enumerate() {
                    if i >= n || seen[i] != usize::MAX {
                        return Err(SolveError::Backend(format!(
                            "ordering is not a permutation (entry {k} = {i})"
                        )));
                    }
                    seen[i] = k;
                }
                fwd = p.clone();
                inv = seen;
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, n))
            }
        };
        factorize_symbolic_cholesky(pattern.symbolic(), Side::Lower, ord, Default::default())
            .map_err(|e| SolveError::Backend(format!("{e:?}")))
    }

    fn with_buffers(
        pattern: Arc<SymmetricPattern>,
        symbolic: Arc<SymbolicCholesky<usize>>,
        precision: Precision,
    ) -> Result<Self, SolveError> {
        let oom = |_| SolveError::Backend("out of memory".into());
        let single = precision == Precision::Single;
        let (n_double, n_single) = if single {
            (0, symbolic.len_val())
        } else {
            (symbolic.len_val(), 0)
        };
        let factor_oom = || SolveError::Backend("out of memory for the factor".into());
        let l_values = Aligned::new(n_double).ok_or_else(factor_oom)?;
        let l_single = Aligned::new(n_single).ok_or_else(factor_oom)?;
        let mut a_single = Vec::new();
        if single {
            a_single
                .try_reserve_exact(pattern.nnz())
                .map_err(|_| factor_oom())?;
            a_single.resize(pattern.nnz(), 0.0);
        }
        let rhs_scratch =
            Aligned::new(pattern.n()).ok_or_else(|| SolveError::Backend("out of memory".into()))?;
        let rhs_single = Aligned::new(if single { pattern.n() } else { 0 })
            .ok_or_else(|| SolveError::Backend("out of memory".into()))?;
        let (factor_req, solve_req) = if single {
            (
                symbolic.factorize_numeric_llt_scratch::<f32>(Par::Seq, Default::default()),
                symbolic.solve_in_place_scratch::<f32>(1, Par::Seq),
            )
        } else {
            (
                symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
            )
        };
        let factor_scratch = MemBuffer::try_new(factor_req).map_err(oom)?;
        let solve_scratch = MemBuffer::try_new(solve_req).map_err(oom)?;
        Ok(Self {
            pattern,
            symbolic,
            precision,
            l_values,
            l_single,
            a_single,
            rhs_scratch,
            rhs_single,
            factor_scratch,
            solve_scratch,
            numeric: true,
            factored: false,
        })
    }

    /// Number of stored entries the factor of `pattern` would have under `ordering`, from the
    /// symbolic analysis alone (no numeric storage is allocated): a memory estimate.
    pub fn predicted_factor_nnz(
        pattern: &SymmetricPattern,
        ordering: Ordering,
    ) -> Result<usize, SolveError> {
        let analysed = Self::analyze_symbolic(pattern, ordering)?;
        Ok(analysed.len_val())
    }

    /// A second solver for the same pattern sharing this one's symbolic analysis, with buffers
    /// of its own (one per thread); without buffers if this one has none.
    pub fn share_symbolic(&self) -> Result<Self, SolveError> {
        if !self.numeric {
            let (p, s) = (self.pattern.clone(), self.symbolic.clone());
            return Ok(Self::symbolic_only(p, s, self.precision));
        }
        self.share_symbolic_with(self.precision)
    }

    /// Like [`share_symbolic`](Self::share_symbolic), with numeric buffers of `precision`.
    pub fn share_symbolic_with(&self, precision: Precision) -> Result<Self, SolveError> {
        Self::with_buffers(self.pattern.clone(), self.symbolic.clone(), precision)
    }

    /// Solves $A x = b$ in place for one right-hand side, with no allocation.
    pub fn solve_one(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        self.check_rhs(rhs, 1)?;
        let stack = MemStack::new(&mut self.solve_scratch);
        let (single, double) = (self.l_single.as_slice(), self.l_values.as_slice());
        let work = (
            self.rhs_single.as_mut_slice(),
            self.rhs_scratch.as_mut_slice(),
        );
        solve_one_stored(
            &self.symbolic,
            self.precision,
            (single, double),
            work,
            rhs,
            stack,
        );
        Ok(())
    }

    fn check_rhs(&self, rhs: &[f64], ncols: usize) -> Result<(), SolveError> {
        if !self.factored {
            return Err(SolveError::Backend(
                "solve called before a successful factorization".into(),
            ));
        }
        self.check_values(rhs, ncols)
    }

    /// `ncols` right-hand sides of this solver's size, all finite.
    fn check_values(&self, rhs: &[f64], ncols: usize) -> Result<(), SolveError> {
        let n = self.pattern.n();
        if rhs.len() != n * ncols {
            return Err(SolveError::Dimension {
                what: "right-hand side",
                expected: n * ncols,
                found: rhs.len(),
            });
        }
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "right-hand side",
            });
        }
        Ok(())
    }

    /// The pattern this solver was analysed for.
    pub fn pattern(&self) -> &SymmetricPattern {
        &self.pattern
    }

    /// The arithmetic of the stored factor.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Numeric factorization of the matrix with the given lower-triangle `values` (one per
    /// pattern slot). Reuses the symbolic analysis and all buffers.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolveError> {
        self.factored = false;
        if !self.numeric {
            return Err(SolveError::Backend(
                "a symbolic analysis without numeric buffers cannot factor".into(),
            ));
        }
        if values.len() != self.pattern.nnz() {
            return Err(SolveError::Dimension {
                what: "values",
                expected: self.pattern.nnz(),
                found: values.len(),
            });
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "matrix values",
            });
        }
        let stack = MemStack::new(&mut self.factor_scratch);
        let a = self.pattern.symbolic();
        let res = match self.precision {
            Precision::Single => {
                for (a, v) in self.a_single.iter_mut().zip(values) {
                    *a = *v as f32;
                }
                let l = self.l_single.as_mut_slice();
                factor_stored(&self.symbolic, a, &self.a_single, l, stack)
            }
            Precision::Double => factor_stored(
                &self.symbolic,
                a,
                values,
                self.l_values.as_mut_slice(),
                stack,
            ),
        };
        match res {
            Ok(_) => {
                self.factored = true;
                Ok(())
            }
            Err(DenseLltError::NonPositivePivot { index }) => {
                Err(SolveError::NotPositiveDefinite {
                    column: index,
                    size: self.pattern.n(),
                })
            }
        }
    }

    /// Solves $A X = B$ in place for `ncols` right-hand sides stored column-major in `rhs`
    /// (`n × ncols`).
    pub fn solve_in_place(&self, rhs: &mut [f64], ncols: usize) -> Result<(), SolveError> {
        self.check_rhs(rhs, ncols)?;
        let oom = || SolveError::Backend("out of memory".into());
        match self.precision {
            Precision::Single => {
                let req = self.symbolic.solve_in_place_scratch::<f32>(ncols, Par::Seq);
                let mut buf = MemBuffer::try_new(req).map_err(|_| oom())?;
                let mut work = Aligned::<f32>::new(rhs.len()).ok_or_else(oom)?;
                let l = self.l_single.as_slice();
                let stack = MemStack::new(&mut buf);
                solve_stored(&self.symbolic, l, work.as_mut_slice(), rhs, ncols, stack);
            }
            Precision::Double => {
                let req = self.symbolic.solve_in_place_scratch::<f64>(ncols, Par::Seq);
                let mut buf = MemBuffer::try_new(req).map_err(|_| oom())?;
                let mut work = Aligned::<f64>::new(rhs.len()).ok_or_else(oom)?;
                let l = self.l_values.as_slice();
                let stack = MemStack::new(&mut buf);
                solve_stored(&self.symbolic, l, work.as_mut_slice(), rhs, ncols, stack);
            }
        }
        Ok(())
    }

    /// Solves $A x = b$ for one right-hand side.
    pub fn solve(&self, b: &[f64]) -> Result<Vec<f64>, SolveError> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x, 1)?;
        Ok(x)
    }
}

/// A factor's arithmetic: `f64` right-hand sides are rounded into it and back.
trait Stored: faer::traits::ComplexField + Copy {
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
}

impl Stored for f32 {
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Stored for f64 {
    fn from_f64(x: f64) -> Self {
        x
    }
    fn to_f64(self) -> f64 {
        self
    }
}

/// Numeric factorization of the matrix `values` (pattern `a`) into `l`.
fn factor_stored<T: Stored>(
    symbolic: &SymbolicCholesky<usize>,
    a: SymbolicSparseColMatRef<'_, usize>,
    values: &[T],
    l: &mut [T],
    stack: &mut MemStack,
) -> Result<(), DenseLltError> {
    let a = SparseColMatRef::new(a, values);
    symbolic
        .factorize_numeric_llt::<T>(
            l,
            a,
            Side::Lower,
            Default::default(),
            Par::Seq,
            stack,
            Spec::default(),
        )
        .map(|_| ())
}

/// Solves with the factor values `l` for the `ncols` right-hand sides in `rhs`, through the
/// (aligned) buffer `work` of the factor's arithmetic.
/// One right-hand side through the stored factor of `precision` (`factor`: its f32 and f64
/// values, one of them empty) with the work vector of the same precision.
fn solve_one_stored(
    symbolic: &SymbolicCholesky<usize>,
    precision: Precision,
    factor: (&[f32], &[f64]),
    work: (&mut [f32], &mut [f64]),
    rhs: &mut [f64],
    stack: &mut MemStack,
) {
    match precision {
        Precision::Single => solve_stored(symbolic, factor.0, work.0, rhs, 1, stack),
        Precision::Double => solve_stored(symbolic, factor.1, work.1, rhs, 1, stack),
    }
}

fn solve_stored<T: Stored>(
    symbolic: &SymbolicCholesky<usize>,
    l: &[T],
    work: &mut [T],
    rhs: &mut [f64],
    ncols: usize,
    stack: &mut MemStack,
) {
    for (w, r) in work.iter_mut().zip(rhs.iter()) {
        *w = T::from_f64(*r);
    }
    let n = rhs.len() / ncols.max(1);
    let mat = MatMut::from_column_major_slice_mut(work, n, ncols);
    LltRef::new(symbolic, l).solve_in_place_with_conj(Conj::No, mat, Par::Seq, stack);
    for (r, w) in rhs.iter_mut().zip(work.iter()) {
        *r = w.to_f64();
    }
}

#[cfg(test)]
#[path = "cholesky_tests.rs"]
pub(crate) mod tests;
