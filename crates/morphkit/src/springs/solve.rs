//! One frame's solve on a prepared [`Rig`]: the start (canonical, plain, or given), the
//! reference factor nearest to the weights, and the Newton iteration
//! ([`super::newton`]). The lazily computed parts of the rig — each target's sampled-start
//! fields and reference factors — are solves themselves, so they are filled from here
//! ([`Sampler`], [`Rig::reference`]): the data lives below in the stack, the solving above it.

use super::direct::projected_newton;
use super::frame::FrameEnergy;
use super::newton::{reference_at, trust_region, Problem};
use super::options::{BlendResult, FrameStats, LinearSolver};
use super::predictor;
use super::reference::{Factor, Reference, References, GRID, PROBE};
use super::rig::Rig;
use super::sampled_start::{half_weight, shifted, SampleSolver, StartSamples, PAIR, SAMPLES};
use super::terms::PointTarget;
use super::weights::one_hot;
use super::workspace::Workspace;
use super::BlendError;
use crate::mesh::Point;
use std::sync::Arc;
use std::time::Instant;

/// Where a solve starts.
#[derive(Clone, Copy)]
pub(super) enum Start<'a> {
    /// The canonical start: the predictor, with the sampled correction when asked for.
    Canonical,
    /// The canonical start without the pairs' fields: the predictor with each target's own
    /// sampled correction (the interactive mode's affine start, whose space holds the pairs'
    /// equilibria as columns).
    Singles,
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
        Ok(self.solve_state(ws, c, targets, from, factor)?.0)
    }

    /// [`solve`](Self::solve), also giving the final iterate in solver coordinates (`3 #V`).
    pub(super) fn solve_state(
        &self,
        ws: &mut Workspace,
        c: &[f64],
        targets: &[PointTarget],
        from: Start<'_>,
        factor: Factor<'_>,
    ) -> Result<(BlendResult, Vec<f64>), BlendError> {
        let start = Instant::now();
        self.check_targets(targets)?;
        let frame = self.frame_energy(c, targets, !matches!(from, Start::From(_)), false);
        let x = self.start_of(ws, c, from, &frame)?;
        let stats = FrameStats {
            gradient_tolerance: self.tolerance,
            clamped_springs: frame.clamped(),
            ..Default::default()
        };
        frame
            .with_terms(|terms, params| {
                let prob = Problem {
                    terms,
                    params,
                    system: &self.system,
                    held: &frame.held,
                    options: &self.options,
                    tolerance: self.tolerance,
                    projected_first: matches!(from, Start::Canonical)
                        && self.options.sampled_start
                        && !StartSamples::needed_pairs(c).is_empty(),
                    factorization_budget: match from {
                        Start::Canonical => self.options.max_factorizations,
                        _ => 0,
                    },
                };
                self.iterate(ws, &prob, c, factor, x, stats, &frame.lin)
            })
            .map(|(mut r, x)| {
                r.stats.seconds = start.elapsed().as_secs_f64();
                if targets.is_empty() {
                    self.own_numbers_at_a_shape(c, &mut r);
                }
                (r, x)
            })
    }

    /// At one-hot coefficients, a result that is its shape to round-off (an equilibrium after
    /// zero iterations, nothing pulling) becomes the shape's own numbers: the full solve and
    /// the interactive mode both end here (issues 54 and 55).
    pub(super) fn own_numbers_at_a_shape(&self, c: &[f64], r: &mut BlendResult) {
        if let Some(s) = one_hot(c) {
            if r.stats.converged && r.stats.newton_iterations == 0 {
                r.positions = self.shapes.positions(s).to_vec();
            }
        }
    }

    /// Where the frame with coefficients `c` and energy `frame` starts from `from`, in solver
    /// coordinates with its held vertices placed (the canonical start is the predictor plus
    /// the sampled correction).
    pub(super) fn start_of(
        &self,
        ws: &mut Workspace,
        c: &[f64],
        from: Start<'_>,
        frame: &FrameEnergy<'_>,
    ) -> Result<Vec<f64>, BlendError> {
        let (lin, rotated) = (&frame.lin, frame.rotated.as_deref());
        let corrected;
        let start_from = match from {
            Start::From(p) => Some(p),
            Start::Plain => None,
            Start::Canonical | Start::Singles if !self.options.sampled_start => None,
            Start::Canonical | Start::Singles => {
                let sampler = &mut Sampler { rig: self, ws };
                let correction = match from {
                    Start::Singles => self.samples.single_correction(c, sampler),
                    _ => self.samples.correction(c, sampler),
                };
                corrected =
                    correction.map(|d| shifted(self.world_prediction(lin, rotated), &d, 1.0));
                corrected.as_deref()
            }
        };
        if start_from.is_some_and(|p| p.len() != self.shapes.num_vertices()) {
            return Err(BlendError::InvalidOption(
                "the start positions must have one point per vertex".into(),
            ));
        }
        let mut x = match (start_from, &frame.predicted) {
            (None, Some(p)) => p.clone(),
            _ => self.start(lin, rotated, start_from),
        };
        frame.held.place(&mut x);
        Ok(x)
    }

    /// The Newton iteration of one frame from `x`, with the reference factor nearest `c`.
    #[allow(clippy::too_many_arguments)]
    fn iterate(
        &self,
        ws: &mut Workspace,
        prob: &Problem<'_>,
        c: &[f64],
        factor: Factor<'_>,
        mut x: Vec<f64>,
        mut stats: FrameStats,
        lin: &[Point],
    ) -> Result<(BlendResult, Vec<f64>), BlendError> {
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
                trust_region(prob, ws, &mut x, &mut stats, reference.as_deref(), probe)?
            }
            LinearSolver::Direct => projected_newton(prob, ws, &mut x, &mut stats)?,
        };
        if let Factor::Produce(out) = factor {
            if stats.converged {
                *out = reference_at(prob, ws, &x)?;
            }
        }
        if !stats.converged {
            stats.unconverged_vertices = prob.failed_vertices(&g);
        }
        let positions = predictor::output(&self.constraints, &x, lin);
        Ok((BlendResult { positions, stats }, x))
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
        r.stats.converged.then(|| difference(&r.positions, &p))
    }

    /// $r_{st} = x^*_0(c^{st}) - (P(c^{st}) + q_s(½) + q_t(½))$, solved from
    /// $P + q_s(½) + q_t(½)$ (see [`sampled_start`](super::sampled_start)).
    fn pair_field(&mut self, s: usize, t: usize, singles: Option<&[Point]>) -> Option<Vec<Point>> {
        let mut c = vec![0.0; self.rig.shapes.len()];
        c[s] = PAIR;
        c[t] = PAIR;
        let p = self.rig.predicted(&c);
        let from = match singles {
            Some(d) => shifted(p, d, 1.0),
            None => p,
        };
        let r = self
            .rig
            .solve(self.ws, &c, &[], Start::From(&from), Factor::Fresh);
        let r = r.ok()?;
        r.stats.converged.then(|| difference(&r.positions, &from))
    }
}

/// `x - p`, pointwise.
fn difference(x: &[Point], p: &[Point]) -> Vec<Point> {
    x.iter()
        .zip(p)
        .map(|(x, p)| std::array::from_fn(|k| x[k] - p[k]))
        .collect()
}
