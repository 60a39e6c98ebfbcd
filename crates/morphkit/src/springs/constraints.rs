//! Boundary conditions (Ma et al. 2012, Sec. 3.4, first part) and the rigid-motion gauge.
//!
//! The equilibrium of a free spring system is defined only up to a rigid motion: the Hessian
//! has six zero modes per connected component, and a Cholesky factorization of it would be
//! singular. morphkit never attempts that. Per connected component:
//!
//! - **fixed vertices spanning a plane** (three or more, not collinear): nothing else is needed;
//!   their positions are interpolated linearly across the shapes, as the paper describes;
//! - **no fixed vertex**: a *minimal gauge* ([`Gauge`]) removes exactly the six rigid degrees
//!   of freedom without straining anything: the solver holds the component in a frame where
//!   `b − a` lies along x and `c` in the xy-plane, and pins `a` in x, y, z, `b` in y, z and `c`
//!   in z. After the solve, the component is rigidly aligned (Kabsch) to the linear blend of the
//!   same weights, so it sits where an artist expects it;
//! - **one or two fixed vertices, or collinear ones**: explicitly given ids are rejected with
//!   [`BlendError::UnderConstrained`](super::BlendError::UnderConstrained) (the component could
//!   still spin about them); with [`FixedVertices::Auto`] those few static vertices are ignored
//!   and the component gets the gauge.

use super::gauge::spans_plane;
pub use super::gauge::Gauge;
use super::BlendError;
use crate::mesh::{bbox_diagonal, norm, sub, Point, ShapeSet, Topology};

/// Which vertices are boundary conditions.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum FixedVertices {
    /// Nothing fixed: every component gets the rigid gauge and is aligned to the linear blend.
    None,
    /// Vertices that do not move across all shapes (within `1e-6 ×` the base's bounding-box
    /// diagonal) are fixed; components without enough of them get the gauge. The default.
    #[default]
    Auto,
    /// These vertex ids are fixed; their positions are interpolated linearly across shapes.
    Ids(Vec<u32>),
}

/// Whether a vertex moves in a shape: farther than `1e-6 ×` the base's bounding-box diagonal
/// from its base position (the rule of [`FixedVertices::Auto`], per rig and per frame).
pub(crate) struct Moves<'a> {
    shapes: &'a ShapeSet,
    tolerance: f64,
}

impl<'a> Moves<'a> {
    pub(crate) fn new(shapes: &'a ShapeSet) -> Self {
        Self {
            shapes,
            tolerance: 1e-6 * bbox_diagonal(shapes.positions(0)),
        }
    }

    /// Whether vertex `v` moves in shape `s`.
    pub(crate) fn in_shape(&self, s: usize, v: usize) -> bool {
        let base = self.shapes.positions(0)[v];
        norm(sub(self.shapes.positions(s)[v], base)) > self.tolerance
    }
}

/// The resolved constraints of a shape set.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraints {
    /// Fully fixed vertices (user-given, automatic or kinematic), sorted. Their positions are
    /// the linear interpolation of their positions in the shapes.
    pub fixed: Vec<u32>,
    /// The kinematic vertices among them (over-stretched triangles), sorted.
    pub kinematic: Vec<u32>,
    /// The vertices of thin bands among them (see [`thin_bands`]), sorted: they are held at
    /// the predictor $P(w)$, not at the linear blend.
    pub bands: Vec<u32>,
    /// Components held only by the gauge, to align after each solve.
    pub gauges: Vec<Gauge>,
    /// Components whose only boundary conditions are kinematic vertices (with at most a few
    /// static ones that do not span a plane): solved with those vertices at the linear blend,
    /// then moved rigidly onto the linear blend as a whole, like a gauged component. A few
    /// over-stretched triangles are no material, so they hold the shape, not its place in
    /// the world: pinned where the linear blend puts them, the body would turn about them
    /// (horse-07, whose 7 kinematic vertices lie on one hind leg, rears about that leg and
    /// ended 0.55 of the largest move away from the linear blend; aligned as a whole, 0.14).
    pub aligned: Vec<AlignedComponent>,
    /// Per degree of freedom (`3 #V`): fixed by a boundary condition or by the gauge.
    pub fixed_dof: Vec<bool>,
}

