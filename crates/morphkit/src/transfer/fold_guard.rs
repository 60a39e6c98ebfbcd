//! The fold guard of the local-stretch gradient frame
//! ([`GradientFrame::LocalStretch`](super::GradientFrame::LocalStretch)).
//!
//! Turning each matched stretch into the target triangle's plane lowers the cycle error
//! (README, issue 9), but where matched triangles face away from each other in the
//! references it turns stretches through large angles, and a few places of a frame can
//! crease: on the horse gallop onto the camel, the camel's rear between the hind legs, whose
//! matches are the sides of the horse's thighs. The guard removes those creases and keeps the
//! turning everywhere else:
//!
//! 1. Solve the frame with the turned gradients $M_j$.
//! 2. Find its *sharp folds* ([`sharp_fold_edges`]: edges folded past 120° that are not in
//!    the target reference). None: done.
//! 3. Once per frame, solve it also with the unturned gradients $M^0_j$
//!    ([`Correspondence::map_gradients_local_unturned`](super::Correspondence::map_gradients_local_unturned):
//!    the same weights and rotations, the stretches carried over as they are) and find its
//!    sharp folds. Folds that the unturned frame has too come from the source motion or the
//!    matching, not from turning: they are left alone.
//! 4. The triangles beside every other fold, and `rings × round` rings of edge neighbours
//!    around them (round 1, 2, …: a fold that is still there after its neighbourhood was
//!    unturned is driven from farther away), take $M^0_j$; solve again with the same
//!    prefactored matrix (one more back-substitution). Repeat from 2 until no new triangle
//!    is marked or after `rounds` rounds.
//!
//! Every step depends on the frame alone, so a guarded frame is still a deterministic function
//! of its source frame, and a frame without folds costs nothing more. A mesh onto itself never
//! folds, so the guard keeps that transfer exact.
//!
//! Measured (cycle error against the baseline, sharp folds; refined, area-weighted, local
//! stretch; README): horse ↔ camel −32.8 % with 16 sharp folds (77 for the baseline; 27
//! unguarded), cat ↔ dog −25.6 %, 96 (99; 98), held-out horse gallop onto the camel, frames
//! 1, 5, … −30.9 %, 36 (86; 130), frames 2, 6, … / 3, 7, … / 4, 8, … 28 / 16 / 16
//! (28 / 50 / 64; 120 / 146 / 92), horse collapse −20.7 %, 1 547 (1 657; 1 722).

use super::error::TransferError;
use super::quality::sharp_fold_edges;
use crate::mesh::{Point, Topology, TriMesh};
use nalgebra::Matrix3;

/// Options of the fold guard ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FoldGuard {
    /// Rings of edge neighbours around a fold's triangles marked in round 1 (`rings × k` in
    /// round k). Default 2.
    pub rings: usize,
    /// Most guard rounds (each one more solve). Default 8.
    pub rounds: usize,
}

impl Default for FoldGuard {
    fn default() -> Self {
        Self {
            rings: 2,
            rounds: 8,
        }
    }
}

/// A transferred frame: its positions, the gradients it was solved with (one per target
/// triangle) and what the fold guard did.
pub type GuardedFrame = (Vec<Point>, Vec<Matrix3<f64>>, GuardOutcome);

/// What the guard did to one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GuardOutcome {
    /// Target triangles that took the unturned gradient.
    pub unturned_triangles: usize,
    /// Solves beyond the first (the unturned frame's included).
    pub extra_solves: usize,
}

