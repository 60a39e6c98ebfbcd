//! Quality of a correspondence and a transfer without a reference answer.
//!
//! - **Cycle consistency** ([`cycle_consistency`]): transfer source frames A → B with the
//!   forward correspondence, transfer the results back B → A with the correspondence of the
//!   reversed markers, and measure how far each round trip lands from the original frame:
//!   per-vertex distance over A's reference bounding-box diagonal, the mean over vertices and
//!   frames, and the maximum. A perfect, invertible correspondence gives 0 (up to the
//!   least-squares fit of each solve); errors of either direction show up.
//! - **Correspondence statistics** ([`correspondence_quality`]): the fraction of target
//!   triangles whose matches all pass the normal test, the fraction of source triangles that
//!   reach some target triangle, and the marker residuals.
//! - **Match confidence** ([`match_confidence`]): per target triangle, how well its matches'
//!   reference normals agree with its own; low where the correspondence takes a triangle's
//!   motion from source triangles that face away (places that need markers).
//! - **Folds** ([`fold_count`]): triangles of a transferred frame that face against their
//!   wanted orientation ([`super::FlipCheck`]), and *sharp folds*: interior edges whose two
//!   triangles' normals are more than 120° apart in the frame but less than 120° apart in the
//!   target reference (a crease the transfer made).

use super::animation::{unit_normals, AnimationTransfer, TransferOptions};
use super::correspondence::Correspondence;
use super::correspondence::GradientCombine;
use super::error::TransferError;
use crate::mesh::{dot, norm, sub, triangle_normal, Point, Topology, TriMesh};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// Normals more than this far apart (cosine) across an edge form a sharp fold: 120°.
pub const SHARP_FOLD_COS: f64 = -0.5;

/// Round-trip errors of [`cycle_consistency`], relative to A's reference diagonal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CycleConsistency {
    /// Mean per-vertex distance over all vertices and frames.
    pub mean: f64,
    /// Largest per-vertex distance over all frames.
    pub max: f64,
    /// Mean per frame.
    pub frame_mean: Vec<f64>,
    /// Largest per frame.
    pub frame_max: Vec<f64>,
    /// Flipped triangles of each forward (A → B) frame.
    pub forward_flipped: Vec<usize>,
    /// Sharp folds of each forward (A → B) frame.
    pub forward_sharp_folds: Vec<usize>,
}

/// Fold counts of one transferred frame ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FoldCount {
    /// Triangles facing against the orientation their wanted gradient gives them.
    pub flipped: usize,
    /// Interior edges folded sharper than 120° that were not in the reference.
    pub sharp_folds: usize,
}

/// Counts sharp folds of `frame` over `reference`'s connectivity (edges with two triangles).
pub fn sharp_folds(reference: &TriMesh, topology: &Topology, frame: &[Point]) -> usize {
    sharp_fold_edges(reference, topology, frame).len()
}

/// The sharply folded edges of `frame` (indices into `topology.edges()`, ascending): interior
/// edges whose triangles' normals are more than 120° apart in `frame` but not in `reference`.
pub fn sharp_fold_edges(reference: &TriMesh, topology: &Topology, frame: &[Point]) -> Vec<usize> {
    let tris = &reference.triangles;
    let sharp = |p: &[Point], a: u32, b: u32| {
        let na = triangle_normal(p, tris[a as usize]);
        let nb = triangle_normal(p, tris[b as usize]);
        let (la, lb) = (norm(na), norm(nb));
        la > 0.0 && lb > 0.0 && dot(na, nb) < SHARP_FOLD_COS * la * lb
    };
    (0..topology.edges().len())
        .filter(|&e| {
            let f = topology.edge_faces(e);
            f.len() == 2 && sharp(frame, f[0], f[1]) && !sharp(&reference.positions, f[0], f[1])
        })
        .collect()
}

/// Fold counts of a frame `x` transferred by `tr` with wanted gradients `wanted`.
pub fn fold_count(
    tr: &AnimationTransfer,
    target: &TriMesh,
    topology: &Topology,
    x: &[Point],
    wanted: &[Matrix3<f64>],
) -> FoldCount {
    FoldCount {
        flipped: tr.flipped_triangles(x, wanted).len(),
        sharp_folds: sharp_folds(target, topology, x),
    }
}

