//! Boundary conditions (Ma et al. 2012, Sec. 3.4, first part) and the rigid-motion gauge.
//!
//! The equilibrium of a free spring system is defined only up to a rigid motion: the Hessian
//! has six zero modes per connected component, and a Cholesky factorization of it would be
//! singular. morphkit never attempts that. Per connected component:
//!
//! - **fixed vertices spanning a plane** (three or more, not collinear): nothing else is needed;
//!   their positions are interpolated linearly across the shapes, as the paper describes;
//! - **no fixed vertex**: a *minimal gauge* removes exactly the six rigid degrees of freedom
//!   without straining anything: vertex `a` (nearest the component's centroid) is pinned in
//!   x, y and z; vertex `b` (farthest from `a`) is pinned in the two axes other than the dominant
//!   axis of `b − a` (this removes the rotations except about `b − a`); vertex `c` (farthest from
//!   the line `ab`) is pinned in the axis along which a rotation about `b − a` moves it most.
//!   After the solve, the component is rigidly aligned (Kabsch) to the linear blend of the
//!   same weights, so it sits where an artist expects it;
//! - **one or two fixed vertices, or collinear ones**: explicitly given ids are rejected with
//!   [`BlendError::UnderConstrained`](super::BlendError::UnderConstrained) (the component could
//!   still spin about them); with [`FixedVertices::Auto`] those few static vertices are ignored
//!   and the component gets the gauge.

use super::BlendError;
use crate::mesh::{bbox_diagonal, cross, norm, sub, Point, ShapeSet, Topology};

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

/// The resolved constraints of a shape set.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraints {
    /// Fully fixed vertices (user-given or automatic), sorted.
    pub fixed: Vec<u32>,
    /// Components held only by the gauge: their vertices, to align after each solve.
    pub gauge_components: Vec<Vec<u32>>,
    /// Per degree of freedom (`3 #V`): fixed by a boundary condition or by the gauge.
    pub fixed_dof: Vec<bool>,
}

impl Constraints {
    /// Resolves `spec` for `shapes` with connectivity `topology`.
    pub fn new(
        shapes: &ShapeSet,
        topology: &Topology,
        spec: &FixedVertices,
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
                let tol = 1e-6 * bbox_diagonal(base);
                for (v, f) in is_fixed.iter_mut().enumerate() {
                    *f = (1..shapes.len())
                        .all(|s| norm(sub(shapes.positions(s)[v], base[v])) <= tol);
                }
                if shapes.len() == 1 {
                    is_fixed.iter_mut().for_each(|f| *f = false);
                }
            }
        }
        let comp = topology.components();
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); topology.num_components()];
        for v in 0..n {
            members[comp[v] as usize].push(v as u32);
        }
        let diag = bbox_diagonal(base).max(f64::MIN_POSITIVE);
        let mut fixed_dof = vec![false; 3 * n];
        let mut gauge_components = Vec::new();
        for (c, verts) in members.iter().enumerate() {
            let fixed_here: Vec<Point> = verts
                .iter()
                .filter(|&&v| is_fixed[v as usize])
                .map(|&v| base[v as usize])
                .collect();
            if spans_plane(&fixed_here, 1e-9 * diag) {
                continue;
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
                for (v, axis) in gauge_pins(base, verts) {
                    fixed_dof[3 * v as usize + axis] = true;
                }
                gauge_components.push(verts.clone());
            } else {
                // A lone vertex or a dangling pair: nothing to solve, keep it where it is.
                for &v in verts {
                    is_fixed[v as usize] = true;
                }
            }
        }
        let fixed: Vec<u32> = (0..n as u32).filter(|&v| is_fixed[v as usize]).collect();
        for &v in &fixed {
            for a in 0..3 {
                fixed_dof[3 * v as usize + a] = true;
            }
        }
        Ok(Self {
            fixed,
            gauge_components,
            fixed_dof,
        })
    }

    /// Number of free degrees of freedom.
    pub fn num_free_dofs(&self) -> usize {
        self.fixed_dof.iter().filter(|f| !**f).count()
    }
}

