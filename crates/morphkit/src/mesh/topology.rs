//! Topology queries computed once from a triangle list and cached in a plain struct.
//!
//! Nothing here is global or lazily memoised: build a [`Topology`] once per connectivity and pass
//! it by reference. Every query is `O(1)` or proportional to its output.

/// Compressed adjacency lists (`offsets` has one more entry than there are rows).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Adjacency {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl Adjacency {
    fn from_lists(lists: Vec<Vec<u32>>) -> Self {
        let mut offsets = Vec::with_capacity(lists.len() + 1);
        offsets.push(0u32);
        let mut items = Vec::new();
        for l in lists {
            items.extend_from_slice(&l);
            offsets.push(items.len() as u32);
        }
        Self { offsets, items }
    }
    /// Items of row `i`.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.items[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }
    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Total number of items in all rows.
    pub fn num_items(&self) -> usize {
        self.items.len()
    }
}

/// Cached topology of a triangle mesh.
#[derive(Clone, Debug)]
pub struct Topology {
    num_vertices: usize,
    /// Unique undirected edges `(i, j)` with `i < j`, sorted.
    edges: Vec<[u32; 2]>,
    /// For edge `e`, the triangles that contain it.
    edge_faces: Adjacency,
    /// For triangle `t`, its three edge ids: edge `k` is opposite corner `k`.
    face_edges: Vec<[u32; 3]>,
    one_ring: Adjacency,
    two_ring: Adjacency,
    face_adjacency: Adjacency,
    component_of_vertex: Vec<u32>,
    num_components: usize,
    consistently_oriented: bool,
}

impl Topology {
    /// Builds the topology of `triangles` over `num_vertices` vertices. Indices must be in range
    /// (see [`super::validate`]).
    pub fn new(num_vertices: usize, triangles: &[[u32; 3]]) -> Self {
        // Half-edges keyed by their undirected edge, then sorted.
        let mut half: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(3 * triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let a = tri[(k + 1) % 3];
                let b = tri[(k + 2) % 3];
                let (lo, hi, fwd) = if a < b { (a, b, 1) } else { (b, a, 0) };
                half.push((lo, hi, t as u32, fwd | ((k as u8) << 1)));
            }
        }
        half.sort_unstable();
        let mut edges = Vec::new();
        let mut ef_off = vec![0u32];
        let mut ef_items = Vec::with_capacity(half.len());
        let mut face_edges = vec![[0u32; 3]; triangles.len()];
        let mut consistent = true;
        let mut i = 0;
        while i < half.len() {
            let (lo, hi) = (half[i].0, half[i].1);
            let mut j = i;
            let e = edges.len() as u32;
            while j < half.len() && half[j].0 == lo && half[j].1 == hi {
                ef_items.push(half[j].2);
                face_edges[half[j].2 as usize][(half[j].3 >> 1) as usize] = e;
                j += 1;
            }
            if j - i == 2 && (half[i].3 & 1) == (half[i + 1].3 & 1) {
                consistent = false;
            }
            edges.push([lo, hi]);
            ef_off.push(ef_items.len() as u32);
            i = j;
        }
        let edge_faces = Adjacency {
            offsets: ef_off,
            items: ef_items,
        };

        let mut ring: Vec<Vec<u32>> = vec![Vec::new(); num_vertices];
        for &[a, b] in &edges {
            ring[a as usize].push(b);
            ring[b as usize].push(a);
        }
        for r in &mut ring {
            r.sort_unstable();
        }
        let one_ring = Adjacency::from_lists(ring);

        // Vertices at graph distance exactly 2.
        let mut mark = vec![u32::MAX; num_vertices];
        let mut two: Vec<Vec<u32>> = vec![Vec::new(); num_vertices];
        for v in 0..num_vertices {
            mark[v] = v as u32;
            for &n in one_ring.row(v) {
                mark[n as usize] = v as u32;
            }
            let mut out = Vec::new();
            for &n in one_ring.row(v) {
                for &m in one_ring.row(n as usize) {
                    if mark[m as usize] != v as u32 {
                        mark[m as usize] = v as u32;
                        out.push(m);
                    }
                }
            }
            out.sort_unstable();
            two[v] = out;
        }
        let two_ring = Adjacency::from_lists(two);

        let mut fadj: Vec<Vec<u32>> = vec![Vec::new(); triangles.len()];
        for e in 0..edges.len() {
            let fs = edge_faces.row(e);
            for &a in fs {
                for &b in fs {
                    if a != b {
                        fadj[a as usize].push(b);
                    }
                }
            }
        }
        for l in &mut fadj {
            l.sort_unstable();
            l.dedup();
        }
        let face_adjacency = Adjacency::from_lists(fadj);

