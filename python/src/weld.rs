//! Welding for the solvers of the module (issue 37), as the CLI does it: vertices split at seams
//! and hard edges are one vertex for a solve ([`morphkit::mesh::Weld`]), and every result,
//! statistic and vertex id goes back in the caller's own layout. Where nothing is welded,
//! nothing is copied or mapped, so results are bit-identical to an unwelded solve.

use morphkit::mesh::{Point, ShapeSet, TriMesh, Weld, WELD_TOLERANCE};
use morphkit::springs::{FixedVertices, FrameStats};
use morphkit::transfer::Correspondence;
use std::sync::Arc;

/// The weld of `shapes` for a solve (`weld=True`), or `None` where nothing is welded.
pub(crate) fn shape_weld(shapes: &ShapeSet, weld: bool) -> Option<Arc<Weld>> {
    if !weld {
        return None;
    }
    let w = Weld::of_shapes(shapes, WELD_TOLERANCE);
    (!w.is_identity()).then(|| Arc::new(w))
}

/// The weld of one mesh for a solve: `None` where nothing is welded, `weld` is false, or a
/// triangle would be lost (triangles keep their ids).
pub(crate) fn mesh_weld(mesh: &TriMesh, weld: bool) -> Option<Weld> {
    if !weld {
        return None;
    }
    let w = Weld::keeping_triangles(mesh, &[]);
    (!w.is_identity()).then_some(w)
}

/// `positions` of the welded mesh in the input's layout (as they are without a weld).
pub(crate) fn unweld(weld: Option<&Weld>, positions: Vec<Point>) -> Vec<Point> {
    match weld {
        Some(w) => w.scatter(&positions),
        None => positions,
    }
}

/// `positions` of one frame with weights `w` over `n` shapes in the input's layout: at a
/// shape's own weights each copy keeps its own numbers ([`Weld::scatter_frame`]).
pub(crate) fn unweld_frame(
    weld: Option<&Weld>,
    positions: Vec<Point>,
    w: &morphkit::springs::Weights,
    n: usize,
) -> Vec<Point> {
    match (weld, w.coefficients(n)) {
        (Some(wd), Ok(c)) => wd.scatter_frame(&positions, &c),
        (Some(wd), Err(_)) => wd.scatter(&positions),
        (None, _) => positions,
    }
}

/// Fixed vertex ids (input numbering, checked) in welded numbering.
pub(crate) fn weld_fixed(weld: Option<&Weld>, fixed: FixedVertices) -> FixedVertices {
    match (weld, fixed) {
        (Some(w), FixedVertices::Ids(ids)) => FixedVertices::Ids(w.welded_ids(&ids)),
        (_, f) => f,
    }
}

/// Statistics of a welded solve in input numbering: the unconverged vertices are every input
/// vertex of an unconverged welded one.
pub(crate) fn unweld_stats(weld: Option<&Weld>, mut stats: FrameStats) -> FrameStats {
    if let Some(w) = weld {
        stats.unconverged_vertices = w.input_vertices(&stats.unconverged_vertices);
    }
    stats
}

/// A correspondence of the input target, for its welded mesh (one of another vertex count is
/// left for the transfer to refuse).
pub(crate) fn welded_target_corr(c: &Correspondence, w: &Weld) -> Correspondence {
    if c.target_vertices != w.num_input() {
        return c.clone();
    }
    c.clone()
        .renumbered(None, Some((w.to_welded(), w.num_welded())))
}
