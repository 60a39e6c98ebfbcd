//! Steihaug–Toint truncated conjugate gradients for the trust-region subproblem
//! (Steihaug 1983; Toint 1981; Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 7.2,
//! with the preconditioned norm of Conn, Gould & Toint, *Trust-Region Methods*, §7.5.1).
//!
//! Approximately minimizes the quadratic model $m(p) = g^\top p + \tfrac12 p^\top H p$ of the
//! energy over $\lVert p \rVert_M \le \Delta$, where $H$ is the *exact* (possibly indefinite)
//! Hessian and $M$ the lagged Cholesky factor of a recent projected Hessian, which serves as
//! preconditioner and defines the trust-region norm. Unlike the projected Newton step, a
//! direction of negative curvature is not discarded: it is followed to the trust-region boundary,
//! which is how the solver gets out of the soft, buckling configurations of thin features.
//! Once the exact Hessian is positive definite near the equilibrium the iteration is plain
//! preconditioned CG and the outer iteration is Newton's, with its quadratic convergence.

/// How [`steihaug`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Termination {
    /// The residual reached the requested tolerance inside the trust region.
    Converged,
    /// The step reached the trust-region boundary (along a CG or a negative-curvature direction).
    Boundary,
    /// The iteration budget ran out inside the trust region.
    Budget,
}

/// Result of [`steihaug`].
pub(crate) struct TruncatedStep {
    /// The step, over free coordinates.
    pub step: Vec<f64>,
    /// Model decrease $-m(p) \ge 0$.
    pub decrease: f64,
    /// $\lVert p \rVert_M$.
    pub m_norm: f64,
    /// Why it stopped.
    pub termination: Termination,
    /// Relative residual $\lVert Hp + g\rVert / \lVert g \rVert$ of the last interior iterate.
    pub relative_residual: f64,
}

