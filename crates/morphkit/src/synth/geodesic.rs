//! Geodesic distance by the heat method, and geodesic blend regions for non-articulated meshes
//! (Wang & Lee 2008, Sec. 4, the face example; Crane, Weischedel & Wardetzky 2013).
//!
//! With $L$ the cotangent Laplacian (#V × #V, positive semi-definite:
//! $L_{ij} = -\tfrac12(\cot\alpha_{ij} + \cot\beta_{ij})$, rows sum to 0) and $M$ the lumped
//! (barycentric) mass matrix:
//! 1. heat flow for time $t = h^2$ ($h$ the mean edge length): $(M + t L)\, u = \delta_\gamma$,
//!    $\delta_\gamma$ one at the source vertices;
//! 2. per triangle $X = -\nabla u / \|\nabla u\|$ (unit, pointing away from the sources);
//! 3. Poisson: $L \phi = -\nabla\!\cdot X$ with the integrated divergence
//!    $(\nabla\!\cdot X)_i = \tfrac12 \sum_{t \ni i} \cot\theta_1 (e_1 \cdot X_t) + \cot\theta_2 (e_2 \cdot X_t)$;
//!    $L$'s constant null space is removed by fixing one vertex per component, and $\phi$ is
//!    shifted so that its minimum over the sources is 0.
//!
//! Both matrices depend only on the mesh, so [`HeatGeodesics`] factors them once and every
//! source set costs two solves. Units: those of the mesh. Components without a source get
//! $+\infty$. Mesh boundaries use the natural (Neumann) condition.
//!
//! **Blend regions** ([`geodesic_weights`]): for a scribbled region, the sources are the
//! vertices on its boundary (shared by scribbled and unscribbled triangles), a triangle's
//! distance is the mean of its vertices', and a band of total width `width` centred on the
//! boundary is the in-between partition; scribbled triangles outside it are selected (1),
//! the others unselected (0), and Eq. 5 ([`super::WeightSolver`]) fills in the band.

use super::{BlendWeights, SynthError, WeightSolver};
use crate::mesh::{cross, dot, norm, sub, Point, Topology, TriMesh};
use crate::sparse::{Cholesky, Dirichlet, Ordering, SymmetricPattern};

/// Cotangent of the angle at `a` in triangle (a, b, c).
fn cot(a: Point, b: Point, c: Point) -> f64 {
    let (u, v) = (sub(b, a), sub(c, a));
    dot(u, v) / norm(cross(u, v)).max(f64::MIN_POSITIVE)
}

/// Lower-triangle triplets of the cotangent Laplacian (PSD) and the lumped mass per vertex.
fn cotangent_laplacian(mesh: &TriMesh) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let p = &mesh.positions;
    let mut lower = Vec::with_capacity(9 * mesh.num_triangles());
    let mut mass = vec![0.0; mesh.num_vertices()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let area = mesh.triangle_area(t);
        for k in 0..3 {
            let (i, j, o) = (
                tri[(k + 1) % 3] as usize,
                tri[(k + 2) % 3] as usize,
                tri[k] as usize,
            );
            let w = 0.5 * cot(p[o], p[i], p[j]);
            lower.push((i.max(j), i.min(j), -w));
            lower.push((i, i, w));
            lower.push((j, j, w));
            mass[tri[k] as usize] += area / 3.0;
        }
    }
    (lower, mass)
}

/// Options of [`HeatGeodesics`].
#[derive(Clone, Debug)]
pub struct HeatOptions {
    /// Heat time as a multiple of the squared mean edge length. Default 1 (Crane et al.'s value).
    pub time_factor: f64,
}

impl Default for HeatOptions {
    fn default() -> Self {
        Self { time_factor: 1.0 }
    }
}

/// The heat method prefactored on one mesh: both factorizations reused for every source set.
#[derive(Debug)]
pub struct HeatGeodesics {
    positions: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    component: Vec<u32>,
    heat: Cholesky,
    poisson: Cholesky,
    dirichlet: Dirichlet,
    pinned: Vec<usize>,
}

