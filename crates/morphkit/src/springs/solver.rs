//! The equilibrium solver (Ma et al. 2012, Eq. 2–4, Sec. 3.2; math notes §1).
//!
//! - [`LinearSolver::LaggedPcg`] (default): trust-region Newton–CG on the *exact* Hessian
//!   (Steihaug–Toint, Nocedal & Wright Alg. 7.2 / Conn, Gould & Toint §7.5.1), preconditioned by
//!   the lagged Cholesky factor of a projected Hessian, which also defines the trust-region
//!   norm. Negative curvature of compressed springs is followed to the trust-region boundary
//!   instead of being clamped away, so the iteration does not creep along soft modes, and it
//!   converges quadratically once the exact Hessian is positive definite. Inner solves stop at
//!   an Eisenstat–Walker-style forcing term `0.1 ‖g‖∞/‖g₀‖∞` or as soon as the linear residual is
//!   a tenth of the gradient tolerance.
//! - [`LinearSolver::Direct`]: projected Newton with an Armijo line search and a fresh
//!   factorization per step.
//!
//! [`PhysicalBlend::new`] does all the set-up once: springs and their rest lengths in every
//! shape, constraints, the sparsity pattern of the Hessian over the free degrees of freedom with
//! a precomputed value slot for every spring block, and the symbolic Cholesky analysis.
//! [`PhysicalBlend::solve`] then only assembles values, refactorizes numerically and solves.
//! The pattern never changes (projection keeps every block, clamped or not), so the symbolic
//! analysis is reused for every Newton step of every frame.
//!
//! Each solve warm-starts from the previous equilibrium. When the weights jump by more than
//! [`BlendOptions::max_weight_step`], the solver walks there in equal sub-steps (a continuation),
//! which keeps each Newton solve in the basin of the equilibrium that continues the path from
//! the base shape: the physically meaningful one of the several a spring system can have
//! (the paper's Sec. 5, "Limitations").

use super::constraints::{Constraints, FixedVertices};
use super::energy::{for_each_block, gradient};
use super::pcg::HessianOperator;
use super::steihaug::{steihaug, StopRule, Termination};
use super::{BlendError, RestLengths, SpringOptions, SpringSet, StiffnessRule, Weights};
use crate::geom::kabsch;
use crate::mesh::{validate, Point, ShapeSet, Topology};
use crate::sparse::{Cholesky, Ordering, SolveError, SymmetricPattern};
use std::time::Instant;

/// Options of the physical blend. Every field has a meaningful default.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendOptions {
    /// Which springs and how stiff.
    pub springs: SpringOptions,
    /// Boundary conditions. Default [`FixedVertices::Auto`].
    pub fixed: FixedVertices,
    /// Convergence: stop when $\max_k |\partial E / \partial x_k| \le$ `gradient_tolerance`
    /// $\cdot k_0 \cdot s$ over the free coordinates, with $s = 1$ for the
    /// $k = k_0/\bar r$ rule (the gradient is then a force in units of $k_0$ times strain, so the
    /// tolerance does not depend on the mesh's scale) and $s$ = the mean base rest length for
    /// uniform stiffness. Default `1e-6`: residual forces equivalent to a strain of one part
    /// per million on a single spring, far below anything visible.
    pub gradient_tolerance: f64,
    /// Newton iterations allowed per (sub-)step before giving up with `converged = false`.
    /// Default 200: surface-only spring systems of real meshes have soft, nearly unstable modes
    /// (thin parts under compression) along which Newton converges only linearly.
    pub max_newton_iterations: usize,
    /// Largest change of any shape coefficient per continuation sub-step. Default `0.25`.
    pub max_weight_step: f64,
    /// Interpolated rest lengths are clamped to at least this fraction of the base rest length
    /// (reported per frame). Default `0.05`.
    pub min_rest_fraction: f64,
    /// Armijo sufficient-decrease constant. Default `1e-4`.
    pub armijo: f64,
    /// How Newton systems are solved. Default [`LinearSolver::LaggedPcg`].
    pub linear_solver: LinearSolver,
    /// Fill-reducing ordering of the Hessian. Default [`FillOrdering::NestedDissection`].
    pub ordering: FillOrdering,
}

/// Fill-reducing ordering for the Hessian's Cholesky factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FillOrdering {
    /// faer's approximate minimum degree on the coordinate graph.
    Amd,
    /// METIS nested dissection on the vertex graph, expanded to coordinates. The default:
    /// less fill on surface meshes of a few thousand vertices and more.
    #[default]
    NestedDissection,
}

