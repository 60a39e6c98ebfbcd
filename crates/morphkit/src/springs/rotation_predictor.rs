//! A rotation-aware predictor: Poisson shape interpolation of the shapes' deformation
//! gradients (Alexa et al. 2000; Xu et al. 2005, "Poisson shape interpolation").
//!
//! Per triangle $t$ and shape $s$, the deformation gradient from the base, $D_{s,t}$
//! ([`GradientOperator`]), is split by polar decomposition into $R_{s,t} S_{s,t}$
//! ([`polar_decomposition`]). For coefficients $c$ the blended gradient is
//!
//! $$\bar D_t = \exp\Big(\sum_s c_s \log R_{s,t}\Big)\, \Big(c_0 I + \sum_{s \ge 1} c_s S_{s,t}\Big),$$
//!
//! rotations blended in the log map (axis–angle vectors, the branch with angle ≤ π), stretches
//! linearly, and one prefactored Poisson solve ([`TransferSolver`], the same system as
//! deformation transfer) gives positions whose gradients best match $\bar D$. Each connected
//! component is then placed rigidly: onto its fixed vertices where it has some, else onto the
//! linear blend. At one-hot weights $\bar D$ is the shape's own gradient and the solve
//! reproduces the shape exactly (up to round-off), so endpoints stay exact; in between, a jaw
//! or a leg that turns by θ is predicted turned by about αθ instead of cut short along the
//! chord as by the linear blend.

use super::constraints::Components;
use crate::geom::{kabsch, polar_decomposition};
use crate::mesh::{Point, ShapeSet};
use crate::transfer::{GradientOperator, SolverOptions, TransferSolver};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// Prefactored Poisson interpolation of a shape set.
pub(crate) struct RotationPredictor {
    solver: TransferSolver,
    /// Per shape ≥ 1, per triangle: log-rotation vector and stretch.
    logs: Vec<Vec<Vector3<f64>>>,
    stretches: Vec<Vec<Matrix3<f64>>>,
    members: Vec<Vec<u32>>,
}

impl RotationPredictor {
    /// Gradients, polar factors and the factorization; `None` when the base cannot carry a
    /// Poisson solve (isolated vertices, say), and the linear blend is used instead.
    pub fn new(shapes: &ShapeSet, components: &Components) -> Option<Self> {
        let base = shapes.mesh(0);
        let solver = TransferSolver::new(&base, &SolverOptions::default()).ok()?;
        let op = GradientOperator::new(&base);
        let (mut logs, mut stretches) = (Vec::new(), Vec::new());
        for s in 1..shapes.len() {
            let grads = op.gradients(shapes.positions(s)).ok()?;
            let (mut l, mut st) = (
                Vec::with_capacity(grads.len()),
                Vec::with_capacity(grads.len()),
            );
            for d in &grads {
                let (r, sm) = polar_decomposition(d);
                let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
                l.push(q.scaled_axis());
                st.push(sm);
            }
            logs.push(l);
            stretches.push(st);
        }
        let mut members = vec![Vec::new(); components.count];
        for (v, &c) in components.label.iter().enumerate() {
            members[c as usize].push(v as u32);
        }
        Some(Self {
            solver,
            logs,
            stretches,
            members,
        })
    }

    /// The predicted world positions for coefficients `c`; `lin` is the linear blend, whose
    /// values the `fixed` vertices take.
    pub fn predict(&self, c: &[f64], lin: &[Point], fixed: &[bool]) -> Option<Vec<Point>> {
        let nt = self.solver.num_triangles();
        let mut grads = Vec::with_capacity(nt);
        for t in 0..nt {
            let mut w = Vector3::zeros();
            let mut st = Matrix3::identity() * c[0];
            for s in 1..c.len() {
                if c[s] != 0.0 {
                    w += self.logs[s - 1][t] * c[s];
                    st += self.stretches[s - 1][t] * c[s];
                }
            }
            let r = UnitQuaternion::from_scaled_axis(w).to_rotation_matrix();
            grads.push(r.matrix() * st);
        }
        let mut p = self.solver.solve(&grads).ok()?;
        for comp in &self.members {
            let anchor: Vec<u32> = comp
                .iter()
                .copied()
                .filter(|&v| fixed[v as usize])
                .collect();
            let use_fixed = anchor.len() >= 3;
            let verts = if use_fixed { &anchor } else { comp };
            let from: Vec<Point> = verts.iter().map(|&v| p[v as usize]).collect();
            let to: Vec<Point> = verts.iter().map(|&v| lin[v as usize]).collect();
            let fit = kabsch(&from, &to, &[]);
            for &v in comp {
                p[v as usize] = if fixed[v as usize] {
                    lin[v as usize]
                } else {
                    fit.apply(p[v as usize])
                };
            }
        }
        p.iter().flatten().all(|v| v.is_finite()).then_some(p)
    }
}
