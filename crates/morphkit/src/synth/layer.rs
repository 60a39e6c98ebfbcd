//! A layer as the [`super::Synthesizer`] holds it, its timing, and the checks made when the
//! synthesizer is built (see the contradiction rule in [`super::synthesizer`]).

use super::gradient_blend::BlendMode;
use super::synthesizer::{LayerInfo, LayerSpec, Timing};
use super::{SynthError, WeightSolver};
use crate::mesh::{Point, TriMesh};
use crate::transfer::correspondence::polar;
use crate::transfer::{Correspondence, GradientCombine, GradientOperator, Placement};
use nalgebra::{Matrix3, Vector3};

/// A layer's source gradients at one output frame, as its transfer carries them: as they are
/// (world frame), or split into rotation and stretch (local-stretch frame).
pub(crate) enum Carried {
    World(Vec<Matrix3<f64>>, GradientCombine),
    Local(Vec<(Matrix3<f64>, Matrix3<f64>)>, GradientCombine),
}

/// One built layer: its source, weights, timing and placement.
#[derive(Debug)]
pub(crate) struct Layer {
    pub(crate) gradients: GradientOperator,
    pub(crate) correspondence: Correspondence,
    pub(crate) frames: Vec<Vec<Point>>,
    pub(crate) mode: BlendMode,
    pub(crate) timing: Timing,
    pub(crate) placement: Placement,
    pub(crate) weight_solver: Option<WeightSolver>,
    /// Source triangles matched by a target triangle of positive weight: the only ones whose
    /// gradients are blended between source frames.
    pub(crate) needed: Vec<bool>,
    pub(crate) info: LayerInfo,
    /// Unit normals of the source reference's triangles (local-stretch frame only).
    pub(crate) source_normals: Option<Vec<Vector3<f64>>>,
}

impl Layer {
    /// Source gradients `g` as this layer carries them.
    pub(crate) fn carry(&self, g: Vec<Matrix3<f64>>, combine: GradientCombine) -> Carried {
        match self.source_normals {
            None => Carried::World(g, combine),
            Some(_) => Carried::Local(g.iter().map(polar).collect(), combine),
        }
    }

    /// The target gradients of carried source gradients, as
    /// [`AnimationTransfer`](crate::transfer::AnimationTransfer) computes them: in the local
    /// frame (`target_normals`) turned, or unturned for the fold guard.
    pub(crate) fn target_gradients(
        &self,
        carried: &Carried,
        target_normals: Option<&[Vector3<f64>]>,
        turned: bool,
    ) -> Vec<Matrix3<f64>> {
        let c = &self.correspondence;
        match carried {
            Carried::World(g, combine) => c.map_gradients(g, *combine),
            Carried::Local(p, combine) => {
                let ns = self.source_normals.as_deref().expect("local stretch");
                let nt = target_normals.expect("local stretch");
                if turned {
                    c.map_gradients_local(p, ns, nt, *combine)
                } else {
                    c.map_gradients_local_unturned(p, ns, nt, *combine)
                }
            }
        }
    }

    /// Source time of output frame `f`: `(frame, next, fraction)`, or `None` when inactive.
    pub(crate) fn source_time(&self, f: usize) -> Option<(usize, usize, f64)> {
        let n = self.frames.len();
        if f < self.timing.offset {
            return None;
        }
        if n == 1 {
            return Some((0, 0, 0.0));
        }
        let mut s = (f - self.timing.offset) as f64 * self.timing.speed;
        if self.timing.looped {
            s = s.rem_euclid(n as f64);
        } else if s > (n - 1) as f64 + 1e-9 {
            return None;
        }
        let i = (s.floor() as usize).min(n - 1);
        let frac = s - i as f64;
        let j = if self.timing.looped {
            (i + 1) % n
        } else {
            (i + 1).min(n - 1)
        };
        Some((i, j, if frac < 1e-9 { 0.0 } else { frac }))
    }
}

pub(crate) fn check_layer(spec: &LayerSpec, target: &TriMesh) -> Result<(), SynthError> {
    spec.correspondence.check(&spec.source_reference, target)?;
    if spec.frames.is_empty() {
        return Err(SynthError::Length {
            what: "layer source frames",
            expected: 1,
            found: 0,
        });
    }
    if spec.scribble.len() != target.num_triangles() {
        return Err(SynthError::Length {
            what: "layer scribble",
            expected: target.num_triangles(),
            found: spec.scribble.len(),
        });
    }
    if !spec.scribble.iter().any(|&s| s) {
        return Err(SynthError::EmptyScribble);
    }
    if !(spec.timing.speed.is_finite() && spec.timing.speed > 0.0) {
        return Err(SynthError::Parameter {
            name: "speed",
            value: spec.timing.speed,
            why: "must be positive",
        });
    }
    Ok(())
}

pub(crate) fn check_contradictions(layers: &[Layer], frames: usize) -> Result<(), SynthError> {
    for b in 0..layers.len() {
        for a in 0..b {
            let (la, lb) = (&layers[a], &layers[b]);
            if lb.mode != BlendMode::Blend {
                continue;
            }
            let both: Vec<usize> = (0..la.info.weights.values.len())
                .filter(|&t| la.info.weights.values[t] == 1.0 && lb.info.weights.values[t] == 1.0)
                .collect();
            if both.is_empty() {
                continue;
            }
            if let Some(f) =
                (0..frames).find(|&f| la.source_time(f).is_some() && lb.source_time(f).is_some())
            {
                return Err(SynthError::ContradictingLayers {
                    first: a,
                    first_mode: la.mode.name(),
                    second: b,
                    second_mode: lb.mode.name(),
                    count: both.len(),
                    triangle: both[0],
                    frame: f,
                });
            }
        }
    }
    Ok(())
}
