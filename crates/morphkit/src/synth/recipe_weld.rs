//! Welded synthesis (issue 37): the split vertices of a recipe's meshes (seams, hard edges of
//! exported meshes) are one vertex for the solve, as in every other solving command.
//!
//! The target is welded where its vertices coincide in the target, in `rest` and in every
//! frame of the layers that animate the target itself; each source reference where they
//! coincide in it and in all of its layer's frames. Vertices that part in any of those shapes
//! stay apart, and a weld that would drop a triangle is not applied (triangle ids carry the
//! scribbles, selections and correspondences), see [`weld_keeping_triangles`]. Frames are
//! synthesised on the welded target and scattered back to the target's own layout
//! ([`super::BuiltRecipe::frame`]).

use crate::mesh::{TriMesh, Weld};
use crate::synth::{Scribble, SynthError};
use crate::transfer::{Correspondence, Markers};

/// The triangle mask of `scribble` on the input `mesh` (range checks in its numbering), taken
/// on the welded mesh for a vertex scribble: a triangle whose corners are scribbled copies of
/// a seam's vertices is covered, as on the unsplit mesh.
pub(super) fn scribble_mask(
    scribble: &Scribble,
    mesh: &TriMesh,
    weld: &Weld,
) -> Result<Vec<bool>, SynthError> {
    match scribble {
        Scribble::Vertices(v) if !weld.is_identity() => {
            let count = mesh.num_vertices();
            if let Some(&index) = v.iter().find(|&&i| i as usize >= count) {
                return Err(SynthError::ScribbleOutOfRange {
                    what: "vertex",
                    index,
                    count,
                });
            }
            let welded = Scribble::Vertices(weld.welded_ids(v));
            welded.triangle_mask(weld.num_welded(), &weld.triangles(&mesh.triangles))
        }
        _ => scribble.triangle_mask(mesh.num_vertices(), &mesh.triangles),
    }
}

/// Markers (input numbering) in the welded numbering of the source and the target (an id out
/// of range stays as it is, for the correspondence's own message).
pub(super) fn welded_markers(m: &Markers, source: &Weld, target: &Weld) -> Markers {
    let map = |w: &Weld, v: u32| w.to_welded().get(v as usize).copied().unwrap_or(v);
    Markers::new(
        m.pairs
            .iter()
            .map(|&[s, t]| [map(source, s), map(target, t)])
            .collect(),
    )
}

/// A correspondence file written for the input meshes, for the welded ones (one of other
/// vertex counts, already welded, is left for the synthesizer's check to refuse).
pub(super) fn welded_correspondence(
    c: Correspondence,
    source: &Weld,
    target: &Weld,
) -> Correspondence {
    if (source.is_identity() && target.is_identity())
        || c.identity
        || c.source_vertices != source.num_input()
        || c.target_vertices != target.num_input()
    {
        return c;
    }
    c.renumbered(
        Some((source.to_welded(), source.num_welded())),
        Some((target.to_welded(), target.num_welded())),
    )
}
