//! Iterative closest-point refinement of the source warp (Sumner & Popović 2004, Sec. 5).
//!
//! After the least-squares-mesh warp ([`super::super::lsmesh`]) has put the source markers on
//! the target markers, the source is deformed towards the **original** target surface by
//! minimising, over the source vertices $x$ (#V_s × 3) and one free fourth vertex per
//! non-degenerate source triangle (Sumner's formulation: #F_s × 3 more unknowns),
//! $$E = w_s \sum_{i} \sum_{j \in \mathrm{adj}(i)} \|T_i - T_j\|_F^2
//!     + w_i \sum_i \|T_i - I\|_F^2
//!     + \frac{w_c}{d_t^2} \sum_{v} \|x_v - c_v\|^2$$
//! subject to $x_m = $ target marker position for every marker $m$ (hard constraints,
//! eliminated). $T_i = \tilde V_i V_i^{-1}$ is triangle $i$'s deformation gradient relative
//! to the source reference (3 × 3; $V_i$ from [`super::super::gradients::triangle_frame`],
//! $\tilde V_i = [x_2 - x_1, x_3 - x_1, x_4 - x_1]$ with $x_4$ the free fourth vertex), linear
//! in the unknowns: $T_i = \sum_u x_u g_u^\top$ with $g_1 = -(r_1 + r_2 + r_3)$,
//! $g_{2,3,4} = r_{1,2,3}$, $r_k$ the rows of $V_i^{-1}$. "Adjacent" means sharing an edge.
//! $c_v$ is the closest *valid* point of the target to $x_v$: the closest point on the
//! triangles around the nearest target vertex whose (area-weighted) vertex normal is less than
//! 90° from $x_v$'s current vertex normal; vertices with no valid point get no term. $d_t$, the
//! target's bounding-box diagonal, makes $w_c$ independent of the units (Sumner's meshes have
//! $d \approx 1$–2). The energy separates into x, y and z with one matrix
//! $$H = w_s S + w_i J + \tfrac{w_c}{d_t^2} D, \qquad D = \operatorname{diag}(\text{has a valid } c_v),$$
//! so the sparsity pattern (the union over all $w_c$ and valid sets) is analysed **once** and
//! each step is a numeric refactorization and a 3-right-hand-side solve. Sumner's weights:
//! $w_s = 1$, $w_i = 0.001$, $w_c$ increasing over a few steps to 5000.
//!
//! Source vertices in no non-degenerate triangle keep their least-squares-mesh position
//! (fixed), so the reduced matrix is positive definite whatever the valid set.

use super::super::error::{CorrespondenceError, Side};
use super::super::gradients::{degeneracy_tolerance, reference_frame_inverse};
use super::super::kdtree::KdTree;
use crate::mesh::{dot, norm, sub, triangle_normal, Point, Topology, TriMesh};
use crate::sparse::{Cholesky, Dirichlet, Ordering, SymmetricPattern};

/// Options of the closest-point refinement ([module docs](self)).
#[derive(Clone, Debug)]
pub struct RefineOptions {
    /// Deformation smoothness weight $w_s$. Default and Sumner's value: 1.
    pub smoothness: f64,
    /// Deformation identity weight $w_i$. Default and Sumner's value: 0.001.
    pub identity: f64,
    /// Closest-point weights $w_c$, one solve each, in units of the target's bounding-box
    /// diagonal. Default `[1, 10, 100, 1000, 5000]` (Sumner: 1 … 5000 in four steps).
    pub closest_weights: Vec<f64>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            smoothness: 1.0,
            identity: 0.001,
            closest_weights: vec![1.0, 10.0, 100.0, 1000.0, 5000.0],
        }
    }
}

/// What one refinement step did (deterministic: no timings).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RefineStep {
    /// $w_c$ of the step.
    pub closest_weight: f64,
    /// Fraction of the free source vertices that had a valid closest point.
    pub valid_fraction: f64,
    /// Mean distance of the solved vertices from their closest points, over the target's
    /// bounding-box diagonal.
    pub mean_distance: f64,
}

/// The prefactored refinement system of one source mesh and marker set.
struct System {
    nv: usize,
    dirichlet: Dirichlet,
    cholesky: Cholesky,
    /// Values of $w_s S + w_i J$ in the pattern's slots.
    base: Vec<f64>,
    /// Pattern slot of each free vertex's diagonal (`usize::MAX` for a fixed vertex).
    vertex_diag: Vec<usize>,
    /// Identity right-hand side $w_i g_u[k]$, `3 × n` (coordinate-major).
    identity_rhs: Vec<f64>,
    /// Unknown count (vertices + fourth vertices).
    n: usize,
    /// Fixed values (full length, coordinate-major), read only at fixed unknowns.
    fixed_values: Vec<f64>,
}

