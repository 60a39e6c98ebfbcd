//! Telling a snap from a fast step (issue 54). A step of a sweep that moves some vertex more
//! than [`JUMP_BOUND`](super::JUMP_BOUND) times the linear blend's largest move is either a
//! *snap* (the frame leaves one equilibrium for another: a discontinuity) or a *fast step*
//! (the equilibrium moving smoothly faster than the bound allows: cragl's cylinder-pose1-4
//! moves at 5× the linear step, whatever the step). Halving the step tells them apart: a
//! discontinuity's move stays whole in one half, whose ratio to the half step's linear move
//! about doubles, while a smooth motion's ratio stays about the same.

use super::{linear_blend, BlendError, PhysicalBlend, Weights};
use crate::geom::max_distance;
use crate::mesh::Point;

/// A step is a snap when one of its halves has a ratio over this multiple of the step's.
pub const SNAP_GROWTH: f64 = 1.5;

/// The step ratio between the canonical frames at `a` and `b`: the largest vertex move over
/// the linear blend's largest move (`0/0` is 0).
pub fn step_ratio(solver: &mut PhysicalBlend, a: &Weights, b: &Weights) -> Result<f64, BlendError> {
    let (fa, fb) = (Frame::of(solver, a)?, Frame::of(solver, b)?);
    Ok(fa.ratio(&fb))
}

/// A canonical frame and the linear blend of the same weights.
struct Frame {
    solved: Vec<Point>,
    linear: Vec<Point>,
}

impl Frame {
    fn of(solver: &mut PhysicalBlend, w: &Weights) -> Result<Self, BlendError> {
        let solved = solver.solve(w)?.positions;
        Ok(Frame {
            linear: linear_blend(solver.shapes(), w)?,
            solved,
        })
    }

    /// The step ratio from `self` to `next`.
    fn ratio(&self, next: &Frame) -> f64 {
        let linear = max_distance(&self.linear, &next.linear);
        if linear > 0.0 {
            max_distance(&self.solved, &next.solved) / linear
        } else {
            0.0
        }
    }
}

/// Whether the step from `a` to `b` (ratio `ratio`, as [`step_ratio`] or
/// [`ContinuityCheck`](super::ContinuityCheck) measured it) is a snap: solves the midpoint
/// and compares the halves' ratios with `ratio` ([`SNAP_GROWTH`]). Deterministic: three
/// canonical solves.
///
/// Errors: those of [`PhysicalBlend::solve`]; `a` and `b` of different kinds or lengths.
pub fn is_snap(
    solver: &mut PhysicalBlend,
    a: &Weights,
    b: &Weights,
    ratio: f64,
) -> Result<bool, BlendError> {
    let mid = |x: &[f64], y: &[f64]| -> Vec<f64> {
        x.iter().zip(y).map(|(p, q)| 0.5 * (p + q)).collect()
    };
    let m = match (a, b) {
        (Weights::Alpha(x), Weights::Alpha(y)) => Weights::Alpha(0.5 * (x + y)),
        (Weights::Delta(x), Weights::Delta(y)) if x.len() == y.len() => Weights::Delta(mid(x, y)),
        (Weights::Convex(x), Weights::Convex(y)) if x.len() == y.len() => {
            Weights::Convex(mid(x, y))
        }
        _ => {
            return Err(BlendError::InvalidOption(
                "a step's two weights must be of one kind and length".into(),
            ))
        }
    };
    let (fa, fm, fb) = (
        Frame::of(solver, a)?,
        Frame::of(solver, &m)?,
        Frame::of(solver, b)?,
    );
    Ok(fa.ratio(&fm).max(fm.ratio(&fb)) > SNAP_GROWTH * ratio)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::turning_head_rig;
    use crate::springs::BlendOptions;

    /// A head turning 180°: its equilibrium moves smoothly (1.37× the linear step at most), so
    /// halving a step keeps its ratio: not a snap (the snaps of a kinking tube are in
    /// `tests/springs_continuity.rs`).
    #[test]
    fn a_smooth_step_is_not_a_snap() {
        let shapes = turning_head_rig(180.0, 20.0);
        let mut solver = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
        let (a, b) = (Weights::Delta(vec![0.50]), Weights::Delta(vec![0.5025]));
        let r = step_ratio(&mut solver, &a, &b).unwrap();
        assert!(r > 0.5 && r < 2.0, "{r}");
        assert!(!is_snap(&mut solver, &a, &b, r).unwrap());
        let e = is_snap(&mut solver, &a, &Weights::Delta(vec![0.5, 0.1]), r);
        assert!(e.is_err());
    }
}
