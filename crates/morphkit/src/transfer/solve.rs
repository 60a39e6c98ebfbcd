//! The deformation-transfer solve (Wang & Lee 2008, Sec. 3.2.3, Eq. 6; Sumner & Popović
//! 2004, Sec. 4), prefactored on the target's reference mesh.
//!
//! **Formulation: vertex-only.** Sumner's fourth vertices are eliminated. For a target
//! triangle $j$ with reference edges $e_1, e_2$ and frame $V_j = [e_1, e_2, n/\sqrt{\|n\|}]$,
//! let $r_1, r_2$ be the first two rows of $V_j^{-1}$: they span the triangle's plane and
//! $[r_1; r_2] = [e_1, e_2]^+$. The gradient of the piecewise-linear map $x$ on triangle $j$
//! is $T_j(x) = [\tilde e_1, \tilde e_2] [e_1, e_2]^+$, linear in the three vertices with
//! coefficients $g_1 = -(r_1 + r_2)$, $g_2 = r_1$, $g_3 = r_2$ (3-vectors). We minimise
//! $$E(x) = \sum_j w_j \|T_j(x) - M_j\|_F^2$$
//! over the target vertices, $M_j$ the wanted gradient, $w_j = 1$ (Eq. 6 as in Sumner) or the
//! reference area ([`TriangleWeighting`]). Because $T_j$ has no normal part,
//! $\|T_j - M_j\|^2 = \|T_j - M_j P_j\|^2 + \text{const}$ with $P_j$ the projector onto the
//! plane: only the tangential action of $M_j$ matters, and the triangle normals follow from the
//! vertices instead of being extra unknowns. When $M_j$ are the gradients of some deformation
//! of the same mesh, that deformation is the exact minimiser (used by the identity test).
//!
//! Normal equations, one per coordinate $k \in \{x, y, z\}$:
//! $$A^\top A\, x_k = A^\top c_k, \qquad (A^\top A)_{ab} = \sum_{j \ni a, b} w_j\, g_a \cdot g_b,
//! \qquad (A^\top c_k)_a = \sum_{j \ni a} w_j\, g_a \cdot M_j^{(k,:)}.$$
//! $A^\top A$ (#V × #V, the cotangent-like Laplacian) depends only on the target reference.
//! Its null space is the constants on each connected component, so one *constraint vertex*
//! per component is fixed at its reference position and eliminated ([`crate::sparse::Dirichlet`]);
//! the reduced matrix is SPD and factored once (sparse Cholesky, AMD ordering). A frame is
//! then one assembly of $A^\top c$ and a 3-right-hand-side solve.

use super::error::{Side, TransferError};
use super::gradients::{degeneracy_tolerance, reference_frame_inverse};
use crate::mesh::{validate, Point, Topology, TriMesh};
use crate::sparse::{Cholesky, Dirichlet, Ordering, SymmetricPattern};
use nalgebra::{Matrix3, Vector3};

/// Per-triangle weights $w_j$ of the transfer energy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TriangleWeighting {
    /// $w_j = 1$: Eq. 6 / Sumner & Popović as written. Default.
    #[default]
    Uniform,
    /// $w_j$ = reference area over the mean area: insensitive to uneven tessellation.
    Area,
}

/// Options of [`TransferSolver`].
#[derive(Clone, Debug, Default)]
pub struct SolverOptions {
    /// Triangle weights. Default [`TriangleWeighting::Uniform`].
    pub weighting: TriangleWeighting,
    /// Constraint vertices, fixed at their reference positions. Components without one get
    /// their lowest-index vertex. Default: empty (one automatic vertex per component).
    pub constraint_vertices: Vec<u32>,
}

/// The prefactored transfer system of one target reference mesh.
#[derive(Debug)]
pub struct TransferSolver {
    reference: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    /// $w_j$ (0 for a skipped, degenerate triangle).
    weight: Vec<f64>,
    /// $g_1, g_2, g_3$ per triangle.
    coeff: Vec<[Vector3<f64>; 3]>,
    constraints: Vec<u32>,
    dirichlet: Dirichlet,
    cholesky: Cholesky,
    skipped: Vec<usize>,
}

