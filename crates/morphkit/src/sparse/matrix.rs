//! General compressed-column sparse matrices assembled from triplets.

use super::SolveError;

/// A real `nrows × ncols` sparse matrix in compressed-column form with sorted row indices.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    nrows: usize,
    ncols: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl SparseMatrix {
    /// Assembles from `(row, col, value)` triplets; duplicates are summed.
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        triplets: &[(usize, usize, f64)],
    ) -> Result<Self, SolveError> {
        let mut count = vec![0usize; ncols + 1];
        for &(r, c, v) in triplets {
            if r >= nrows {
                return Err(SolveError::Dimension {
                    what: "triplet row",
                    expected: nrows,
                    found: r,
                });
            }
            if c >= ncols {
                return Err(SolveError::Dimension {
                    what: "triplet column",
                    expected: ncols,
                    found: c,
                });
            }
            if !v.is_finite() {
                return Err(SolveError::NonFinite {
                    what: "triplet value",
                });
            }
            count[c + 1] += 1;
        }
        for c in 0..ncols {
            count[c + 1] += count[c];
        }
        let mut next = count.clone();
        let mut rows = vec![0usize; triplets.len()];
        let mut vals = vec![0f64; triplets.len()];
        for &(r, c, v) in triplets {
            rows[next[c]] = r;
            vals[next[c]] = v;
            next[c] += 1;
        }
        // Sort each column and sum duplicates.
        let mut col_ptr = Vec::with_capacity(ncols + 1);
        let mut row_idx = Vec::with_capacity(triplets.len());
        let mut values = Vec::with_capacity(triplets.len());
        col_ptr.push(0);
        let mut buf: Vec<(usize, f64)> = Vec::new();
        for c in 0..ncols {
            buf.clear();
            buf.extend((count[c]..count[c + 1]).map(|k| (rows[k], vals[k])));
            buf.sort_unstable_by_key(|e| e.0);
            for &(r, v) in &buf {
                if row_idx.len() > col_ptr[c] && *row_idx.last().unwrap() == r {
                    *values.last_mut().unwrap() += v;
                } else {
                    row_idx.push(r);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Ok(Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }
    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }
    /// Entries `(row, value)` of column `c`.
    pub fn col(&self, c: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        (self.col_ptr[c]..self.col_ptr[c + 1]).map(move |k| (self.row_idx[k], self.values[k]))
    }
    /// The entry at `(r, c)`, zero when not stored.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let rows = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
        rows.binary_search(&r)
            .map(|k| self.values[self.col_ptr[c] + k])
            .unwrap_or(0.0)
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        debug_assert_eq!(x.len(), self.ncols);
        let mut y = vec![0.0; self.nrows];
        for (c, &xc) in x.iter().enumerate() {
            if xc != 0.0 {
                for (r, v) in self.col(c) {
                    y[r] += v * xc;
                }
            }
        }
        y
    }

    /// `y = Aᵀ x`.
    pub fn tr_mul_vec(&self, x: &[f64]) -> Vec<f64> {
        debug_assert_eq!(x.len(), self.nrows);
        (0..self.ncols)
            .map(|c| self.col(c).map(|(r, v)| v * x[r]).sum())
            .collect()
    }

    /// The transpose, `ncols × nrows`.
    pub fn transpose(&self) -> SparseMatrix {
        let t: Vec<(usize, usize, f64)> = (0..self.ncols)
            .flat_map(|c| self.col(c).map(move |(r, v)| (c, r, v)))
            .collect();
        SparseMatrix::from_triplets(self.ncols, self.nrows, &t)
            .expect("transpose of a valid matrix")
    }

    /// Lower-triangle triplets `(i, j, v)`, `i ≥ j`, of the normal matrix $A^\top A$
    /// (`ncols × ncols`). Duplicates are left for the consumer to sum.
    pub fn normal_lower_triplets(&self) -> Vec<(usize, usize, f64)> {
        let at = self.transpose(); // columns of Aᵀ are rows of A
        let mut out = Vec::new();
        for r in 0..at.ncols() {
            let row: Vec<(usize, f64)> = at.col(r).collect();
            for &(i, vi) in &row {
                for &(j, vj) in &row {
                    if i >= j {
                        out.push((i, j, vi * vj));
                    }
                }
            }
        }
        out
    }

    /// Dense copy, row-major, for tests and tiny systems.
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.ncols]; self.nrows];
        for c in 0..self.ncols {
            for (r, v) in self.col(c) {
                d[r][c] += v;
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_are_summed_and_products_agree() {
        let a = SparseMatrix::from_triplets(
            3,
            2,
            &[
                (0, 0, 1.0),
                (2, 1, 2.0),
                (0, 0, 3.0),
                (1, 1, -1.0),
                (2, 0, 5.0),
            ],
        )
        .unwrap();
        assert_eq!(a.nnz(), 4);
        assert_eq!(a.get(0, 0), 4.0);
        assert_eq!(a.mul_vec(&[1.0, 2.0]), vec![4.0, -2.0, 9.0]);
        assert_eq!(a.tr_mul_vec(&[1.0, 1.0, 1.0]), vec![9.0, 1.0]);
        let n = a.normal_lower_triplets();
        let ata = SparseMatrix::from_triplets(2, 2, &n).unwrap();
        // AᵀA = [[16+25, 10], [10, 1+4]] (lower triangle only)
        assert_eq!(ata.get(0, 0), 41.0);
        assert_eq!(ata.get(1, 0), 10.0);
        assert_eq!(ata.get(1, 1), 5.0);
        assert_eq!(ata.get(0, 1), 0.0);
    }

    #[test]
    fn bad_triplets_are_errors() {
        assert!(SparseMatrix::from_triplets(2, 2, &[(2, 0, 1.0)]).is_err());
        assert!(SparseMatrix::from_triplets(2, 2, &[(0, 0, f64::NAN)]).is_err());
    }
}
