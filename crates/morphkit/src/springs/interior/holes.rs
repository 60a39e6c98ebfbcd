//! Small holes of an open component, capped for the inside test only (see the
//! [`lattice`](super::lattice) module docs): a fan around each boundary loop's vertex centroid.

use crate::mesh::{norm, sub, Point};

/// Largest area of one hole's cap, as a fraction of its component's surface area, for the hole
/// to be capped for the inside test (see the module docs).
pub const MAX_HOLE_AREA_FRACTION: f64 = 0.1;

/// A hole's cap: its vertex centroid and the boundary edges `a → b` it closes.
pub(super) struct Cap {
    pub centre: Point,
    pub edges: Vec<[u32; 2]>,
}

/// The boundary loops of a component's triangles as caps, or `None` when a boundary vertex
/// has more than one outgoing boundary edge (a pinched boundary: no unique loop).
fn boundary_caps(base: &[Point], tris: &[[u32; 3]]) -> Option<Vec<Cap>> {
    let mut directed: Vec<[u32; 2]> = tris
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .collect();
    directed.sort_unstable();
    let boundary: Vec<[u32; 2]> = directed
        .iter()
        .copied()
        .filter(|&[a, b]| directed.binary_search(&[b, a]).is_err())
        .collect();
    if boundary.windows(2).any(|w| w[0][0] == w[1][0]) {
        return None;
    }
    let next = |v: u32| {
        boundary
            .binary_search_by(|e| e[0].cmp(&v))
            .ok()
            .map(|k| boundary[k][1])
    };
    let mut used = vec![false; boundary.len()];
    let mut caps = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        let mut edges = Vec::new();
        let mut k = start;
        loop {
            used[k] = true;
            edges.push(boundary[k]);
            let b = boundary[k][1];
            if b == boundary[start][0] {
                break;
            }
            let nb = next(b)?;
            k = boundary.binary_search(&[b, nb]).ok()?;
            if used[k] {
                return None;
            }
        }
        let mut centre = [0.0; 3];
        for e in &edges {
            for a in 0..3 {
                centre[a] += base[e[0] as usize][a] / edges.len() as f64;
            }
        }
        caps.push(Cap { centre, edges });
    }
    Some(caps)
}

fn triangle_area(a: Point, b: Point, c: Point) -> f64 {
    0.5 * norm(crate::mesh::cross(sub(b, a), sub(c, a)))
}

/// The caps of every hole of a component's triangles `tris`, when each hole is small (its cap
/// has at most [`MAX_HOLE_AREA_FRACTION`] of the triangles' area) and the boundary is not
/// pinched; `None` otherwise.
pub(super) fn small_hole_caps(base: &[Point], tris: &[[u32; 3]]) -> Option<Vec<Cap>> {
    let area: f64 = tris
        .iter()
        .map(|t| {
            triangle_area(
                base[t[0] as usize],
                base[t[1] as usize],
                base[t[2] as usize],
            )
        })
        .sum();
    let caps = boundary_caps(base, tris)?;
    let small = |cap: &Cap| {
        let a: f64 = cap
            .edges
            .iter()
            .map(|&[p, q]| triangle_area(base[q as usize], base[p as usize], cap.centre))
            .sum();
        a <= MAX_HOLE_AREA_FRACTION * area
    };
    caps.iter().all(small).then_some(caps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// An open tube has two small end holes, each capped by a loop of its `around` boundary
    /// edges; a flat patch's outline is one hole as large as the patch, so it gets no caps.
    #[test]
    fn tube_ends_are_small_holes_and_a_patch_outline_is_not() {
        let t = generate::tube(0.5, 4.0, 12, 16, false);
        let caps = small_hole_caps(&t.positions, &t.triangles).unwrap();
        assert_eq!(caps.len(), 2);
        assert!(caps.iter().all(|c| c.edges.len() == 12));
        let p = generate::grid(12, 12, 4.0, 1.0);
        assert!(small_hole_caps(&p.positions, &p.triangles).is_none());
    }
}
