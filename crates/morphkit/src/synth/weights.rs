//! Blend weights over the triangle adjacency (Wang & Lee 2008, Sec. 3.2.2, Eq. 5).
//!
//! Over the target's triangles $T$ with edge neighbours $Q_i$, selected stiff triangles $\Phi$
//! and unselected stiff triangles $\Psi$, minimise
//! $$E(w) = \sum_{i \in T} \sum_{j \in Q_i} (w_i - w_j)^2 \;+\; \kappa \sum_{a \in \Phi} (w_a - 1)^2 \;+\; \kappa \sum_{b \in \Psi} w_b^2,$$
//! κ = 10 000. Each adjacent pair appears twice in the double sum, so $\tfrac12 \nabla E = 0$ is
//! $$(2 L + \kappa C)\, w = \kappa\, C\, c,$$
//! with $L$ the graph Laplacian of the triangle adjacency (#F × #F, degree on the diagonal,
//! −1 per adjacent pair), $C$ the diagonal mask of constrained (stiff) triangles and $c$ their
//! target values (1 selected, 0 not). The matrix depends only on *which* triangles are
//! constrained, not on the selection, so [`WeightSolver`] factors it once (sparse Cholesky,
//! AMD) and each new selection is one solve.
//!
//! Choices where the paper is silent:
//! - the soft constraints leave stiff weights at $1 - O(1/\kappa)$; the paper states stiff
//!   weights are exactly 1.0 or 0.0, so after the solve they are set to exactly that and only
//!   the free (flexible) triangles keep their solved values;
//! - a connected component without any constrained triangle would make the system singular;
//!   its triangles get weight 0 (the layer does not reach it);
//! - free weights lie in [0, 1] by the discrete maximum principle; values outside by more
//!   than 1e-6 are reported as an error, round-off is clamped.

use super::{Partitions, Selection, SynthError};
use crate::mesh::Topology;
use crate::sparse::{Cholesky, Ordering, SymmetricPattern};

/// The paper's soft-constraint weight κ.
pub const KAPPA: f64 = 10_000.0;

/// One blend weight per target triangle, in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct BlendWeights {
    /// $w_t$.
    pub values: Vec<f64>,
}

impl BlendWeights {
    /// All triangles at weight `w`.
    pub fn constant(num_triangles: usize, w: f64) -> Self {
        Self {
            values: vec![w; num_triangles],
        }
    }
}

/// Eq. 5 prefactored for one set of constrained triangles.
#[derive(Debug)]
pub struct WeightSolver {
    constrained: Vec<bool>,
    kappa: f64,
    cholesky: Cholesky,
}

impl WeightSolver {
    /// Assembles $2L + \kappa C$ over the edge adjacency of `topology` (whose triangles are
    /// `constrained.len()`), and factors it.
    pub fn new(topology: &Topology, constrained: &[bool], kappa: f64) -> Result<Self, SynthError> {
        if !(kappa.is_finite() && kappa > 0.0) {
            return Err(SynthError::Parameter {
                name: "kappa",
                value: kappa,
                why: "must be positive",
            });
        }
        let nf = constrained.len();
        // Components of the triangle adjacency with no constraint are pinned to 0.
        let mut comp = vec![u32::MAX; nf];
        let mut reached = vec![false; nf];
        let mut stack = Vec::new();
        let mut ncomp = 0u32;
        for s in 0..nf {
            if comp[s] != u32::MAX {
                continue;
            }
            let mut any = false;
            comp[s] = ncomp;
            stack.push(s);
            let mut members = Vec::new();
            while let Some(t) = stack.pop() {
                members.push(t);
                any |= constrained[t];
                for &j in topology.face_neighbors(t) {
                    if comp[j as usize] == u32::MAX {
                        comp[j as usize] = ncomp;
                        stack.push(j as usize);
                    }
                }
            }
            if any {
                members.iter().for_each(|&t| reached[t] = true);
            }
            ncomp += 1;
        }
        let mut lower = Vec::with_capacity(3 * nf);
        for t in 0..nf {
            let nb = topology.face_neighbors(t);
            let mut diag = 2.0 * nb.len() as f64;
            if constrained[t] {
                diag += kappa;
            } else if !reached[t] {
                diag += 1.0;
            }
            lower.push((t, t, diag));
            for &j in nb {
                if (j as usize) < t {
                    lower.push((t, j as usize, -2.0));
                }
            }
        }
        let (pattern, values) = SymmetricPattern::from_triplets(nf, &lower)?;
        let mut cholesky = Cholesky::analyze(pattern, Ordering::Amd)?;
        cholesky.factorize(&values)?;
        Ok(Self {
            constrained: constrained.to_vec(),
            kappa,
            cholesky,
        })
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.constrained.len()
    }

    /// The constrained triangles.
    pub fn constrained(&self) -> &[bool] {
        &self.constrained
    }