/// When to stop the inner iteration.
pub(crate) struct StopRule {
    /// Relative residual (forcing term).
    pub rtol: f64,
    /// Absolute max-norm of the residual that is small enough whatever `rtol` says (a step
    /// whose linear residual is far below the gradient tolerance needs no more accuracy).
    pub atol_max: f64,
    /// Iteration budget.
    pub max_iter: usize,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The $\tau \ge 0$ with $\lVert z + \tau d\rVert_M = \Delta$ given $z^\top M z$, $z^\top M d$,
/// $d^\top M d$.
fn to_boundary(zz: f64, zd: f64, dd: f64, radius: f64) -> f64 {
    let c = zz - radius * radius;
    let disc = (zd * zd - dd * c).max(0.0);
    if dd <= 0.0 {
        return 0.0;
    }
    ((-zd + disc.sqrt()) / dd).max(0.0)
}

/// Steihaug–Toint CG on $H p = -g$ (free coordinates) within $\lVert p\rVert_M \le$ `radius`.
/// `g` is the gradient restricted to free coordinates; `op(p, out)` writes $H p$ and
/// `precond(r)` overwrites `r` with $M^{-1} r$. Returns `None` when the preconditioner fails
/// (no valid factorization) or the operator gives non-finite values.
///
/// A NaN `radius` asks for the initial one, $\Delta_0 = 2 \sqrt{g^\top M^{-1} g}$ (twice
/// the $M$-norm of the preconditioned Newton step), written back to `radius`: it comes from
/// the first preconditioner application, which the iteration needs anyway, so it costs no
/// extra solve.
pub(crate) fn steihaug(
    op: &mut dyn FnMut(&[f64], &mut [f64]),
    precond: &mut dyn FnMut(&mut [f64]) -> bool,
    g: &[f64],
    radius: &mut f64,
    stop: &StopRule,
    iterations: &mut usize,
) -> Option<TruncatedStep> {
    let n = g.len();
    let mut z = vec![0.0; n];
    let mut hz = vec![0.0; n];
    let mut r = g.to_vec();
    let gnorm = dot(g, g).sqrt();
    let done = |z: Vec<f64>, hz: &[f64], zz: f64, termination, rel| {
        let decrease = -(dot(g, &z) + 0.5 * dot(&z, hz));
        TruncatedStep {
            step: z,
            decrease,
            m_norm: zz.max(0.0).sqrt(),
            termination,
            relative_residual: rel,
        }
    };
    if gnorm == 0.0 {
        return Some(done(z, &hz, 0.0, Termination::Converged, 0.0));
    }
    let mut y = r.clone();
    if !precond(&mut y) {
        return None;
    }
    let mut d: Vec<f64> = y.iter().map(|v| -v).collect();
    let mut ry = dot(&r, &y);
    if radius.is_nan() {
        *radius = 2.0 * ry.max(0.0).sqrt();
    }
    let radius = *radius;
    // M-inner products of the iterate and the direction, by recurrence.
    let (mut zz, mut zd, mut dd) = (0.0, 0.0, ry);
    let mut hd = vec![0.0; n];
    let mut rel = 1.0;
    for _ in 0..stop.max_iter {
        *iterations += 1;
        op(&d, &mut hd);
        let kappa = dot(&d, &hd);
        if !kappa.is_finite() {
            return None;
        }
        let alpha = ry / kappa;
        let zz_next = zz + 2.0 * alpha * zd + alpha * alpha * dd;
        if kappa <= 0.0 || zz_next >= radius * radius {
            let tau = to_boundary(zz, zd, dd, radius);
            for k in 0..n {
                z[k] += tau * d[k];
                hz[k] += tau * hd[k];
            }
            let zz_b = zz + 2.0 * tau * zd + tau * tau * dd;
            return Some(done(z, &hz, zz_b, Termination::Boundary, rel));
        }
        for k in 0..n {
            z[k] += alpha * d[k];
            hz[k] += alpha * hd[k];
            r[k] += alpha * hd[k];
        }
        zz = zz_next;
        rel = dot(&r, &r).sqrt() / gnorm;
        let rmax = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if rel <= stop.rtol || rmax <= stop.atol_max {
            return Some(done(z, &hz, zz, Termination::Converged, rel));
        }
        y.copy_from_slice(&r);
        if !precond(&mut y) {
            return None;
        }
        let ry_next = dot(&r, &y);
        let beta = ry_next / ry;
        ry = ry_next;
        for k in 0..n {
            d[k] = -y[k] + beta * d[k];
        }
        zd = beta * (zd + alpha * dd);
        dd = ry + beta * beta * dd;
    }
    Some(done(z, &hz, zz, Termination::Budget, rel))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 3 SPD operator and a diagonal preconditioner.
    fn problem() -> ([[f64; 3]; 3], [f64; 3], [f64; 3]) {
        let h = [[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]];
        (h, [2.0, 3.0, 1.5], [1.0, -2.0, 0.5])
    }

    fn run(radius: &mut f64) -> TruncatedStep {
        let (h, m, g) = problem();
        let mut op = |p: &[f64], out: &mut [f64]| {
            for r in 0..3 {
                out[r] = (0..3).map(|c| h[r][c] * p[c]).sum();
            }
        };
        let mut pre = |r: &mut [f64]| {
            r.iter_mut().zip(m).for_each(|(v, d)| *v /= d);
            true
        };
        let stop = StopRule {
            rtol: 1e-12,
            atol_max: 0.0,
            max_iter: 40,
        };
        let mut its = 0;
        steihaug(&mut op, &mut pre, &g, radius, &stop, &mut its).expect("valid operator")
    }

    #[test]
    fn a_nan_radius_becomes_twice_the_preconditioned_newton_norm_at_no_extra_cost() {
        let (_, m, g) = problem();
        let expected = 2.0 * g.iter().zip(m).map(|(v, d)| v * v / d).sum::<f64>().sqrt();
        let mut radius = f64::NAN;
        let first = run(&mut radius);
        assert!(
            (radius - expected).abs() <= 1e-14 * expected,
            "{radius} vs {expected}"
        );
        // The same step as with that radius given explicitly, which is left as it is.
        let mut given = radius;
        let second = run(&mut given);
        assert_eq!(first.step, second.step);
        assert_eq!(given, radius);
        // Δ₀ is wide enough here: plain CG converges to H p = -g inside it.
        assert_eq!(first.termination, Termination::Converged);
        let (h, _, g) = problem();
        for r in 0..3 {
            let res: f64 = (0..3).map(|c| h[r][c] * first.step[c]).sum::<f64>() + g[r];
            assert!(res.abs() < 1e-10, "row {r}: residual {res}");
        }
        // A small radius cuts the step at the boundary, at that M-norm.
        let mut small = 0.1;
        let cut = run(&mut small);
        assert_eq!(cut.termination, Termination::Boundary);
        assert!((cut.m_norm - 0.1).abs() < 1e-12, "{}", cut.m_norm);
    }
}
