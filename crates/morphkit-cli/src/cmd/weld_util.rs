//! Welded solves for the commands beside `blend` (issue 37): the welds of a source and a
//! target mesh, vertex ids from the command line mapped into them, and correspondences
//! carried between input and welded numbering (triangles keep their ids: a weld that would
//! drop a triangle is not applied, see [`mesh_weld`]).

use super::corr_args::{CorrespondenceArgs, Obtained};
use super::correspond::{confidence_summary, print_summary, summary};
use anyhow::{bail, Context};
use morphkit::mesh::{Point, Weld};
use morphkit::transfer::{correspond, Correspondence, Markers};
use morphkit::TriMesh;
use std::time::Instant;

/// [`Weld::keeping_triangles`]: the weld transfer, correspondence and flexibility solve on.
pub fn mesh_weld(mesh: &TriMesh, shapes: &[&[Point]]) -> Weld {
    Weld::keeping_triangles(mesh, shapes)
}

/// Says on stderr what `weld` did to the mesh called `what`.
pub fn announce(weld: &Weld, what: &str) {
    if !weld.is_identity() {
        eprintln!(
            "welded {} split vertices (seams, hard edges) of {what} into the {} they share a position with; results keep its {} vertices",
            weld.merged(),
            weld.num_welded(),
            weld.num_input()
        );
    }
}

/// The welds of a source (`reference` with the positions of `shapes`, its animation or
/// expressions) and of a target mesh, announced on stderr and recorded in `report` as
/// `welded_vertices: {source, target}`.
pub fn source_and_target(
    reference: &TriMesh,
    shapes: &morphkit::ShapeSet,
    target: &TriMesh,
    report: &mut serde_json::Value,
) -> (Weld, Weld) {
    let all: Vec<&[Point]> = shapes.all_positions().iter().map(|p| &p[..]).collect();
    let source = mesh_weld(reference, &all);
    let target = mesh_weld(target, &[]);
    announce(&source, "the source");
    announce(&target, "the target");
    report["welded_vertices"] = serde_json::json!({
        "source": source.merged(),
        "target": target.merged(),
    });
    (source, target)
}

/// Input vertex `v` (named `what` in errors) in welded numbering.
pub fn welded_id(weld: &Weld, v: u32, what: &str) -> anyhow::Result<u32> {
    match weld.to_welded().get(v as usize) {
        Some(&w) => Ok(w),
        None => bail!(
            "{what} {v} is out of range: the mesh has {} vertices",
            weld.num_input()
        ),
    }
}

/// Marker pairs in welded numbering (an id out of range stays as it is, for the
/// correspondence's own message naming the marker).
pub fn welded_markers(m: &Markers, source: &Weld, target: &Weld) -> anyhow::Result<Markers> {
    let map = |w: &Weld, v: u32| w.to_welded().get(v as usize).copied().unwrap_or(v);
    Ok(Markers::new(
        m.pairs
            .iter()
            .map(|&[s, t]| [map(source, s), map(target, t)])
            .collect(),
    ))
}

/// A correspondence written for the input meshes, for the welded ones: vertex counts and
/// markers mapped (one already welded, or of other counts, is left for `check` to judge).
pub fn welded_correspondence(c: Correspondence, source: &Weld, target: &Weld) -> Correspondence {
    if (source.is_identity() && target.is_identity())
        || c.source_vertices != source.num_input()
        || c.target_vertices != target.num_input()
        || c.identity
    {
        return c;
    }
    c.renumbered(
        Some((source.to_welded(), source.num_welded())),
        Some((target.to_welded(), target.num_welded())),
    )
}

/// A correspondence of the welded meshes, for the input ones: vertex counts and markers
/// (each at its welded vertex's first input vertex).
pub fn input_correspondence(c: Correspondence, source: &Weld, target: &Weld) -> Correspondence {
    if (source.is_identity() && target.is_identity()) || c.identity {
        return c;
    }
    c.renumbered(
        Some((source.representative(), source.num_input())),
        Some((target.representative(), target.num_input())),
    )
}

/// [`CorrespondenceArgs::obtain`] on welded meshes: markers (input numbering) are mapped
/// through the welds before the correspondence is computed on the welded meshes, and a
/// correspondence file (input numbering) is carried to the welded meshes.
pub fn obtain_welded(
    args: &CorrespondenceArgs,
    (source, source_weld): (&TriMesh, &Weld),
    (target, target_weld): (&TriMesh, &Weld),
    report: &mut serde_json::Value,
    confidence: bool,
) -> anyhow::Result<Obtained> {
    let Some(m) = &args.markers else {
        let mut o = args.obtain(source, target, report, confidence)?;
        o.correspondence = welded_correspondence(o.correspondence, source_weld, target_weld);
        return Ok(o);
    };
    if source_weld.is_identity() && target_weld.is_identity() {
        return args.obtain(source, target, report, confidence);
    }
    args.require()?;
    let given = Markers::read(m)?;
    let markers = welded_markers(&given, source_weld, target_weld)
        .with_context(|| format!("{}", m.display()))?;
    crate::util::announce_work("computing the correspondence", target.num_vertices());
    let t0 = Instant::now();
    let copts = args.correspondence_options();
    let mut r = correspond(source, target, &markers, &copts).context("correspondence")?;
    let secs = t0.elapsed().as_secs_f64();
    let welded = r.correspondence.clone();
    // Reported in input numbering, the markers as given.
    r.correspondence = input_correspondence(r.correspondence, source_weld, target_weld);
    r.correspondence.markers = given.pairs;
    print_summary(&r, secs);
    report["correspondence"] = summary(&r, secs);
    r.correspondence = welded;
    if confidence {
        let (_, conf) = confidence_summary(
            source,
            target,
            &r.correspondence,
            args.combine(),
            "; `morphkit correspond --confidence FILE.ply` shows where",
        )?;
        report["correspondence"]["match_confidence"] = conf;
    }
    Ok(Obtained {
        correspondence: r.correspondence,
        computed_from: Some((markers, copts)),
    })
}
