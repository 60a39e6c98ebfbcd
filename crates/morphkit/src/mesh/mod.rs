//! Triangle meshes, their topology, validation, and shape sets that share one connectivity.
//!
//! Conventions used throughout morphkit:
//! - positions are `f64` triples, `#V × 3`, stored as `Vec<[f64; 3]>`;
//! - triangles are `u32` index triples, `#F × 3`, counter-clockwise seen from outside
//!   (the normal is `(v1 − v0) × (v2 − v0)`);
//! - polygons read from files are fan-triangulated on load; [`TriMesh::face_origin`] maps each
//!   triangle back to the polygon it came from, and [`TriMesh::polygons`] keeps the polygons so
//!   that writers can emit the original quads.

pub mod generate;
mod shape_set;
mod topology;
mod validate;
mod weld;

pub use shape_set::{ShapeSet, ShapeSetError};
pub use topology::{Adjacency, Topology};
pub use validate::{validate, MeshError, ValidationReport, ValidationWarning};
pub use weld::{Weld, WELD_TOLERANCE};

/// A point or vector in 3-space.
pub type Point = [f64; 3];

/// Polygonal faces as read from a file, in compressed-row form.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Polygons {
    /// `offsets[f]..offsets[f + 1]` indexes `indices` for polygon `f`; length `#P + 1`.
    pub offsets: Vec<u32>,
    /// Concatenated vertex indices of all polygons.
    pub indices: Vec<u32>,
}

impl Polygons {
    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }
    /// True when there are no polygons.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Vertex indices of polygon `f`.
    pub fn get(&self, f: usize) -> &[u32] {
        &self.indices[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }
    /// Iterates over the polygons.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        (0..self.len()).map(move |f| self.get(f))
    }
}

/// A triangle mesh with `f64` positions and `u32` triangle indices.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions, `#V`.
    pub positions: Vec<Point>,
    /// Triangles, `#F`, each a counter-clockwise triple of vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the index of the file polygon it came from. Empty when the mesh was
    /// built from triangles directly (then triangle `t` is polygon `t`).
    pub face_origin: Vec<u32>,
    /// The original polygons, when the file had faces with more than three vertices.
    pub polygons: Option<Polygons>,
}

impl TriMesh {
    /// A mesh from positions and triangles (no polygon information).
    pub fn new(positions: Vec<Point>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
            face_origin: Vec::new(),
            polygons: None,
        }
    }

    /// Builds a mesh from polygons by fan triangulation `(p0, p_k, p_{k+1})`, recording
    /// [`TriMesh::face_origin`]. Polygons with fewer than three vertices are skipped by the
    /// caller; indices are not checked here (see [`validate`]).
    pub fn from_polygons(positions: Vec<Point>, polygons: Polygons) -> Self {
        let mut triangles = Vec::with_capacity(polygons.indices.len());
        let mut face_origin = Vec::with_capacity(polygons.indices.len());
        let mut any_poly = false;
        for (f, poly) in polygons.iter().enumerate() {
            if poly.len() > 3 {
                any_poly = true;
            }
            for k in 1..poly.len().saturating_sub(1) {
                triangles.push([poly[0], poly[k], poly[k + 1]]);
                face_origin.push(f as u32);
            }
        }
        Self {
            positions,
            triangles,
            face_origin: if any_poly { face_origin } else { Vec::new() },
            polygons: if any_poly { Some(polygons) } else { None },
        }
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounding box `(min, max)`; `([0; 3], [0; 3])` for an empty mesh.
    pub fn bounding_box(&self) -> (Point, Point) {
        bounding_box(&self.positions)
    }

    /// Length of the bounding-box diagonal, the length scale used by scale-aware tolerances.
    pub fn bbox_diagonal(&self) -> f64 {
        bbox_diagonal(&self.positions)
    }

    /// The same connectivity with other positions (which must have `#V` entries).
    pub fn with_positions(&self, positions: Vec<Point>) -> Self {
        debug_assert_eq!(positions.len(), self.positions.len());
        Self {
            positions,
            ..self.clone()
        }
    }

    /// Unnormalised normal `(v1 − v0) × (v2 − v0)` of triangle `t`; its length is twice the area.
    pub fn triangle_normal(&self, t: usize) -> Point {
        triangle_normal(&self.positions, self.triangles[t])
    }

    /// Area of triangle `t`.
    pub fn triangle_area(&self, t: usize) -> f64 {
        0.5 * norm(self.triangle_normal(t))
    }
}

/// Axis-aligned bounding box of a point set.
pub fn bounding_box(p: &[Point]) -> (Point, Point) {
    if p.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in p {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    (lo, hi)
}

/// Bounding-box diagonal of a point set.
pub fn bbox_diagonal(p: &[Point]) -> f64 {
    let (lo, hi) = bounding_box(p);
    let d = sub(hi, lo);
    let n = norm(d);
    // Where squaring underflowed (denormal sizes, 1e-310) or overflowed (1e200), scaled by the
    // largest extent; other sizes keep the plain norm, bit for bit.
    let m = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if n.is_normal() || m == 0.0 || !m.is_finite() {
        n
    } else {
        m * norm(d.map(|x| x / m))
    }
}

/// Signed volume enclosed by the triangles `tris` over the points `p`: $\sum_t a \cdot (b
/// \times c) / 6$ over triangles $t = (a, b, c)$, positive when they wind counter-clockwise
/// seen from outside. Meaningful for closed meshes; independent of the origin only then.
pub fn enclosed_volume(p: &[Point], tris: &[[u32; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Unnormalised normal of a triangle given by indices into `p`.
pub fn triangle_normal(p: &[Point], t: [u32; 3]) -> Point {
    let a = p[t[0] as usize];
    let e1 = sub(p[t[1] as usize], a);
    let e2 = sub(p[t[2] as usize], a);
    cross(e1, e2)
}

#[inline]
pub(crate) fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
pub(crate) fn dot(a: Point, b: Point) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub(crate) fn norm(a: Point) -> f64 {
    dot(a, a).sqrt()
}
#[inline]
pub(crate) fn cross(a: Point, b: Point) -> Point {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A fast hash of integer keys (multiply and rotate, as rustc's FxHash) for maps of mesh
/// elements: the keys are not chosen by an adversary, and SipHash made welding and validating
/// a 2M-vertex mesh take seconds each.
#[derive(Default)]
pub(crate) struct FastHasher(u64);

impl std::hash::Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
}

/// A `HashMap` with [`FastHasher`].
pub(crate) type FastMap<K, V> =
    std::collections::HashMap<K, V, std::hash::BuildHasherDefault<FastHasher>>;