    /// Weights with every constrained triangle at 1 where `selected` and 0 elsewhere
    /// (`selected` is read only on constrained triangles). One triangular solve.
    pub fn solve(&self, selected: &[bool]) -> Result<BlendWeights, SynthError> {
        let nf = self.constrained.len();
        if selected.len() != nf {
            return Err(SynthError::Length {
                what: "selection",
                expected: nf,
                found: selected.len(),
            });
        }
        let mut w: Vec<f64> = (0..nf)
            .map(|t| {
                if self.constrained[t] && selected[t] {
                    self.kappa
                } else {
                    0.0
                }
            })
            .collect();
        self.cholesky.solve_in_place(&mut w, 1)?;
        for (t, x) in w.iter_mut().enumerate() {
            if self.constrained[t] {
                *x = if selected[t] { 1.0 } else { 0.0 };
            } else if !(-1e-6..=1.0 + 1e-6).contains(x) {
                return Err(SynthError::WeightOutOfRange {
                    triangle: t,
                    value: *x,
                });
            } else {
                *x = x.clamp(0.0, 1.0);
            }
        }
        Ok(BlendWeights { values: w })
    }
}

/// One-shot Eq. 5 for intelligent scribbling: stiff triangles constrained, 1 on `selection`.
pub fn blend_weights(
    partitions: &Partitions,
    topology: &Topology,
    selection: &Selection,
    kappa: f64,
) -> Result<BlendWeights, SynthError> {
    WeightSolver::new(topology, &partitions.stiff_mask(), kappa)?.solve(&selection.triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::synth::partitions::partitions_of;
    use crate::synth::{refine_scribble, Scribble};

    #[test]
    fn exact_on_stiff_and_strictly_between_elsewhere() {
        // A strip: stiff | flexible band | stiff; the left part selected.
        let g = generate::grid(12, 2, 12.0, 2.0);
        let topo = Topology::new(g.num_vertices(), &g.triangles);
        let x = |t: usize| {
            (0..3)
                .map(|k| g.positions[g.triangles[t][k] as usize][0])
                .sum::<f64>()
                / 3.0
        };
        let values = (0..g.num_triangles())
            .map(|t| if (4.0..8.0).contains(&x(t)) { 1.0 } else { 0.0 })
            .collect();
        let p = partitions_of(&g, values);
        assert_eq!(p.num_stiff(), 2);
        let left: Vec<u32> = (0..g.num_triangles() as u32)
            .filter(|&t| x(t as usize) < 4.0)
            .collect();
        let sel = refine_scribble(
            &Scribble::Triangles(left),
            &p,
            g.num_vertices(),
            &g.triangles,
        )
        .unwrap();
        let w = blend_weights(&p, &topo, &sel, KAPPA).unwrap();
        for t in 0..g.num_triangles() {
            let v = w.values[t];
            if x(t) < 4.0 {
                assert_eq!(v, 1.0);
            } else if x(t) >= 8.0 {
                assert_eq!(v, 0.0);
            } else {
                assert!(v > 0.0 && v < 1.0, "triangle {t}: {v}");
            }
        }
        // Decreasing across the band.
        let mean = |a: f64, b: f64| {
            let ts: Vec<usize> = (0..g.num_triangles())
                .filter(|&t| (a..b).contains(&x(t)))
                .collect();
            ts.iter().map(|&t| w.values[t]).sum::<f64>() / ts.len() as f64
        };
        assert!(mean(4.0, 5.0) > mean(5.0, 6.0) && mean(6.0, 7.0) > mean(7.0, 8.0));
        // A new selection on the same factorization: the right part instead.
        let solver = WeightSolver::new(&topo, &p.stiff_mask(), KAPPA).unwrap();
        let right: Vec<bool> = (0..g.num_triangles()).map(|t| x(t) >= 8.0).collect();
        let w2 = solver.solve(&right).unwrap();
        for t in 0..g.num_triangles() {
            assert!((w2.values[t] - (1.0 - w.values[t])).abs() < 1e-9);
        }
    }

    #[test]
    fn a_component_without_constraints_gets_zero() {
        let a = generate::grid(3, 3, 1.0, 1.0);
        let mut m = a.clone();
        let off = a.num_vertices() as u32;
        m.positions
            .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        m.triangles
            .extend(a.triangles.iter().map(|t| t.map(|i| i + off)));
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let n = a.num_triangles();
        let constrained: Vec<bool> = (0..2 * n).map(|t| t < 2).collect();
        let w = WeightSolver::new(&topo, &constrained, KAPPA)
            .unwrap()
            .solve(&vec![true; 2 * n])
            .unwrap();
        assert!(w.values[..n].iter().all(|&v| (v - 1.0).abs() < 1e-9));
        assert!(w.values[n..].iter().all(|&v| v == 0.0));
    }
}
