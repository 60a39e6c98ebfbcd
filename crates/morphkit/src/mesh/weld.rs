//! Welding the split vertices of exported meshes for a solve, and scattering results back.
//!
//! Exporters (Blender, Maya, glTF tools) split a vertex wherever a UV seam, a hard edge or a
//! material border passes: two or more vertices at one position, each used by the triangles on
//! its side. A solver that takes them as separate vertices solves each piece on its own and the
//! mesh tears open along every seam. [`Weld::of_shapes`] finds the vertices that coincide in
//! *every* shape of a rig (within [`WELD_TOLERANCE`] of the base's bounding-box diagonal) and
//! makes them one where that is what an exporter split: vertices that touch in one shape and
//! part in another (lips closed at rest) stay apart, and so do separate shells that only touch
//! (issue 54, below).
//!
//! **Seams, not touching shells.** Coincidence alone does not tell a seam from two shells that
//! touch: a head's eyelashes, eye occlusion and gums are separate shells whose borders lie on
//! the skin, vertex on vertex (the ICT head: 857 coincident pairs, almost all between shells).
//! Fusing them makes edges shared by three or more triangles (110 there), couples shells that
//! the artist kept apart and made the welded blend pop. An exporter's split is undone by
//! joining *edges*: two copies of a seam edge are each on the border of their side (one
//! triangle each), and joined they are an ordinary edge of two triangles. So the weld joins
//! coincident vertices only through edges whose two copies, joined, are used by two triangles
//! on the edge's two sides (one manifold surface), and joins the copies' endpoints pairwise.
//! A border lying on another shell's surface (one triangle against two), a shell lying on
//! another's border (its triangle folded onto the other's) and vertices that coincide without a
//! common edge stay apart. [`Weld::shapes`] gives the welded rig to solve on and [`Weld::scatter`] writes a
//! welded result back in the input's own vertex layout and order, so seams never open.
//!
//! The welded numbering keeps the input's order of first occurrence: a mesh whose duplicates
//! all follow their originals welds to exactly the unsplit mesh, and solves to the same bits.

use super::FastMap;
use super::{bbox_diagonal, Point, ShapeSet, ShapeSetError, TriMesh};

/// Vertices closer than this fraction of the base's bounding-box diagonal, in every shape,
/// are welded: far below any modelled detail, above `f32` round-off of exported positions
/// (2⁻²⁴ ≈ 6e-8 relative).
pub const WELD_TOLERANCE: f64 = 1e-6;

/// Which input vertices are one vertex for a solve; see the module docs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Weld {
    /// The welded vertex of each input vertex (`#V_in`).
    to_welded: Vec<u32>,
    /// The first input vertex of each welded vertex (`#V_welded`).
    representative: Vec<u32>,
    /// The input vertices welded with others (ascending) and, per set the weld was made from,
    /// their own positions (bits of `f64`), so that a frame that is one of the sets gives each
    /// copy its own numbers ([`Weld::scatter_frame`]). Empty where unknown.
    grouped: Vec<u32>,
    grouped_positions: Vec<Vec<[u64; 3]>>,
}

impl Weld {
    /// The identity on `n` vertices (nothing welded).
    pub fn identity(n: usize) -> Self {
        Self {
            to_welded: (0..n as u32).collect(),
            representative: (0..n as u32).collect(),
            grouped: Vec::new(),
            grouped_positions: Vec::new(),
        }
    }

    /// Welds the vertices of `shapes` that coincide in every shape within
    /// `tolerance × diagonal` of the base ([`WELD_TOLERANCE`] is the default). Groups are
    /// transitive: a chain of close vertices is one vertex.
    pub fn of_shapes(shapes: &ShapeSet, tolerance: f64) -> Self {
        let all: Vec<&[Point]> = shapes.all_positions().iter().map(|p| &p[..]).collect();
        Self::of_positions(&all, shapes.triangles(), tolerance)
    }

    /// Welds the vertices of one mesh that coincide within `tolerance × diagonal`.
    pub fn of_mesh(mesh: &TriMesh, tolerance: f64) -> Self {
        Self::of_positions(&[&mesh.positions[..]], &mesh.triangles, tolerance)
    }

