//! One frame's solve on a prepared [`Rig`]: the start (canonical, plain, or given), the
//! reference factor nearest to the weights, and the Newton iteration
//! ([`super::newton`]). The lazily computed parts of the rig — each target's sampled-start
//! fields and reference factors — are solves themselves, so they are filled from here
//! ([`Sampler`], [`Rig::reference`]): the data lives below in the stack, the solving above it.

use super::newton::{projected_newton, reference_at, trust_region, Problem, Workspace};
use super::options::{BlendResult, FrameStats, LinearSolver};
use super::predictor;
use super::reference::{Factor, Reference, References, GRID, PROBE};
use super::rig::Rig;
use super::sampled_start::{half_weight, shifted, SampleSolver, SAMPLES};
use super::terms::{EnergyTerm, Held, OrientationTerm, PointTarget, PointTerm, TermParameters};
use super::BlendError;
use crate::mesh::Point;
use std::sync::Arc;
use std::time::Instant;

/// Where a solve starts.
#[derive(Clone, Copy)]
pub(super) enum Start<'a> {
    /// The canonical start: the predictor, with the sampled correction when asked for.
    Canonical,
    /// The predictor alone (the sampled start's own samples).
    Plain,
    /// Given world positions (`#V`).
    From(&'a [Point]),
}

impl Rig {
    pub(super) fn solve(
        &self,
        ws: &mut Workspace,
        c: &[f64],
        targets: &[PointTarget],
        from: Start<'_>,
        factor: Factor<'_>,
    ) -> Result<BlendResult, BlendError> {
        let start = Instant::now();
        self.check_targets(targets)?;
        let lin = predictor::linear(&self.shapes, c);
        // The frame's own holds first, so that a user's target on the same vertex wins.
        let mut all_targets = self.holds.targets(c, &lin);
        let holds = all_targets.len();
        all_targets.extend_from_slice(targets);
        let targets = &all_targets[..];
        // One Poisson solve per frame: a given start needs the prediction only for the bands.
        let rotated = match from {
            // The tether pulls towards P, so it needs the prediction whatever the start.
            Start::From(_) if self.constraints.bands.is_empty() && self.options.tether == 0.0 => {
                None
            }
            _ => self.rotation_prediction(c, &lin, &targets[..holds]),
        };
        let corrected;
        let start_from = match from {
            Start::From(p) => Some(p),
            Start::Plain => None,
            Start::Canonical if !self.options.sampled_start => None,
            Start::Canonical => {
                let correction = self.samples.correction(c, &mut Sampler { rig: self, ws });
                corrected = correction
                    .map(|d| shifted(self.world_prediction(&lin, rotated.as_deref()), &d, 1.0));
                corrected.as_deref()
            }
        };
        if start_from.is_some_and(|p| p.len() != self.shapes.num_vertices()) {
            return Err(BlendError::InvalidOption(
                "the start positions must have one point per vertex".into(),
            ));
        }
        let n = self.shapes.num_vertices();
        let dof = &self.system.dof_index;
        let free = |v: usize| (0..3).all(|a| dof[3 * v + a] != u32::MAX);
        let held = Held::new(n, targets, free);
        let mut soft: Vec<PointTarget> = targets.iter().filter(|t| !t.is_hard()).copied().collect();
        // P(w) in solver coordinates: the tether's targets, and the start when none is given.
        let guarded = self.guard_weight > 0.0;
        let predicted = (self.options.tether > 0.0 || start_from.is_none() || guarded)
            .then(|| self.start(&lin, rotated.as_deref(), None));
        if let Some(p) = predicted.as_deref().filter(|_| self.options.tether > 0.0) {
            soft.extend(super::tether::targets(p, free, self.options.tether));
        }
        let points = PointTerm {
            targets: &soft,
            scale: self.mean_stiffness,
        };
        let mut terms: Vec<&dyn EnergyTerm> = self.terms.iter().map(|t| t.as_ref()).collect();
        let mut params: Vec<TermParameters> = self.terms.iter().map(|t| t.prepare(c)).collect();
        if !soft.is_empty() {
            terms.push(&points);
            params.push(TermParameters::default());
        }
        let guard = predicted.as_deref().filter(|_| guarded).map(|p| {
            let world = rotated.as_deref().unwrap_or(&lin);
            OrientationTerm::new(self.shapes.triangles(), p, world, &lin, self.guard_weight)
        });
        if let Some(g) = &guard {
            terms.push(g);
            params.push(TermParameters::default());
        }
        let mut x = match (start_from, predicted) {
            (None, Some(p)) => p,
            _ => self.start(&lin, rotated.as_deref(), start_from),
        };
        let mut stats = FrameStats {
            gradient_tolerance: self.tolerance,
            clamped_springs: params.iter().map(|p| p.clamped).sum(),
            ..Default::default()
        };
        held.place(&mut x);
        let prob = Problem {
            terms: &terms,
            params: &params,
            system: &self.system,
            held: &held,
            options: &self.options,
            tolerance: self.tolerance,
        };
        let reference = match factor {
            _ if self.options.linear_solver != LinearSolver::TrustRegion => None,
            Factor::Reference => self.reference(ws, c, true),
            Factor::Probe => self.reference(ws, c, false),
            _ => None,
        };
        stats.reference_factor = reference.is_some();
        let g = match self.options.linear_solver {
            LinearSolver::TrustRegion => {
                let probe = matches!(factor, Factor::Probe);
                trust_region(&prob, ws, &mut x, &mut stats, reference.as_deref(), probe)?
            }
            LinearSolver::Direct => projected_newton(&prob, ws, &mut x, &mut stats)?,
        };
        if let Factor::Produce(out) = factor {
            if stats.converged {
                *out = reference_at(&prob, ws, &x)?;
            }
        }
        if !stats.converged {
            stats.unconverged_vertices = prob.failed_vertices(&g);
        }
        let positions = predictor::output(&self.constraints, &x, &lin);
        stats.seconds = start.elapsed().as_secs_f64();
        Ok(BlendResult { positions, stats })
    }

