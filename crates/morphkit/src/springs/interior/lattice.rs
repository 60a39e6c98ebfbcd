//! Interior points and internal springs: a body-centred cubic (BCC) lattice inside each closed
//! component of the base (Ma et al. 2012, Sec. 3.1, with a lattice in place of the paper's
//! constrained Delaunay tetrahedralization).
//!
//! For a closed, consistently oriented component with mean surface edge $\bar e$ the lattice
//! spacing is $h = 2 \bar e / \text{density}$. The lattice has corner points $o + h(i, j, k)$
//! and cell centres $o + h(i + \frac12, j + \frac12, k + \frac12)$; a point is kept when it is
//! inside (`parry3d-f64` pseudo-normal test, trimesh with the `ORIENTED` flag) and at least
//! `margin · h` from the surface. Springs:
//!
//! - lattice edges: corner–corner and centre–centre along the axes (length $h$), centre–corner
//!   to the 8 corners of its cell (length $\frac{\sqrt3}{2}h$): the edges of the BCC
//!   tetrahedralization, whose tetrahedra are $(c, c', q_m, q_{m+1})$ for axis-adjacent centres
//!   $c, c'$ and the corners $q_0..q_3$ of their shared face, in cyclic order;
//! - ties: each surface vertex to its `ties_per_vertex` nearest kept points within
//!   `tie_radius · h`.
//!
//! A spring whose segment leaves the solid (a ray cast from its interior end hits the surface
//! before the other end) is dropped, so that no spring bridges a gap between two fingers.
//! Lattice points not connected through lattice edges to a tied point are dropped as well
//! (their positions in a target would not be determined by the surface). Everything is
//! deterministic: index arithmetic, no hashing order, no randomness.
//!
//! **Small holes.** A component whose only defects are boundary loops that are *small* (each
//! loop's fan cap around its vertex centroid has at most [`MAX_HOLE_AREA_FRACTION`] of the
//! component's surface area: the horse's hoof holes, an open tube's end caps, a scan's gaps)
//! is filled as if those holes were capped: the caps enter the inside test and the volume
//! only, never the surface or its springs. A larger opening (a face mask's outline) leaves the
//! component open, with no interior.

pub use super::holes::MAX_HOLE_AREA_FRACTION;
use super::holes::{small_hole_caps, Cap};
use super::options::InteriorOptions;
use crate::mesh::{norm, sub, Point, Topology};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::{TriMesh as ParryMesh, TriMeshFlags};

/// A closed (or closed up to small capped holes), consistently oriented component of the base
/// with its inside test.
pub struct Solid {
    /// Component label (as in [`Topology::components`]).
    pub component: usize,
    /// Its surface vertices, sorted.
    pub vertices: Vec<u32>,
    /// Mean structure edge length in the base.
    pub mean_edge: f64,
    /// Volume enclosed in the base.
    pub volume: f64,
    /// Volume centroid in the base.
    pub centroid: Point,
    /// Holes capped for the inside test (0 for a closed component).
    pub capped_holes: usize,
    mesh: ParryMesh,
}

/// A component that gets no interior, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SkippedComponent {
    /// Component label.
    pub component: usize,
    /// One of its vertices.
    pub example_vertex: u32,
    /// Why: `"open"` (boundary or non-manifold edges), `"not consistently oriented"`, `"too
    /// thin for the lattice"`, `"inside test unavailable"`, `"tetgen made no tetrahedra"`.
    pub reason: String,
}

fn v3(p: Point) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

impl Solid {
    /// Signed distance-like query: `(inside, distance to the surface)`.
    pub fn query(&self, p: Point) -> (bool, f64) {
        let q = v3(p);
        let proj = self.mesh.project_local_point(q, false);
        (proj.is_inside, (proj.point - q).length())
    }

    /// True when the segment from `from` (inside) to `to` stays inside, up to `tol` at its end.
    pub fn segment_inside(&self, from: Point, to: Point, tol: f64) -> bool {
        let d = sub(to, from);
        let len = norm(d);
        if len <= tol {
            return true;
        }
        let ray = Ray::new(v3(from), v3([d[0] / len, d[1] / len, d[2] / len]));
        match self.mesh.cast_local_ray(&ray, len, false) {
            Some(t) => t >= len - tol,
            None => true,
        }
    }
}

