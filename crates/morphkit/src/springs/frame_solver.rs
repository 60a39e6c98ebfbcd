//! One thread's view of a [`PhysicalBlend`](super::PhysicalBlend) ([`FrameSolver`]), and the
//! results of parallel frames with lost items reported.

use super::reference::Factor;
use super::rig::Rig;
use super::solve::Start;
use super::terms::PointTarget;
use super::workspace::Workspace;
use super::{BlendError, BlendResult, Weights};

/// The results of [`PhysicalBlend::map_frames`] with every lost item (`None`, a thread that
/// panicked) reported as an error naming its frame.
pub(crate) fn report_lost<R, E: From<BlendError>>(
    slots: Vec<Option<Result<R, E>>>,
) -> Vec<Result<R, E>> {
    slots
        .into_iter()
        .enumerate()
        .map(|(k, r)| {
            r.unwrap_or_else(
                || Err(BlendError::InvalidOption(format!("frame {k} was lost")).into()),
            )
        })
        .collect()
}

/// One thread's view of a [`PhysicalBlend`]: the shared rig and that thread's numeric
/// workspace. Its solves are those of the blend, bit for bit.
pub struct FrameSolver<'a> {
    pub(super) rig: &'a Rig,
    pub(super) ws: &'a mut Workspace,
}

impl FrameSolver<'_> {
    /// As [`PhysicalBlend::solve_with`].
    pub fn solve_with(
        &mut self,
        weights: &Weights,
        targets: &[PointTarget],
        start: Option<&[crate::mesh::Point]>,
    ) -> Result<BlendResult, BlendError> {
        let c = weights.coefficients(self.rig.shapes.len())?;
        let k = self.rig.options.continuation_steps;
        if start.is_none() && k > 1 && super::weights::one_hot(&c).is_none() {
            return self.continued(&c, targets, k);
        }
        let from = match start {
            Some(p) => Start::From(p),
            None => Start::Canonical,
        };
        let factor = match from {
            Start::Canonical if targets.is_empty() => Factor::Reference,
            _ => Factor::Fresh,
        };
        self.rig.solve(self.ws, &c, targets, from, factor)
    }

    /// The frame for coefficients `c` by continuation along the ray from the rest shape in
    /// `k` steps ([`BlendOptions::continuation_steps`](super::BlendOptions::continuation_steps)):
    /// its statistics are the last solve's, with the Newton iterations, rejected steps,
    /// factorizations, CG iterations and seconds of every step.
    fn continued(
        &mut self,
        c: &[f64],
        targets: &[PointTarget],
        k: usize,
    ) -> Result<BlendResult, BlendError> {
        // c(t) = e₀ + t (c − e₀): the weights t w.
        let at = |t: f64| -> Vec<f64> {
            c.iter()
                .enumerate()
                .map(|(i, &x)| if i == 0 { 1.0 + t * (x - 1.0) } else { t * x })
                .collect()
        };
        let first = at(1.0 / k as f64);
        let factor = if targets.is_empty() {
            Factor::Reference
        } else {
            Factor::Fresh
        };
        let mut r = self
            .rig
            .solve(self.ws, &first, targets, Start::Canonical, factor)?;
        let mut p = self.rig.predicted(&first);
        let mut total = r.stats.clone();
        for j in 2..=k {
            let cj = if j == k {
                c.to_vec()
            } else {
                at(j as f64 / k as f64)
            };
            let q = self.rig.predicted(&cj);
            let start: Vec<crate::mesh::Point> = r
                .positions
                .iter()
                .zip(p.iter().zip(&q))
                .map(|(x, (p, q))| std::array::from_fn(|i| x[i] + q[i] - p[i]))
                .collect();
            r = self
                .rig
                .solve(self.ws, &cj, targets, Start::From(&start), Factor::Fresh)?;
            total.newton_iterations += r.stats.newton_iterations;
            total.rejected_steps += r.stats.rejected_steps;
            total.factorizations += r.stats.factorizations;
            total.cg_iterations += r.stats.cg_iterations;
            total.seconds += r.stats.seconds;
            p = q;
        }
        r.stats.newton_iterations = total.newton_iterations;
        r.stats.rejected_steps = total.rejected_steps;
        r.stats.factorizations = total.factorizations;
        r.stats.cg_iterations = total.cg_iterations;
        r.stats.seconds = total.seconds;
        Ok(r)
    }
}
