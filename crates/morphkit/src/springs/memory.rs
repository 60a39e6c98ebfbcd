//! Refusing a mesh too large for the memory limit early, before its connectivity is built.
//!
//! The solver's memory is known exactly only after the symbolic analysis of its Hessian
//! (`system::predicted_bytes`), which on a 2M-vertex mesh costs 35 s and 3.6 GB itself. Two
//! earlier checks refuse what is clearly too large:
//! 1. a lower bound from the triangles alone (`system::predicted_bytes_lower_bound`);
//! 2. for meshes of [`SAMPLED_ABOVE`] vertices or more, the exact estimate of a connected
//!    part of [`SAMPLE_VERTICES`] vertices (a breadth-first ball from the first triangle),
//!    scaled to the whole mesh. The part's estimate is that of the path its blend takes,
//!    with the aggregation cycle's levels and coarse factor where the cycle preconditions
//!    (before 6 December it left them out, and a 1.21M-vertex sheet passed this check, then
//!    took 39 s and 8.0 GB of set-up to be refused at 8.92 GiB; now it is refused here in
//!    6.8 s at 1.2 GB, with 8.65 GiB). Scaled linearly it under-estimates every surface whose
//!    factor fill per vertex grows with size (nested dissection of a sheet: `n log n`), and
//!    a ball's rim fills less than the interior, so the mesh is refused only when the linear
//!    scaling is over the limit; the message gives the likelier size: the `n log n` scaling
//!    where only a factor can precondition, the linear one where the aggregation cycle may
//!    replace it (its levels and the per-vertex structures grow like the vertices).
//!
//! What passes both goes on to the exact analysis, which decides as before.

use super::options::BlendOptions;
use super::sampled_start::StartSamples;
use super::system::predicted_bytes_lower_bound;
use super::{BlendError, MemoryEstimate};
use crate::mesh::{ShapeSet, TriMesh};

/// Meshes with at least this many vertices get the sampled estimate.
pub const SAMPLED_ABOVE: usize = 400_000;

/// Vertices in the sampled part.
pub const SAMPLE_VERTICES: usize = 100_000;

/// Fails with [`BlendError::TooLarge`] when `shapes` is clearly over `o.max_memory_bytes`
/// (see the module docs); `Ok` says only that the exact analysis must decide. `exact` is the
/// symbolic analysis's estimate of a mesh (the rig's), run on the sampled part; it is passed
/// in so that this check stays below the rig that calls it.
pub(crate) fn check_early(
    shapes: &ShapeSet,
    o: &BlendOptions,
    exact: fn(&ShapeSet, &BlendOptions) -> Result<u64, BlendError>,
) -> Result<(), BlendError> {
    let n = shapes.num_vertices();
    let bound =
        predicted_bytes_lower_bound(n, shapes.triangles(), o.factor_precision, o.may_aggregate())
            + StartSamples::bytes(n, shapes.len() - 1, o.sampled_start);
    let too_large = |predicted_bytes, basis| BlendError::TooLarge {
        vertices: n,
        predicted_bytes,
        limit_bytes: o.max_memory_bytes,
        basis,
    };
    if bound > o.max_memory_bytes {
        return Err(too_large(bound, MemoryEstimate::LowerBound));
    }
    if n < SAMPLED_ABOVE {
        return Ok(());
    }
    let Some(part) = sample(shapes, SAMPLE_VERTICES) else {
        return Ok(());
    };
    let m = part.num_vertices();
    let Ok(part_bytes) = exact(&part, o) else {
        // The part may not solve on its own (say, all of it fixed): the exact analysis decides.
        return Ok(());
    };
    let scale = n as f64 / m as f64;
    let linear = part_bytes as f64 * scale;
    if linear > o.max_memory_bytes as f64 {
        // Where the aggregation cycle may replace the factor, the memory grows like the
        // vertices (the cycle and the per-vertex structures); a factor's fill like n log n.
        let likely = if o.may_aggregate() {
            linear
        } else {
            linear * (n as f64).log2() / (m as f64).log2()
        };
        return Err(too_large(
            likely as u64,
            MemoryEstimate::Sampled { vertices: m },
        ));
    }
    Ok(())
}

