//! Pose modification of the target's reference pose (Wang & Lee 2008, Sec. 3.2.4).
//!
//! The user selects a partition by intelligent scribbling and turns it by a rotation $R$
//! (axis, angle). Each triangle gets the gradient
//! $$P_t = \operatorname{slerp}(I, R, w_t),$$
//! $w$ the Eq. 5 weights of the selection (1 on the selected stiff partitions, 0 on the other
//! stiff ones, smooth across the flexible joints), and the edited pose is the transfer solve of
//! $P$ on the target reference. It is then translated so that the centroid of the vertices of
//! unselected stiff triangles ($w = 0$) stays where it was: the rest of the body stays put and
//! the selected part turns about its joint. Synthesis then applies every synthesised gradient
//! $M_t$ after the edit, $N_t = M_t P_t$ (the $R$ of Eq. 6).
//!
//! [`PoseEditor`] borrows an already factored [`TransferSolver`] and [`WeightSolver`], so an
//! edit costs one weight solve and one transfer solve, with no factorization: interactive.

use super::{BlendWeights, Partitions, Selection, SynthError, WeightSolver};
use crate::geom::slerp;
use crate::mesh::Point;
use crate::transfer::TransferSolver;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// The rotation by `angle` radians about `axis` (need not be unit; must not be zero).
pub fn axis_angle(axis: [f64; 3], angle: f64) -> Result<Matrix3<f64>, SynthError> {
    let a = Vector3::from(axis);
    let n = a.norm();
    if !(n.is_finite() && n > 0.0 && angle.is_finite()) {
        return Err(SynthError::Parameter {
            name: "axis",
            value: n,
            why: "the rotation axis must be a non-zero, finite vector and the angle finite",
        });
    }
    Ok(Rotation3::from_axis_angle(&Unit::new_normalize(a), angle).into_inner())
}

/// $P_t = \operatorname{slerp}(I, R, w_t)$ for every triangle.
pub fn rotation_gradients(weights: &BlendWeights, rotation: &Matrix3<f64>) -> Vec<Matrix3<f64>> {
    let id = Matrix3::identity();
    weights
        .values
        .iter()
        .map(|&w| {
            if w <= 0.0 {
                id
            } else if w >= 1.0 {
                *rotation
            } else {
                slerp(&id, rotation, w)
            }
        })
        .collect()
}

/// One edited pose.
#[derive(Clone, Debug)]
pub struct PoseEdit {
    /// The edited reference positions.
    pub positions: Vec<Point>,
    /// $P_t$ per triangle.
    pub gradients: Vec<Matrix3<f64>>,
    /// The Eq. 5 weights used.
    pub weights: BlendWeights,
}

/// Interactive pose editing on prefactored solvers.
#[derive(Debug)]
pub struct PoseEditor<'a> {
    solver: &'a TransferSolver,
    weights: &'a WeightSolver,
    partitions: &'a Partitions,
    triangles: &'a [[u32; 3]],
}

impl<'a> PoseEditor<'a> {
    /// An editor over `solver` (the target's transfer solve) and `weights` (Eq. 5 factored for
    /// `partitions`' stiff triangles); `triangles` is the target's connectivity.
    pub fn new(
        solver: &'a TransferSolver,
        weights: &'a WeightSolver,
        partitions: &'a Partitions,
        triangles: &'a [[u32; 3]],
    ) -> Result<Self, SynthError> {
        let nf = solver.num_triangles();
        for (what, n) in [
            ("weight solver triangles", weights.num_triangles()),
            ("partition triangles", partitions.num_triangles()),
            ("target triangles", triangles.len()),
        ] {
            if n != nf {
                return Err(SynthError::Length {
                    what,
                    expected: nf,
                    found: n,
                });
            }
        }
        Ok(Self {
            solver,
            weights,
            partitions,
            triangles,
        })
    }

    /// The partitions selections refer to.
    pub fn partitions(&self) -> &Partitions {
        self.partitions
    }

    /// Rotates the selected partitions by `rotation`: one weight solve, one transfer solve.
    pub fn rotate(
        &self,
        selection: &Selection,
        rotation: &Matrix3<f64>,
    ) -> Result<PoseEdit, SynthError> {
        let weights = self.weights.solve(&selection.triangles)?;
        let gradients = rotation_gradients(&weights, rotation);
        let positions = self.solve_pinned(&gradients, &weights)?;
        Ok(PoseEdit {
            positions,
            gradients,
            weights,
        })
    }