impl HeatGeodesics {
    /// Assembles and factors $M + tL$ and the pinned $L$.
    pub fn new(mesh: &TriMesh, opts: &HeatOptions) -> Result<Self, SynthError> {
        if !(opts.time_factor.is_finite() && opts.time_factor > 0.0) {
            return Err(SynthError::Parameter {
                name: "time_factor",
                value: opts.time_factor,
                why: "must be positive",
            });
        }
        let nv = mesh.num_vertices();
        let topo = Topology::new(nv, &mesh.triangles);
        let edges = topo.edges();
        let h = edges
            .iter()
            .map(|e| {
                norm(sub(
                    mesh.positions[e[0] as usize],
                    mesh.positions[e[1] as usize],
                ))
            })
            .sum::<f64>()
            / edges.len().max(1) as f64;
        let t = opts.time_factor * h * h;
        let (lower, mass) = cotangent_laplacian(mesh);
        let mut heat_trip: Vec<(usize, usize, f64)> =
            lower.iter().map(|&(i, j, v)| (i, j, t * v)).collect();
        // Isolated vertices get unit mass so that both systems stay definite.
        heat_trip.extend(
            mass.iter()
                .enumerate()
                .map(|(i, &m)| (i, i, if m > 0.0 { m } else { 1.0 })),
        );
        let (pattern, values) = SymmetricPattern::from_triplets(nv, &heat_trip)?;
        let mut heat = Cholesky::analyze(pattern, Ordering::Amd)?;
        heat.factorize(&values)?;
        let component = topo.components().to_vec();
        let mut seen = vec![false; topo.num_components()];
        let mut fixed = vec![false; nv];
        let mut pinned = Vec::new();
        for (v, &c) in component.iter().enumerate() {
            if !seen[c as usize] {
                seen[c as usize] = true;
                fixed[v] = true;
                pinned.push(v);
            }
        }
        let dirichlet = Dirichlet::new(nv, &fixed, &lower)?;
        let (pattern, values) =
            SymmetricPattern::from_triplets(dirichlet.num_free(), dirichlet.reduced_triplets())?;
        let mut poisson = Cholesky::analyze(pattern, Ordering::Amd)?;
        poisson.factorize(&values)?;
        Ok(Self {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            component,
            heat,
            poisson,
            dirichlet,
            pinned,
        })
    }

    /// Approximate geodesic distance of every vertex from the nearest of `sources`.
    pub fn distance(&self, sources: &[u32]) -> Result<Vec<f64>, SynthError> {
        let nv = self.positions.len();
        if let Some((k, &s)) = sources.iter().enumerate().find(|(_, &s)| s as usize >= nv) {
            return Err(SynthError::Index {
                what: "geodesic sources",
                position: k,
                index: s as usize,
                element: "vertex",
                count: nv,
            });
        }
        let mut u = vec![0.0; nv];
        sources.iter().for_each(|&s| u[s as usize] = 1.0);
        self.heat.solve_in_place(&mut u, 1)?;
        let p = &self.positions;
        let mut div = vec![0.0; nv];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            let area2 = norm(n);
            if area2 <= 0.0 {
                continue;
            }
            let nn = n.map(|x| x / area2);
            // ∇u = Σ u_i (N × e_i) / (2A), e_i the edge opposite i, counter-clockwise.
            let mut g = [0.0; 3];
            for k in 0..3 {
                let e = sub(p[tri[(k + 2) % 3] as usize], p[tri[(k + 1) % 3] as usize]);
                let ne = cross(nn, e);
                for d in 0..3 {
                    g[d] += u[tri[k] as usize] * ne[d] / area2;
                }
            }
            let gl = norm(g);
            if gl <= 0.0 {
                continue;
            }
            let x = g.map(|v| -v / gl);
            for k in 0..3 {
                let (i, j, l) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let (pi, pj, pl) = (p[i as usize], p[j as usize], p[l as usize]);
                let (e1, e2) = (sub(pj, pi), sub(pl, pi));
                // θ1 is opposite e1 (at l), θ2 opposite e2 (at j).
                div[i as usize] +=
                    0.5 * (cot(pl, pi, pj) * dot(e1, x) + cot(pj, pl, pi) * dot(e2, x));
            }
        }
        let b: Vec<f64> = div.iter().map(|d| -d).collect();
        let zero = vec![0.0; nv];
        let mut r = self.dirichlet.rhs(&b, &zero);
        self.poisson.solve_in_place(&mut r, 1)?;
        let mut phi = vec![0.0; nv];
        self.dirichlet.expand_into(&r, &mut phi);
        // Shift each component so that its sources are at distance 0.
        let ncomp = self.pinned.len();
        let mut lo = vec![f64::INFINITY; ncomp];
        for &s in sources {
            let c = self.component[s as usize] as usize;
            lo[c] = lo[c].min(phi[s as usize]);
        }
        for (v, d) in phi.iter_mut().enumerate() {
            let c = self.component[v] as usize;
            *d = if lo[c].is_finite() {
                (*d - lo[c]).max(0.0)
            } else {
                f64::INFINITY
            };
        }
        Ok(phi)
    }
}

/// One-shot heat-method distance from `sources` on `mesh`.
pub fn geodesic_distance(mesh: &TriMesh, sources: &[u32]) -> Result<Vec<f64>, SynthError> {
    HeatGeodesics::new(mesh, &HeatOptions::default())?.distance(sources)
}