/// Statistics of a correspondence that need no frames.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrespondenceQuality {
    /// Fraction of target triangles with at least one match passing the normal test (all of
    /// them but the normal violations).
    pub normal_pass_fraction: f64,
    /// Fraction of source triangles that are some target triangle's match.
    pub source_coverage: f64,
    /// Mean number of matches per target triangle.
    pub mean_matches: f64,
    /// Mean marker residual over the target diagonal.
    pub marker_residual_mean: f64,
    /// Largest marker residual over the target diagonal.
    pub marker_residual_max: f64,
}

/// [`CorrespondenceQuality`] of `c`.
pub fn correspondence_quality(c: &Correspondence) -> CorrespondenceQuality {
    let mut reached = vec![false; c.source_triangles];
    for &s in &c.matches {
        reached[s as usize] = true;
    }
    let r = &c.marker_residuals;
    CorrespondenceQuality {
        normal_pass_fraction: 1.0
            - c.normal_violations.len() as f64 / c.target_triangles.max(1) as f64,
        source_coverage: reached.iter().filter(|&&x| x).count() as f64
            / c.source_triangles.max(1) as f64,
        mean_matches: c.mean_matches(),
        marker_residual_mean: r.iter().map(|m| m.relative).sum::<f64>() / r.len().max(1) as f64,
        marker_residual_max: r.iter().map(|m| m.relative).fold(0.0, f64::max),
    }
}

/// Confidence below which [`match_confidence`] counts a target triangle as doubtful: its
/// matches' reference normals are, on average, about 65° or more away from its own
/// ($\cos^4(\theta/2) = 0.5$ at θ ≈ 65°).
pub const LOW_CONFIDENCE: f64 = 0.5;

/// The confidence of every target triangle's matches in the reference meshes:
/// [`Correspondence::local_confidence`] with the unit reference normals of `source` and
/// `target` and the `combine` weights, in [[`CONFIDENCE_FLOOR`](super::CONFIDENCE_FLOOR), 1].
/// 1 where every match faces the way the target triangle does (a mesh onto itself), near 0
/// where its matches face away, so that its motion is carried over through a large turn or
/// from the wrong side; more markers near such triangles help. `#T_target` values.
pub fn match_confidence(
    source: &TriMesh,
    target: &TriMesh,
    c: &Correspondence,
    combine: GradientCombine,
) -> Result<Vec<f64>, TransferError> {
    c.check(source, target)?;
    Ok(c.local_confidence(&unit_normals(source), &unit_normals(target), combine))
}