/// How each Newton system $H \Delta = -\nabla E$ is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// A fresh numeric Cholesky factorization at every Newton step (symbolic analysis reused).
    Direct,
    /// Trust-region Newton–CG (Steihaug–Toint) on the exact Hessian, preconditioned by the most
    /// recent factorization of a projected Hessian, refactorizing only when CG stops making
    /// progress within a few iterations. The default: several times faster along animations
    /// and on one-shot blends of real meshes, with the same converged result.
    #[default]
    LaggedPcg,
}

impl Default for BlendOptions {
    fn default() -> Self {
        Self {
            springs: SpringOptions::default(),
            fixed: FixedVertices::Auto,
            gradient_tolerance: 1e-6,
            max_newton_iterations: 200,
            max_weight_step: 0.25,
            min_rest_fraction: 0.05,
            armijo: 1e-4,
            linear_solver: LinearSolver::LaggedPcg,
            ordering: FillOrdering::NestedDissection,
        }
    }
}

/// Solver statistics of one [`PhysicalBlend::solve`].
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Newton iterations, summed over sub-steps.
    pub newton_iterations: usize,
    /// Line-search step halvings, summed.
    pub line_search_backtracks: usize,
    /// Numeric factorizations (including regularization retries).
    pub factorizations: usize,
    /// Conjugate-gradient iterations of the lagged-preconditioner solver.
    pub cg_iterations: usize,
    /// Continuation sub-steps taken.
    pub substeps: usize,
    /// Final $\max_k |\partial E/\partial x_k|$ over free coordinates.
    pub gradient_norm: f64,
    /// The tolerance it was compared with (absolute).
    pub gradient_tolerance: f64,
    /// Final energy.
    pub energy: f64,
    /// Whether the gradient reached the tolerance.
    pub converged: bool,
    /// Springs whose interpolated rest length was clamped.
    pub clamped_springs: usize,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// A blended shape and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendResult {
    /// Vertex positions, `#V`.
    pub positions: Vec<Point>,
    /// Solver statistics.
    pub stats: FrameStats,
}

/// Physical blendshape solver: build once, then [`solve`](Self::solve) for as many weight
/// vectors as needed (a slider, an animation).
pub struct PhysicalBlend {
    shapes: ShapeSet,
    springs: SpringSet,
    constraints: Constraints,
    options: BlendOptions,
    /// Free-DOF index of each of the `3 #V` coordinates, `u32::MAX` when fixed.
    dof_index: Vec<u32>,
    /// Value slots of each spring's 21 lower-triangle Hessian entries (6 + 6 + 9).
    slots: Vec<[u32; 21]>,
    diag_slots: Vec<u32>,
    chol: Cholesky,
    values: Vec<f64>,
    /// Current equilibrium, in solver coordinates (before gauge alignment), `3 #V`.
    x: Vec<f64>,
    /// Shape coefficients of the current equilibrium.
    coefficients: Vec<f64>,
    tol_abs: f64,
    regularization: f64,
    /// Diagonal shift of the current factorization; `None` until one succeeded.
    factor_shift: Option<f64>,
    /// Per-spring Hessian blocks of the current Newton step.
    blocks: Vec<super::energy::Block>,
    /// The equilibrium before the current one and its coefficients (for the secant predictor).
    previous: Option<(Vec<f64>, Vec<f64>)>,
    /// The equilibrium before `previous` (for the quadratic predictor).
    older: Option<(Vec<f64>, Vec<f64>)>,
    timing: Timing,
}

/// Running averages of the cost of one factorization and one CG iteration, in seconds.
#[derive(Clone, Copy, Debug, Default)]
struct Timing {
    factor: f64,
    cg: f64,
}

impl std::fmt::Debug for PhysicalBlend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicalBlend")
            .field("vertices", &self.shapes.num_vertices())
            .field("springs", &self.springs.len())
            .field("free_dofs", &self.chol.pattern().n())
            .finish()
    }
}