impl TransferSolver {
    /// Validates `target`, builds $A^\top A$, eliminates the constraint vertices and factors.
    pub fn new(target: &TriMesh, opts: &SolverOptions) -> Result<Self, TransferError> {
        Self::with_confidence(target, opts, &[])
    }

    /// [`TransferSolver::new`] with every triangle's weight $w_j$ also multiplied by
    /// `confidence[j]` (positive, one per triangle; empty: all 1), the weighted least squares
    /// of [`Correspondence::local_confidence`](super::Correspondence::local_confidence).
    pub(crate) fn with_confidence(
        target: &TriMesh,
        opts: &SolverOptions,
        confidence: &[f64],
    ) -> Result<Self, TransferError> {
        debug_assert!(
            confidence.is_empty()
                || (confidence.len() == target.num_triangles()
                    && confidence.iter().all(|c| c.is_finite() && *c > 0.0))
        );
        let report = validate(target).map_err(|source| TransferError::Mesh {
            side: Side::Target,
            source,
        })?;
        if !report.isolated_vertices().is_empty() {
            return Err(TransferError::IsolatedVertices {
                vertices: report.isolated_vertices().to_vec(),
            });
        }
        let nv = target.num_vertices();
        let p = &target.positions;
        let tol = degeneracy_tolerance(target);
        let nf = target.num_triangles();
        let mean_area = (0..nf).map(|t| target.triangle_area(t)).sum::<f64>() / nf as f64;
        let mut weight = Vec::with_capacity(nf);
        let mut coeff = Vec::with_capacity(nf);
        let mut skipped = Vec::new();
        for (t, &tri) in target.triangles.iter().enumerate() {
            match reference_frame_inverse(p, tri, tol) {
                Some(inv) => {
                    let r1: Vector3<f64> = inv.row(0).transpose();
                    let r2: Vector3<f64> = inv.row(1).transpose();
                    coeff.push([-(r1 + r2), r1, r2]);
                    weight.push(
                        match opts.weighting {
                            TriangleWeighting::Uniform => 1.0,
                            TriangleWeighting::Area => target.triangle_area(t) / mean_area,
                        } * confidence.get(t).copied().unwrap_or(1.0),
                    );
                }
                None => {
                    skipped.push(t);
                    coeff.push([Vector3::zeros(); 3]);
                    weight.push(0.0);
                }
            }
        }
        // Every vertex needs a non-degenerate triangle.
        let mut covered = vec![false; nv];
        for (t, tri) in target.triangles.iter().enumerate() {
            if weight[t] > 0.0 {
                for &v in tri {
                    covered[v as usize] = true;
                }
            }
        }
        if let Some(v) = covered.iter().position(|c| !c) {
            return Err(TransferError::UnconstrainedVertex { vertex: v });
        }
        // Constraint vertices: the caller's, plus the lowest vertex of each uncovered component.
        let topo = Topology::new(nv, &target.triangles);
        let comps = topo.components();
        let mut has = vec![false; topo.num_components()];
        let mut constraints = Vec::new();
        for &v in &opts.constraint_vertices {
            if v as usize >= nv {
                return Err(TransferError::ConstraintOutOfRange {
                    vertex: v,
                    num_vertices: nv,
                });
            }
            if !constraints.contains(&v) {
                constraints.push(v);
            }
            has[comps[v as usize] as usize] = true;
        }
        for (v, &c) in comps.iter().enumerate() {
            let c = c as usize;
            if !has[c] {
                has[c] = true;
                constraints.push(v as u32);
            }
        }
        let mut lower = Vec::with_capacity(6 * nf);
        for (t, tri) in target.triangles.iter().enumerate() {
            let w = weight[t];
            if w == 0.0 {
                continue;
            }
            let g = &coeff[t];
            for a in 0..3 {
                for b in 0..3 {
                    let (i, j) = (tri[a] as usize, tri[b] as usize);
                    if i > j || (i == j && a == b) {
                        lower.push((i, j, w * g[a].dot(&g[b])));
                    }
                }
            }
        }
        let mut fixed = vec![false; nv];
        for &c in &constraints {
            fixed[c as usize] = true;
        }
        let dirichlet = Dirichlet::new(nv, &fixed, &lower)?;
        let (pattern, values) =
            SymmetricPattern::from_triplets(dirichlet.num_free(), dirichlet.reduced_triplets())?;
        let mut cholesky = Cholesky::analyze(pattern, Ordering::Amd)?;
        cholesky.factorize(&values)?;
        Ok(Self {
            reference: target.positions.clone(),
            triangles: target.triangles.clone(),
            weight,
            coeff,
            constraints,
            dirichlet,
            cholesky,
            skipped,
        })
    }