/// The part of `shapes` within a breadth-first ball of `size` vertices from the first
/// triangle's first vertex: those vertices, renumbered in ball order, and the triangles with
/// all three corners among them. `None` when the ball has no triangle.
fn sample(shapes: &ShapeSet, size: usize) -> Option<ShapeSet> {
    let n = shapes.num_vertices();
    let tris = shapes.triangles();
    // Vertex adjacency in compressed rows, from the sorted directed edges.
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| {
            [
                (t[0], t[1]),
                (t[1], t[0]),
                (t[1], t[2]),
                (t[2], t[1]),
                (t[2], t[0]),
                (t[0], t[2]),
            ]
        })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut start = vec![0usize; n + 1];
    for &(a, _) in &edges {
        start[a as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut index = vec![u32::MAX; n];
    let mut order = Vec::with_capacity(size);
    let seed = tris.first()?[0];
    index[seed as usize] = 0;
    order.push(seed);
    let mut head = 0;
    while head < order.len() && order.len() < size {
        let v = order[head] as usize;
        head += 1;
        for &(_, w) in &edges[start[v]..start[v + 1]] {
            if index[w as usize] == u32::MAX && order.len() < size {
                index[w as usize] = order.len() as u32;
                order.push(w);
            }
        }
    }
    drop(edges);
    let part_tris: Vec<[u32; 3]> = tris
        .iter()
        .filter(|t| t.iter().all(|&v| index[v as usize] != u32::MAX))
        .map(|t| t.map(|v| index[v as usize]))
        .collect();
    if part_tris.is_empty() {
        return None;
    }
    let gather = |p: &[crate::mesh::Point]| order.iter().map(|&v| p[v as usize]).collect();
    let frames = (0..shapes.len())
        .map(|s| (shapes.name(s).to_string(), gather(shapes.positions(s))))
        .collect();
    ShapeSet::new(TriMesh::new(gather(shapes.positions(0)), part_tris), frames).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_ball_is_connected_renumbered_and_keeps_whole_triangles() {
        let g = generate::grid(40, 40, 1.0, 1.0);
        let shapes = ShapeSet::new(
            g.clone(),
            vec![
                ("a".into(), g.positions.clone()),
                ("b".into(), g.positions.clone()),
            ],
        )
        .unwrap();
        let part = sample(&shapes, 300).unwrap();
        assert_eq!(part.num_vertices(), 300);
        assert!(part.triangles().len() > 400);
        // Every vertex of the part is a vertex of the grid at its place.
        for p in part.positions(1) {
            assert!(g.positions.contains(p));
        }
    }

    /// Issue 39: a 2M-vertex mesh was refused only after 35 s of set-up. The sampled estimate
    /// of a sheet is within 10 % of the exact one, refuses below it, and lets a limit above the
    /// exact estimate through to the exact analysis.
    #[test]
    fn the_sampled_estimate_of_a_large_sheet_is_close_and_refuses_only_what_is_over() {
        let g = generate::grid(649, 649, 1.0, 1.0);
        assert!(g.num_vertices() >= SAMPLED_ABOVE);
        let bent = generate::bend(&g.positions, 0.5, 0.5, 1.0);
        let shapes = ShapeSet::new(
            g.clone(),
            vec![("a".into(), g.positions.clone()), ("b".into(), bent)],
        )
        .unwrap();
        let o = BlendOptions::default();
        let exact = super::super::rig::Rig::estimate_bytes(&shapes, &o).unwrap();
        // A limit under the exact estimate but over the lower bound from the triangles
        // (which, counting the per-vertex structures, is within 20 % of it on a sheet).
        let n = shapes.num_vertices();
        let bound = predicted_bytes_lower_bound(n, shapes.triangles(), o.factor_precision, true)
            + StartSamples::bytes(n, 1, o.sampled_start);
        assert!(bound < exact * 9 / 10, "bound {bound}, exact {exact}");
        let under = BlendOptions {
            max_memory_bytes: (bound + exact * 9 / 10) / 2,
            ..o.clone()
        };
        match check_early(&shapes, &under, super::super::rig::Rig::estimate_bytes) {
            Err(BlendError::TooLarge {
                predicted_bytes,
                basis: MemoryEstimate::Sampled { vertices },
                ..
            }) => {
                assert_eq!(vertices, SAMPLE_VERTICES);
                let r = predicted_bytes as f64 / exact as f64;
                assert!((0.9..1.1).contains(&r), "sampled/exact = {r}");
            }
            other => panic!("expected the sampled refusal, got {other:?}"),
        }
        let over = BlendOptions {
            max_memory_bytes: exact + exact / 10,
            ..o
        };
        assert!(check_early(&shapes, &over, super::super::rig::Rig::estimate_bytes).is_ok());
    }
}
