//! Least-squares meshes for marker-driven warping (Wang & Lee 2008, Sec. 3.1.2, Eq. 2 and 4;
//! Sorkine & Cohen-Or 2004).
//!
//! Minimises $\|L V'\|^2 + \omega \sum_{c \in C} \|v'_c - c\|^2$ with $L$ the mean-value
//! Laplacian of Eq. 3 ([`super::laplacian`]), through the normal equations
//! $$(L^\top L + \omega \textstyle\sum_c e_c e_c^\top)\, V' = \omega \textstyle\sum_c e_c\, c^\top,$$
//! an SPD system of size #V (used vertices only) with three right-hand sides (x, y, z).
//! `L` is #V × #V and not symmetric; $L^\top L$ is symmetric with the 2-ring sparsity.
//! The matrix depends only on the mesh and the *set* of constrained vertices, so it is
//! factored once ([`LeastSquaresMesh::new`]) and any constraint positions are a cheap solve.
//!
//! Vertices used by no triangle have no Laplacian row; they are left out of the system and
//! keep their input positions. Every connected component needs at least one constrained
//! vertex, else $L^\top L$ is singular on it (its translation is free).

use super::error::{CorrespondenceError, Side};
use super::laplacian::{mean_value_laplacian, LaplacianOptions, MeanValueLaplacian};
use crate::mesh::{Point, Topology, TriMesh};
use crate::sparse::{Cholesky, Ordering, SparseMatrix, SymmetricPattern};

/// The paper's constraint weight ω (Sec. 3.1.2).
pub const OMEGA: f64 = 10_000.0;

/// Options of [`LeastSquaresMesh`].
#[derive(Clone, Debug)]
pub struct LsMeshOptions {
    /// Soft-constraint weight ω, dimensionless because `L`'s rows are normalised. Default and
    /// paper value: 10 000.
    pub omega: f64,
    /// Laplacian options.
    pub laplacian: LaplacianOptions,
}

impl Default for LsMeshOptions {
    fn default() -> Self {
        Self {
            omega: OMEGA,
            laplacian: LaplacianOptions::default(),
        }
    }
}

/// A prefactored least-squares mesh for one mesh and one set of constrained vertices.
#[derive(Debug)]
pub struct LeastSquaresMesh {
    positions: Vec<Point>,
    constrained: Vec<u32>,
    /// Unknown index of each vertex, `u32::MAX` for an isolated vertex.
    unknown: Vec<u32>,
    num_unknowns: usize,
    omega: f64,
    cholesky: Cholesky,
    laplacian: MeanValueLaplacian,
    /// Which mesh this is, for errors.
    side: Side,
}

impl LeastSquaresMesh {
    /// Builds and factors the system for `mesh` (validated, with its `topology`) with the
    /// vertices `constrained` (in range, distinct). `side` only labels errors.
    pub fn new(
        mesh: &TriMesh,
        topology: &Topology,
        constrained: &[u32],
        opts: &LsMeshOptions,
        side: Side,
    ) -> Result<Self, CorrespondenceError> {
        let nv = mesh.num_vertices();
        let laplacian = mean_value_laplacian(mesh, topology, &opts.laplacian);
        // Components without a constraint.
        let comps = topology.components();
        let mut has = vec![false; topology.num_components()];
        for &c in constrained {
            has[comps[c as usize] as usize] = true;
        }
        let mut is_isolated = vec![false; nv];
        for &v in &laplacian.isolated {
            is_isolated[v] = true;
        }
        for v in 0..nv {
            let c = comps[v] as usize;
            if !has[c] && !is_isolated[v] {
                let size = comps.iter().filter(|&&x| x as usize == c).count();
                return Err(CorrespondenceError::ComponentWithoutMarker {
                    side,
                    component: c,
                    vertex: v,
                    size,
                });
            }
        }
        let mut unknown = vec![u32::MAX; nv];
        let mut num_unknowns = 0usize;
        for v in 0..nv {
            if !is_isolated[v] {
                unknown[v] = num_unknowns as u32;
                num_unknowns += 1;
            }
        }
        // L restricted to used vertices (isolated rows and columns are empty anyway).
        let l = &laplacian.matrix;
        let mut trip = Vec::with_capacity(l.nnz());
        for c in 0..nv {
            for (r, v) in l.col(c) {
                trip.push((unknown[r] as usize, unknown[c] as usize, v));
            }
        }
        let lr = SparseMatrix::from_triplets(num_unknowns, num_unknowns, &trip)
            .map_err(|source| CorrespondenceError::Solve { side, source })?;
        let mut normal = lr.normal_lower_triplets();
        for &c in constrained {
            let u = unknown[c as usize] as usize;
            if u != u32::MAX as usize {
                normal.push((u, u, opts.omega));
            }
        }
        let (pattern, values) = SymmetricPattern::from_triplets(num_unknowns, &normal)
            .map_err(|source| CorrespondenceError::Solve { side, source })?;
        let mut cholesky = Cholesky::analyze(pattern, Ordering::Amd)
            .map_err(|source| CorrespondenceError::Solve { side, source })?;
        cholesky
            .factorize(&values)
            .map_err(|source| CorrespondenceError::Solve { side, source })?;
        Ok(Self {
            positions: mesh.positions.clone(),
            constrained: constrained.to_vec(),
            unknown,
            num_unknowns,
            omega: opts.omega,
            cholesky,
            laplacian,
            side,
        })
    }

