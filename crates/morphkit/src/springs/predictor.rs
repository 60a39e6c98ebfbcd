//! The predictor $P(w)$ that every solve starts from (with the sampled correction of
//! [`sampled_start`](super::sampled_start) added), and the output alignment.
//!
//! $P(w)$ is the linear blend $L(c) = \sum_s c_s x^s$ of the shapes, expressed in solver
//! coordinates: a component held by a rigid [`Gauge`](super::Gauge) is rotated into the frame
//! of its three pinned vertices *in the predictor* ([`Gauge::frame_for`](super::Gauge)), so the
//! pins strain nothing; fixed and kinematic vertices sit at their linear blend. $P$ depends on
//! the weights alone and equals shape $s$ exactly at one-hot weights $e_s$, where every term's
//! energy and gradient vanish: endpoints are exact after zero iterations.
//!
//! After the solve, each gauged component, and each component held only by kinematic vertices
//! ([`Constraints::aligned`]), is moved rigidly (Kabsch) onto $L(c)$, so it sits where an
//! artist expects it; fixed vertices are already in world coordinates.
//!
//! The rig's own view of $P$ (with the rotation-aware prediction of
//! [`rotation_predictor`](super::rotation_predictor) and thin bands placed on it) is the
//! `impl Rig` block at the end.

use super::gauge::rotate_into;
use super::rig::Rig;
use super::terms::PointTarget;
use super::{BlendError, Constraints, Weights};
use crate::geom::kabsch;
use crate::mesh::{Point, ShapeSet};
use std::sync::Arc;

/// The linear blend $\sum_s c_s x^s$.
pub(crate) fn linear(shapes: &ShapeSet, c: &[f64]) -> Vec<Point> {
    let mut out = vec![[0.0; 3]; shapes.num_vertices()];
    for (s, &w) in c.iter().enumerate() {
        if w != 0.0 {
            for (o, p) in out.iter_mut().zip(shapes.positions(s)) {
                for a in 0..3 {
                    o[a] += w * p[a];
                }
            }
        }
    }
    out
}

/// Positions `p` (world coordinates, `#V`) in solver coordinates, flattened (`3 #V`): each
/// gauged component rotated into its gauge's frame, each [aligned](Constraints::aligned)
/// component moved rigidly so that its held vertices best fit the linear blend `lin` (where
/// the solver holds them; the identity when they are there already).
pub(crate) fn predict(constraints: &Constraints, p: &[Point], lin: &[Point]) -> Vec<f64> {
    let mut x = p.to_vec();
    for g in &constraints.gauges {
        let frame = g.frame_for(p);
        for &v in &g.vertices {
            x[v as usize] = rotate_into(&frame, p[v as usize]);
        }
    }
    for a in &constraints.aligned {
        let from: Vec<Point> = a.held.iter().map(|&v| p[v as usize]).collect();
        let to: Vec<Point> = a.held.iter().map(|&v| lin[v as usize]).collect();
        let fit = kabsch(&from, &to, &[]);
        for &v in &a.vertices {
            x[v as usize] = fit.apply(p[v as usize]);
        }
    }
    x.into_iter().flatten().collect()
}

/// Solver coordinates back to world positions: gauged and aligned components moved rigidly
/// onto `lin`.
pub(crate) fn output(constraints: &Constraints, x: &[f64], lin: &[Point]) -> Vec<Point> {
    let mut p: Vec<Point> = x.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect();
    let gauged = constraints.gauges.iter().map(|g| &g.vertices);
    for comp in gauged.chain(constraints.aligned.iter().map(|a| &a.vertices)) {
        let from: Vec<Point> = comp.iter().map(|&v| p[v as usize]).collect();
        let to: Vec<Point> = comp.iter().map(|&v| lin[v as usize]).collect();
        let fit = kabsch(&from, &to, &[]);
        for &v in comp {
            p[v as usize] = fit.apply(p[v as usize]);
        }
    }
    p
}

