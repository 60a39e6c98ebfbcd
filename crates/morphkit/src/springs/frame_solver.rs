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
}