impl Constraints {
    /// Resolves `spec` for `shapes` whose vertices are coupled into connected components as
    /// `components` gives them (one label per vertex, `0..count`; see [`Components`]).
    /// `kinematic` vertices (see
    /// [`stretched_vertices`]) are held like automatic ones: where they, with the other fixed
    /// vertices of their component, span a plane they follow the linear blend; otherwise that
    /// component keeps its gauge and they are solved for. The vertices of `bands` (whole
    /// components, see [`thin_bands`]) that are not fixed are held too, at the predictor;
    /// such a component needs no gauge.
    pub fn new(
        shapes: &ShapeSet,
        components: &Components,
        spec: &FixedVertices,
        kinematic: &[u32],
        bands: &[u32],
    ) -> Result<Self, BlendError> {
        let n = shapes.num_vertices();
        let base = shapes.positions(0);
        let mut is_fixed = vec![false; n];
        let explicit = matches!(spec, FixedVertices::Ids(_));
        match spec {
            FixedVertices::None => {}
            FixedVertices::Ids(ids) => {
                for &v in ids {
                    if v as usize >= n {
                        return Err(BlendError::FixedOutOfRange {
                            vertex: v,
                            num_vertices: n,
                        });
                    }
                    is_fixed[v as usize] = true;
                }
            }
            FixedVertices::Auto => {
                let moves = Moves::new(shapes);
                for (v, f) in is_fixed.iter_mut().enumerate() {
                    *f = (1..shapes.len()).all(|s| !moves.in_shape(s, v));
                }
                if shapes.len() == 1 {
                    is_fixed.iter_mut().for_each(|f| *f = false);
                }
            }
        }
        let mut is_kinematic = vec![false; n];
        for &v in kinematic {
            if (v as usize) < n && !is_fixed[v as usize] {
                is_kinematic[v as usize] = true;
            }
        }
        let mut is_band = vec![false; n];
        for &v in bands {
            if (v as usize) < n {
                is_band[v as usize] = true;
            }
        }
        let comp = &components.label;
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); components.count];
        for v in 0..n {
            members[comp[v] as usize].push(v as u32);
        }
        let diag = bbox_diagonal(base).max(f64::MIN_POSITIVE);
        let mut fixed_dof = vec![false; 3 * n];
        let mut gauges = Vec::new();
        let mut aligned = Vec::new();
        for (c, verts) in members.iter().enumerate() {
            if verts.iter().all(|&v| is_band[v as usize]) {
                // A thin band follows the predictor: every vertex held, nothing to gauge.
                for &v in verts {
                    is_kinematic[v as usize] = false;
                    is_band[v as usize] = !is_fixed[v as usize];
                }
                continue;
            }
            for &v in verts {
                is_band[v as usize] = false;
            }
            let fixed_here: Vec<Point> = verts
                .iter()
                .filter(|&&v| is_fixed[v as usize])
                .map(|&v| base[v as usize])
                .collect();
            if spans_plane(&fixed_here, 1e-9 * diag) {
                continue;
            }
            let held: Vec<u32> = verts
                .iter()
                .copied()
                .filter(|&v| is_fixed[v as usize] || is_kinematic[v as usize])
                .collect();
            let held_at: Vec<Point> = held.iter().map(|&v| base[v as usize]).collect();
            if !explicit_here(explicit, &fixed_here) && spans_plane(&held_at, 1e-9 * diag) {
                aligned.push(AlignedComponent {
                    vertices: verts.clone(),
                    held,
                });
                continue;
            }
            for &v in verts {
                is_kinematic[v as usize] = false;
            }
            if !fixed_here.is_empty() {
                if explicit {
                    return Err(BlendError::UnderConstrained {
                        component: c,
                        example_vertex: verts[0] as usize,
                        fixed: fixed_here.len(),
                    });
                }
                for &v in verts {
                    is_fixed[v as usize] = false;
                }
            }
            if verts.len() >= 3 {
                let gauge = Gauge::new(base, verts);
                for (v, axis) in gauge.pins() {
                    fixed_dof[3 * v as usize + axis] = true;
                }
                gauges.push(gauge);
            } else {
                // A lone vertex or a dangling pair: nothing to solve, keep it where it is.
                for &v in verts {
                    is_fixed[v as usize] = true;
                }
            }
        }
        let kinematic: Vec<u32> = (0..n as u32)
            .filter(|&v| is_kinematic[v as usize])
            .collect();
        let bands: Vec<u32> = (0..n as u32).filter(|&v| is_band[v as usize]).collect();
        let fixed: Vec<u32> = (0..n as u32)
            .filter(|&v| is_fixed[v as usize] || is_kinematic[v as usize] || is_band[v as usize])
            .collect();
        for &v in &fixed {
            for a in 0..3 {
                fixed_dof[3 * v as usize + a] = true;
            }
        }
        Ok(Self {
            fixed,
            kinematic,
            bands,
            gauges,
            aligned,
            fixed_dof,
        })
    }

    /// Frees the kinematic vertices of components anchored by fixed vertices (those of
    /// [aligned](Self::aligned) components stay: they are that component's frame) and returns
    /// them, sorted. A solve then holds them per frame, with the weights of the targets that
    /// over-stretch them ([`holds`](super::holds)).
    pub fn release_kinematic(&mut self) -> Vec<u32> {
        let mut keep = std::collections::BTreeSet::new();
        for a in &self.aligned {
            keep.extend(a.held.iter().copied());
        }
        let (kept, released): (Vec<u32>, Vec<u32>) =
            self.kinematic.iter().partition(|v| keep.contains(v));
        for &v in &released {
            for a in 0..3 {
                self.fixed_dof[3 * v as usize + a] = false;
            }
        }
        self.fixed.retain(|v| released.binary_search(v).is_err());
        self.kinematic = kept;
        released
    }

    /// Number of free degrees of freedom.
    pub fn num_free_dofs(&self) -> usize {
        self.fixed_dof.iter().filter(|f| !**f).count()
    }
}

