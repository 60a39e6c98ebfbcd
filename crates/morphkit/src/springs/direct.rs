//! The direct Newton iteration ([`LinearSolver::Direct`](super::LinearSolver::Direct)): a
//! fresh factorization of the projected Hessian every step and an Armijo backtracking line
//! search, over the same [`Problem`] and [`Workspace`] as the default
//! [`trust_region`](super::newton::trust_region).

use super::newton::{dot, Problem, ROUNDOFF};
use super::options::FrameStats;
use super::terms::HessianKind;
use super::workspace::Workspace;
use super::BlendError;

/// Projected Newton with an Armijo line search from `x`. Returns the final gradient.
pub(crate) fn projected_newton(
    prob: &Problem<'_>,
    ws: &mut Workspace,
    x: &mut Vec<f64>,
    stats: &mut FrameStats,
) -> Result<Vec<f64>, BlendError> {
    let sys = prob.system;
    ws.use_double = false;
    let n3 = x.len();
    let mut g = vec![0.0; n3];
    let mut e = prob.gradient(x, &mut g);
    let mut gmax = sys.max_free(&g);
    let mut x_trial = vec![0.0; n3];
    let mut g_trial = vec![0.0; n3];
    let mut step = vec![0.0; sys.num_free()];
    stats.converged = gmax <= prob.tolerance;
    while !stats.converged && stats.newton_iterations < prob.options.max_newton_iterations {
        stats.newton_iterations += 1;
        prob.hessian(ws, x, HessianKind::Projected, false);
        prob.factorize(ws, stats)?;
        sys.gather(&g, &mut step);
        step.iter_mut().for_each(|v| *v = -*v);
        ws.factor()?.solve_one(&mut step)?;
        let mut slope = 0.0;
        for (k, &i) in sys.dof_index.iter().enumerate() {
            if i != u32::MAX {
                slope += g[k] * step[i as usize];
            }
        }
        if slope >= 0.0 {
            // Not a descent direction (round-off at convergence): steepest descent.
            sys.gather(&g, &mut step);
            step.iter_mut().for_each(|v| *v = -*v);
            slope = -dot(&step, &step);
        }
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..60 {
            x_trial.copy_from_slice(x);
            sys.add_step(&mut x_trial, t, &step);
            let e_trial = prob.gradient(&x_trial, &mut g_trial);
            let g_trial_max = sys.max_free(&g_trial);
            let roundoff = ROUNDOFF * e.abs().max(f64::MIN_POSITIVE);
            if e_trial.is_finite()
                && (e_trial <= e + prob.options.armijo * t * slope
                    || (e_trial - e <= roundoff && g_trial_max < gmax))
            {
                accepted = true;
                e = e_trial;
                gmax = g_trial_max;
                std::mem::swap(x, &mut x_trial);
                std::mem::swap(&mut g, &mut g_trial);
                break;
            }
            stats.rejected_steps += 1;
            t *= 0.5;
        }
        stats.converged = gmax <= prob.tolerance;
        if !accepted {
            break;
        }
    }
    if !e.is_finite() {
        return Err(BlendError::Diverged {
            iteration: stats.newton_iterations,
        });
    }
    stats.gradient_norm = gmax;
    stats.energy = e;
    Ok(g)
}
