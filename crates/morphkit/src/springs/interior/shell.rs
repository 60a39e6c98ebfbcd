//! Shell tetrahedra: the part of a closed component between its surface and its lattice,
//! for the volume term (issue 40, "Volume under twist").
//!
//! The lattice's tetrahedra fill only the core, at least `margin · h` inside; the shell around
//! it, most of the volume of a shape a few lattice cells thick, has no element. Each surface
//! triangle gets one *cone*: the tetrahedron of the triangle and one interior point tied to its
//! vertices, the one nearest the triangle's centroid among the points tied to all three
//! (else to any of them) that lies at least a fifth of the triangle's longest edge off its
//! plane. Cones need not tile the shell; each holds the volume between its triangle and the
//! interior near its blended value. A triangle none of whose vertices is tied (a part too thin
//! for the lattice) gets no cone.

use crate::mesh::{cross, dot, norm, sub, Point};

/// One cone per surface triangle that has a suitable apex (module doc). `n` surface vertices;
/// `points` are the interior vertices `n..`; `springs` the internal springs, whose pairs
/// `(surface, interior)` are the ties.
pub fn cones(
    base: &[Point],
    triangles: &[[u32; 3]],
    points: &[Point],
    springs: &[[u32; 2]],
) -> Vec<[u32; 4]> {
    let n = base.len();
    let mut ties: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &[a, b] in springs {
        let (s, i) = (a.min(b), a.max(b));
        if (s as usize) < n && (i as usize) >= n {
            ties[s as usize].push(i);
        }
    }
    let at = |v: u32| {
        if (v as usize) < n {
            base[v as usize]
        } else {
            points[v as usize - n]
        }
    };
    let mut out = Vec::new();
    let mut apex_of: Vec<Option<u32>> = Vec::with_capacity(triangles.len());
    for &t in triangles {
        let lists = t.map(|v| &ties[v as usize]);
        apex_of.push(None);
        if lists.iter().all(|l| l.is_empty()) {
            continue;
        }
        let [a, b, c] = t.map(at);
        let normal = cross(sub(b, a), sub(c, a));
        let area2 = norm(normal);
        if area2 == 0.0 {
            continue;
        }
        let slot = apex_of.len() - 1;
        let unit = normal.map(|x| x / area2);
        let longest = norm(sub(b, a)).max(norm(sub(c, b))).max(norm(sub(a, c)));
        let centroid = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
        let shared: Vec<u32> = lists[0]
            .iter()
            .copied()
            .filter(|p| lists[1].contains(p) && lists[2].contains(p))
            .collect();
        let mut any: Vec<u32> = lists.iter().flat_map(|l| l.iter().copied()).collect();
        any.sort_unstable();
        any.dedup();
        let best = |cand: &[u32]| {
            cand.iter()
                .copied()
                .filter(|&p| dot(sub(at(p), a), unit).abs() >= 0.2 * longest)
                .min_by(|&p, &q| {
                    let dp = norm(sub(at(p), centroid));
                    let dq = norm(sub(at(q), centroid));
                    dp.total_cmp(&dq).then(p.cmp(&q))
                })
        };
        if let Some(apex) = best(&shared).or_else(|| best(&any)) {
            out.push([t[0], t[1], t[2], apex]);
            apex_of[slot] = Some(apex);
        }
    }
    wedges(triangles, &apex_of, n, &mut out);
    out
}

/// Between two cones of one edge with different apexes, the wedge `(u, v, p, q)`; around each
/// surface vertex, the fan from it to the polygon of its cones' apexes.
fn wedges(triangles: &[[u32; 3]], apex_of: &[Option<u32>], n: usize, out: &mut Vec<[u32; 4]>) {
    let mut edges: std::collections::HashMap<[u32; 2], Vec<u32>> = Default::default();
    let mut around: Vec<Vec<([u32; 2], u32)>> = vec![Vec::new(); n];
    for (t, apex) in triangles.iter().zip(apex_of) {
        let Some(p) = *apex else { continue };
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            edges.entry([u.min(v), u.max(v)]).or_default().push(p);
            // At vertex t[k]: the triangle's two other vertices, in order.
            around[t[k] as usize].push(([t[(k + 1) % 3], t[(k + 2) % 3]], p));
        }
    }
    let mut keys: Vec<&[u32; 2]> = edges.keys().collect();
    keys.sort_unstable();
    for e in keys {
        let ps = &edges[e];
        if ps.len() == 2 && ps[0] != ps[1] {
            out.push([e[0], e[1], ps[0], ps[1]]);
        }
    }
    for (u, fan) in around.iter().enumerate() {
        // Order the fan's apexes by walking the triangles around u.
        if fan.len() < 3 {
            continue;
        }
        let mut ring = vec![fan[0].1];
        let mut next = fan[0].0[1];
        for _ in 1..fan.len() {
            match fan.iter().find(|f| f.0[0] == next) {
                Some(f) => {
                    ring.push(f.1);
                    next = f.0[1];
                }
                None => break,
            }
        }
        ring.dedup();
        if ring.len() > 1 && ring[0] == ring[ring.len() - 1] {
            ring.pop();
        }
        for i in 1..ring.len().saturating_sub(1) {
            out.push([u as u32, ring[0], ring[i], ring[i + 1]]);
        }
    }
}