/// The closed components of the base and those that cannot hold an interior.
pub fn solids(base: &[Point], triangles: &[[u32; 3]]) -> (Vec<Solid>, Vec<SkippedComponent>) {
    let topo = Topology::new(base.len(), triangles);
    let label = topo.components();
    let nc = topo.num_components();
    let mut reason: Vec<Option<&str>> = vec![None; nc];
    let mut holed = vec![false; nc];
    for e in topo.boundary_edges() {
        holed[label[topo.edges()[e][0] as usize] as usize] = true;
    }
    for e in topo.non_manifold_edges() {
        reason[label[topo.edges()[e][0] as usize] as usize] = Some("open");
    }
    let mut tris: Vec<Vec<[u32; 3]>> = vec![Vec::new(); nc];
    for &t in triangles {
        tris[label[t[0] as usize] as usize].push(t);
    }
    // Consistent orientation: no directed edge occurs twice.
    for (c, ts) in tris.iter().enumerate() {
        if reason[c].is_some() {
            continue;
        }
        let mut directed: Vec<(u32, u32)> = ts
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        directed.sort_unstable();
        if directed.windows(2).any(|w| w[0] == w[1]) {
            reason[c] = Some("not consistently oriented");
        }
    }
    let mut out = Vec::new();
    let mut skipped = Vec::new();
    let mut first = vec![u32::MAX; nc];
    for v in (0..base.len()).rev() {
        first[label[v] as usize] = v as u32;
    }
    for c in 0..nc {
        if tris[c].is_empty() {
            continue; // isolated vertices: no component to fill
        }
        if let Some(r) = reason[c] {
            skipped.push(SkippedComponent {
                component: c,
                example_vertex: first[c],
                reason: r.into(),
            });
            continue;
        }
        let caps = if holed[c] {
            match small_hole_caps(base, &tris[c]) {
                Some(caps) => caps,
                _ => {
                    skipped.push(SkippedComponent {
                        component: c,
                        example_vertex: first[c],
                        reason: "open".into(),
                    });
                    continue;
                }
            }
        } else {
            Vec::new()
        };
        match Solid::new(base, &tris[c], &caps, c, &topo) {
            Some(s) => out.push(s),
            None => skipped.push(SkippedComponent {
                component: c,
                example_vertex: first[c],
                reason: "inside test unavailable".into(),
            }),
        }
    }
    (out, skipped)
}

impl Solid {
    fn new(
        base: &[Point],
        tris: &[[u32; 3]],
        caps: &[Cap],
        component: usize,
        topo: &Topology,
    ) -> Option<Self> {
        let mut vertices: Vec<u32> = tris.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let local = |v: u32| vertices.binary_search(&v).unwrap_or(0) as u32;
        // The closed surface of the inside test: the triangles, then each cap's fan (its
        // centre is point `vertices.len() + k`), in local ids.
        let nv = vertices.len() as u32;
        let mut closed: Vec<[u32; 3]> = tris.iter().map(|t| t.map(local)).collect();
        for (k, cap) in caps.iter().enumerate() {
            for &[a, b] in &cap.edges {
                closed.push([local(b), local(a), nv + k as u32]);
            }
        }
        let point = |i: u32| {
            if i < nv {
                base[vertices[i as usize] as usize]
            } else {
                caps[(i - nv) as usize].centre
            }
        };
        // Signed volume and centroid (divergence theorem over the closed surface).
        let (mut vol, mut cen) = (0.0, [0.0; 3]);
        for t in &closed {
            let [a, b, c] = t.map(point);
            let v = crate::mesh::dot(a, crate::mesh::cross(b, c)) / 6.0;
            vol += v;
            for k in 0..3 {
                cen[k] += v * (a[k] + b[k] + c[k]) / 4.0;
            }
        }
        if vol == 0.0 || !vol.is_finite() {
            return None;
        }
        let flip = vol < 0.0;
        let cen = cen.map(|x| x / vol);
        let indices: Vec<[u32; 3]> = closed
            .iter()
            .map(|&l| if flip { [l[0], l[2], l[1]] } else { l })
            .collect();
        let pts: Vec<Vector> = (0..nv + caps.len() as u32).map(|i| v3(point(i))).collect();
        let mesh = ParryMesh::with_flags(pts, indices, TriMeshFlags::ORIENTED).ok()?;
        mesh.pseudo_normals()?;
        let (mut sum, mut n) = (0.0, 0usize);
        for &[i, j] in topo.edges() {
            if vertices.binary_search(&i).is_ok() {
                sum += norm(sub(base[i as usize], base[j as usize]));
                n += 1;
            }
        }
        Some(Self {
            component,
            vertices,
            mean_edge: sum / n.max(1) as f64,
            volume: vol.abs(),
            centroid: cen,
            capped_holes: caps.len(),
            mesh,
        })
    }
}

/// Interior points and internal springs of a base mesh with `n` surface vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Interior {
    /// Base positions of the interior vertices; vertex `n + k` is `points[k]`.
    pub points: Vec<Point>,
    /// Internal springs (lattice edges and surface ties, or tetgen's non-surface tetrahedron
    /// edges) in extended ids, `i < j`.
    pub springs: Vec<[u32; 2]>,
    /// Tetrahedra (lattice or tetgen) in extended ids, positively oriented in the base.
    pub tets: Vec<[u32; 4]>,
    /// Lattice spacing (tetgen: edge of the volume bound) per filled component `(component, h)`.
    pub spacing: Vec<(usize, f64)>,
    /// Components left without interior, and why.
    pub skipped: Vec<SkippedComponent>,
}

