//! The lower-triangle pattern of a symmetric matrix, with the value slot of every entry given
//! at construction (see the module docs of [`super`]).

use super::SolveError;
use faer::sparse::SymbolicSparseColMatRef;

/// The lower-triangle sparsity pattern of a symmetric `n × n` matrix, compressed by column,
/// row indices sorted. Values live outside, in a `Vec<f64>` with one slot per stored entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SymmetricPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl SymmetricPattern {
    /// Builds the pattern holding every `(i, j)` in `entries` (either triangle; `(i, j)` and
    /// `(j, i)` are the same entry) plus the full diagonal, and returns, for each input entry,
    /// the index of its value slot.
    pub fn new(n: usize, entries: &[(usize, usize)]) -> Result<(Self, Vec<usize>), SolveError> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (c, col) in cols.iter_mut().enumerate() {
            col.push(c);
        }
        for &(i, j) in entries {
            let (r, c) = if i >= j { (i, j) } else { (j, i) };
            if r >= n {
                return Err(SolveError::Dimension {
                    what: "pattern index",
                    expected: n,
                    found: r,
                });
            }
            cols[c].push(r);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for col in &mut cols {
            col.sort_unstable();
            col.dedup();
            row_idx.extend_from_slice(col);
            col_ptr.push(row_idx.len());
        }
        let pattern = Self {
            n,
            col_ptr,
            row_idx,
        };
        let slots = entries
            .iter()
            .map(|&(i, j)| pattern.slot(i, j).expect("entry is in the pattern"))
            .collect();
        Ok((pattern, slots))
    }

    /// Builds the pattern of lower-triangle triplets `(i, j, v)` (entries with `i < j` are
    /// mirrored) and the summed values.
    pub fn from_triplets(
        n: usize,
        triplets: &[(usize, usize, f64)],
    ) -> Result<(Self, Vec<f64>), SolveError> {
        let entries: Vec<(usize, usize)> = triplets.iter().map(|t| (t.0, t.1)).collect();
        let (p, slots) = Self::new(n, &entries)?;
        let mut values = vec![0.0; p.nnz()];
        for (t, s) in triplets.iter().zip(slots) {
            values[s] += t.2;
        }
        Ok((p, values))
    }

    /// Column pointers and row indices (lower triangle, rows sorted, diagonal first).
    pub(crate) fn columns(&self) -> (&[usize], &[usize]) {
        (&self.col_ptr, &self.row_idx)
    }
    /// Matrix size `n`.
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of stored (lower-triangle) entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    /// Value slot of entry `(i, j)` (either triangle), if stored.
    pub fn slot(&self, i: usize, j: usize) -> Option<usize> {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if c >= self.n {
            return None;
        }
        let rows = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
        rows.binary_search(&r).ok().map(|k| self.col_ptr[c] + k)
    }
    /// Value slot of diagonal entry `i` (always stored).
    pub fn diag_slot(&self, i: usize) -> usize {
        self.col_ptr[i]
    }

    /// `y = A x` for the symmetric matrix with these `values`.
    pub fn mul_vec(&self, values: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        self.mul_vec_into(values, x, &mut y);
        y
    }

    /// `y = A x` into a caller's buffer (length `n`).
    pub fn mul_vec_into(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.n {
            // Column c holds its diagonal first, then rows below it (sorted): the column adds
            // A_rc x_c to y_r and, by symmetry, A_rc x_r to y_c (summed here, added once).
            let (start, end) = (self.col_ptr[c], self.col_ptr[c + 1]);
            let xc = x[c];
            let mut acc = values[start] * xc;
            for (&r, &v) in self.row_idx[start + 1..end]
                .iter()
                .zip(&values[start + 1..end])
            {
                y[r] += v * xc;
                acc += v * x[r];
            }
            y[c] += acc;
        }
    }

    /// `Y = A X` for `m` vectors at once, each of `X` (`n × m`) and `Y` stored by rows (`m`
    /// consecutive values per row): one pass over the matrix instead of `m`.
    pub fn mul_rows_into(&self, values: &[f64], m: usize, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        let mut acc = vec![0.0; m];
        for c in 0..self.n {
            let (start, end) = (self.col_ptr[c], self.col_ptr[c + 1]);
            let xc = &x[m * c..m * c + m];
            let diagonal = values[start];
            acc.iter_mut().zip(xc).for_each(|(a, v)| *a = diagonal * v);
            for (&r, &v) in self.row_idx[start + 1..end]
                .iter()
                .zip(&values[start + 1..end])
            {
                let xr = &x[m * r..m * r + m];
                acc.iter_mut().zip(xr).for_each(|(a, x)| *a += v * x);
                y[m * r..m * r + m]
                    .iter_mut()
                    .zip(xc)
                    .for_each(|(o, x)| *o += v * x);
            }
            y[m * c..m * c + m]
                .iter_mut()
                .zip(&acc)
                .for_each(|(o, a)| *o += a);
        }
    }

    /// The pattern as faer's symbolic matrix (lower triangle).
    pub(super) fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

#[cfg(test)]
mod tests {
    use super::SymmetricPattern;

    #[test]
    fn rows_product_is_each_vectors_product() {
        // A 7×7 pattern with scattered off-diagonal entries, values and 3 vectors made up.
        let entries = [(1, 0), (3, 0), (6, 2), (4, 3), (5, 1), (6, 5), (2, 1)];
        let (pattern, _) = SymmetricPattern::new(7, &entries).unwrap();
        let values: Vec<f64> = (0..pattern.nnz()).map(|k| 1.0 + 0.37 * k as f64).collect();
        let m = 3;
        let x: Vec<f64> = (0..7 * m).map(|k| ((k * 7 % 11) as f64) - 4.5).collect();
        let mut rows = vec![f64::NAN; 7 * m];
        pattern.mul_rows_into(&values, m, &x, &mut rows);
        for j in 0..m {
            let column: Vec<f64> = (0..7).map(|i| x[m * i + j]).collect();
            let single = pattern.mul_vec(&values, &column);
            for i in 0..7 {
                assert!((rows[m * i + j] - single[i]).abs() <= 1e-12 * single[i].abs().max(1.0));
            }
        }
        // Not the identity: some product differs from its input.
        assert!(rows.iter().zip(&x).any(|(a, b)| (a - b).abs() > 1.0));
    }
}