    /// Solves `gradients` and translates the result so that the vertices of weight-0 triangles
    /// keep their reference centroid (module doc).
    pub fn solve_pinned(
        &self,
        gradients: &[Matrix3<f64>],
        weights: &BlendWeights,
    ) -> Result<Vec<Point>, SynthError> {
        let mut x = self.solver.solve(gradients)?;
        let reference = self.solver.reference();
        let mut still = vec![false; x.len()];
        for (tri, &w) in self.triangles.iter().zip(&weights.values) {
            if w == 0.0 {
                tri.iter().for_each(|&v| still[v as usize] = true);
            }
        }
        let n = still.iter().filter(|&&s| s).count();
        if n > 0 {
            let mut shift = [0.0; 3];
            for v in (0..x.len()).filter(|&v| still[v]) {
                for k in 0..3 {
                    shift[k] += (reference[v][k] - x[v][k]) / n as f64;
                }
            }
            for p in &mut x {
                for k in 0..3 {
                    p[k] += shift[k];
                }
            }
        }
        Ok(x)
    }
}

/// One-shot pose edit: factors the target's transfer solve and Eq. 5 for `partitions`, then
/// rotates the partitions that `scribble` (one entry per triangle) selects by `angle` radians
/// about `axis`. For repeated edits keep a [`PoseEditor`] (or use
/// [`super::Synthesizer::edit_pose`]).
pub fn edit_pose(
    target: &crate::mesh::TriMesh,
    partitions: &Partitions,
    scribble: &[bool],
    axis: [f64; 3],
    angle: f64,
) -> Result<PoseEdit, SynthError> {
    let solver = TransferSolver::new(target, &crate::transfer::SolverOptions::default())?;
    let topo = crate::mesh::Topology::new(target.num_vertices(), &target.triangles);
    let ws = WeightSolver::new(&topo, &partitions.stiff_mask(), super::KAPPA)?;
    let editor = PoseEditor::new(&solver, &ws, partitions, &target.triangles)?;
    editor.rotate(
        &Selection::refine(partitions, scribble)?,
        &axis_angle(axis, angle)?,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{generate, norm, sub, Topology};
    use crate::synth::partitions::partitions_of;
    use crate::synth::KAPPA;
    use crate::transfer::SolverOptions;

    #[test]
    fn rotating_the_far_half_of_a_bar_turns_it_rigidly_and_keeps_the_near_half() {
        let bar = generate::bar(4.0, 0.5, 2, 32);
        let cx = |t: usize| {
            (0..3)
                .map(|k| bar.positions[bar.triangles[t][k] as usize][0])
                .sum::<f64>()
                / 3.0
        };
        // A flexible joint at x ≈ 2.
        let values = (0..bar.num_triangles())
            .map(|t| {
                if (1.8..2.2).contains(&cx(t)) {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        let p = partitions_of(&bar, values);
        assert_eq!(p.num_stiff(), 2);
        let topo = Topology::new(bar.num_vertices(), &bar.triangles);
        let ws = WeightSolver::new(&topo, &p.stiff_mask(), KAPPA).unwrap();
        let solver = TransferSolver::new(&bar, &SolverOptions::default()).unwrap();
        let editor = PoseEditor::new(&solver, &ws, &p, &bar.triangles).unwrap();
        let far: Vec<bool> = (0..bar.num_triangles()).map(|t| cx(t) > 2.2).collect();
        let sel = Selection::refine(&p, &far).unwrap();
        let r = axis_angle([0.0, 0.0, 1.0], 0.5).unwrap();
        let edit = editor.rotate(&sel, &r).unwrap();
        // The near end stays; the far end's edges are rotated by R.
        for (v, q) in edit.positions.iter().enumerate() {
            if bar.positions[v][0] < 1.0 {
                assert!(norm(sub(*q, bar.positions[v])) < 2e-2, "vertex {v} moved");
            }
        }
        let (a, b) = (
            (0..bar.num_vertices())
                .find(|&v| bar.positions[v][0] > 3.5)
                .unwrap(),
            (0..bar.num_vertices())
                .rev()
                .find(|&v| bar.positions[v][0] > 3.5)
                .unwrap(),
        );
        let e0 = Vector3::from(sub(bar.positions[b], bar.positions[a]));
        let e1 = Vector3::from(sub(edit.positions[b], edit.positions[a]));
        assert!((r * e0 - e1).norm() < 2e-2 * e0.norm(), "{e0} → {e1}");
        let once = edit_pose(&bar, &p, &far, [0.0, 0.0, 1.0], 0.5).unwrap();
        for (a, b) in once.positions.iter().zip(&edit.positions) {
            assert!(norm(sub(*a, *b)) < 1e-12);
        }
        assert!(axis_angle([0.0; 3], 1.0).is_err());
    }
}