    /// The reference nearest to coefficients `c` (see [`reference`](super::reference)),
    /// computed on first need: the samples' from their sampled-start solves, the ends' from
    /// a solve at the shape itself.
    pub(super) fn reference(
        &self,
        ws: &mut Workspace,
        c: &[f64],
        probe: bool,
    ) -> Option<Arc<Reference>> {
        let (s, g) = References::nearest(c)?;
        let cell = self.references.cell(s, g)?;
        if probe && !self.references_fit(ws, s) {
            return None;
        }
        if (1..=3).contains(&g) && self.options.sampled_start {
            // The sample's solve sets the cell.
            self.samples.field(s, g - 1, &mut Sampler { rig: self, ws });
            return cell.get().cloned().flatten();
        }
        cell.get_or_init(|| {
            let c = self.sample_coefficients(s, GRID[g]);
            let mut out = None;
            let r = self.solve(ws, &c, &[], Start::Plain, Factor::Produce(&mut out));
            r.ok().and(out).map(Arc::new)
        })
        .clone()
    }

    /// The probe of target `s`: a solve at $a = ⅜$, ⅛ from the ½ reference, which passes
    /// when it converges on the reference alone (no factorization of its own).
    fn references_fit(&self, ws: &mut Workspace, s: usize) -> bool {
        *self.references.fit[s - 1].get_or_init(|| {
            let c = self.sample_coefficients(s, PROBE);
            let r = self.solve(ws, &c, &[], Start::Canonical, Factor::Probe);
            r.is_ok_and(|r| r.stats.converged && r.stats.factorizations == 0)
        })
    }
}

/// Solves the sampled start's fields on one thread's workspace.
pub(super) struct Sampler<'a> {
    pub rig: &'a Rig,
    pub ws: &'a mut Workspace,
}

impl SampleSolver for Sampler<'_> {
    /// $d_s(a) = x^*_0(c^s(a)) - P(c^s(a))$: ½ solved from $P$, the others from
    /// $P + 4a(1-a)\,d_s(½)$ (see [`sampled_start`](super::sampled_start)).
    fn field(&mut self, s: usize, k: usize, half: Option<&[Point]>) -> Option<Vec<Point>> {
        let a = SAMPLES[k];
        let c = self.rig.sample_coefficients(s, a);
        let p = self.rig.predicted(&c);
        let mut reference = None;
        let cell = self.rig.references.cell(s, k + 1);
        let produce = match cell {
            Some(_) => Factor::Produce(&mut reference),
            None => Factor::Fresh,
        };
        let r = match half {
            None => self.rig.solve(self.ws, &c, &[], Start::Plain, produce),
            Some(d) => {
                let from = shifted(p.clone(), d, half_weight(a));
                self.rig
                    .solve(self.ws, &c, &[], Start::From(&from), produce)
            }
        };
        if let Some(cell) = cell {
            let _ = cell.set(reference.map(Arc::new));
        }
        let r = r.ok()?;
        r.stats.converged.then(|| {
            r.positions
                .iter()
                .zip(&p)
                .map(|(x, p)| std::array::from_fn(|k| x[k] - p[k]))
                .collect()
        })
    }
}