impl PhysicalBlend {
    /// Builds springs, constraints, the Hessian pattern and its symbolic factorization.
    pub fn new(shapes: &ShapeSet, options: &BlendOptions) -> Result<Self, BlendError> {
        let o = options;
        if !(o.gradient_tolerance.is_finite() && o.gradient_tolerance > 0.0) {
            return Err(BlendError::InvalidOption(format!(
                "gradient_tolerance must be positive, got {}",
                o.gradient_tolerance
            )));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !(positive(o.springs.k0) && non_negative(o.springs.bending_scale)) {
            return Err(BlendError::InvalidOption(
                "k0 must be positive and bending_scale non-negative".into(),
            ));
        }
        if !positive(o.max_weight_step)
            || !(0.0..1.0).contains(&o.min_rest_fraction)
            || o.min_rest_fraction <= 0.0
        {
            return Err(BlendError::InvalidOption(
                "max_weight_step must be positive and min_rest_fraction in (0, 1)".into(),
            ));
        }
        for s in 0..shapes.len() {
            validate(&shapes.mesh(s))?;
        }
        let n = shapes.num_vertices();
        let topology = Topology::new(n, shapes.triangles());
        let springs = SpringSet::new(shapes, &topology, &o.springs);
        if springs.is_empty() {
            return Err(BlendError::NoSprings);
        }
        let constraints = Constraints::new(shapes, &topology, &o.fixed)?;

        let mut dof_index = vec![u32::MAX; 3 * n];
        let mut nfree = 0u32;
        for (k, fixed) in constraints.fixed_dof.iter().enumerate() {
            if !fixed {
                dof_index[k] = nfree;
                nfree += 1;
            }
        }
        let nfree = nfree as usize;
        // Lower-triangle entries of every spring block, in a fixed order.
        let mut entries = Vec::with_capacity(21 * springs.len());
        let mut owner = Vec::with_capacity(21 * springs.len());
        for (q, s) in springs.springs().iter().enumerate() {
            for (e, (r, c)) in block_entries(s.i as usize, s.j as usize)
                .into_iter()
                .enumerate()
            {
                let (ri, ci) = (dof_index[r], dof_index[c]);
                if ri != u32::MAX && ci != u32::MAX {
                    entries.push((ri as usize, ci as usize));
                    owner.push((q, e));
                }
            }
        }
        let (pattern, entry_slots) = SymmetricPattern::new(nfree, &entries)?;
        let mut slots = vec![[u32::MAX; 21]; springs.len()];
        for ((q, e), s) in owner.into_iter().zip(entry_slots) {
            slots[q][e] = s as u32;
        }
        let diag_slots = (0..nfree).map(|k| pattern.diag_slot(k) as u32).collect();
        let values = vec![0.0; pattern.nnz()];
        let ordering = match o.ordering {
            FillOrdering::Amd => Ordering::Amd,
            FillOrdering::NestedDissection => {
                Ordering::Custom(vertex_nested_dissection(&springs, &dof_index, nfree)?)
            }
        };
        let chol = Cholesky::analyze(pattern, ordering)?;

        let scale = match o.springs.stiffness {
            StiffnessRule::InverseRestLength => 1.0,
            StiffnessRule::Uniform => {
                let r = springs.rest_lengths(0);
                r.iter().sum::<f64>() / r.len() as f64
            }
        };
        let x = initial_state(shapes, &constraints);
        let mut coefficients = vec![0.0; shapes.len()];
        coefficients[0] = 1.0;
        Ok(Self {
            shapes: shapes.clone(),
            springs,
            constraints,
            options: o.clone(),
            dof_index,
            slots,
            diag_slots,
            chol,
            values,
            x,
            coefficients,
            tol_abs: o.gradient_tolerance * o.springs.k0 * scale,
            regularization: 0.0,
            factor_shift: None,
            blocks: Vec::new(),
            previous: None,
            older: None,
            timing: Timing::default(),
        })
    }

    /// The springs.
    pub fn springs(&self) -> &SpringSet {
        &self.springs
    }
    /// The resolved constraints.
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }
    /// Number of free unknowns of the Newton system.
    pub fn num_free_dofs(&self) -> usize {
        self.chol.pattern().n()
    }
    /// Number of stored entries of the Cholesky factor (memory ≈ 8 bytes each).
    pub fn factor_nnz(&self) -> usize {
        self.chol.factor_nnz()
    }
    /// The shape set.
    pub fn shapes(&self) -> &ShapeSet {
        &self.shapes
    }

    /// Forgets the warm start: the next solve starts again from the base shape.
    pub fn reset(&mut self) {
        self.x = initial_state(&self.shapes, &self.constraints);
        self.coefficients.iter_mut().for_each(|c| *c = 0.0);
        self.coefficients[0] = 1.0;
        self.previous = None;
        self.older = None;
    }