/// Adds `w · Σ_c a_c a_cᵀ` for the coefficient lists `a_c` (unknown, coefficient) into
/// lower triplets.
fn push_gram(idx: &[usize], rows: &[[f64; 3]], w: f64, out: &mut Vec<(usize, usize, f64)>) {
    for a in 0..idx.len() {
        for b in 0..=a {
            let v = w * (0..3).map(|c| rows[a][c] * rows[b][c]).sum::<f64>();
            if v != 0.0 || a == b {
                let (i, j) = (idx[a].max(idx[b]), idx[a].min(idx[b]));
                out.push((i, j, v));
            }
        }
    }
}

impl System {
    fn new(
        source: &TriMesh,
        topo: &Topology,
        start: &[Point],
        marker_vertices: &[u32],
        marker_goal: &[Point],
        opts: &RefineOptions,
    ) -> Result<Self, CorrespondenceError> {
        let nv = source.num_vertices();
        let nf = source.num_triangles();
        let tol = degeneracy_tolerance(source);
        // Coefficients g_u (3-vectors) of the four unknowns of every usable triangle.
        let mut fourth = vec![usize::MAX; nf];
        let mut coeff: Vec<Option<[[f64; 3]; 4]>> = Vec::with_capacity(nf);
        let mut n = nv;
        for (t, &tri) in source.triangles.iter().enumerate() {
            match reference_frame_inverse(&source.positions, tri, tol) {
                Some(inv) => {
                    let r = |k: usize| [inv[(k, 0)], inv[(k, 1)], inv[(k, 2)]];
                    let (r1, r2, r3) = (r(0), r(1), r(2));
                    let g1 = [0, 1, 2].map(|c| -(r1[c] + r2[c] + r3[c]));
                    coeff.push(Some([g1, r1, r2, r3]));
                    fourth[t] = n;
                    n += 1;
                }
                None => coeff.push(None),
            }
        }
        let unknowns = |t: usize| {
            let tri = source.triangles[t];
            [tri[0] as usize, tri[1] as usize, tri[2] as usize, fourth[t]]
        };
        let mut lower = Vec::with_capacity(40 * nf);
        let mut identity_rhs = vec![0.0; 3 * n];
        let mut covered = vec![false; nv];
        let mut idx: Vec<usize> = Vec::with_capacity(8);
        let mut rows: Vec<[f64; 3]> = Vec::with_capacity(8);
        for t in 0..nf {
            let Some(g) = coeff[t] else { continue };
            let u = unknowns(t);
            for &v in &u[..3] {
                covered[v] = true;
            }
            // Identity term.
            push_gram(&u, &g, opts.identity, &mut lower);
            for (a, &ua) in u.iter().enumerate() {
                for k in 0..3 {
                    identity_rhs[k * n + ua] += opts.identity * g[a][k];
                }
            }
            // Smoothness with each edge neighbour of higher index (each pair once).
            for &s in topo.face_neighbors(t) {
                let s = s as usize;
                if s <= t {
                    continue;
                }
                let Some(h) = coeff[s] else { continue };
                idx.clear();
                rows.clear();
                for (ui, gi) in u.iter().zip(&g) {
                    idx.push(*ui);
                    rows.push(*gi);
                }
                for (us, gs) in unknowns(s).iter().zip(&h) {
                    let neg = gs.map(|x| -x);
                    match idx.iter().position(|&x| x == *us) {
                        Some(p) => rows[p] = add(rows[p], neg),
                        None => {
                            idx.push(*us);
                            rows.push(neg);
                        }
                    }
                }
                push_gram(&idx, &rows, opts.smoothness, &mut lower);
            }
        }
        let mut fixed = vec![false; n];
        let mut fixed_values = vec![0.0; 3 * n];
        for v in 0..nv {
            if !covered[v] {
                fixed[v] = true;
                for k in 0..3 {
                    fixed_values[k * n + v] = start[v][k];
                }
            }
        }
        for (&m, g) in marker_vertices.iter().zip(marker_goal) {
            fixed[m as usize] = true;
            for k in 0..3 {
                fixed_values[k * n + m as usize] = g[k];
            }
        }
        let solve_err = |source| CorrespondenceError::Solve {
            side: Side::Source,
            source,
        };
        let dirichlet = Dirichlet::new(n, &fixed, &lower).map_err(solve_err)?;
        let (pattern, base) =
            SymmetricPattern::from_triplets(dirichlet.num_free(), dirichlet.reduced_triplets())
                .map_err(solve_err)?;
        let vertex_diag = (0..nv)
            .map(|v| {
                dirichlet
                    .reduced_index(v)
                    .map_or(usize::MAX, |r| pattern.diag_slot(r))
            })
            .collect();
        let cholesky = Cholesky::analyze(pattern, Ordering::Amd).map_err(solve_err)?;
        Ok(Self {
            nv,
            dirichlet,
            cholesky,
            base,
            vertex_diag,
            identity_rhs,
            n,
            fixed_values,
        })
    }