    /// The weld of the vertices of `mesh` that coincide in it and in every one of `shapes`
    /// (each `#V` positions; none: in `mesh` alone), within [`WELD_TOLERANCE`], or the identity
    /// where it would drop a triangle (so that per-triangle data and correspondences keep their
    /// triangle ids) or a count differs. What transfer, correspondence, flexibility and
    /// synthesis weld with.
    pub fn keeping_triangles(mesh: &TriMesh, shapes: &[&[Point]]) -> Self {
        let n = mesh.num_vertices();
        if shapes.iter().any(|s| s.len() != n) {
            return Self::identity(n);
        }
        let mut sets: Vec<&[Point]> = vec![&mesh.positions];
        sets.extend(shapes.iter().copied());
        let w = Self::of_positions(&sets, &mesh.triangles, WELD_TOLERANCE);
        if w.keeps_triangles(&mesh.triangles) {
            w
        } else {
            Self::identity(n)
        }
    }

    /// [`Weld::of_shapes`] on bare position sets of one vertex count (the first is the base
    /// whose diagonal scales `tolerance`) and their `triangles`: vertices are welded where they
    /// coincide in every set and join a seam's edges (module docs). Sets of another vertex
    /// count than the first weld nothing.
    pub fn of_positions(sets: &[&[Point]], triangles: &[[u32; 3]], tolerance: f64) -> Self {
        let coincident = Self::coincident(sets, tolerance);
        if coincident.is_identity() {
            return coincident;
        }
        let mut w = Self::seams(&coincident, triangles, sets[0]);
        let mut size = vec![0u32; w.num_welded()];
        for &g in &w.to_welded {
            size[g as usize] += 1;
        }
        w.grouped = (0..w.num_input() as u32)
            .filter(|&v| size[w.to_welded[v as usize] as usize] > 1)
            .collect();
        w.grouped_positions = sets
            .iter()
            .map(|set| {
                w.grouped
                    .iter()
                    .map(|&v| set[v as usize].map(f64::to_bits))
                    .collect()
            })
            .collect();
        w
    }

    /// The groups of vertices that coincide in every set (transitively), seams or not.
    fn coincident(sets: &[&[Point]], tolerance: f64) -> Self {
        let Some(base) = sets.first().copied() else {
            return Self::identity(0);
        };
        let n = base.len();
        if sets.iter().any(|s| s.len() != n) {
            return Self::identity(n);
        }
        let tol = tolerance * bbox_diagonal(base);
        if n == 0 || !tol.is_finite() || tol <= 0.0 {
            return Self::identity(n);
        }
        // Cells of side 4 tol: a point has a partner in a neighbouring cell only along the axes
        // where it lies within tol of its cell's side, so about 3.4 of the 27 neighbours are
        // looked up on average, in a map with a fast hash of the integer cell.
        let side = 4.0 * tol;
        let cell = |p: &Point| p.map(|x| (x / side).floor() as i64);
        let mut grid: FastMap<[i64; 3], Vec<u32>> =
            FastMap::with_capacity_and_hasher(n, Default::default());
        for (v, p) in base.iter().enumerate() {
            grid.entry(cell(p)).or_default().push(v as u32);
        }
        let close = |a: usize, b: usize| {
            sets.iter().all(|s| {
                let (p, q) = (s[a], s[b]);
                let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                d2 <= tol * tol
            })
        };
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for (v, p) in base.iter().enumerate() {
            let c = cell(p);
            // Per axis, the neighbouring cells that may hold a point within tol.
            let range = |k: usize| {
                let f = p[k] / side - c[k] as f64;
                let lo = if f * side < tol { -1 } else { 0 };
                let hi = if (1.0 - f) * side <= tol { 1 } else { 0 };
                lo..=hi
            };
            for dx in range(0) {
                for dy in range(1) {
                    for dz in range(2) {
                        let Some(others) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &w in others {
                            if (w as usize) <= v || !close(v, w as usize) {
                                continue;
                            }
                            union(&mut parent, v as u32, w);
                        }
                    }
                }
            }
        }
        Self::from_parents(&mut parent)
    }

