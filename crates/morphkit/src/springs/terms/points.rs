//! Per-frame point targets: vertices pulled towards given positions (Ma et al. 2012, Sec. 4,
//! Fig. 5: a pulled vertex; and the contact constraints of Sec. 4, Fig. 2).
//!
//! Each target adds $E = \tfrac12 \kappa \lVert x_v - p \rVert^2$: gradient $\kappa (x_v - p)$,
//! Hessian $\kappa I$ on the vertex's own diagonal block, so targets never change the sparsity
//! pattern and can differ from frame to frame (keyframed pulls, contacts found per collision
//! round) without a new symbolic analysis.
//!
//! A *hard* target (the paper's boundary condition; stiffness at least
//! [`PointTarget::HARD_STIFFNESS`]) is no energy: [`Held`] places the vertex exactly at its
//! target before the solve and holds it there, by zeroing its gradient and every Hessian entry of
//! its rows and columns except the diagonal. The pattern stays; the held coordinates get a zero
//! step. (A stiff penalty in their place, as before, made the conjugate-gradient residual
//! follow errors amplified by the stiffness: the 18k-vertex contact benchmark took 96 inner
//! iterations for 7 Newton steps, and the held vertices were only within about `1e-8` of the
//! forces of their targets.)

use super::{BlockHessian, EnergyTerm, HessianKind, TermParameters};
use crate::mesh::Point;

/// A vertex pulled towards a position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTarget {
    /// The vertex.
    pub vertex: u32,
    /// Where it is pulled, in world coordinates.
    pub position: Point,
    /// Stiffness κ in units of the mean spring stiffness; [`PointTarget::HARD_STIFFNESS`] for a
    /// boundary condition.
    pub stiffness: f64,
}

impl PointTarget {
    /// Relative stiffness of a hard target: a target at least this stiff is a boundary
    /// condition, held exactly (see the [module docs](self)).
    pub const HARD_STIFFNESS: f64 = 1e8;

    /// Whether the target is a boundary condition rather than a spring.
    pub fn is_hard(&self) -> bool {
        self.stiffness >= Self::HARD_STIFFNESS
    }

    /// A hard target (boundary condition).
    pub fn hard(vertex: u32, position: Point) -> Self {
        Self {
            vertex,
            position,
            stiffness: Self::HARD_STIFFNESS,
        }
    }
}

/// The targets of one solve as an energy term; `scale` turns relative stiffness into absolute.
pub(crate) struct PointTerm<'a> {
    pub targets: &'a [PointTarget],
    pub scale: f64,
}

impl EnergyTerm for PointTerm<'_> {
    fn name(&self) -> &'static str {
        "point targets"
    }

    fn couplings(&self, _out: &mut Vec<[u32; 2]>) {}

    fn prepare(&self, _c: &[f64]) -> TermParameters {
        TermParameters::default()
    }

    fn energy(&self, _p: &TermParameters, x: &[f64]) -> f64 {
        self.targets
            .iter()
            .map(|t| {
                let i = 3 * t.vertex as usize;
                let d2: f64 = (0..3).map(|a| (x[i + a] - t.position[a]).powi(2)).sum();
                0.5 * t.stiffness * self.scale * d2
            })
            .sum()
    }

    fn add_gradient(&self, p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64 {
        for t in self.targets {
            let i = 3 * t.vertex as usize;
            for a in 0..3 {
                g[i + a] += t.stiffness * self.scale * (x[i + a] - t.position[a]);
            }
        }
        self.energy(p, x)
    }

    fn add_hessian(
        &self,
        _p: &TermParameters,
        _x: &[f64],
        _kind: HessianKind,
        h: &mut BlockHessian,
    ) {
        for t in self.targets {
            let k = t.stiffness * self.scale;
            let b = [[k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k]];
            h.add(t.vertex as usize, t.vertex as usize, &b);
        }
    }
}

/// The vertices of one solve held at their hard targets: boundary conditions imposed on the
/// free coordinates without changing the Newton system's pattern.
#[derive(Debug, Default)]
pub(crate) struct Held {
    /// `#V` flags (empty when nothing is held).
    mask: Vec<bool>,
    /// The held vertices with their positions.
    targets: Vec<(usize, Point)>,
}

impl Held {
    /// The hard targets of `targets` on vertices whose three coordinates are all free
    /// (`dof_free(v)`); a hard target on a fixed vertex changes nothing, as before.
    pub fn new(n: usize, targets: &[PointTarget], dof_free: impl Fn(usize) -> bool) -> Self {
        let mut held = Self::default();
        for t in targets.iter().filter(|t| t.is_hard()) {
            let v = t.vertex as usize;
            if dof_free(v) {
                if held.mask.is_empty() {
                    held.mask = vec![false; n];
                }
                held.mask[v] = true;
                held.targets.push((v, t.position));
            }
        }
        held
    }

    /// Whether nothing is held.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty()
    }

    /// The held vertices.
    pub fn vertices(&self) -> impl Iterator<Item = usize> + '_ {
        self.targets.iter().map(|t| t.0)
    }

    /// Puts the held vertices of `x` (`3 #V`) at their targets.
    pub fn place(&self, x: &mut [f64]) {
        for (v, p) in &self.targets {
            x[3 * v..3 * v + 3].copy_from_slice(p);
        }
    }

    /// Zeroes the gradient `g` (`3 #V`) at held coordinates.
    pub fn mask_gradient(&self, g: &mut [f64]) {
        for (v, _) in &self.targets {
            g[3 * v..3 * v + 3].iter_mut().for_each(|c| *c = 0.0);
        }
    }

    /// Decouples the held vertices in `h`: their off-diagonal blocks and the off-diagonal
    /// entries of their diagonal blocks become zero, their diagonal entries stay (or become 1
    /// where not positive), so that every Newton step is zero on them.
    pub fn mask_hessian(&self, h: &mut BlockHessian) {
        if self.is_empty() {
            return;
        }
        let pattern = std::sync::Arc::clone(h.pattern_arc());
        for i in 0..pattern.num_vertices() {
            let start = pattern.row_start(i);
            for (k, &j) in pattern.row(i).iter().enumerate() {
                if self.mask[i] || self.mask[j as usize] {
                    h.off[start + k] = [[0.0; 3]; 3];
                }
            }
        }
        for (v, _) in &self.targets {
            let b = &mut h.diag[*v];
            for a in 0..3 {
                for c in 0..3 {
                    if a != c {
                        b[a][c] = 0.0;
                    } else if b[a][a].is_nan() || b[a][a] <= 0.0 {
                        b[a][a] = 1.0;
                    }
                }
            }
        }
    }
}