    /// Number of target vertices.
    pub fn num_vertices(&self) -> usize {
        self.reference.len()
    }

    /// Number of target triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The constraint vertices (fixed at their reference positions by [`TransferSolver::solve`]).
    pub fn constraint_vertices(&self) -> &[u32] {
        &self.constraints
    }

    /// Degenerate target triangles left out of the energy.
    pub fn skipped_triangles(&self) -> &[usize] {
        &self.skipped
    }

    /// Stored entries of the Cholesky factor.
    pub fn factor_nnz(&self) -> usize {
        self.cholesky.factor_nnz()
    }

    /// The target reference positions.
    pub fn reference(&self) -> &[Point] {
        &self.reference
    }

    /// Solves for the target positions whose triangle gradients best match `gradients`
    /// (one 3 × 3 matrix per target triangle), the constraint vertices at their reference
    /// positions (the paper's convention).
    pub fn solve(&self, gradients: &[Matrix3<f64>]) -> Result<Vec<Point>, TransferError> {
        let nf = self.triangles.len();
        if gradients.len() != nf {
            return Err(TransferError::GradientCount {
                expected: nf,
                found: gradients.len(),
            });
        }
        if let Some(t) = gradients
            .iter()
            .position(|m| m.iter().any(|x| !x.is_finite()))
        {
            return Err(TransferError::NonFinite {
                what: "gradient of target triangle",
                index: t,
            });
        }
        let nv = self.reference.len();
        let mut b = vec![0.0; 3 * nv];
        for (t, tri) in self.triangles.iter().enumerate() {
            let w = self.weight[t];
            if w == 0.0 {
                continue;
            }
            let m = &gradients[t];
            for (a, &v) in tri.iter().enumerate() {
                let g = self.coeff[t][a] * w;
                for k in 0..3 {
                    b[k * nv + v as usize] += g.x * m[(k, 0)] + g.y * m[(k, 1)] + g.z * m[(k, 2)];
                }
            }
        }
        let nfree = self.dirichlet.num_free();
        let mut rhs = Vec::with_capacity(3 * nfree);
        let mut xfixed = vec![0.0; nv];
        for k in 0..3 {
            for &c in &self.constraints {
                xfixed[c as usize] = self.reference[c as usize][k];
            }
            rhs.extend(self.dirichlet.rhs(&b[k * nv..(k + 1) * nv], &xfixed));
        }
        self.cholesky.solve_in_place(&mut rhs, 3)?;
        let mut out = vec![[0.0; 3]; nv];
        for &c in &self.constraints {
            out[c as usize] = self.reference[c as usize];
        }
        for (r, &v) in self.dirichlet.free().iter().enumerate() {
            out[v] = [rhs[r], rhs[nfree + r], rhs[2 * nfree + r]];
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::gradients::deformation_gradients;
    use crate::transfer::testmesh::{grid, sphere};
    use nalgebra::Rotation3;

    #[test]
    fn gradients_of_a_deformation_are_reproduced_exactly() {
        for weighting in [TriangleWeighting::Uniform, TriangleWeighting::Area] {
            let m = sphere(14, 9, 1.0);
            // A smooth non-rigid deformation.
            let def: Vec<Point> = m
                .positions
                .iter()
                .map(|p| {
                    [
                        p[0] * (1.0 + 0.3 * p[2]),
                        p[1] + 0.2 * p[0] * p[0],
                        0.8 * p[2],
                    ]
                })
                .collect();
            let g = deformation_gradients(&m, &def).unwrap();
            let s = TransferSolver::new(
                &m,
                &SolverOptions {
                    weighting,
                    ..Default::default()
                },
            )
            .unwrap();
            let x = s.solve(&g).unwrap();
            // Equal up to a translation: compare edge vectors.
            let c = s.constraint_vertices()[0] as usize;
            for (a, b) in x.iter().zip(&def) {
                for k in 0..3 {
                    let d = (a[k] - x[c][k]) - (b[k] - def[c][k]);
                    assert!(d.abs() < 1e-9, "{d}");
                }
            }
        }
    }

    #[test]
    fn a_triangle_of_low_confidence_gives_way_to_its_neighbours() {
        // Every triangle wants the identity but one, which wants 3 I: with full confidence
        // it drags its neighbours; with a low one they keep the identity.
        let m = grid(4, 4, 1.0);
        let mut g = vec![Matrix3::identity(); m.num_triangles()];
        g[9] = Matrix3::identity() * 3.0;
        let worst_elsewhere = |confidence: &[f64]| {
            let s =
                TransferSolver::with_confidence(&m, &SolverOptions::default(), confidence).unwrap();
            let x = s.solve(&g).unwrap();
            let got = deformation_gradients(&m, &x).unwrap();
            (0..m.num_triangles())
                .filter(|&t| t != 9)
                .map(|t| {
                    (got[t] - Matrix3::identity())
                        .fixed_view::<3, 2>(0, 0)
                        .norm()
                })
                .fold(0.0, f64::max)
        };
        let mut low = vec![1.0; m.num_triangles()];
        low[9] = 1e-3;
        let (full, weak) = (worst_elsewhere(&[]), worst_elsewhere(&low));
        assert!(full > 0.3, "{full}");
        assert!(weak < 0.01, "{weak}");
        assert_eq!(worst_elsewhere(&vec![1.0; m.num_triangles()]), full);
    }

    #[test]
    fn two_components_get_two_constraints_and_rotate_rigidly() {
        let a = grid(4, 3, 0.5);
        let mut m = a.clone();
        let off = a.num_vertices() as u32;
        m.positions
            .extend(a.positions.iter().map(|p| [p[0] + 3.0, p[1], 1.0]));
        m.triangles
            .extend(a.triangles.iter().map(|t| t.map(|i| i + off)));
        let s = TransferSolver::new(&m, &SolverOptions::default()).unwrap();
        assert_eq!(s.constraint_vertices(), &[0, off]);
        let r = Rotation3::from_euler_angles(0.2, 0.5, -0.3).into_inner();
        let x = s.solve(&vec![r; m.num_triangles()]).unwrap();
        for comp in [0usize, off as usize] {
            for v in comp..comp + off as usize {
                let want = r * (Vector3::from(m.positions[v]) - Vector3::from(m.positions[comp]));
                let got = Vector3::from(x[v]) - Vector3::from(x[comp]);
                assert!((want - got).norm() < 1e-10);
            }
        }
    }

    #[test]
    fn bad_targets_are_errors() {
        let mut m = grid(2, 2, 1.0);
        m.positions.push([5.0, 5.0, 5.0]);
        let e = TransferSolver::new(&m, &SolverOptions::default()).unwrap_err();
        assert!(matches!(e, TransferError::IsolatedVertices { ref vertices } if vertices == &[9]));
        assert!(e.to_string().contains("9"));
        let m = grid(2, 2, 1.0);
        let e = TransferSolver::new(
            &m,
            &SolverOptions {
                constraint_vertices: vec![99],
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(matches!(
            e,
            TransferError::ConstraintOutOfRange { vertex: 99, .. }
        ));
        let s = TransferSolver::new(&m, &SolverOptions::default()).unwrap();
        assert!(matches!(
            s.solve(&[Matrix3::identity()]),
            Err(TransferError::GradientCount { .. })
        ));
    }
}
