//! A static 3-d tree over points (triangle centroids) for radius and filtered-nearest queries.
//!
//! Built once by median splits on the axis of largest spread (`select_nth_unstable`, so
//! `O(n log n)`), leaves of at most [`LEAF_SIZE`] points. Points with equal coordinates are
//! fine (a planar grid of centroids has one constant axis). Written here rather than taken
//! from `kiddo` because the correspondence needs a *filtered* nearest query ("nearest source
//! triangle whose normal is compatible"), which branch-and-bound answers exactly in one pass.

use crate::mesh::Point;

/// Most points in a leaf.
pub const LEAF_SIZE: usize = 8;

#[derive(Clone, Debug)]
struct Node {
    /// Range `lo..hi` of [`KdTree::order`] covered by this node.
    lo: u32,
    hi: u32,
    /// Split axis; `u8::MAX` for a leaf.
    axis: u8,
    split: f64,
    /// Child node indices (left: coordinates ≤ split, right: ≥ split).
    left: u32,
    right: u32,
}

/// A balanced 3-d tree over a fixed point set; queries return indices into that set.
#[derive(Clone, Debug)]
pub struct KdTree {
    points: Vec<Point>,
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl KdTree {
    /// Builds the tree over `points` (copied).
    pub fn new(points: &[Point]) -> Self {
        let mut tree = Self {
            points: points.to_vec(),
            order: (0..points.len() as u32).collect(),
            nodes: Vec::with_capacity(2 * points.len() / LEAF_SIZE + 1),
        };
        if !points.is_empty() {
            tree.build(0, points.len());
        }
        tree
    }

    fn build(&mut self, lo: usize, hi: usize) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(Node {
            lo: lo as u32,
            hi: hi as u32,
            axis: u8::MAX,
            split: 0.0,
            left: 0,
            right: 0,
        });
        if hi - lo <= LEAF_SIZE {
            return id;
        }
        let mut lo_b = [f64::INFINITY; 3];
        let mut hi_b = [f64::NEG_INFINITY; 3];
        for &i in &self.order[lo..hi] {
            let p = self.points[i as usize];
            for k in 0..3 {
                lo_b[k] = lo_b[k].min(p[k]);
                hi_b[k] = hi_b[k].max(p[k]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi_b[a] - lo_b[a]).total_cmp(&(hi_b[b] - lo_b[b])))
            .unwrap_or(0);
        let mid = (lo + hi) / 2;
        let pts = &self.points;
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
            pts[a as usize][axis].total_cmp(&pts[b as usize][axis])
        });
        let split = self.points[self.order[mid] as usize][axis];
        let left = self.build(lo, mid);
        let right = self.build(mid, hi);
        let n = &mut self.nodes[id as usize];
        n.axis = axis as u8;
        n.split = split;
        n.left = left;
        n.right = right;
        id
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the tree holds no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Appends to `out` every point index within distance `radius` of `q` (unsorted).
    pub fn within(&self, q: Point, radius: f64, out: &mut Vec<u32>) {
        if self.nodes.is_empty() {
            return;
        }
        let r2 = radius * radius;
        let mut stack = vec![0u32];
        while let Some(id) = stack.pop() {
            let n = &self.nodes[id as usize];
            if n.axis == u8::MAX {
                for &i in &self.order[n.lo as usize..n.hi as usize] {
                    if dist2(self.points[i as usize], q) <= r2 {
                        out.push(i);
                    }
                }
                continue;
            }
            let d = q[n.axis as usize] - n.split;
            if d <= radius {
                stack.push(n.left);
            }
            if d >= -radius {
                stack.push(n.right);
            }
        }
    }

    /// The nearest point index `i` with `accept(i)` true, and its squared distance; `None`
    /// when no point is accepted. Exact (branch and bound); visits every point only when
    /// almost none are accepted.
    pub fn nearest_filtered(&self, q: Point, accept: impl Fn(u32) -> bool) -> Option<(u32, f64)> {
        let mut best: Option<(u32, f64)> = None;
        if !self.nodes.is_empty() {
            self.nearest_rec(0, q, &accept, &mut best);
        }
        best
    }

    fn nearest_rec(
        &self,
        id: u32,
        q: Point,
        accept: &impl Fn(u32) -> bool,
        best: &mut Option<(u32, f64)>,
    ) {
        let n = &self.nodes[id as usize];
        if n.axis == u8::MAX {
            for &i in &self.order[n.lo as usize..n.hi as usize] {
                let d2 = dist2(self.points[i as usize], q);
                if best.is_none_or(|b| d2 < b.1 || (d2 == b.1 && i < b.0)) && accept(i) {
                    *best = Some((i, d2));
                }
            }
            return;
        }
        let d = q[n.axis as usize] - n.split;
        let (near, far) = if d <= 0.0 {
            (n.left, n.right)
        } else {
            (n.right, n.left)
        };
        self.nearest_rec(near, q, accept, best);
        if best.is_none_or(|b| d * d <= b.1) {
            self.nearest_rec(far, q, accept, best);
        }
    }
}

#[inline]
fn dist2(a: Point, b: Point) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute_nearest(p: &[Point], q: Point, accept: impl Fn(u32) -> bool) -> Option<(u32, f64)> {
        let mut best: Option<(u32, f64)> = None;
        for (i, &x) in p.iter().enumerate() {
            let d2 = dist2(x, q);
            if accept(i as u32) && best.is_none_or(|b| d2 < b.1) {
                best = Some((i as u32, d2));
            }
        }
        best
    }

    #[test]
    fn queries_match_brute_force_on_random_and_planar_points() {
        for (n, planar, seed) in [
            (1, false, 1),
            (50, false, 2),
            (2000, false, 3),
            (900, true, 4),
        ] {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let pts: Vec<Point> = (0..n)
                .map(|i| {
                    if planar {
                        // A 30 × 30 grid: z constant, many equal x and y values.
                        [(i % 30) as f64, (i / 30) as f64, 2.0]
                    } else {
                        [rng.random(), rng.random(), rng.random()]
                    }
                })
                .collect();
            let tree = KdTree::new(&pts);
            assert_eq!(tree.len(), n);
            for _ in 0..50 {
                let s = if planar { 30.0 } else { 1.0 };
                let q = [
                    rng.random::<f64>() * s,
                    rng.random::<f64>() * s,
                    rng.random(),
                ];
                let r = rng.random::<f64>() * 0.2 * s;
                let mut got = Vec::new();
                tree.within(q, r, &mut got);
                got.sort_unstable();
                let want: Vec<u32> = (0..n as u32)
                    .filter(|&i| dist2(pts[i as usize], q) <= r * r)
                    .collect();
                assert_eq!(got, want);
                let filt = |i: u32| i % 7 == 3;
                let a = tree.nearest_filtered(q, filt);
                let b = brute_nearest(&pts, q, filt);
                assert_eq!(a.map(|x| x.1), b.map(|x| x.1));
            }
        }
        assert!(KdTree::new(&[])
            .nearest_filtered([0.0; 3], |_| true)
            .is_none());
    }
}
