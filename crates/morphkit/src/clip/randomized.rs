//! Principal directions in blocks, from a randomized range finder, for clips too large for
//! the Gram matrix (Halko, Martinsson and Tropp 2011, "Finding structure with randomness",
//! algorithms 4.1 and 4.3: a random test matrix, one power iteration, then the SVD of the
//! small projected matrix).
//!
//! [`super::residual_basis_on`] asks for a block only when it has used the previous one, and
//! draws it from what the shapes chosen so far leave, so the work grows with the shapes the
//! tolerance needs (about `4 · F · 3V · BLOCK` operations a block) instead of with `F² · 3V`.
//! The test matrix is ±1 from a fixed-seed SplitMix64 stream and every sum runs in a fixed
//! order on one thread, so the same frames give the same shapes, bytes included, anywhere.

use faer::{Mat, Side};

/// Columns of the test matrix a block draws (the directions it yields plus oversampling).
const BLOCK: usize = 24;
/// Directions a block yields: the most accurate of its `BLOCK` (Halko et al. §4.2: an
/// oversampling of 5–10 makes the leading ones accurate).
pub(super) const YIELD: usize = 16;
/// Above this many operations for the Gram matrix route (`min² · max + min³` for `F` frames
/// and `3V` coordinates), directions come in blocks.
pub const EXACT_FLOPS: f64 = 4e10;

/// The Gram route's operation count for `frames` rows of `d` values.
pub fn exact_flops(frames: usize, d: usize) -> f64 {
    let (a, b) = (frames as f64, d as f64);
    let (small, large) = (a.min(b), a.max(b));
    small * small * large + small.powi(3)
}

/// The block route's operation count for `shapes` shapes of `frames` rows of `d` values.
pub fn block_flops(frames: usize, d: usize, shapes: usize) -> f64 {
    let blocks = shapes.div_ceil(YIELD).max(1) as f64;
    blocks * 4.0 * frames as f64 * d as f64 * BLOCK as f64
}

/// SplitMix64: a fixed stream of ±1.
pub(super) struct Signs(u64);

impl Signs {
    pub(super) fn new() -> Self {
        Signs(0x9E37_79B9_7F4A_7C15)
    }

    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        if z >> 63 == 0 {
            1.0
        } else {
            -1.0
        }
    }
}

/// `rows · m`: `F × k` for `F` rows of `d` values and `m` of `d × k` (row-major).
fn times(rows: &[Vec<f64>], m: &[f64], k: usize) -> Vec<Vec<f64>> {
    rows.iter()
        .map(|r| {
            let mut y = vec![0.0; k];
            for (i, &x) in r.iter().enumerate() {
                if x != 0.0 {
                    let mi = &m[i * k..(i + 1) * k];
                    for (yj, mj) in y.iter_mut().zip(mi) {
                        *yj += x * mj;
                    }
                }
            }
            y
        })
        .collect()
}

/// `rowsᵀ · y`: `d × k` (row-major) for `F` rows of `d` values and `y` of `F × k`.
fn times_transposed(rows: &[Vec<f64>], y: &[Vec<f64>], d: usize, k: usize) -> Vec<f64> {
    let mut z = vec![0.0; d * k];
    for (r, yf) in rows.iter().zip(y) {
        for (i, &x) in r.iter().enumerate() {
            if x != 0.0 {
                for (zj, yj) in z[i * k..(i + 1) * k].iter_mut().zip(yf) {
                    *zj += x * yj;
                }
            }
        }
    }
    z
}

/// Orthonormal columns spanning the columns of `y` (`F × k`), by modified Gram–Schmidt twice;
/// columns that vanish (rank below `k`) are dropped. Returned as columns.
fn orthonormal_columns(y: &[Vec<f64>], k: usize) -> Vec<Vec<f64>> {
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(k);
    let largest = (0..k)
        .map(|j| y.iter().map(|r| r[j] * r[j]).sum::<f64>())
        .fold(0.0, f64::max);
    for j in 0..k {
        let mut c: Vec<f64> = y.iter().map(|r| r[j]).collect();
        for _ in 0..2 {
            for p in &q {
                let a: f64 = p.iter().zip(&c).map(|(x, y)| x * y).sum();
                for (ci, pi) in c.iter_mut().zip(p) {
                    *ci -= a * pi;
                }
            }
        }
        let n2: f64 = c.iter().map(|x| x * x).sum();
        if n2 > largest * 1e-24 && n2 > 0.0 {
            let n = n2.sqrt();
            q.push(c.into_iter().map(|x| x / n).collect());
        }
    }
    q
}

/// Up to [`YIELD`] approximate principal directions of the rows of `rest` (`F` rows of `d`
/// values), unnormalised, in order of decreasing singular value; none when the rows vanish.
pub(super) fn block_directions(rest: &[Vec<f64>], d: usize, signs: &mut Signs) -> Vec<Vec<f64>> {
    let k = BLOCK.min(rest.len()).min(d);
    let omega: Vec<f64> = (0..d * k).map(|_| signs.next()).collect();
    let y = times(rest, &omega, k);
    // One power iteration: the range of (R Rᵀ) R Ω, orthonormalised between the products.
    let q = orthonormal_columns(&y, k);
    if q.is_empty() {
        return Vec::new();
    }
    let as_rows = |q: &[Vec<f64>]| -> Vec<Vec<f64>> {
        (0..rest.len())
            .map(|f| q.iter().map(|c| c[f]).collect())
            .collect()
    };
    let z = times_transposed(rest, &as_rows(&q), d, q.len());
    let y = times(rest, &z, q.len());
    let q = orthonormal_columns(&y, q.len());
    if q.is_empty() {
        return Vec::new();
    }
    // B = Qᵀ R (k × d, row-major) and the eigenvectors of B Bᵀ.
    let k = q.len();
    let bt = times_transposed(rest, &as_rows(&q), d, k);
    let gram = Mat::<f64>::from_fn(k, k, |a, b| {
        (0..d).map(|i| bt[i * k + a] * bt[i * k + b]).sum()
    });
    let Ok(eig) = gram.self_adjoint_eigen(Side::Lower) else {
        return Vec::new();
    };
    let s = eig.S().column_vector();
    let u = eig.U();
    let largest = (0..k).map(|i| s[i]).fold(0.0, f64::max);
    let floor = largest * 1e-24 + f64::MIN_POSITIVE;
    (0..k)
        .rev()
        .filter(|&i| s[i] > floor)
        .take(YIELD)
        .map(|i| {
            (0..d)
                .map(|c| (0..k).map(|a| bt[c * k + a] * u[(a, i)]).sum())
                .collect()
        })
        .collect()
}