    /// The weld of the coincident groups of `coincident` that join edges into one manifold
    /// surface: for each edge of `triangles` between two groups, its copies (edges between the
    /// same two groups) are joined, endpoint with endpoint, where together they are used by
    /// two triangles that lie on the edge's two sides (not folded one onto the other). Joins are unions, so a vertex split three ways along a seam's end
    /// still welds. The two ends of an edge that has no length in any shape are joined too
    /// (its triangle has no area in any shape; the welded rig leaves it out).
    fn seams(coincident: &Self, triangles: &[[u32; 3]], base: &[Point]) -> Self {
        let n = coincident.num_input();
        let group = |v: u32| coincident.to_welded[v as usize];
        // Per edge between two groups (smaller group first): its input edges, each with the
        // endpoint in the smaller group first, and how many triangles use it.
        let mut edges: FastMap<(u32, u32), Vec<EdgeUse>> = FastMap::default();
        let mut collapsed = Vec::new();
        for t in triangles {
            if t.iter().any(|&v| v as usize >= n) {
                continue;
            }
            for k in 0..3 {
                let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (ga, gb) = (group(a), group(b));
                if ga == gb {
                    // An edge of no length in any shape: its triangle has no area and goes.
                    collapsed.push((a, b));
                    continue;
                }
                let (key, e) = if ga < gb {
                    ((ga, gb), (a, b, o))
                } else {
                    ((gb, ga), (b, a, o))
                };
                edges.entry(key).or_default().push(e);
            }
        }
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for (a, b) in collapsed {
            union(&mut parent, a, b);
        }
        let mut keys: Vec<&(u32, u32)> = edges.keys().collect();
        keys.sort_unstable();
        for key in keys {
            let uses = &edges[key];
            // Two triangles over all copies: a seam's two sides (one is a border, more are
            // a shell's border lying on another surface).
            if uses.len() != 2 {
                continue;
            }
            let ((a0, b0, o0), (a1, b1, o1)) = (uses[0], uses[1]);
            if (a0, b0) == (a1, b1) || folded_onto(base, a0, b0, o0, o1) {
                continue;
            }
            union(&mut parent, a0, a1);
            union(&mut parent, b0, b1);
        }
        Self::from_parents(&mut parent)
    }

    /// The weld of a union-find forest whose roots are their groups' smallest vertex.
    fn from_parents(parent: &mut [u32]) -> Self {
        let n = parent.len();
        let mut to_welded = vec![u32::MAX; n];
        let mut representative = Vec::new();
        for v in 0..n {
            let r = find(parent, v as u32) as usize;
            if to_welded[r] == u32::MAX {
                to_welded[r] = representative.len() as u32;
                representative.push(r as u32);
            }
            to_welded[v] = to_welded[r];
        }
        Self {
            to_welded,
            representative,
            grouped: Vec::new(),
            grouped_positions: Vec::new(),
        }
    }

    /// Input vertices.
    pub fn num_input(&self) -> usize {
        self.to_welded.len()
    }

    /// Welded vertices.
    pub fn num_welded(&self) -> usize {
        self.representative.len()
    }

    /// How many input vertices were merged into others (`#V_in − #V_welded`).
    pub fn merged(&self) -> usize {
        self.num_input() - self.num_welded()
    }

    /// True when nothing was welded.
    pub fn is_identity(&self) -> bool {
        self.merged() == 0
    }

    /// The welded vertex of each input vertex.
    pub fn to_welded(&self) -> &[u32] {
        &self.to_welded
    }

    /// The first input vertex of each welded vertex.
    pub fn representative(&self) -> &[u32] {
        &self.representative
    }

    /// True when every triangle keeps its corners apart after the weld, so that welded
    /// triangles are the input's, in the same order (per-triangle data needs no mapping).
    pub fn keeps_triangles(&self, triangles: &[[u32; 3]]) -> bool {
        self.is_identity() || self.triangles(triangles).len() == triangles.len()
    }

    /// The welded mesh: [`Weld::gather`]ed positions and [`Weld::triangles`].
    pub fn mesh(&self, mesh: &TriMesh) -> TriMesh {
        if self.is_identity() {
            return mesh.clone();
        }
        TriMesh::new(
            self.gather(&mesh.positions),
            self.triangles(&mesh.triangles),
        )
    }

    /// Vertex ids of the input (fixed or pinned vertices) in welded numbering, sorted and
    /// without repeats; an id out of the input's range is kept as it is, for the consumer's
    /// own range check to name.
    pub fn welded_ids(&self, ids: &[u32]) -> Vec<u32> {
        let mut w: Vec<u32> = ids
            .iter()
            .map(|&v| self.to_welded.get(v as usize).copied().unwrap_or(v))
            .collect();
        w.sort_unstable();
        w.dedup();
        w
    }

    /// The input vertices of the welded vertices `welded` (say, those a solve did not
    /// converge on), in increasing order.
    pub fn input_vertices(&self, welded: &[u32]) -> Vec<u32> {
        let mut mark = vec![false; self.num_welded()];
        for &v in welded {
            if let Some(m) = mark.get_mut(v as usize) {
                *m = true;
            }
        }
        (0..self.num_input() as u32)
            .filter(|&v| mark[self.to_welded[v as usize] as usize])
            .collect()
    }