/// Blend weights of a region by geodesic distance from its boundary (module doc): returns the
/// weights and each triangle's distance. `region` has one entry per triangle; `width` is in
/// mesh units and positive. A region without a boundary (all or nothing of every component)
/// needs no band: its weights are its mask.
pub fn geodesic_weights(
    mesh: &TriMesh,
    topology: &Topology,
    heat: &HeatGeodesics,
    region: &[bool],
    width: f64,
    kappa: f64,
) -> Result<(BlendWeights, Vec<f64>), SynthError> {
    let nf = mesh.num_triangles();
    if region.len() != nf {
        return Err(SynthError::Length {
            what: "region",
            expected: nf,
            found: region.len(),
        });
    }
    if !(width.is_finite() && width > 0.0) {
        return Err(SynthError::Parameter {
            name: "blend_width",
            value: width,
            why: "must be positive",
        });
    }
    let nv = mesh.num_vertices();
    let (mut inside, mut outside) = (vec![false; nv], vec![false; nv]);
    for (tri, &r) in mesh.triangles.iter().zip(region) {
        for &v in tri {
            if r {
                inside[v as usize] = true;
            } else {
                outside[v as usize] = true;
            }
        }
    }
    let sources: Vec<u32> = (0..nv as u32)
        .filter(|&v| inside[v as usize] && outside[v as usize])
        .collect();
    if sources.is_empty() {
        let w = region.iter().map(|&r| if r { 1.0 } else { 0.0 }).collect();
        return Ok((BlendWeights { values: w }, vec![f64::INFINITY; nf]));
    }
    let d = heat.distance(&sources)?;
    let td: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| t.iter().map(|&v| d[v as usize]).sum::<f64>() / 3.0)
        .collect();
    let constrained: Vec<bool> = td.iter().map(|&x| x > 0.5 * width).collect();
    let w = WeightSolver::new(topology, &constrained, kappa)?.solve(region)?;
    Ok((w, td))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn heat_distances_match_exact_geodesics_on_a_plane_and_a_sphere() {
        // Plane: a 1 × 1 grid, source at the centre; exact = Euclidean distance.
        let n = 60;
        let g = generate::grid(n, n, 1.0, 1.0);
        let c = (n / 2) * (n + 1) + n / 2;
        let d = geodesic_distance(&g, &[c as u32]).unwrap();
        let mut worst: f64 = 0.0;
        for (v, p) in g.positions.iter().enumerate() {
            let exact = norm(sub(*p, g.positions[c]));
            if (0.1..0.4).contains(&exact) {
                worst = worst.max((d[v] - exact).abs() / exact);
            }
        }
        assert!(worst < 0.05, "plane: worst relative error {worst}");
        // Sphere of radius 2, source at the north pole; exact = R · acos(z / R).
        let r = 2.0;
        let s = generate::uv_sphere(r, 40, 80);
        let top = (0..s.num_vertices())
            .max_by(|&a, &b| s.positions[a][2].total_cmp(&s.positions[b][2]))
            .unwrap();
        let d = geodesic_distance(&s, &[top as u32]).unwrap();
        let mut worst: f64 = 0.0;
        for (v, p) in s.positions.iter().enumerate() {
            let exact = r * (p[2] / r).clamp(-1.0, 1.0).acos();
            if exact > 0.2 * r {
                worst = worst.max((d[v] - exact).abs() / exact);
            }
        }
        assert!(worst < 0.05, "sphere: worst relative error {worst}");
    }

    #[test]
    fn a_band_around_the_region_boundary_blends_and_the_rest_is_exact() {
        let g = generate::grid(40, 4, 4.0, 0.4);
        let topo = Topology::new(g.num_vertices(), &g.triangles);
        let heat = HeatGeodesics::new(&g, &HeatOptions::default()).unwrap();
        let cx = |t: usize| {
            (0..3)
                .map(|k| g.positions[g.triangles[t][k] as usize][0])
                .sum::<f64>()
                / 3.0
        };
        let region: Vec<bool> = (0..g.num_triangles()).map(|t| cx(t) < 2.0).collect();
        let (w, _) = geodesic_weights(&g, &topo, &heat, &region, 1.0, 1e4).unwrap();
        for t in 0..g.num_triangles() {
            let x = cx(t);
            if x < 1.4 {
                assert_eq!(w.values[t], 1.0, "x = {x}");
            } else if x > 2.6 {
                assert_eq!(w.values[t], 0.0, "x = {x}");
            } else if (1.6..2.4).contains(&x) {
                assert!(w.values[t] > 0.0 && w.values[t] < 1.0, "x = {x}");
            }
        }
    }
}