    /// The equilibrium for `weights`, warm-started from the previous solve.
    ///
    /// A solve that does not reach the tolerance within the iteration budget still returns the
    /// best state found, with `stats.converged == false`; it never returns NaNs.
    pub fn solve(&mut self, weights: &Weights) -> Result<BlendResult, BlendError> {
        let start = Instant::now();
        let target = weights.coefficients(self.shapes.len())?;
        // A diagonal shift needed by an earlier, harder solve is not carried over.
        self.regularization = 0.0;
        let jump = target
            .iter()
            .zip(&self.coefficients)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let substeps = ((jump / self.options.max_weight_step).ceil() as usize).max(1);
        let from = self.coefficients.clone();
        let mut stats = FrameStats {
            substeps,
            gradient_tolerance: self.tol_abs,
            ..Default::default()
        };
        for step in 1..=substeps {
            let t = step as f64 / substeps as f64;
            let c: Vec<f64> = from
                .iter()
                .zip(&target)
                .map(|(a, b)| a + t * (b - a))
                .collect();
            let rest = RestLengths::interpolate(&self.springs, &c, self.options.min_rest_fraction);
            let before = self.x.clone();
            self.predict(&c, &rest.values);
            self.place_fixed(&c);
            match self.options.linear_solver {
                LinearSolver::Direct => self.newton(&rest.values, &mut stats)?,
                LinearSolver::LaggedPcg => self.newton_trust_region(&rest.values, &mut stats)?,
            }
            stats.clamped_springs = rest.clamped.len();
            self.older = self.previous.take();
            self.previous = Some((before, std::mem::replace(&mut self.coefficients, c)));
        }
        self.coefficients = target.clone();
        let positions = self.output(&target);
        stats.seconds = start.elapsed().as_secs_f64();
        Ok(BlendResult { positions, stats })
    }

    /// Secant predictor: when the weights keep moving in the direction of the previous solve,
    /// extrapolate the previous motion of the free coordinates (first-order continuation), or,
    /// with three equilibria on that line, the quadratic through them (second order). The
    /// lowest-energy of the current state and the two predictions is kept.
    fn predict(&mut self, c: &[f64], rest: &[f64]) {
        let Some((x_prev, c_prev)) = &self.previous else {
            return;
        };
        let d_old: Vec<f64> = self
            .coefficients
            .iter()
            .zip(c_prev)
            .map(|(a, b)| a - b)
            .collect();
        let d_new: Vec<f64> = c
            .iter()
            .zip(&self.coefficients)
            .map(|(a, b)| a - b)
            .collect();
        let (oo, nn, on) = (
            dot(&d_old, &d_old),
            dot(&d_new, &d_new),
            dot(&d_old, &d_new),
        );
        if oo == 0.0 || nn == 0.0 || on <= 0.99 * (oo * nn).sqrt() {
            return;
        }
        let lambda = on / oo;
        let mut trial = self.x.clone();
        for (k, &i) in self.dof_index.iter().enumerate() {
            if i != u32::MAX {
                trial[k] += lambda * (self.x[k] - x_prev[k]);
            }
        }
        let e_now = super::energy::energy(&self.springs, rest, &self.x);
        let e_trial = super::energy::energy(&self.springs, rest, &trial);
        let quadratic = self.quadratic_prediction(c, nn.sqrt());
        let e_quad = quadratic.as_ref().map_or(f64::INFINITY, |q| {
            super::energy::energy(&self.springs, rest, q)
        });
        if let Some(q) = quadratic.filter(|_| e_quad < e_trial.min(e_now)) {
            self.x = q;
        } else if e_trial.is_finite() && e_trial < e_now {
            self.x = trial;
        }
    }

    /// Second-order continuation: the quadratic through the last three equilibria, when their
    /// coefficients and `c` lie on one line, evaluated at `c` (Lagrange form in the arc length
    /// `s` along that line; the current equilibrium is at `s = 0`, `c` at `s = step`).
    fn quadratic_prediction(&self, c: &[f64], step: f64) -> Option<Vec<f64>> {
        let (x1, c1) = self.previous.as_ref()?;
        let (x0, c0) = self.older.as_ref()?;
        let u: Vec<f64> = c
            .iter()
            .zip(&self.coefficients)
            .map(|(a, b)| (a - b) / step)
            .collect();
        let along = |ck: &[f64]| -> Option<f64> {
            let d: Vec<f64> = ck
                .iter()
                .zip(&self.coefficients)
                .map(|(a, b)| a - b)
                .collect();
            let s = dot(&d, &u);
            let off = (dot(&d, &d) - s * s).max(0.0).sqrt();
            (s < 0.0 && off <= 1e-9 * s.abs()).then_some(s)
        };
        let (s0, s1) = (along(c0)?, along(c1)?);
        if !(s0 < s1 && s1 - s0 > 1e-12 && -s1 > 1e-12) {
            return None;
        }
        let s = step;
        let l0 = (s - s1) * s / ((s0 - s1) * s0);
        let l1 = (s - s0) * s / ((s1 - s0) * s1);
        let l2 = (s - s0) * (s - s1) / (s0 * s1);
        let mut q = self.x.clone();
        for (k, &i) in self.dof_index.iter().enumerate() {
            if i != u32::MAX {
                q[k] = l0 * x0[k] + l1 * x1[k] + l2 * self.x[k];
            }
        }
        Some(q)
    }

