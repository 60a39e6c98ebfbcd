//! Per-frame point targets: vertices pulled towards given positions (Ma et al. 2012, Sec. 4,
//! Fig. 5: a pulled vertex; and the contact constraints of Sec. 4, Fig. 2).
//!
//! Each target adds $E = \tfrac12 \kappa \lVert x_v - p \rVert^2$: gradient $\kappa (x_v - p)$,
//! Hessian $\kappa I$ on the vertex's own diagonal block, so targets never change the sparsity
//! pattern and can differ from frame to frame (keyframed pulls, contacts found per collision
//! round) without a new symbolic analysis. A *hard* target (the paper's boundary condition) is a
//! stiff one, [`PointTarget::HARD_STIFFNESS`] times the mean spring stiffness: the vertex then
//! sits at its target within about `1e-8` of the forces acting on it.

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
    /// Relative stiffness of a hard target.
    pub const HARD_STIFFNESS: f64 = 1e8;

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