/// True when the points are not all within `tol` of one line.
fn spans_plane(p: &[Point], tol: f64) -> bool {
    if p.len() < 3 {
        return false;
    }
    let a = p[0];
    let Some(b) = p
        .iter()
        .copied()
        .max_by(|x, y| norm(sub(*x, a)).total_cmp(&norm(sub(*y, a))))
    else {
        return false;
    };
    let d = sub(b, a);
    let ld = norm(d);
    if ld <= tol {
        return false;
    }
    p.iter().any(|&c| norm(cross(d, sub(c, a))) / ld > tol)
}

/// The six pinned (vertex, axis) pairs of the minimal gauge of one component.
fn gauge_pins(p: &[Point], verts: &[u32]) -> Vec<(u32, usize)> {
    let inv = 1.0 / verts.len() as f64;
    let mut centroid = [0.0; 3];
    for &v in verts {
        for k in 0..3 {
            centroid[k] += p[v as usize][k] * inv;
        }
    }
    let dist = |v: u32, q: Point| norm(sub(p[v as usize], q));
    let a = *verts
        .iter()
        .min_by(|&&x, &&y| dist(x, centroid).total_cmp(&dist(y, centroid)))
        .expect("non-empty");
    let pa = p[a as usize];
    let b = *verts
        .iter()
        .max_by(|&&x, &&y| dist(x, pa).total_cmp(&dist(y, pa)))
        .expect("non-empty");
    let d = sub(p[b as usize], pa);
    let m = argmax_abs(d);
    let moved = |v: u32| cross(d, sub(p[v as usize], pa));
    let c = *verts
        .iter()
        .max_by(|&&x, &&y| norm(moved(x)).total_cmp(&norm(moved(y))))
        .expect("non-empty");
    let k = argmax_abs(moved(c));
    let mut pins = vec![(a, 0), (a, 1), (a, 2)];
    pins.extend((0..3).filter(|&ax| ax != m).map(|ax| (b, ax)));
    pins.push((c, k));
    pins
}

fn argmax_abs(v: Point) -> usize {
    (0..3)
        .max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs()))
        .expect("three axes")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

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
        let c = Constraints::new(&s, &t, &FixedVertices::None).unwrap();
        assert_eq!(c.fixed_dof.iter().filter(|f| **f).count(), 6);
        assert_eq!(c.gauge_components.len(), 1);
        // Auto finds the two poles on the rotation axis: collinear, so ignored.
        let c = Constraints::new(&s, &t, &FixedVertices::Auto).unwrap();
        assert_eq!(c.fixed_dof.iter().filter(|f| **f).count(), 6);
        assert!(c.fixed.is_empty());
    }

    #[test]
    fn auto_fixes_the_static_half_and_explicit_collinear_ids_are_rejected() {
        let m = generate::tube(0.5, 4.0, 8, 8, false);
        let s = set_of(&m, generate::bend(&m.positions, 2.0, 2.0, 1.5));
        let t = Topology::new(m.num_vertices(), &m.triangles);
        let c = Constraints::new(&s, &t, &FixedVertices::Auto).unwrap();
        assert_eq!(c.fixed.len(), 5 * 8, "rings at x ≤ 2 do not move");
        assert!(c.gauge_components.is_empty());
        let e = Constraints::new(&s, &t, &FixedVertices::Ids(vec![0, 8])).unwrap_err();
        assert!(matches!(e, BlendError::UnderConstrained { fixed: 2, .. }));
        let e = Constraints::new(&s, &t, &FixedVertices::Ids(vec![0, 9999])).unwrap_err();
        assert!(matches!(
            e,
            BlendError::FixedOutOfRange { vertex: 9999, .. }
        ));
    }
}