    /// Sets fixed vertices to the linear interpolation of their positions.
    fn place_fixed(&mut self, c: &[f64]) {
        for &v in &self.constraints.fixed {
            let v = v as usize;
            for a in 0..3 {
                self.x[3 * v + a] = c
                    .iter()
                    .enumerate()
                    .map(|(s, w)| w * self.shapes.positions(s)[v][a])
                    .sum();
            }
        }
    }

    /// $g^\top s$ for a full-length `g` and a free-coordinate vector `s`.
    fn free_dot(&self, g: &[f64], s: &[f64]) -> f64 {
        let free = self
            .dof_index
            .iter()
            .enumerate()
            .filter(|(_, i)| **i != u32::MAX);
        free.map(|(k, &i)| g[k] * s[i as usize]).sum()
    }

    fn max_free_gradient(&self, g: &[f64]) -> f64 {
        g.iter()
            .zip(&self.dof_index)
            .filter(|(_, i)| **i != u32::MAX)
            .map(|(v, _)| v.abs())
            .fold(0.0, f64::max)
    }

    fn newton(&mut self, rest: &[f64], stats: &mut FrameStats) -> Result<(), BlendError> {
        let n3 = self.x.len();
        let mut g = vec![0.0; n3];
        let mut e = gradient(&self.springs, rest, &self.x, &mut g);
        let mut gmax = self.max_free_gradient(&g);
        let mut x_trial = vec![0.0; n3];
        let mut g_trial = vec![0.0; n3];
        stats.converged = gmax <= self.tol_abs;
        let mut iter = 0;
        // Projected Newton converges only linearly when the equilibrium has compressed springs
        // (the projection then differs from the true Hessian there). Once a full step is
        // accepted, the exact Hessian is tried; it is positive definite near a stable
        // equilibrium, which restores quadratic convergence. If its factorization finds a
        // non-positive pivot, the projected Hessian takes over again for this solve.
        let mut exact = false;
        // Gradient norm when the exact Hessian last failed: retried after a tenfold decrease.
        let mut exact_failed_at = f64::INFINITY;
        while !stats.converged && iter < self.options.max_newton_iterations {
            iter += 1;
            stats.newton_iterations += 1;
            let mut step = match self.newton_direction(rest, &g, exact, stats)? {
                Some(step) => step,
                None => {
                    exact = false;
                    exact_failed_at = gmax;
                    match self.newton_direction(rest, &g, false, stats)? {
                        Some(step) => step,
                        None => break,
                    }
                }
            };
            // Armijo backtracking on the energy.
            let slope = self.free_dot(&g, &step);
            if slope >= 0.0 {
                // Not a descent direction (round-off at convergence): fall back to steepest descent.
                for (k, &i) in self.dof_index.iter().enumerate() {
                    if i != u32::MAX {
                        step[i as usize] = -g[k];
                    }
                }
            }
            let slope = self.free_dot(&g, &step);
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..60 {
                x_trial.copy_from_slice(&self.x);
                for (k, &i) in self.dof_index.iter().enumerate() {
                    if i != u32::MAX {
                        x_trial[k] += t * step[i as usize];
                    }
                }
                let e_trial = gradient(&self.springs, rest, &x_trial, &mut g_trial);
                if !e_trial.is_finite() {
                    stats.line_search_backtracks += 1;
                    t *= 0.5;
                    continue;
                }
                let g_trial_max = self.max_free_gradient(&g_trial);
                // Near the minimum, energy differences drown in round-off; then accept a step
                // that reduces the gradient instead.
                let roundoff = 1e-13 * e.abs().max(f64::MIN_POSITIVE);
                if e_trial <= e + self.options.armijo * t * slope
                    || (e_trial - e <= roundoff && g_trial_max < gmax)
                {
                    accepted = true;
                    e = e_trial;
                    gmax = g_trial_max;
                    exact = t == 1.0 && gmax < 0.1 * exact_failed_at;
                    std::mem::swap(&mut self.x, &mut x_trial);
                    std::mem::swap(&mut g, &mut g_trial);
                    break;
                }
                stats.line_search_backtracks += 1;
                t *= 0.5;
            }
            if !e.is_finite() {
                return Err(BlendError::Diverged { iteration: iter });
            }
            stats.converged = gmax <= self.tol_abs;
            if !accepted {
                break; // stalled: no decrease possible in floating point
            }
        }
        stats.gradient_norm = gmax;
        stats.energy = e;
        Ok(())
    }