        // Connected components over vertices (isolated vertices are their own component).
        let mut parent: Vec<u32> = (0..num_vertices as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for &[a, b] in &edges {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        let mut label = vec![u32::MAX; num_vertices];
        let mut component_of_vertex = vec![0u32; num_vertices];
        let mut num_components = 0usize;
        for v in 0..num_vertices {
            let r = find(&mut parent, v as u32) as usize;
            if label[r] == u32::MAX {
                label[r] = num_components as u32;
                num_components += 1;
            }
            component_of_vertex[v] = label[r];
        }

        Self {
            num_vertices,
            edges,
            edge_faces,
            face_edges,
            one_ring,
            two_ring,
            face_adjacency,
            component_of_vertex,
            num_components,
            consistently_oriented: consistent,
        }
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }
    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.face_adjacency.len()
    }
    /// Unique undirected edges `(i, j)`, `i < j`, sorted lexicographically.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// Triangles incident to edge `e` (1 on a boundary, 2 inside, more on a non-manifold edge).
    pub fn edge_faces(&self, e: usize) -> &[u32] {
        self.edge_faces.row(e)
    }
    /// Edge ids of triangle `t`; entry `k` is the edge opposite corner `k`.
    pub fn face_edges(&self, t: usize) -> [u32; 3] {
        self.face_edges[t]
    }
    /// Sorted neighbours of vertex `v` (its 1-ring).
    pub fn one_ring(&self, v: usize) -> &[u32] {
        self.one_ring.row(v)
    }
    /// Sorted vertices at graph distance exactly 2 from `v`.
    pub fn two_ring(&self, v: usize) -> &[u32] {
        self.two_ring.row(v)
    }
    /// Sorted triangles sharing an edge with triangle `t`.
    pub fn face_neighbors(&self, t: usize) -> &[u32] {
        self.face_adjacency.row(t)
    }
    /// Edges with exactly one incident triangle.
    pub fn boundary_edges(&self) -> Vec<usize> {
        (0..self.edges.len())
            .filter(|&e| self.edge_faces(e).len() == 1)
            .collect()
    }
    /// Edges with three or more incident triangles.
    pub fn non_manifold_edges(&self) -> Vec<usize> {
        (0..self.edges.len())
            .filter(|&e| self.edge_faces(e).len() > 2)
            .collect()
    }
    /// Vertices on a boundary edge.
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut b = vec![false; self.num_vertices];
        for e in self.boundary_edges() {
            b[self.edges[e][0] as usize] = true;
            b[self.edges[e][1] as usize] = true;
        }
        b
    }
    /// Component label of each vertex, `0..num_components()`, numbered by first vertex.
    pub fn components(&self) -> &[u32] {
        &self.component_of_vertex
    }
    /// Number of connected components (an isolated vertex counts as one).
    pub fn num_components(&self) -> usize {
        self.num_components
    }
    /// True when every edge shared by exactly two triangles is traversed in opposite directions.
    pub fn is_consistently_oriented(&self) -> bool {
        self.consistently_oriented
    }
    /// True when there are no boundary and no non-manifold edges.
    pub fn is_closed(&self) -> bool {
        (0..self.edges.len()).all(|e| self.edge_faces(e).len() == 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tetrahedron: closed, 6 edges, every vertex sees the other three.
    fn tet() -> Vec<[u32; 3]> {
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    }

    #[test]
    fn tetrahedron_is_closed_and_oriented() {
        let t = Topology::new(4, &tet());
        assert_eq!(t.edges().len(), 6);
        assert!(t.is_closed());
        assert!(t.is_consistently_oriented());
        assert_eq!(t.one_ring(0), &[1, 2, 3]);
        assert!(t.two_ring(0).is_empty());
        assert_eq!(t.face_neighbors(0), &[1, 2, 3]);
        assert_eq!(t.num_components(), 1);
        for f in 0..4 {
            for (k, &e) in t.face_edges(f).iter().enumerate() {
                let tri = tet()[f];
                let mut want = [tri[(k + 1) % 3], tri[(k + 2) % 3]];
                want.sort();
                assert_eq!(t.edges()[e as usize], want);
            }
        }
    }

    #[test]
    fn strip_boundary_two_ring_and_flip() {
        // 0-1-2 on top, 3-4-5 below: a 2×1 quad strip.
        let tris = vec![[0, 3, 1], [1, 3, 4], [1, 4, 2], [2, 4, 5]];
        let t = Topology::new(7, &tris);
        assert_eq!(t.boundary_edges().len(), 6);
        assert!(t.non_manifold_edges().is_empty());
        assert_eq!(t.two_ring(0), &[2, 4]);
        assert_eq!(t.two_ring(5), &[1, 3]);
        assert_eq!(t.num_components(), 2, "vertex 6 is isolated");
        assert!(t.is_consistently_oriented());
        let mut flipped = tris.clone();
        flipped[1] = [1, 4, 3];
        assert!(!Topology::new(6, &flipped).is_consistently_oriented());
    }

    #[test]
    fn three_fins_make_a_non_manifold_edge() {
        let tris = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let t = Topology::new(5, &tris);
        let nm = t.non_manifold_edges();
        assert_eq!(nm.len(), 1);
        assert_eq!(t.edges()[nm[0]], [0, 1]);
        assert!(!t.is_closed());
    }
}