/// A component held only by kinematic vertices (see [`Constraints::aligned`]).
#[derive(Clone, Debug, PartialEq)]
pub struct AlignedComponent {
    /// Its vertices, sorted.
    pub vertices: Vec<u32>,
    /// Its held (kinematic or static) vertices, sorted: they span a plane, so the rigid
    /// motion between the solver's frame and the world is recovered from them.
    pub held: Vec<u32>,
}

/// Connected components of the vertices under every coupling of the energy (mesh edges,
/// 2-ring springs, hinges, internal springs…), not only the triangles: an interior vertex tied
/// to the surface by springs belongs to the surface's component.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Components {
    /// Label of each vertex, `0..count`, numbered in order of first vertex.
    pub label: Vec<u32>,
    /// Number of components (an uncoupled vertex is one).
    pub count: usize,
}

impl Components {
    /// Components of `n` vertices under the pairs `pairs`.
    pub fn from_pairs(n: usize, pairs: impl IntoIterator<Item = [u32; 2]>) -> Self {
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for [a, b] in pairs {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        let mut label = vec![u32::MAX; n];
        let mut count = 0usize;
        for v in 0..n as u32 {
            let r = find(&mut parent, v) as usize;
            if label[r] == u32::MAX {
                label[r] = count as u32;
                count += 1;
            }
            label[v as usize] = label[r];
        }
        Self { label, count }
    }

    /// Components of a triangle mesh's topology.
    pub fn of_topology(topology: &Topology) -> Self {
        Self {
            label: topology.components().to_vec(),
            count: topology.num_components(),
        }
    }
}

/// Explicit ids that do not span a plane in a component are an error (raised by the caller);
/// kinematic vertices are then not added to them.
fn explicit_here(explicit: bool, fixed_here: &[Point]) -> bool {
    explicit && !fixed_here.is_empty()
}

/// Vertices of triangles whose in-plane stretch between the base and some shape exceeds
/// `threshold`: $\max(\sigma_{\max}, 1/\sigma_{\min}) >$ `threshold`, with $\sigma$ the
/// singular values of the triangle's 2D deformation (from the metric tensors $G_0 = E_0^\top E_0$,
/// $G_s = E_s^\top E_s$ of the edge matrices). A triangle that is a sliver in the base and opens
/// in a target (a closed slit) counts as infinitely stretched.
pub fn stretched_vertices(shapes: &ShapeSet, threshold: f64) -> Vec<u32> {
    let mut all: Vec<u32> = stretched_by_target(shapes, threshold)
        .into_iter()
        .flatten()
        .collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// Per target `s ≥ 1` (entry `s - 1`): the vertices of triangles that target over-stretches,
/// by the rule of [`stretched_vertices`] (their union), sorted.
pub fn stretched_by_target(shapes: &ShapeSet, threshold: f64) -> Vec<Vec<u32>> {
    if !threshold.is_finite() {
        return vec![Vec::new(); shapes.len().saturating_sub(1)];
    }
    let base = shapes.positions(0);
    let metric = |p: &[Point], t: [u32; 3]| {
        let e1 = sub(p[t[1] as usize], p[t[0] as usize]);
        let e2 = sub(p[t[2] as usize], p[t[0] as usize]);
        let d = crate::mesh::dot;
        [d(e1, e1), d(e1, e2), d(e2, e2)]
    };
    let n = shapes.num_vertices();
    (1..shapes.len())
        .map(|s| {
            let mut mark = vec![false; n];
            for &t in shapes.triangles() {
                let g0 = metric(base, t);
                let det0 = g0[0] * g0[2] - g0[1] * g0[1];
                let tr0 = g0[0] + g0[2];
                let g = metric(shapes.positions(s), t);
                let det = g[0] * g[2] - g[1] * g[1];
                let stretched = if det0 <= 1e-12 * tr0 * tr0 {
                    // A sliver in the base: stretched when it opens up in this shape.
                    det > 1e-6 * (g[0] + g[2]).powi(2) && tr0 < (g[0] + g[2])
                } else {
                    // Eigenvalues of G0⁻¹ G are the squared singular values.
                    let m = [
                        (g0[2] * g[0] - g0[1] * g[1]) / det0,
                        (g0[0] * g[2] - g0[1] * g[1]) / det0,
                    ];
                    let tr = m[0] + m[1];
                    let dt = det / det0;
                    let disc = (0.25 * tr * tr - dt).max(0.0).sqrt();
                    0.5 * tr + disc > threshold * threshold
                };
                if stretched {
                    for v in t {
                        mark[v as usize] = true;
                    }
                }
            }
            (0..n as u32).filter(|&v| mark[v as usize]).collect()
        })
        .collect()
}

/// Vertices of *thin bands*: connected components (under `components`) that are narrow, every
/// vertex within `rings` mesh edges of the mesh boundary, and long, at least twice as long as
/// they are wide: with $d$ the largest ring distance from the boundary, a band is
/// $W = 2d + 1$ vertices across, and it has at least $2W^2$ vertices (about $W$ per row along
/// a length of at least $2W$ rows). Such are the eye-occlusion strips, tear films and eyelash
/// cards of a face rig, or hair cards; a small square patch (an 8 × 8 grid, a leaf) is no
/// band and is solved. `rings = 0` finds none.
///
/// Why they are not solved for: a band a few triangles wide has no material across its
/// width to hold its shape, and when a target compresses it (a blink folds the strip along
/// the closing lid) the blended rest lengths are met better by a crumpled band than by the
/// smooth one, so its equilibrium snaps from one crumpled state to another between frames
/// (ICT eyeBlink_L: 30 folded triangles where the linear blend has none, a jump of 12.8×
/// the linear blend's step). The rotation-aware predictor $P(w)$ interpolates each triangle's
/// rotation and stretch and has no such folds, so bands are held there (see
/// [`Constraints::bands`]). Components with a vertex that no triangle uses (an interior
/// lattice) or without boundary are never bands.
pub fn thin_bands(topology: &Topology, components: &Components, rings: usize) -> Vec<u32> {
    let n = topology.num_vertices();
    if rings == 0 {
        return Vec::new();
    }
    // Breadth-first ring distance from the boundary over mesh edges.
    let mut dist = vec![usize::MAX; n];
    let mut queue = std::collections::VecDeque::new();
    for (v, b) in topology.boundary_vertices().into_iter().enumerate() {
        if b {
            dist[v] = 0;
            queue.push_back(v);
        }
    }
    while let Some(v) = queue.pop_front() {
        if dist[v] >= rings {
            continue;
        }
        for &w in topology.one_ring(v) {
            if dist[w as usize] == usize::MAX {
                dist[w as usize] = dist[v] + 1;
                queue.push_back(w as usize);
            }
        }
    }
    // Per component: the largest ring distance (MAX when some vertex is beyond `rings`).
    let mut depth = vec![0usize; components.count];
    let mut size = vec![0usize; components.count];
    for v in 0..n {
        let c = components.label[v] as usize;
        size[c] += 1;
        depth[c] = depth[c].max(dist[v]);
    }
    let is_band = |c: usize| {
        // `depth` is usize::MAX beyond `rings`: test it before any arithmetic on it.
        depth[c] <= rings && size[c] >= 3 && size[c] >= 2 * (2 * depth[c] + 1).pow(2)
    };
    (0..n as u32)
        .filter(|&v| is_band(components.label[v as usize] as usize))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// The constraints of `spec` on `s` with topology `t`, no kinematic vertices or bands.
    fn resolve(
        s: &ShapeSet,
        t: &Topology,
        spec: &FixedVertices,
    ) -> Result<Constraints, BlendError> {
        Constraints::new(s, &Components::of_topology(t), spec, &[], &[])
    }

    fn set_of(m: &crate::mesh::TriMesh, other: Vec<Point>) -> ShapeSet {
        ShapeSet::new(
            m.clone(),
            vec![("a".into(), m.positions.clone()), ("b".into(), other)],
        )
        .unwrap()
    }

    #[test]
    fn gauge_pins_exactly_six_dofs_per_component() {
        let m = generate::uv_sphere(1.0, 6, 8);
        let s = set_of(
            &m,
            generate::rotate(&m.positions, [0.0; 3], [0.0, 0.0, 1.0], 1.0),
        );
        let t = Topology::new(m.num_vertices(), &m.triangles);
        let c = resolve(&s, &t, &FixedVertices::None).unwrap();
        assert_eq!(c.fixed_dof.iter().filter(|f| **f).count(), 6);
        assert_eq!(c.gauges.len(), 1);
        // Auto finds the two poles on the rotation axis: collinear, so ignored.
        let c = resolve(&s, &t, &FixedVertices::Auto).unwrap();
        assert_eq!(c.fixed_dof.iter().filter(|f| **f).count(), 6);
        assert!(c.fixed.is_empty());
    }

    #[test]
    fn auto_fixes_the_static_half_and_explicit_collinear_ids_are_rejected() {
        let m = generate::tube(0.5, 4.0, 8, 8, false);
        let s = set_of(&m, generate::bend(&m.positions, 2.0, 2.0, 1.5));
        let t = Topology::new(m.num_vertices(), &m.triangles);
        let c = resolve(&s, &t, &FixedVertices::Auto).unwrap();
        assert_eq!(c.fixed.len(), 5 * 8, "rings at x ≤ 2 do not move");
        assert!(c.gauges.is_empty());
        let e = resolve(&s, &t, &FixedVertices::Ids(vec![0, 8])).unwrap_err();
        assert!(matches!(e, BlendError::UnderConstrained { fixed: 2, .. }));
        let e = resolve(&s, &t, &FixedVertices::Ids(vec![0, 9999])).unwrap_err();
        assert!(matches!(
            e,
            BlendError::FixedOutOfRange { vertex: 9999, .. }
        ));
    }

    /// A strip 4 quads wide and 30 long (every vertex within 2 rings of its boundary) is a
    /// band at 2 rings and not at 1; a 12 × 12 patch beside it (6 rings deep) is none even at
    /// 6 rings (it is as long as it is wide), nor is a closed sphere; a band needs no gauge and
    /// all of it is held, and `0` rings finds nothing.
    #[test]
    fn thin_bands_are_whole_narrow_components() {
        let strip = generate::grid(30, 4, 6.0, 0.8);
        let patch = generate::grid(12, 12, 3.0, 3.0);
        let sphere = generate::uv_sphere(1.0, 6, 8);
        let mut p = strip.positions.clone();
        let mut t = strip.triangles.clone();
        for m in [&patch, &sphere] {
            let off = p.len() as u32;
            p.extend(m.positions.iter().map(|q| [q[0], q[1] + 5.0, q[2]]));
            t.extend(m.triangles.iter().map(|f| f.map(|v| v + off)));
        }
        let m = crate::mesh::TriMesh::new(p, t);
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let comps = Components::of_topology(&topo);
        let ns = strip.num_vertices() as u32;
        assert_eq!(thin_bands(&topo, &comps, 2), (0..ns).collect::<Vec<_>>());
        assert!(thin_bands(&topo, &comps, 1).is_empty());
        assert!(thin_bands(&topo, &comps, 0).is_empty());
        assert_eq!(thin_bands(&topo, &comps, 6), (0..ns).collect::<Vec<_>>());
        let moved: Vec<Point> = m
            .positions
            .iter()
            .map(|q| [q[0], q[1], q[2] + q[0]])
            .collect();
        let s = set_of(&m, moved);
        let bands = thin_bands(&topo, &comps, 2);
        let c = Constraints::new(&s, &comps, &FixedVertices::None, &[], &bands).unwrap();
        assert_eq!(c.bands, bands);
        assert!(bands.iter().all(|v| c.fixed.binary_search(v).is_ok()));
        assert_eq!(
            c.gauges.len(),
            2,
            "the patch and the sphere keep their gauges"
        );
    }
}