    /// Solves $H \Delta = -\nabla E$ on the free coordinates with the projected Hessian,
    /// adding a small multiple of the identity when needed: flat regions have no stiffness
    /// normal to their plane at rest, and round-off can make such a pivot non-positive.
    ///
    /// With `exact`, the unprojected Hessian is used and `None` is returned when it is not
    /// positive definite.
    fn newton_direction(
        &mut self,
        rest: &[f64],
        g: &[f64],
        exact: bool,
        stats: &mut FrameStats,
    ) -> Result<Option<Vec<f64>>, BlendError> {
        self.blocks.clear();
        let blocks = &mut self.blocks;
        for_each_block(&self.springs, rest, &self.x, !exact, |_, _, _, b| {
            blocks.push(*b)
        });
        let mut rhs = vec![0.0; self.diag_slots.len()];
        for (k, &i) in self.dof_index.iter().enumerate() {
            if i != u32::MAX {
                rhs[i as usize] = -g[k];
            }
        }
        if !self.factorize_blocks(exact, stats)? {
            return Ok(None);
        }
        self.chol.solve_in_place(&mut rhs, 1)?;
        Ok(Some(rhs))
    }

    /// Fills `self.blocks` with the exact (or projected) Hessian blocks at `self.x`.
    fn compute_blocks(&mut self, rest: &[f64], projected: bool) {
        self.blocks.clear();
        let blocks = &mut self.blocks;
        for_each_block(&self.springs, rest, &self.x, projected, |_, _, _, b| {
            blocks.push(*b)
        });
    }

