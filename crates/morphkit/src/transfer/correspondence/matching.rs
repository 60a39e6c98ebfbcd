//! Compatible-triangle matching on two meshes placed in the same space (Wang & Lee 2008,
//! Sec. 3.1.3; two-way as in Sumner & Popović 2004, Sec. 5.2).
//!
//! Target → source: every target triangle gets the source triangles whose centroids lie within
//! `radius` of its own and whose normals are less than 90° from its own (cosine above
//! `min_cos`, 0 by default: [`super::CorrespondenceOptions::min_normal_cos`]; at most
//! `max_matches`, nearest first), else the nearest compatible one at any distance, else (no
//! compatible normal anywhere) the nearest usable one, listed as a normal violation.
//!
//! Source → target (two-way): every usable source triangle with a normal is also added to the
//! list of its nearest compatible target triangle, so that every source triangle's motion
//! reaches the target somewhere. Lists stay sorted nearest first (ties by index).

use super::super::kdtree::KdTree;
use crate::mesh::{dot, norm, sub, Point};

/// The matches of every target triangle, CSR, with centroid distances.
pub(super) struct Matching {
    pub offsets: Vec<u32>,
    pub matches: Vec<u32>,
    pub distances: Vec<f32>,
    pub normal_violations: Vec<u32>,
    /// Source triangles added by the source → target pass.
    pub added_by_source: usize,
}

/// The two meshes' centroids and unit normals (zero: no normal) in one space.
pub(super) struct Placed<'a> {
    pub source_centroids: &'a [Point],
    pub source_normals: &'a [Point],
    /// Source triangles that may be matched.
    pub usable: &'a [bool],
    pub target_centroids: &'a [Point],
    pub target_normals: &'a [Point],
}

/// Matches as in the module docs.
pub(super) fn match_triangles(
    p: &Placed,
    radius: f64,
    max_matches: usize,
    two_way: bool,
    min_cos: f64,
) -> Matching {
    let (cs, ns, usable) = (p.source_centroids, p.source_normals, p.usable);
    let (ct, nt) = (p.target_centroids, p.target_normals);
    let tree = KdTree::new(cs);
    let nft = ct.len();
    let mut lists: Vec<Vec<(f64, u32)>> = Vec::with_capacity(nft);
    let mut normal_violations = Vec::new();
    let mut cand = Vec::new();
    for t in 0..nft {
        let (q, n) = (ct[t], nt[t]);
        let compatible = |s: u32| usable[s as usize] && dot(ns[s as usize], n) > min_cos;
        cand.clear();
        let mut scored: Vec<(f64, u32)> = Vec::new();
        if norm(n) > 0.0 && radius > 0.0 {
            tree.within(q, radius, &mut cand);
            scored.extend(
                cand.iter()
                    .filter(|&&s| compatible(s))
                    .map(|&s| (norm(sub(cs[s as usize], q)), s)),
            );
            scored.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            scored.truncate(max_matches.max(1));
        }
        if scored.is_empty() {
            let nearest = if norm(n) > 0.0 {
                tree.nearest_filtered(q, compatible)
            } else {
                None
            };
            match nearest {
                Some((s, d2)) => scored.push((d2.sqrt(), s)),
                None => {
                    normal_violations.push(t as u32);
                    let (s, d2) = tree
                        .nearest_filtered(q, |s| usable[s as usize])
                        .or_else(|| tree.nearest_filtered(q, |_| true))
                        .expect("the source mesh has triangles");
                    scored.push((d2.sqrt(), s));
                }
            }
        }
        lists.push(scored);
    }
    let mut added_by_source = 0;
    if two_way && nft > 0 {
        let ttree = KdTree::new(ct);
        for s in 0..cs.len() {
            let n = ns[s];
            if !usable[s] || norm(n) == 0.0 {
                continue;
            }
            let Some((t, d2)) = ttree.nearest_filtered(cs[s], |t| {
                let m = nt[t as usize];
                norm(m) > 0.0 && dot(m, n) > min_cos
            }) else {
                continue;
            };
            let list = &mut lists[t as usize];
            if !list.iter().any(|x| x.1 == s as u32) {
                list.push((d2.sqrt(), s as u32));
                added_by_source += 1;
            }
        }
        for list in &mut lists {
            list.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
    }
    let mut offsets = Vec::with_capacity(nft + 1);
    offsets.push(0u32);
    let total: usize = lists.iter().map(Vec::len).sum();
    let mut matches = Vec::with_capacity(total);
    let mut distances = Vec::with_capacity(total);
    for list in &lists {
        matches.extend(list.iter().map(|x| x.1));
        distances.extend(list.iter().map(|x| x.0 as f32));
        offsets.push(matches.len() as u32);
    }
    Matching {
        offsets,
        matches,
        distances,
        normal_violations,
        added_by_source,
    }
}
