//! The mean-value Laplacian of Wang & Lee 2008, Sec. 3.1.2, Eq. 3 (Floater 2003).
//!
//! For an edge $\{i, j\}$,
//! $$\delta_{ij} = \frac{\tan(\alpha_{ij}/2) + \tan(\beta_{ij}/2)}{\|v_i - v_j\|},$$
//! $\alpha_{ij}, \beta_{ij}$ the angles **at $v_i$** between edge $ij$ and the neighbouring
//! edges of the two triangles that contain it. We sum one $\tan(\theta/2)$ term per incident
//! triangle, which is Eq. 3 on interior edges and extends it to boundary edges (one term) and
//! non-manifold edges (three or more terms). The weights are not symmetric:
//! $\delta_{ij} \ne \delta_{ji}$.
//!
//! The matrix $L$ is #V × #V with rows normalised, $L_{ii} = -1$ and
//! $L_{ij} = \delta_{ij} / q_i$, $q_i = \sum_k \delta_{ik}$, so rows sum to zero and
//! $(L V)_i = \bar v_i - v_i$ with $\bar v_i$ the mean-value average of the neighbours. Eq. 3
//! as printed ($L_{ii} = -q_i$) has rows that scale like 1/length, which would make the
//! weight ω = 10 000 of Eq. 2 depend on the mesh's units; normalising (as Sorkine &
//! Cohen-Or's least-squares meshes do) keeps each row's equation and makes the warp
//! scale-invariant. [`LaplacianOptions::normalize_rows`] turns it off.
//!
//! Safeguards, so that $L$ is finite for any input:
//! - $\tan(\theta/2)$ is evaluated as $\|a \times b\| / (\|a\|\|b\| + a \cdot b)$ (no
//!   trigonometry), and is capped at $\tan(\theta_{max}/2)$ with $\theta_{max} = 175°$: a corner
//!   of nearly 180° (a sliver, or a vertex on its neighbours' segment) would otherwise give an
//!   unbounded weight. Obtuse corners below the cap are exact; the weights stay positive.
//! - A corner with an edge shorter than $10^{-12} \times$ the bounding-box diagonal has no
//!   defined angle and contributes nothing; edge lengths are floored at the same value.
//! - A row whose weights sum to zero or overflow (every corner degenerate) falls back to
//!   uniform weights $1/\deg(i)$ over the one-ring.
//! - An isolated vertex has an empty row (its `L` row is zero); callers exclude it.

use crate::mesh::{cross, dot, norm, sub, Point, Topology, TriMesh};
use crate::sparse::SparseMatrix;

/// Largest corner angle used for the half-angle tangent, in degrees.
pub const MAX_CORNER_ANGLE_DEG: f64 = 175.0;

/// Options of [`mean_value_laplacian`].
#[derive(Clone, Debug)]
pub struct LaplacianOptions {
    /// Normalise rows to $L_{ii} = -1$ (default `true`; see the module docs).
    pub normalize_rows: bool,
}

impl Default for LaplacianOptions {
    fn default() -> Self {
        Self {
            normalize_rows: true,
        }
    }
}

/// The Laplacian and what its safeguards did.
#[derive(Clone, Debug)]
pub struct MeanValueLaplacian {
    /// `L`, #V × #V.
    pub matrix: SparseMatrix,
    /// Corners whose half-angle tangent was capped (angle above [`MAX_CORNER_ANGLE_DEG`]).
    pub capped_corners: usize,
    /// Corners skipped because an edge had (nearly) zero length.
    pub skipped_corners: usize,
    /// Rows that fell back to uniform weights.
    pub uniform_rows: Vec<usize>,
    /// Vertices used by no triangle (zero rows).
    pub isolated: Vec<usize>,
}

/// $\tan(\theta/2)$ of the angle between `a` and `b`, capped; `None` when either is shorter
/// than `eps`.
fn half_angle_tan(a: Point, b: Point, eps: f64, cap: f64) -> Option<(f64, bool)> {
    let (la, lb) = (norm(a), norm(b));
    if la <= eps || lb <= eps {
        return None;
    }
    let s = norm(cross(a, b));
    let denom = la * lb + dot(a, b);
    // tan(θ/2) = sin θ / (1 + cos θ); denom = |a||b| (1 + cos θ).
    if denom <= 0.0 || s >= cap * denom {
        return Some((cap, true));
    }
    Some((s / denom, false))
}