    /// Trust-region Newton–CG on the exact Hessian (Steihaug–Toint), preconditioned by the
    /// lagged Cholesky factor of a projected Hessian, which also defines the trust-region norm.
    /// The factor is refreshed only when the inner iteration stops making progress.
    fn newton_trust_region(
        &mut self,
        rest: &[f64],
        stats: &mut FrameStats,
    ) -> Result<(), BlendError> {
        let n3 = self.x.len();
        let nfree = self.diag_slots.len();
        let mut g = vec![0.0; n3];
        let mut e = gradient(&self.springs, rest, &self.x, &mut g);
        let mut gmax = self.max_free_gradient(&g);
        let g0max = gmax;
        let mut x_trial = vec![0.0; n3];
        let mut g_trial = vec![0.0; n3];
        let mut gfree = vec![0.0; nfree];
        stats.converged = gmax <= self.tol_abs;
        let mut refactor = self.factor_shift.is_none();
        let mut blocks_current = false;
        let mut radius = f64::NAN;
        // Inner-iteration budget multiplier: a truncated inner solve wastes an outer iteration.
        let mut extend = 1.0;
        let mut iter = 0;
        while !stats.converged && iter < self.options.max_newton_iterations {
            iter += 1;
            stats.newton_iterations += 1;
            if refactor {
                self.compute_blocks(rest, true);
                self.factorize_blocks(false, stats)?;
                blocks_current = false;
                refactor = false;
            }
            if !blocks_current {
                self.compute_blocks(rest, false);
                blocks_current = true;
            }
            for (k, &i) in self.dof_index.iter().enumerate() {
                if i != u32::MAX {
                    gfree[i as usize] = g[k];
                }
            }
            if radius.is_nan() {
                let mg = self.chol.solve(&gfree)?;
                radius = 2.0 * dot(&gfree, &mg).max(0.0).sqrt();
            }
            let op = HessianOperator {
                springs: &self.springs,
                blocks: &self.blocks,
                dof_index: &self.dof_index,
                mu: 0.0,
            };
            let stop = StopRule {
                rtol: (0.1 * gmax / g0max).clamp(1e-6, 0.1),
                atol_max: 0.1 * self.tol_abs,
                max_iter: cg_budget(self.timing, extend),
            };
            let t = Instant::now();
            let before = stats.cg_iterations;
            let result = steihaug(
                &op,
                &self.chol,
                &gfree,
                radius,
                &stop,
                &mut stats.cg_iterations,
            );
            let done = (stats.cg_iterations - before).max(1) as f64;
            self.timing.cg = 0.5 * self.timing.cg + 0.5 * t.elapsed().as_secs_f64() / done;
            let Some(step) = result else {
                refactor = true;
                continue;
            };
            extend = if step.termination == Termination::Budget {
                (2.0 * extend).min(25.0)
            } else {
                1.0
            };
            if step.termination == Termination::Budget && step.relative_residual > 0.1 {
                // The lagged preconditioner no longer fits the Hessian: refresh it.
                refactor = true;
                if step.relative_residual > 0.9 {
                    continue;
                }
            }
            x_trial.copy_from_slice(&self.x);
            for (k, &i) in self.dof_index.iter().enumerate() {
                if i != u32::MAX {
                    x_trial[k] += step.step[i as usize];
                }
            }
            let e_trial = gradient(&self.springs, rest, &x_trial, &mut g_trial);
            let g_trial_max = self.max_free_gradient(&g_trial);
            // Near the minimum, energy differences drown in round-off; then a step that
            // reduces the gradient counts as a success.
            let roundoff = 1e-13 * e.abs().max(f64::MIN_POSITIVE);
            let actual = e - e_trial;
            let rho = if !e_trial.is_finite() {
                f64::NEG_INFINITY
            } else if actual.abs() <= roundoff || step.decrease <= roundoff {
                if g_trial_max < gmax {
                    1.0
                } else {
                    f64::NEG_INFINITY
                }
            } else {
                actual / step.decrease.max(f64::MIN_POSITIVE)
            };
            if rho < 0.25 {
                radius = 0.25 * step.m_norm.min(radius);
            } else if rho > 0.75 && step.termination == Termination::Boundary {
                radius *= 2.0;
            }
            if rho > 1e-4 {
                e = e_trial;
                gmax = g_trial_max;
                std::mem::swap(&mut self.x, &mut x_trial);
                std::mem::swap(&mut g, &mut g_trial);
                blocks_current = false;
            } else {
                stats.line_search_backtracks += 1;
                if radius.is_nan() || radius <= 1e-300 {
                    break;
                }
            }
            stats.converged = gmax <= self.tol_abs;
        }
        if !e.is_finite() {
            return Err(BlendError::Diverged { iteration: iter });
        }
        stats.gradient_norm = gmax;
        stats.energy = e;
        Ok(())
    }

