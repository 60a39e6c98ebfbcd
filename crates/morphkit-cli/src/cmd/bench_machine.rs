//! The machine check that opens every `morphkit bench` run: the speed of the two kernels that
//! dominate a physical-blend frame, on a fixed problem, so that benchmark rows measured on
//! different days (or machines) can be compared.
//!
//! This project's 2-core machine has run the same binary at speeds up to 2.5× apart on
//! different days, with identical iteration counts. The check factorizes a fixed matrix in
//! single precision (the Newton preconditioner's arithmetic) and solves with the factor once,
//! each best of five, and reports the time and the rate. A bench row divided by the
//! factorization time is then a number of "machine units" that does not move with the
//! machine's phase. Reported only: no solver decision reads it.

use morphkit::sparse::{Cholesky, Ordering, Precision, SymmetricPattern};
use serde_json::json;
use std::sync::Arc;
use std::time::Instant;

/// Side of the check's grid: `SIDE³` unknowns (21 952).
const SIDE: usize = 28;
/// Timed repeats of each kernel; the fastest is kept.
const REPEATS: usize = 5;

/// The check's matrix: the 7-point Laplacian of a `SIDE³` grid plus the identity (symmetric
/// positive definite), as lower-triangle triplets.
fn grid_laplacian() -> (usize, Vec<(usize, usize, f64)>) {
    let idx = |x: usize, y: usize, z: usize| (z * SIDE + y) * SIDE + x;
    let mut t = Vec::with_capacity(4 * SIDE * SIDE * SIDE);
    for z in 0..SIDE {
        for y in 0..SIDE {
            for x in 0..SIDE {
                let i = idx(x, y, z);
                t.push((i, i, 7.0));
                if x > 0 {
                    t.push((i, idx(x - 1, y, z), -1.0));
                }
                if y > 0 {
                    t.push((i, idx(x, y - 1, z), -1.0));
                }
                if z > 0 {
                    t.push((i, idx(x, y, z - 1), -1.0));
                }
            }
        }
    }
    (SIDE * SIDE * SIDE, t)
}

/// Fastest of [`REPEATS`] runs of `f`, in seconds.
fn best_of(mut f: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let t = Instant::now();
        f()?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// Runs the check on this thread, prints one line and returns it for the report.
pub fn machine_check() -> anyhow::Result<serde_json::Value> {
    let (n, triplets) = grid_laplacian();
    let (pattern, values) = SymmetricPattern::from_triplets(n, &triplets)?;
    let pattern = Arc::new(pattern);
    let mut chol = Cholesky::analyze_shared(pattern.clone(), Ordering::Amd, Precision::Single)?;
    let flops = chol.factor_flops();
    let factor_s = best_of(|| Ok(chol.factorize(&values)?))?;
    let rhs: Vec<f64> = (0..n).map(|i| ((i % 7) as f64) - 3.0).collect();
    let mut x = rhs.clone();
    let solve_s = best_of(|| {
        x.copy_from_slice(&rhs);
        Ok(chol.solve_one(&mut x)?)
    })?;
    // A wrong factor would make the timings meaningless: check A x = b to the factor's
    // single precision.
    let ax = pattern.mul_vec(&values, &x);
    let residual = ax
        .iter()
        .zip(&rhs)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    anyhow::ensure!(
        residual <= 1e-3,
        "machine check: the factor of the check's grid solves with residual {residual:e}"
    );
    let gflops = flops / factor_s / 1e9;
    println!(
        "machine check: single-precision factorization of a {SIDE}³ grid Laplacian ({:.2} Gflop) {:.1} ms ({gflops:.1} Gflop/s), one solve {:.2} ms (best of {REPEATS}, one thread)",
        flops / 1e9,
        factor_s * 1e3,
        solve_s * 1e3
    );
    Ok(json!({
        "grid": SIDE, "unknowns": n, "factor_gflop": flops / 1e9,
        "factorization_ms": factor_s * 1e3, "gflop_per_s": gflops, "solve_ms": solve_s * 1e3,
        "repeats": REPEATS,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_check_factorizes_the_fixed_grid_and_reports_its_rate() {
        let (n, t) = grid_laplacian();
        assert_eq!(n, SIDE * SIDE * SIDE);
        // One diagonal entry per unknown and one per grid edge (3 · SIDE² · (SIDE − 1)).
        assert_eq!(t.len(), n + 3 * SIDE * SIDE * (SIDE - 1));
        let r = machine_check().unwrap();
        assert_eq!(r["unknowns"], n);
        let gflop = r["factor_gflop"].as_f64().unwrap();
        let ms = r["factorization_ms"].as_f64().unwrap();
        let rate = r["gflop_per_s"].as_f64().unwrap();
        assert!(gflop > 1.0 && ms > 0.0 && r["solve_ms"].as_f64().unwrap() > 0.0);
        assert!((rate - gflop / ms * 1e3).abs() <= 1e-9 * rate, "{r}");
    }
}