/// Index arithmetic of one component's lattice.
struct Grid {
    origin: Point,
    h: f64,
    /// Corner counts per axis; cells are one fewer.
    n: [usize; 3],
}

impl Grid {
    fn corner(&self, i: [usize; 3]) -> usize {
        (i[2] * self.n[1] + i[1]) * self.n[0] + i[0]
    }
    fn centre(&self, i: [usize; 3]) -> usize {
        let c = [self.n[0] - 1, self.n[1] - 1];
        self.n[0] * self.n[1] * self.n[2] + (i[2] * c[1] + i[1]) * c[0] + i[0]
    }
    fn num_cells(&self) -> [usize; 3] {
        self.n.map(|k| k - 1)
    }
    fn total(&self) -> usize {
        let c = self.num_cells();
        self.n[0] * self.n[1] * self.n[2] + c[0] * c[1] * c[2]
    }
    fn position(&self, id: usize) -> Point {
        let nc = self.n[0] * self.n[1] * self.n[2];
        let (dims, idx, off) = if id < nc {
            (self.n, id, 0.0)
        } else {
            (self.num_cells(), id - nc, 0.5)
        };
        let i = [
            idx % dims[0],
            (idx / dims[0]) % dims[1],
            idx / (dims[0] * dims[1]),
        ];
        [0, 1, 2].map(|a| self.origin[a] + self.h * (i[a] as f64 + off))
    }
}

/// Builds the lattice interior of every closed component of `base`.
pub fn build(base: &[Point], triangles: &[[u32; 3]], o: &InteriorOptions) -> Interior {
    let (solids, skipped) = solids(base, triangles);
    build_in(base, &solids, skipped, o)
}

/// Builds the lattice interior inside the given solids (see [`solids`]).
pub fn build_in(
    base: &[Point],
    solids: &[Solid],
    mut skipped: Vec<SkippedComponent>,
    o: &InteriorOptions,
) -> Interior {
    let n = base.len() as u32;
    let mut out = Interior::default();
    for s in solids {
        let before = out.points.len();
        fill(base, s, o, n, &mut out);
        if out.points.len() == before {
            skipped.push(SkippedComponent {
                component: s.component,
                example_vertex: s.vertices[0],
                reason: "too thin for the lattice".into(),
            });
        }
    }
    skipped.sort_by_key(|k| k.component);
    out.skipped = skipped;
    out
}