    /// One step: refactor with closest-point weight `wc` (already divided by $d_t^2$) on the
    /// vertices with `Some` closest point, and solve.
    fn step(
        &mut self,
        wc: f64,
        closest: &[Option<Point>],
    ) -> Result<Vec<Point>, CorrespondenceError> {
        let solve_err = |source| CorrespondenceError::Solve {
            side: Side::Source,
            source,
        };
        let mut values = self.base.clone();
        let n = self.n;
        let mut b = self.identity_rhs.clone();
        for v in 0..self.nv {
            let slot = self.vertex_diag[v];
            if slot == usize::MAX {
                continue;
            }
            if let Some(c) = closest[v] {
                values[slot] += wc;
                for k in 0..3 {
                    b[k * n + v] += wc * c[k];
                }
            }
        }
        self.cholesky.factorize(&values).map_err(solve_err)?;
        let nfree = self.dirichlet.num_free();
        let mut rhs = Vec::with_capacity(3 * nfree);
        for k in 0..3 {
            rhs.extend(self.dirichlet.rhs(
                &b[k * n..(k + 1) * n],
                &self.fixed_values[k * n..(k + 1) * n],
            ));
        }
        self.cholesky
            .solve_in_place(&mut rhs, 3)
            .map_err(solve_err)?;
        let mut out = vec![[0.0; 3]; self.nv];
        for (v, o) in out.iter_mut().enumerate() {
            match self.dirichlet.reduced_index(v) {
                Some(r) => *o = [rhs[r], rhs[nfree + r], rhs[2 * nfree + r]],
                None => *o = [0, 1, 2].map(|k| self.fixed_values[k * n + v]),
            }
        }
        if let Some(v) = out.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(CorrespondenceError::Invalid(format!(
                "closest-point refinement: source vertex {v} is not finite after the solve"
            )));
        }
        Ok(out)
    }
}

fn add(a: Point, b: Point) -> Point {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: Point, s: f64) -> Point {
    a.map(|x| x * s)
}

/// Area-weighted vertex normals (not normalised; zero for a vertex of zero-area triangles).
pub(crate) fn vertex_normals(p: &[Point], tris: &[[u32; 3]]) -> Vec<Point> {
    let mut n = vec![[0.0; 3]; p.len()];
    for &t in tris {
        let f = triangle_normal(p, t);
        for &v in &t {
            n[v as usize] = add(n[v as usize], f);
        }
    }
    n
}