    /// `mesh`'s triangles in welded numbering; triangles that lose a corner to the weld (they
    /// had no area in any shape) are left out.
    pub fn triangles(&self, triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        triangles
            .iter()
            .map(|t| t.map(|v| self.to_welded[v as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
            .collect()
    }

    /// Welded positions: each welded vertex at its first input vertex.
    pub fn gather(&self, positions: &[Point]) -> Vec<Point> {
        self.representative
            .iter()
            .map(|&v| positions[v as usize])
            .collect()
    }

    /// A welded result written back in the input's layout: every input vertex at its welded
    /// vertex's position (`#V_welded` in, `#V_in` out).
    pub fn scatter(&self, welded: &[Point]) -> Vec<Point> {
        self.to_welded.iter().map(|&w| welded[w as usize]).collect()
    }

    /// [`Weld::scatter`] of a frame with coefficients `c` over the sets the weld was made from
    /// (for [`Weld::of_shapes`], `c` over the shapes, `Σ c = 1`). Where the frame is one set
    /// (`c` one-hot at `s`) and a welded vertex is exactly at that set's position of its
    /// representative, each of its copies takes its own position in `s`: copies within the
    /// weld tolerance of each other keep their own numbers at the shapes themselves
    /// (issues 54 and 55: at one-hot weights every input vertex is exactly its target).
    pub fn scatter_frame(&self, welded: &[Point], c: &[f64]) -> Vec<Point> {
        let mut out = self.scatter(welded);
        let one_hot = c.iter().filter(|&&x| x != 0.0).count() == 1;
        let Some(s) = c.iter().position(|&x| x == 1.0).filter(|_| one_hot) else {
            return out;
        };
        let Some(own) = self.grouped_positions.get(s) else {
            return out;
        };
        let index = |v: u32| self.grouped.binary_search(&v).ok();
        for (k, &v) in self.grouped.iter().enumerate() {
            let g = self.to_welded[v as usize] as usize;
            let r = self.representative[g];
            let at_rep = index(r).is_some_and(|i| welded[g].map(f64::to_bits) == own[i]);
            if at_rep {
                out[v as usize] = own[k].map(f64::from_bits);
            }
        }
        out
    }

    /// The welded rig: the base with welded triangles and every shape gathered, names kept.
    ///
    /// Triangles that use a vertex twice (exporters write them; they have no area) are left
    /// out here too, so that every solve on a welded rig sees only proper triangles, while
    /// the input (and every output written in its layout) keeps them.
    pub fn shapes(&self, shapes: &ShapeSet) -> Result<ShapeSet, ShapeSetError> {
        let proper = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[2] != t[0];
        if self.is_identity() && shapes.triangles().iter().all(proper) {
            return Ok(shapes.clone());
        }
        let base = TriMesh::new(
            self.gather(shapes.positions(0)),
            self.triangles(shapes.triangles()),
        );
        let frames = (0..shapes.len())
            .map(|s| (shapes.name(s).to_string(), self.gather(shapes.positions(s))))
            .collect();
        ShapeSet::new(base, frames)
    }
}

/// Whether the triangles `(a, b, o0)` and `(a, b, o1)` lie on the same side of their edge,
/// one on the other (within 0.01 radians about it): two shells' borders that coincide with
/// one shell folded onto the other, not a seam's two sides.
fn folded_onto(p: &[Point], a: u32, b: u32, o0: u32, o1: u32) -> bool {
    let at = |v: u32| nalgebra::Vector3::from(p[v as usize]);
    let e = at(b) - at(a);
    let wing = |o: u32| {
        let d = at(o) - at(a);
        d - e * (d.dot(&e) / e.norm_squared().max(f64::MIN_POSITIVE))
    };
    let (w0, w1) = (wing(o0), wing(o1));
    let n = w0.norm() * w1.norm();
    n > 0.0 && w0.dot(&w1) > n * (1.0 - 5e-5)
}

/// One triangle's use of an edge: its two ends (the one in the smaller group first) and the
/// triangle's third corner.
type EdgeUse = (u32, u32, u32);

/// The root of `v`'s tree, halving the path on the way.
fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

/// Joins the trees of `v` and `w`; the smaller root stays, so a group's first vertex
/// represents it.
fn union(parent: &mut [u32], v: u32, w: u32) {
    let (a, b) = (find(parent, v), find(parent, w));
    if a < b {
        parent[b as usize] = a;
    } else if b < a {
        parent[a as usize] = b;
    }
}

#[cfg(test)]
#[path = "weld_tests.rs"]
mod tests;