fn fill(base: &[Point], s: &Solid, o: &InteriorOptions, n: u32, out: &mut Interior) {
    let h = 2.0 * s.mean_edge / o.density;
    if h.is_nan() || h <= 0.0 {
        return;
    }
    let sp: Vec<Point> = s.vertices.iter().map(|&v| base[v as usize]).collect();
    let (lo, hi) = crate::mesh::bounding_box(&sp);
    let n3 = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / h).ceil() as usize + 1);
    // Centre the lattice on the bounding box.
    let origin = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - 0.5 * h * (n3[a] - 1) as f64);
    let grid = Grid {
        origin,
        h,
        n: n3.map(|k| k.max(2)),
    };
    let total = grid.total();
    let mut keep = vec![false; total];
    for (id, k) in keep.iter_mut().enumerate() {
        let (inside, dist) = s.query(grid.position(id));
        *k = inside && dist >= o.margin * h;
    }
    let tol = 1e-6 * h;
    // Lattice edges among kept points whose segment stays inside.
    let mut edges: Vec<[usize; 2]> = Vec::new();
    let nc = grid.num_cells();
    let mut push = |a: usize, b: usize, keep: &[bool]| {
        if keep[a] && keep[b] && s.segment_inside(grid.position(a), grid.position(b), tol) {
            edges.push([a, b]);
        }
    };
    for k in 0..grid.n[2] {
        for j in 0..grid.n[1] {
            for i in 0..grid.n[0] {
                let c = grid.corner([i, j, k]);
                for (a, lim) in [(0, grid.n[0]), (1, grid.n[1]), (2, grid.n[2])] {
                    let mut q = [i, j, k];
                    q[a] += 1;
                    if q[a] < lim {
                        push(c, grid.corner(q), &keep);
                    }
                }
                if i < nc[0] && j < nc[1] && k < nc[2] {
                    let m = grid.centre([i, j, k]);
                    for (a, lim) in [(0, nc[0]), (1, nc[1]), (2, nc[2])] {
                        let mut q = [i, j, k];
                        q[a] += 1;
                        if q[a] < lim {
                            push(m, grid.centre(q), &keep);
                        }
                    }
                    for d in 0..8 {
                        let q = [i + (d & 1), j + ((d >> 1) & 1), k + (d >> 2)];
                        push(m, grid.corner(q), &keep);
                    }
                }
            }
        }
    }
    // Ties from each surface vertex to its nearest kept points.
    let reach = o.tie_radius * h;
    let mut ties: Vec<(u32, usize)> = Vec::new();
    for &v in &s.vertices {
        let p = base[v as usize];
        let lo_i = [0, 1, 2].map(|a| (((p[a] - reach - origin[a]) / h).floor().max(0.0)) as usize);
        let hi_i = [0, 1, 2].map(|a| {
            (((p[a] + reach - origin[a]) / h).ceil().max(0.0) as usize).min(grid.n[a] - 1)
        });
        let mut cand: Vec<(f64, usize)> = Vec::new();
        for k in lo_i[2]..=hi_i[2] {
            for j in lo_i[1]..=hi_i[1] {
                for i in lo_i[0]..=hi_i[0] {
                    let mut ids = vec![grid.corner([i, j, k])];
                    if i < nc[0] && j < nc[1] && k < nc[2] {
                        ids.push(grid.centre([i, j, k]));
                    }
                    for id in ids {
                        if keep[id] {
                            let d = norm(sub(grid.position(id), p));
                            if d <= reach {
                                cand.push((d, id));
                            }
                        }
                    }
                }
            }
        }
        cand.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut taken = 0;
        for (_, id) in cand {
            if taken == o.ties_per_vertex {
                break;
            }
            if s.segment_inside(grid.position(id), p, tol) {
                ties.push((v, id));
                taken += 1;
            }
        }
    }
    // Keep the lattice points connected (through lattice edges) to a tied point.
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); total];
    for &[a, b] in &edges {
        adj[a].push(b);
        adj[b].push(a);
    }
    let mut reached = vec![false; total];
    let mut stack: Vec<usize> = ties.iter().map(|t| t.1).collect();
    while let Some(a) = stack.pop() {
        if !std::mem::replace(&mut reached[a], true) {
            stack.extend(adj[a].iter().copied().filter(|&b| !reached[b]));
        }
    }
    let mut id_of = vec![u32::MAX; total];
    for (g, &r) in reached.iter().enumerate() {
        if r {
            id_of[g] = n + out.points.len() as u32;
            out.points.push(grid.position(g));
        }
    }
    if !reached.iter().any(|r| *r) {
        return;
    }
    out.spacing.push((s.component, h));
    for &[a, b] in &edges {
        if reached[a] && reached[b] {
            out.springs.push(order(id_of[a], id_of[b]));
        }
    }
    for &(v, g) in &ties {
        out.springs.push(order(v, id_of[g]));
    }
    // BCC tetrahedra around each centre–centre edge.
    for k in 0..nc[2] {
        for j in 0..nc[1] {
            for i in 0..nc[0] {
                let c = grid.centre([i, j, k]);
                for a in 0..3 {
                    let mut q = [i, j, k];
                    q[a] += 1;
                    if q[a] >= nc[a] {
                        continue;
                    }
                    let c2 = grid.centre(q);
                    let (b1, b2) = ((a + 1) % 3, (a + 2) % 3);
                    let face: [usize; 4] = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(u, w)| {
                        let mut r = [i, j, k];
                        r[a] += 1;
                        r[b1] += u;
                        r[b2] += w;
                        grid.corner(r)
                    });
                    for m in 0..4 {
                        let t = [c, c2, face[m], face[(m + 1) % 4]];
                        if t.iter().all(|&g| reached[g]) {
                            let ids = t.map(|g| id_of[g]);
                            out.tets
                                .push(oriented(ids, |v| out_pos(base, &out.points, v)));
                        }
                    }
                }
            }
        }
    }
}

fn out_pos(base: &[Point], points: &[Point], v: u32) -> Point {
    let n = base.len();
    if (v as usize) < n {
        base[v as usize]
    } else {
        points[v as usize - n]
    }
}

fn order(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// Signed volume ×6 of tetrahedron `t` at positions `p`.
pub fn tet_volume6(p: impl Fn(u32) -> Point, t: [u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(&p);
    crate::mesh::dot(sub(b, a), crate::mesh::cross(sub(c, a), sub(d, a)))
}

fn oriented(t: [u32; 4], p: impl Fn(u32) -> Point) -> [u32; 4] {
    if tet_volume6(p, t) < 0.0 {
        [t[0], t[1], t[3], t[2]]
    } else {
        t
    }
}

#[cfg(test)]
#[path = "lattice_tests.rs"]
mod tests;