/// Closest point to `q` on triangle `(a, b, c)` (Ericson, Real-Time Collision Detection 5.1.5).
pub(crate) fn closest_on_triangle(q: Point, a: Point, b: Point, c: Point) -> Point {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(q, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(q, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return add(a, scale(ab, v));
    }
    let cp = sub(q, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return add(a, scale(ac, w));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return add(b, scale(sub(c, b), w));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    add(a, add(scale(ab, v), scale(ac, w)))
}

/// The target surface for closest-valid-point queries.
struct TargetSurface<'a> {
    mesh: &'a TriMesh,
    tree: KdTree,
    normals: Vec<Point>,
    /// Triangles around each vertex (CSR).
    ring_offsets: Vec<usize>,
    ring: Vec<u32>,
}

impl<'a> TargetSurface<'a> {
    fn new(mesh: &'a TriMesh) -> Self {
        let nv = mesh.num_vertices();
        let mut count = vec![0usize; nv + 1];
        for t in &mesh.triangles {
            for &v in t {
                count[v as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            count[v + 1] += count[v];
        }
        let mut fill = count.clone();
        let mut ring = vec![0u32; count[nv]];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                ring[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }
        Self {
            mesh,
            tree: KdTree::new(&mesh.positions),
            normals: vertex_normals(&mesh.positions, &mesh.triangles),
            ring_offsets: count,
            ring,
        }
    }

    /// Closest valid point to `q` with vertex normal `n` (see the module docs).
    fn closest(&self, q: Point, n: Point) -> Option<Point> {
        if norm(n) == 0.0 {
            return None;
        }
        let (v, _) = self
            .tree
            .nearest_filtered(q, |v| dot(self.normals[v as usize], n) > 0.0)?;
        let p = &self.mesh.positions;
        let mut best = p[v as usize];
        let mut best_d = norm(sub(best, q));
        for &t in &self.ring[self.ring_offsets[v as usize]..self.ring_offsets[v as usize + 1]] {
            let tri = self.mesh.triangles[t as usize];
            let f = triangle_normal(p, tri);
            if dot(f, n) <= 0.0 {
                continue;
            }
            let c = closest_on_triangle(
                q,
                p[tri[0] as usize],
                p[tri[1] as usize],
                p[tri[2] as usize],
            );
            let d = norm(sub(c, q));
            if d < best_d {
                best = c;
                best_d = d;
            }
        }
        Some(best)
    }
}

/// Deforms `source` (starting from `start`, the least-squares-mesh warp) towards `target`'s
/// surface by the steps of `opts.closest_weights`, the source markers held at `marker_goal`.
/// Returns the deformed source positions (#V_s) and what each step did.
pub fn refine(
    source: &TriMesh,
    topo: &Topology,
    target: &TriMesh,
    start: &[Point],
    marker_vertices: &[u32],
    marker_goal: &[Point],
    opts: &RefineOptions,
) -> Result<(Vec<Point>, Vec<RefineStep>), CorrespondenceError> {
    if let Some(w) = [opts.smoothness, opts.identity]
        .iter()
        .chain(&opts.closest_weights)
        .find(|w| !(w.is_finite() && **w > 0.0))
    {
        return Err(CorrespondenceError::Invalid(format!(
            "refinement weight {w}: every weight must be positive and finite"
        )));
    }
    if opts.closest_weights.is_empty() {
        return Ok((start.to_vec(), Vec::new()));
    }
    let mut sys = System::new(source, topo, start, marker_vertices, marker_goal, opts)?;
    let surface = TargetSurface::new(target);
    let d = target.bbox_diagonal().max(f64::MIN_POSITIVE);
    let mut x = start.to_vec();
    let mut steps = Vec::with_capacity(opts.closest_weights.len());
    for &wc in &opts.closest_weights {
        let normals = vertex_normals(&x, &source.triangles);
        let closest: Vec<Option<Point>> = (0..x.len())
            .map(|v| {
                if sys.vertex_diag[v] == usize::MAX {
                    None
                } else {
                    surface.closest(x[v], normals[v])
                }
            })
            .collect();
        x = sys.step(wc / (d * d), &closest)?;
        let (mut sum, mut count, mut free) = (0.0, 0usize, 0usize);
        for (v, c) in closest.iter().enumerate() {
            if sys.vertex_diag[v] == usize::MAX {
                continue;
            }
            free += 1;
            if let Some(c) = c {
                sum += norm(sub(x[v], *c));
                count += 1;
            }
        }
        steps.push(RefineStep {
            closest_weight: wc,
            valid_fraction: count as f64 / free.max(1) as f64,
            mean_distance: sum / count.max(1) as f64 / d,
        });
    }
    Ok((x, steps))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_on_a_triangle_covers_every_region() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let cases = [
            ([0.2, 0.2, 1.0], [0.2, 0.2, 0.0]),
            ([-1.0, -1.0, 0.0], a),
            ([2.0, -0.5, 0.0], b),
            ([-0.5, 2.0, 0.3], c),
            ([0.5, -1.0, 0.0], [0.5, 0.0, 0.0]),
            ([-1.0, 0.5, 0.0], [0.0, 0.5, 0.0]),
            ([1.0, 1.0, 0.0], [0.5, 0.5, 0.0]),
        ];
        for (q, want) in cases {
            let got = closest_on_triangle(q, a, b, c);
            assert!(norm(sub(got, want)) < 1e-12, "{q:?}: {got:?} vs {want:?}");
        }
    }
}