    /// Assembles the Hessian from `self.blocks` and factorizes it (symbolic analysis reused),
    /// adding a small multiple of the identity when a pivot is not positive. With `exact`
    /// (unprojected blocks), returns `false` instead of shifting when it is not positive
    /// definite.
    fn factorize_blocks(
        &mut self,
        exact: bool,
        stats: &mut FrameStats,
    ) -> Result<bool, BlendError> {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (s, b) in self.slots.iter().zip(&self.blocks) {
            let mut e = 0;
            for _vertex in 0..2 {
                for a in 0..3 {
                    for c in 0..=a {
                        if s[e] != u32::MAX {
                            self.values[s[e] as usize] += b[a][c];
                        }
                        e += 1;
                    }
                }
            }
            for a in 0..3 {
                for c in 0..3 {
                    if s[e] != u32::MAX {
                        self.values[s[e] as usize] -= b[a][c];
                    }
                    e += 1;
                }
            }
        }
        let mean_diag = self
            .diag_slots
            .iter()
            .map(|&d| self.values[d as usize])
            .sum::<f64>()
            / self.diag_slots.len().max(1) as f64;
        let mut mu = self.regularization.max(1e-10 * mean_diag);
        self.factor_shift = None;
        loop {
            let mut v = self.values.clone();
            for &d in &self.diag_slots {
                v[d as usize] += mu;
            }
            stats.factorizations += 1;
            let t = Instant::now();
            let result = self.chol.factorize(&v);
            self.timing.factor = 0.5 * self.timing.factor + 0.5 * t.elapsed().as_secs_f64();
            match result {
                Ok(()) => {
                    self.factor_shift = Some(mu);
                    return Ok(true);
                }
                Err(SolveError::NotPositiveDefinite { .. }) if exact => return Ok(false),
                Err(SolveError::NotPositiveDefinite { .. }) if mu < 1e-2 * mean_diag => {
                    mu = (mu * 100.0).max(1e-8 * mean_diag);
                    self.regularization = mu;
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Current equilibrium as positions, gauge components aligned to the linear blend.
    fn output(&self, c: &[f64]) -> Vec<Point> {
        let mut p: Vec<Point> = self.x.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect();
        for comp in self.constraints.gauges.iter().map(|g| &g.vertices) {
            let from: Vec<Point> = comp.iter().map(|&v| p[v as usize]).collect();
            let to: Vec<Point> = comp
                .iter()
                .map(|&v| {
                    let mut q = [0.0; 3];
                    for (s, w) in c.iter().enumerate() {
                        for a in 0..3 {
                            q[a] += w * self.shapes.positions(s)[v as usize][a];
                        }
                    }
                    q
                })
                .collect();
            let fit = kabsch(&from, &to, &[]);
            for &v in comp {
                p[v as usize] = fit.apply(p[v as usize]);
            }
        }
        p
    }
}

/// The 21 lower-triangle entries `(row, col)` of a spring block over coordinates, in the order
/// the assembly loop visits them: `ii` (6), `jj` (6), then the 9 coupling entries
/// `(3j + c, 3i + a)`, row-major in `(a, c)`.
fn block_entries(i: usize, j: usize) -> [(usize, usize); 21] {
    let mut out = [(0, 0); 21];
    let mut e = 0;
    for v in [i, j] {
        for a in 0..3 {
            for c in 0..=a {
                out[e] = (3 * v + a, 3 * v + c);
                e += 1;
            }
        }
    }
    for a in 0..3 {
        for c in 0..3 {
            out[e] = (3 * j + c, 3 * i + a);
            e += 1;
        }
    }
    out
}

/// The base shape in solver coordinates: gauge components rotated into their frames.
fn initial_state(shapes: &ShapeSet, constraints: &Constraints) -> Vec<f64> {
    let mut p = shapes.positions(0).to_vec();
    for g in &constraints.gauges {
        for &v in &g.vertices {
            p[v as usize] = g.to_solver(p[v as usize]);
        }
    }
    p.into_iter().flatten().collect()
}

/// METIS ordering of the vertices with free coordinates (graph: the springs), expanded so that
/// each vertex's free coordinates are eliminated together.
fn vertex_nested_dissection(
    springs: &SpringSet,
    dof_index: &[u32],
    nfree: usize,
) -> Result<Vec<usize>, SolveError> {
    let nv = dof_index.len() / 3;
    let has_free = |v: usize| (0..3).any(|a| dof_index[3 * v + a] != u32::MAX);
    let mut local = vec![usize::MAX; nv];
    let mut verts = Vec::new();
    for v in 0..nv {
        if has_free(v) {
            local[v] = verts.len();
            verts.push(v);
        }
    }
    let mut adj = vec![Vec::new(); verts.len()];
    for s in springs.springs() {
        let (a, b) = (local[s.i as usize], local[s.j as usize]);
        if a != usize::MAX && b != usize::MAX {
            adj[a].push(b);
            adj[b].push(a);
        }
    }
    let perm = crate::sparse::metis::nested_dissection(&adj)?;
    let mut out = Vec::with_capacity(nfree);
    for p in perm {
        let v = verts[p];
        for a in 0..3 {
            if dof_index[3 * v + a] != u32::MAX {
                out.push(dof_index[3 * v + a] as usize);
            }
        }
    }
    Ok(out)
}

/// CG iterations worth one factorization (measured), times `extend` (doubled after each inner
/// solve that ran out of iterations), within bounds. Small systems, whose factorization takes
/// only milliseconds, get a larger floor: their CG iterations cost mostly fixed overhead.
fn cg_budget(timing: Timing, extend: f64) -> usize {
    let floor = if timing.factor < 5e-3 { 20.0 } else { 8.0 };
    (extend * 0.7 * timing.factor / timing.cg.max(1e-9)).clamp(floor * extend, 200.0) as usize
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// One-shot physical blend: builds a [`PhysicalBlend`] and solves once.
pub fn blend(
    shapes: &ShapeSet,
    weights: &Weights,
    options: &BlendOptions,
) -> Result<BlendResult, BlendError> {
    PhysicalBlend::new(shapes, options)?.solve(weights)
}
