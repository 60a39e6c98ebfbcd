//! In-betweens where a tolerance needs them (issue 56: "in-betweens at as many weights as a
//! tolerance needs"). A target's path that turns (a bend of 105°, a twist) is not piecewise
//! linear at the eighths: on cragl's cylinder its bend at 0.55 is 5.9e-3 of the diagonal from
//! the eighths' interpolation. So, after the regular in-betweens:
//!
//! 1. **Which segments to test.** Each segment `[w_k, w_{k+1}]` of a target's regular grid
//!    (from 0) is estimated from the samples it already has: a path `D(w)` that bends deviates
//!    from its chord at the segment's middle by about `h² |D''| / 8`, and the second difference
//!    `D_{k−1} − 2 D_k + D_{k+1}` is `h² D''`; a segment whose larger neighbouring second
//!    difference, over 8, passes a quarter of the tolerance is tested. Smooth targets (the ICT
//!    expressions, within 8.1e-5 at the eighths) cost no solve.
//! 2. **Testing** solves the target alone at the segment's middle (all tests of a round in one
//!    `solve_many`); where that equilibrium is farther than the tolerance from the
//!    interpolation, the middle becomes an in-between (its solve is the shape), and its two
//!    halves are tested in the next round, up to [`ROUNDS`] rounds (down to 1/64 from the
//!    eighths).
//! 3. **Budget.** At most `max_refined` in-betweens are added over all targets (the room a
//!    client leaves: WebGL2 plays 200 targets a mesh), the farthest first; ties by target and
//!    weight, so the result does not depend on threads.

use super::{add_scaled, hat, sub, BakeError, BakedTarget};
use crate::geom::max_distance;
use crate::mesh::Point;
use crate::springs::{PhysicalBlend, Weights};

/// Rounds of halving after the regular grid (the eighths: down to 1/64).
pub const ROUNDS: usize = 3;

/// `target`'s interpolated delta at `w` (`#V` of them).
fn interpolated(target: &BakedTarget, w: f64, nv: usize) -> Vec<Point> {
    let mut out = vec![[0.0; 3]; nv];
    for (k, f) in hat(&target.weights, w) {
        add_scaled(&mut out, f, &target.deltas[k]);
    }
    out
}

/// The segments of `target`'s regular grid (weights from 0) worth testing: see the module
/// documentation, step 1.
fn suspects(t: usize, target: &BakedTarget, tolerance: f64) -> Vec<(usize, f64, f64)> {
    let nv = target.deltas.first().map_or(0, Vec::len);
    let zero = vec![[0.0; 3]; nv];
    // Points 0 … m+1: the zero delta at 0, then the in-betweens and the target.
    let points: Vec<(f64, &Vec<Point>)> = std::iter::once((0.0, &zero))
        .chain(target.weights.iter().copied().zip(&target.deltas))
        .collect();
    let second = |k: usize| -> f64 {
        if k == 0 || k + 1 >= points.len() {
            return 0.0;
        }
        let (a, b, c) = (points[k - 1].1, points[k].1, points[k + 1].1);
        a.iter()
            .zip(b)
            .zip(c)
            .map(|((p, q), r)| {
                let d = [0, 1, 2].map(|i| p[i] - 2.0 * q[i] + r[i]);
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            })
            .fold(0.0, f64::max)
    };
    (0..points.len() - 1)
        .filter(|&k| second(k).max(second(k + 1)) / 8.0 > tolerance / 4.0)
        .map(|k| (t, points[k].0, points[k + 1].0))
        .collect()
}

/// Adds in-betweens to `targets` where their interpolation is farther than `tolerance` (a
/// distance) from the target's own equilibrium, at most `max_refined` in all: see the module
/// documentation. `base` is the rig's `#V` base positions. Returns the solves it made.
pub(super) fn refine(
    solver: &mut PhysicalBlend,
    targets: &mut [BakedTarget],
    base: &[Point],
    tolerance: f64,
    mut max_refined: usize,
    threads: usize,
) -> Result<usize, BakeError> {
    let n = targets.len();
    let nv = base.len();
    let mut tests: Vec<(usize, f64, f64)> = targets
        .iter()
        .enumerate()
        .flat_map(|(t, target)| suspects(t, target, tolerance))
        .collect();
    let mut solves = 0;
    for _ in 0..ROUNDS {
        if tests.is_empty() || max_refined == 0 {
            break;
        }
        let weights: Vec<Vec<f64>> = tests
            .iter()
            .map(|&(t, a, b)| {
                let mut w = vec![0.0; n];
                w[t] = 0.5 * (a + b);
                w
            })
            .collect();
        let as_weights: Vec<Weights> = weights.iter().map(|w| Weights::Delta(w.clone())).collect();
        let mut found: Vec<(f64, usize, Vec<Point>)> = Vec::new();
        for (k, (w, r)) in weights
            .iter()
            .zip(solver.solve_many(&as_weights, threads))
            .enumerate()
        {
            let r = r.map_err(|source| BakeError::Solve {
                weights: w.clone(),
                source,
            })?;
            let (t, a, b) = tests[k];
            let delta = sub(&r.positions, base);
            let chord = interpolated(&targets[t], 0.5 * (a + b), nv);
            let e = max_distance(&delta, &chord);
            if e > tolerance {
                found.push((e, k, delta));
            }
        }
        solves += tests.len();
        // The farthest first; ties in test order (target, then weight).
        found.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        found.truncate(max_refined);
        max_refined -= found.len();
        found.sort_by_key(|f| f.1);
        let mut next = Vec::with_capacity(2 * found.len());
        for (_, k, delta) in found {
            let (t, a, b) = tests[k];
            let c = 0.5 * (a + b);
            let target = &mut targets[t];
            let at = target.weights.partition_point(|&x| x < c);
            target.weights.insert(at, c);
            target.deltas.insert(at, delta);
            next.push((t, a, c));
            next.push((t, c, b));
        }
        tests = next;
    }
    Ok(solves)
}
