//! One frame's energy on a prepared [`Rig`]: the rig's terms with the frame's parameters,
//! the frame's holds ([`super::holds`]) and a user's point targets, the tether to the
//! predictor $P(w)$ and the fold guard (with the trust and references of
//! [`guard_trust`](super::guard_trust)). The full solve ([`super::solve`]) and the
//! interactive mode ([`super::interactive`]) minimise this same energy, so that the
//! interactive shape approximates the canonical equilibrium and not a neighbouring one.

use super::guard_trust::guard_references;
use super::predictor;
use super::rig::Rig;
use super::terms::{EnergyTerm, Held, OrientationTerm, PointTarget, PointTerm, TermParameters};
use crate::mesh::Point;

/// The energy of one frame, and the predictions it was built from.
pub(super) struct FrameEnergy<'r> {
    rig: &'r Rig,
    /// The linear blend $\sum_s c_s x^s$ (world, `#V`).
    pub lin: Vec<Point>,
    /// The rotation-aware prediction (world, `#V`), where there is one and it was asked for.
    pub rotated: Option<Vec<Point>>,
    /// Vertices held exactly in this frame (hard holds and hard user targets).
    pub held: Held,
    /// Soft point targets: soft holds, soft user targets, the tether.
    soft: Vec<PointTarget>,
    /// $P(w)$ in solver coordinates (`3 #V`), where asked for or needed.
    pub predicted: Option<Vec<f64>>,
    guard: Option<OrientationTerm<'r>>,
    /// The rig terms' parameters at this frame's coefficients.
    pub params: Vec<TermParameters>,
}

impl Rig {
    /// The energy of the frame with coefficients `c` and the user's point `targets`.
    /// `rotate`: compute the rotation-aware prediction even where nothing in the energy
    /// needs it (the start does); `predict`: likewise for $P(w)$ in solver coordinates.
    pub(super) fn frame_energy(
        &self,
        c: &[f64],
        targets: &[PointTarget],
        rotate: bool,
        predict: bool,
    ) -> FrameEnergy<'_> {
        let lin = predictor::linear(&self.shapes, c);
        // The frame's own holds first, so that a user's target on the same vertex wins.
        let mut all = self.holds.targets(c, &lin);
        let holds = all.len();
        all.extend_from_slice(targets);
        // The tether pulls towards P, and the bands are held at it.
        let rotate = rotate || !self.constraints.bands.is_empty() || self.options.tether > 0.0;
        let rotated = rotate
            .then(|| self.rotation_prediction(c, &lin, &all[..holds]))
            .flatten();
        let n = self.shapes.num_vertices();
        let dof = &self.system.dof_index;
        let free = |v: usize| (0..3).all(|a| dof[3 * v + a] != u32::MAX);
        let held = Held::new(n, &all, free);
        let mut soft: Vec<PointTarget> = all.iter().filter(|t| !t.is_hard()).copied().collect();
        let guarded = self.guard_weight > 0.0;
        let predicted = (self.options.tether > 0.0 || predict || guarded)
            .then(|| self.start(&lin, rotated.as_deref(), None));
        if let Some(p) = predicted.as_deref().filter(|_| self.options.tether > 0.0) {
            soft.extend(super::tether::targets(p, free, self.options.tether));
        }
        let guard = predicted.as_deref().filter(|_| guarded).map(|p| {
            let world = rotated.as_deref().unwrap_or(&lin);
            let reference = guard_references(&self.shapes, c, p, world, &lin);
            let trust = self.guard_trust(c);
            OrientationTerm::new(self.shapes.triangles(), reference, trust, self.guard_weight)
        });
        let params = self.terms.iter().map(|t| t.prepare(c)).collect();
        FrameEnergy {
            rig: self,
            lin,
            rotated,
            held,
            soft,
            predicted,
            guard,
            params,
        }
    }
}

impl FrameEnergy<'_> {
    /// Calls `f` with the frame's terms and their parameters (the rig's terms, then the
    /// point targets and the guard where there are any).
    pub fn with_terms<R>(&self, f: impl FnOnce(&[&dyn EnergyTerm], &[TermParameters]) -> R) -> R {
        let points = PointTerm {
            targets: &self.soft,
            scale: self.rig.mean_stiffness,
        };
        let mut terms: Vec<&dyn EnergyTerm> = self.rig.terms.iter().map(|t| t.as_ref()).collect();
        let mut params = self.params.clone();
        if !self.soft.is_empty() {
            terms.push(&points);
            params.push(TermParameters::default());
        }
        if let Some(g) = &self.guard {
            terms.push(g);
            params.push(TermParameters::default());
        }
        f(&terms, &params)
    }

    /// Springs clamped at this frame's parameters.
    pub fn clamped(&self) -> usize {
        self.params.iter().map(|p| p.clamped).sum()
    }
}