    /// Which mesh this least-squares mesh was built for (as given to
    /// [`LeastSquaresMesh::new`]).
    pub fn side(&self) -> Side {
        self.side
    }

    /// The Laplacian used, with its safeguard statistics.
    pub fn laplacian(&self) -> &MeanValueLaplacian {
        &self.laplacian
    }

    /// Solves with the constrained vertices pulled towards `targets` (one per constrained
    /// vertex, in the order given to [`LeastSquaresMesh::new`]); returns all #V positions.
    pub fn solve(&self, targets: &[Point]) -> Result<Vec<Point>, CorrespondenceError> {
        if targets.len() != self.constrained.len() {
            return Err(CorrespondenceError::Invalid(format!(
                "{} least-squares mesh: {} constraint positions for {} constrained vertices",
                self.side,
                targets.len(),
                self.constrained.len()
            )));
        }
        let n = self.num_unknowns;
        let mut rhs = vec![0.0; 3 * n];
        for (&c, t) in self.constrained.iter().zip(targets) {
            let u = self.unknown[c as usize];
            if u == u32::MAX {
                continue;
            }
            for k in 0..3 {
                rhs[k * n + u as usize] += self.omega * t[k];
            }
        }
        self.cholesky
            .solve_in_place(&mut rhs, 3)
            .map_err(|source| CorrespondenceError::Solve {
                side: self.side,
                source,
            })?;
        let mut out = self.positions.clone();
        for (v, &u) in self.unknown.iter().enumerate() {
            if u != u32::MAX {
                out[v] = [
                    rhs[u as usize],
                    rhs[n + u as usize],
                    rhs[2 * n + u as usize],
                ];
            }
        }
        Ok(out)
    }
}

/// One-shot least-squares mesh: `mesh` warped so that `constrained[k]` moves to `targets[k]`.
pub fn least_squares_mesh(
    mesh: &TriMesh,
    constrained: &[u32],
    targets: &[Point],
    opts: &LsMeshOptions,
) -> Result<Vec<Point>, CorrespondenceError> {
    let topo = Topology::new(mesh.num_vertices(), &mesh.triangles);
    LeastSquaresMesh::new(mesh, &topo, constrained, opts, Side::Source)?.solve(targets)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::testmesh::{grid, sphere};

    #[test]
    fn constraints_are_met_and_flat_grids_stay_flat() {
        let m = grid(8, 6, 1.0);
        let corners = [0u32, 8, 6 * 9, 6 * 9 + 8];
        let targets: Vec<Point> = corners
            .iter()
            .map(|&c| {
                let p = m.positions[c as usize];
                [2.0 * p[0] + 1.0, 2.0 * p[1], 0.5]
            })
            .collect();
        let w = least_squares_mesh(&m, &corners, &targets, &LsMeshOptions::default()).unwrap();
        for (k, &c) in corners.iter().enumerate() {
            let d = crate::mesh::norm(crate::mesh::sub(w[c as usize], targets[k]));
            assert!(d < 1e-3, "marker {k} residual {d}");
        }
        // A planar mesh with planar constraints stays in that plane (linear precision).
        for p in &w {
            assert!((p[2] - 0.5).abs() < 1e-9);
        }
    }

    #[test]
    fn scaling_the_mesh_does_not_change_the_warp() {
        let m = sphere(12, 8, 1.0);
        let cons = [0u32, 20, 40, 60, 80];
        let targets: Vec<Point> = cons
            .iter()
            .map(|&c| m.positions[c as usize].map(|x| 3.0 * x + 1.0))
            .collect();
        let a = least_squares_mesh(&m, &cons, &targets, &LsMeshOptions::default()).unwrap();
        let small = m.with_positions(m.positions.iter().map(|p| p.map(|x| 1e-4 * x)).collect());
        let b = least_squares_mesh(&small, &cons, &targets, &LsMeshOptions::default()).unwrap();
        for (p, q) in a.iter().zip(&b) {
            assert!(crate::mesh::norm(crate::mesh::sub(*p, *q)) < 1e-8);
        }
    }

    #[test]
    fn a_component_without_markers_is_an_error() {
        let a = grid(2, 2, 1.0);
        let mut m = a.clone();
        let off = a.num_vertices() as u32;
        m.positions
            .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        m.triangles
            .extend(a.triangles.iter().map(|t| t.map(|i| i + off)));
        let e =
            least_squares_mesh(&m, &[0, 4], &[[0.0; 3]; 2], &LsMeshOptions::default()).unwrap_err();
        assert!(matches!(
            e,
            CorrespondenceError::ComponentWithoutMarker {
                component: 1,
                vertex: 9,
                ..
            }
        ));
    }

    #[test]
    fn solve_errors_name_the_mesh_side() {
        let m = grid(4, 3, 1.0);
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let ls = LeastSquaresMesh::new(&m, &topo, &[0, 4], &LsMeshOptions::default(), Side::Target)
            .unwrap();
        assert_eq!(ls.side(), Side::Target);
        let e = ls.solve(&[[0.0; 3]]).unwrap_err().to_string();
        assert!(e.contains("target"), "{e}");
    }
}