/// Cycle consistency of the correspondences `forward` (A → B) and `backward` (B → A, from
/// the same markers reversed) on the frames `frames` of `a_reference` (each #V_A × 3):
/// see the [module docs](self). Both transfers use `opts` (the translation convention maps
/// the marker centroid there and back, so it cancels).
pub fn cycle_consistency(
    a_reference: &TriMesh,
    frames: &[Vec<Point>],
    b: &TriMesh,
    forward: &Correspondence,
    backward: &Correspondence,
    opts: &TransferOptions,
) -> Result<CycleConsistency, TransferError> {
    let fwd = AnimationTransfer::new(a_reference, b, forward, opts)?;
    let bwd = AnimationTransfer::new(b, a_reference, backward, opts)?;
    let topo_b = Topology::new(b.num_vertices(), &b.triangles);
    let d = a_reference.bbox_diagonal().max(f64::MIN_POSITIVE);
    let mut out = CycleConsistency {
        mean: 0.0,
        max: 0.0,
        frame_mean: Vec::with_capacity(frames.len()),
        frame_max: Vec::with_capacity(frames.len()),
        forward_flipped: Vec::with_capacity(frames.len()),
        forward_sharp_folds: Vec::with_capacity(frames.len()),
    };
    for (i, f) in frames.iter().enumerate() {
        let (y, g, _) = fwd.transfer_gradients(&fwd.source_gradients_at(i, f)?, Some(f))?;
        let folds = fold_count(&fwd, b, &topo_b, &y, &g);
        out.forward_flipped.push(folds.flipped);
        out.forward_sharp_folds.push(folds.sharp_folds);
        let z = bwd.transfer_frame_at(i, &y)?;
        let (mut sum, mut worst) = (0.0f64, 0.0f64);
        for (p, q) in z.iter().zip(f) {
            let e = norm(sub(*p, *q)) / d;
            sum += e;
            worst = worst.max(e);
        }
        out.frame_mean.push(sum / z.len().max(1) as f64);
        out.frame_max.push(worst);
    }
    let n = out.frame_mean.len().max(1) as f64;
    out.mean = out.frame_mean.iter().sum::<f64>() / n;
    out.max = out.frame_max.iter().copied().fold(0.0, f64::max);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::testmesh::{grid, sphere};

    #[test]
    fn the_identity_cycle_is_exact_and_a_crease_is_a_sharp_fold() {
        let m = sphere(12, 8, 1.0);
        let frame: Vec<Point> = m
            .positions
            .iter()
            .map(|p| [p[0] * 1.3, p[1] + 0.2 * p[2] * p[2], p[2]])
            .collect();
        let id = Correspondence::identity(&m);
        let c = cycle_consistency(
            &m,
            std::slice::from_ref(&frame),
            &m,
            &id,
            &id,
            &TransferOptions::default(),
        )
        .unwrap();
        assert!(c.max < 1e-9, "{c:?}");
        assert_eq!(c.forward_flipped, vec![0]);
        assert_eq!(c.forward_sharp_folds, vec![0]);
        // Fold a flat grid by 150° along x = 2: the edges on the fold line are sharp folds.
        let g = grid(4, 3, 1.0);
        let topo = Topology::new(g.num_vertices(), &g.triangles);
        let (c, s) = (150f64.to_radians().cos(), 150f64.to_radians().sin());
        let folded: Vec<Point> = g
            .positions
            .iter()
            .map(|p| {
                if p[0] > 2.0 {
                    [2.0 + (p[0] - 2.0) * c, p[1], (p[0] - 2.0) * s]
                } else {
                    *p
                }
            })
            .collect();
        let n = sharp_folds(&g, &topo, &folded);
        assert!(n >= 3, "{n} sharp folds");
        assert_eq!(sharp_folds(&g, &topo, &g.positions), 0);
        // Folded the other way is no fold relative to itself.
        assert_eq!(
            sharp_folds(&g.with_positions(folded.clone()), &topo, &folded),
            0
        );
        let q = correspondence_quality(&id);
        assert_eq!((q.normal_pass_fraction, q.source_coverage), (1.0, 1.0));
    }

    #[test]
    fn match_confidence_is_one_onto_itself_and_low_where_the_target_faces_away() {
        let m = sphere(12, 8, 1.0);
        let id = Correspondence::identity(&m);
        let combine = GradientCombine::default();
        let c = match_confidence(&m, &m, &id, combine).unwrap();
        assert_eq!(c.len(), m.num_triangles());
        assert!(c.iter().all(|&x| (x - 1.0).abs() < 1e-12), "{c:?}");
        // The target with every triangle's orientation reversed: each match faces away.
        let mut inside_out = m.clone();
        for t in &mut inside_out.triangles {
            t.swap(1, 2);
        }
        let away = match_confidence(&m, &inside_out, &id, combine).unwrap();
        assert!(away.iter().all(|&x| x < LOW_CONFIDENCE), "{away:?}");
        // The upper half turned inside out: only those triangles lose confidence.
        let mut half = m.clone();
        let flipped: Vec<bool> = (0..m.num_triangles())
            .map(|t| {
                m.triangles[t]
                    .iter()
                    .map(|&v| m.positions[v as usize][2])
                    .sum::<f64>()
                    > 0.0
            })
            .collect();
        for (t, &f) in half.triangles.iter_mut().zip(&flipped) {
            if f {
                t.swap(1, 2);
            }
        }
        let part = match_confidence(&m, &half, &id, combine).unwrap();
        for (t, (&x, &f)) in part.iter().zip(&flipped).enumerate() {
            assert_eq!(x < LOW_CONFIDENCE, f, "triangle {t}: {x}");
        }
        // A correspondence of other meshes is refused.
        let other = grid(4, 3, 1.0);
        assert!(match_confidence(&m, &other, &id, combine).is_err());
    }
}