/// The guard's loop ([module docs](self)): `wanted` are the turned gradients, `unturned`
/// computes $M^0$ on first need, `solve` is the prefactored solve. Returns the frame, the
/// gradients it was solved with and what the guard did.
pub(crate) fn guarded_solve(
    opts: &FoldGuard,
    target: &TriMesh,
    topology: &Topology,
    mut wanted: Vec<Matrix3<f64>>,
    unturned: impl FnOnce() -> Vec<Matrix3<f64>>,
    solve: impl Fn(&[Matrix3<f64>]) -> Result<Vec<Point>, TransferError>,
) -> Result<GuardedFrame, TransferError> {
    let mut x = solve(&wanted)?;
    let mut outcome = GuardOutcome::default();
    let nf = target.num_triangles();
    let mut marked = vec![false; nf];
    let mut count = 0usize;
    // M⁰ and the unturned frame's folds, on first need.
    let mut fallback: Option<(Vec<Matrix3<f64>>, Vec<usize>)> = None;
    let mut unturned = Some(unturned);
    for round in 1..=opts.rounds {
        let edges = sharp_fold_edges(target, topology, &x);
        if edges.is_empty() {
            break;
        }
        if fallback.is_none() {
            let g0 = (unturned.take().expect("computed once"))();
            let x0 = solve(&g0)?;
            outcome.extra_solves += 1;
            fallback = Some((g0, sharp_fold_edges(target, topology, &x0)));
        }
        let (g0, folds0) = fallback.as_ref().expect("set above");
        let mut front: Vec<usize> = edges
            .iter()
            .filter(|e| folds0.binary_search(e).is_err())
            .flat_map(|&e| topology.edge_faces(e).iter().map(|&t| t as usize))
            .collect();
        let before = count;
        let mut seen = vec![false; nf];
        for &t in &front {
            seen[t] = true;
            if !marked[t] {
                marked[t] = true;
                count += 1;
            }
        }
        for _ in 0..opts.rings * round {
            let mut next = Vec::new();
            for &t in &front {
                for &n in topology.face_neighbors(t) {
                    let n = n as usize;
                    if !seen[n] {
                        seen[n] = true;
                        next.push(n);
                        if !marked[n] {
                            marked[n] = true;
                            count += 1;
                        }
                    }
                }
            }
            front = next;
        }
        if count == before {
            break;
        }
        for (w, (&m, g)) in wanted.iter_mut().zip(marked.iter().zip(g0)) {
            if m {
                *w = *g;
            }
        }
        x = solve(&wanted)?;
        outcome.extra_solves += 1;
    }
    outcome.unturned_triangles = count;
    Ok((x, wanted, outcome))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::testmesh::grid;

    fn centroid_x(m: &TriMesh, t: usize) -> f64 {
        m.triangles[t]
            .iter()
            .map(|&v| m.positions[v as usize][0])
            .sum::<f64>()
            / 3.0
    }

    /// Identity gradients left of `x = at`, a mirror in x to its right.
    fn half_mirrored(m: &TriMesh, at: f64) -> Vec<Matrix3<f64>> {
        let mirror = Matrix3::from_diagonal(&nalgebra::Vector3::new(-1.0, 1.0, 1.0));
        (0..m.num_triangles())
            .map(|t| {
                if centroid_x(m, t) > at {
                    mirror
                } else {
                    Matrix3::identity()
                }
            })
            .collect()
    }

    /// A grid whose wanted gradients fold it along a line: the guard's fallback (the identity)
    /// removes the fold, and only triangles near it are marked.
    #[test]
    fn a_fold_made_by_the_wanted_gradients_is_replaced_by_the_fallback_nearby_only() {
        let m = grid(12, 12, 1.0);
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let solver =
            crate::transfer::TransferSolver::new(&m, &Default::default()).expect("grid solves");
        // Triangles right of x = 6 want to be mirrored (a fold of 180° along the line).
        let wanted = half_mirrored(&m, 6.0);
        let plain = solver.solve(&wanted).unwrap();
        assert!(!sharp_fold_edges(&m, &topo, &plain).is_empty());
        let (x, used, outcome) = guarded_solve(
            &FoldGuard::default(),
            &m,
            &topo,
            wanted.clone(),
            || vec![Matrix3::identity(); m.num_triangles()],
            |g| solver.solve(g),
        )
        .unwrap();
        assert!(sharp_fold_edges(&m, &topo, &x).is_empty());
        assert!(outcome.unturned_triangles > 0 && outcome.extra_solves >= 2);
        // Far from the line (x < 2) nothing is marked.
        for t in 0..m.num_triangles() {
            if centroid_x(&m, t) < 2.0 {
                assert_eq!(used[t], wanted[t], "triangle {t} far from the fold");
            }
        }
        // Without folds, one solve and the gradients untouched.
        let id = vec![Matrix3::identity(); m.num_triangles()];
        let (x1, used1, o1) = guarded_solve(
            &FoldGuard::default(),
            &m,
            &topo,
            id.clone(),
            || unreachable!("no fold, no fallback"),
            |g| solver.solve(g),
        )
        .unwrap();
        assert_eq!(o1, GuardOutcome::default());
        assert_eq!(used1, id);
        assert_eq!(x1, solver.solve(&id).unwrap());
    }

    /// Folds that the fallback frame has too are left alone: nothing is marked.
    #[test]
    fn folds_of_the_fallback_itself_are_not_guarded() {
        let m = grid(8, 8, 1.0);
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let solver =
            crate::transfer::TransferSolver::new(&m, &Default::default()).expect("grid solves");
        let wanted = half_mirrored(&m, 4.0);
        let plain = solver.solve(&wanted).unwrap();
        assert!(!sharp_fold_edges(&m, &topo, &plain).is_empty());
        let (x, used, outcome) = guarded_solve(
            &FoldGuard::default(),
            &m,
            &topo,
            wanted.clone(),
            || wanted.clone(),
            |g| solver.solve(g),
        )
        .unwrap();
        assert_eq!(outcome.unturned_triangles, 0);
        assert_eq!(outcome.extra_solves, 1);
        assert_eq!(used, wanted);
        assert_eq!(x, plain);
    }
}