/// Builds the mean-value Laplacian of `mesh` from its own positions. `topology` must be the
/// mesh's topology (for the one-ring fallback).
pub fn mean_value_laplacian(
    mesh: &TriMesh,
    topology: &Topology,
    opts: &LaplacianOptions,
) -> MeanValueLaplacian {
    let nv = mesh.num_vertices();
    let p = &mesh.positions;
    let eps = 1e-12 * mesh.bbox_diagonal().max(f64::MIN_POSITIVE);
    let cap = (MAX_CORNER_ANGLE_DEG.to_radians() / 2.0).tan();
    // Directed weights δ_ij accumulated per (i, j); duplicates summed later.
    let mut directed: Vec<(usize, usize, f64)> = Vec::with_capacity(6 * mesh.num_triangles());
    let (mut capped, mut skipped) = (0, 0);
    for tri in &mesh.triangles {
        for k in 0..3 {
            let i = tri[k] as usize;
            let j = tri[(k + 1) % 3] as usize;
            let l = tri[(k + 2) % 3] as usize;
            let (a, b) = (sub(p[j], p[i]), sub(p[l], p[i]));
            match half_angle_tan(a, b, eps, cap) {
                None => skipped += 1,
                Some((t, was_capped)) => {
                    capped += was_capped as usize;
                    directed.push((i, j, t / norm(a).max(eps)));
                    directed.push((i, l, t / norm(b).max(eps)));
                }
            }
        }
    }
    let mut q = vec![0.0f64; nv];
    for &(i, _, w) in &directed {
        q[i] += w;
    }
    let mut uniform_rows = Vec::new();
    let mut isolated = Vec::new();
    let mut uniform = vec![false; nv];
    for v in 0..nv {
        let deg = topology.one_ring(v).len();
        if deg == 0 {
            isolated.push(v);
        } else if !(q[v].is_finite() && q[v] > 0.0) {
            uniform[v] = true;
            uniform_rows.push(v);
        }
    }
    let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(directed.len() + nv);
    for &(i, j, w) in &directed {
        if uniform[i] {
            continue;
        }
        let w = if opts.normalize_rows { w / q[i] } else { w };
        trip.push((i, j, w));
    }
    for v in 0..nv {
        let ring = topology.one_ring(v);
        if ring.is_empty() {
            continue;
        }
        if uniform[v] {
            let scale = if opts.normalize_rows {
                1.0
            } else {
                ring.len() as f64
            };
            for &j in ring {
                trip.push((v, j as usize, scale / ring.len() as f64));
            }
            trip.push((v, v, -scale));
        } else {
            trip.push((v, v, if opts.normalize_rows { -1.0 } else { -q[v] }));
        }
    }
    let matrix =
        SparseMatrix::from_triplets(nv, nv, &trip).expect("finite weights with valid indices");
    MeanValueLaplacian {
        matrix,
        capped_corners: capped,
        skipped_corners: skipped,
        uniform_rows,
        isolated,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn apply(l: &SparseMatrix, p: &[Point]) -> Vec<Point> {
        let mut out = vec![[0.0; 3]; p.len()];
        for k in 0..3 {
            let x: Vec<f64> = p.iter().map(|q| q[k]).collect();
            for (i, y) in l.mul_vec(&x).into_iter().enumerate() {
                out[i][k] = y;
            }
        }
        out
    }

    /// A random star-shaped planar one-ring around vertex 0, then rotated into 3-D.
    fn planar_ring(n: usize, rng: &mut ChaCha8Rng) -> TriMesh {
        let mut angles: Vec<f64> = (0..n)
            .map(|k| (k as f64 + rng.random_range(-0.2..0.2)) * std::f64::consts::TAU / n as f64)
            .collect();
        angles.sort_by(f64::total_cmp);
        let centre = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
        let mut pts2 = vec![centre];
        for a in &angles {
            let r = rng.random_range(0.3..2.0);
            pts2.push([centre[0] + r * a.cos(), centre[1] + r * a.sin()]);
        }
        let rot = nalgebra::Rotation3::from_euler_angles(0.4, 1.0, -0.7);
        let positions = pts2
            .iter()
            .map(|q| (rot * nalgebra::Vector3::new(q[0], q[1], 0.3)).into())
            .collect();
        let triangles = (0..n as u32)
            .map(|k| [0, 1 + k, 1 + (k + 1) % n as u32])
            .collect();
        TriMesh::new(positions, triangles)
    }

    #[test]
    fn linear_precision_on_planar_one_rings() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for n in [3, 4, 5, 7, 12] {
            for _ in 0..20 {
                let m = planar_ring(n, &mut rng);
                let topo = Topology::new(m.num_vertices(), &m.triangles);
                for normalize_rows in [true, false] {
                    let l = mean_value_laplacian(&m, &topo, &LaplacianOptions { normalize_rows });
                    let lv = apply(&l.matrix, &m.positions);
                    let err = norm(lv[0]);
                    assert!(err < 1e-12, "n = {n}: |L v|_0 = {err}");
                    assert_eq!(l.capped_corners, 0);
                }
            }
        }
    }

    #[test]
    fn rows_sum_to_zero_and_stay_finite_on_bad_triangles() {
        // A fan with an obtuse corner, a sliver (angle ≈ 180°), a zero-length edge and a
        // non-manifold fin, plus an isolated vertex.
        let positions = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 1e-9, 0.0], // sliver with 0, 1: angle at 0 ≈ 180°
            [1.0, 0.0, 0.0],   // coincides with 1
            [0.5, 0.5, 1.0],
            [9.0, 9.0, 9.0], // isolated
        ];
        let triangles = vec![
            [0, 1, 2],
            [0, 2, 3],
            [0, 3, 1],
            [1, 4, 2],
            [0, 1, 5],
            [1, 0, 2],
        ];
        let m = TriMesh::new(positions, triangles);
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let l = mean_value_laplacian(&m, &topo, &LaplacianOptions::default());
        assert!(l.capped_corners >= 1, "the sliver corner is capped");
        assert!(
            l.skipped_corners >= 2,
            "corners on the zero-length edge are skipped"
        );
        assert_eq!(l.isolated, vec![6]);
        let ones = vec![1.0; m.num_vertices()];
        for (i, s) in l.matrix.mul_vec(&ones).iter().enumerate() {
            assert!(s.abs() < 1e-12, "row {i} sums to {s}");
        }
        for c in 0..m.num_vertices() {
            for (_, v) in l.matrix.col(c) {
                assert!(v.is_finite() && v.abs() <= 1.0 + 1e-12);
            }
        }
    }
}