impl Rig {
    /// The rotation-aware prediction for coefficients `c` (world coordinates, fixed vertices
    /// and the frame's hard `holds` at `lin`, the linear blend), or `None` where the linear
    /// blend is the predictor.
    pub(super) fn rotation_prediction(
        &self,
        c: &[f64],
        lin: &[Point],
        holds: &[PointTarget],
    ) -> Option<Vec<Point>> {
        let rotation = self.rotation.as_ref()?;
        if !holds.iter().any(|h| h.is_hard()) {
            return rotation.predict(c, lin, &self.is_fixed);
        }
        let mut fixed = self.is_fixed.clone();
        for h in holds.iter().filter(|h| h.is_hard()) {
            fixed[h.vertex as usize] = true;
        }
        rotation.predict(c, lin, &fixed)
    }

    /// Where a solve starts, in solver coordinates: `start_from` (with fixed vertices at
    /// their linear blend `lin` and thin bands at `rotated`) when given, else the predictor:
    /// `rotated` ([`rotation_prediction`](Self::rotation_prediction)) or `lin`.
    pub(super) fn start(
        &self,
        lin: &[Point],
        rotated: Option<&[Point]>,
        start_from: Option<&[Point]>,
    ) -> Vec<f64> {
        let predicted = rotated.unwrap_or(lin);
        let mut x = predict(&self.constraints, start_from.unwrap_or(predicted), lin);
        if start_from.is_some() {
            for &v in &self.constraints.fixed {
                let v = v as usize;
                x[3 * v..3 * v + 3].copy_from_slice(&lin[v]);
            }
            for &v in &self.constraints.bands {
                let v = v as usize;
                x[3 * v..3 * v + 3].copy_from_slice(&predicted[v]);
            }
        }
        x
    }

    /// The predictor $P$ in world coordinates, from the linear blend and the rotation-aware
    /// prediction of the same coefficients.
    pub(super) fn world_prediction(&self, lin: &[Point], rotated: Option<&[Point]>) -> Vec<Point> {
        output(&self.constraints, &self.start(lin, rotated, None), lin)
    }

    /// The predictor $P(c)$ in world coordinates.
    pub(super) fn predicted(&self, c: &[f64]) -> Vec<Point> {
        if let Some(s) = super::weights::one_hot(c) {
            // Exactly the shape (the Poisson solve and the alignment give it to round-off).
            return self.shapes.positions(s).to_vec();
        }
        let lin = linear(&self.shapes, c);
        let holds = self.holds.targets(c, &lin);
        self.world_prediction(&lin, self.rotation_prediction(c, &lin, &holds).as_deref())
    }
}

/// The predictor $P(w)$ of a [`PhysicalBlend`](super::PhysicalBlend) on its own (see [`PhysicalBlend::predictor`](super::PhysicalBlend::predictor)):
/// cheap to clone, `Send + Sync`, and usable while the blend it came from is solving on
/// another thread.
#[derive(Clone)]
pub struct BlendPredictor {
    pub(super) rig: Arc<Rig>,
}

impl std::fmt::Debug for BlendPredictor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlendPredictor")
            .field("vertices", &self.rig.shapes.num_vertices())
            .finish()
    }
}

impl BlendPredictor {
    /// Vertices of a prediction.
    pub fn num_vertices(&self) -> usize {
        self.rig.shapes.num_vertices()
    }
    /// Shapes of the blend (base and targets).
    pub fn num_shapes(&self) -> usize {
        self.rig.shapes.len()
    }
    /// The predictor $P(w)$, in world coordinates (`#V`): the rotation-aware interpolation of
    /// the shapes (the linear blend with [`Predictor::Linear`](super::Predictor::Linear)), with fixed and kinematic
    /// vertices at their linear blend; a solve starts from it plus the
    /// [sampled correction](super::sampled_start), which needs equilibria and so is not part
    /// of this preview. It
    /// equals each shape exactly at its one-hot weights and costs one prefactored solve, so it
    /// can follow a slider while the equilibrium is computed (a preview, not the equilibrium).
    pub fn predict(&self, weights: &Weights) -> Result<Vec<crate::mesh::Point>, BlendError> {
        Ok(self
            .rig
            .predicted(&weights.coefficients(self.rig.shapes.len())?))
    }
}
