//! Frame-by-frame animation transfer: source gradients → correspondence → prefactored solve →
//! translation convention (Wang & Lee 2008, Sec. 3.2.3; Sumner & Popović 2004).
//!
//! Each target triangle's wanted gradient $M_j$ combines the gradients of its matched source
//! triangles ([`GradientCombine`]: inverse-distance weights by default), with each match's
//! stretch turned into the target triangle's plane ([`GradientFrame`]). The solve fixes one constraint vertex
//! per component, which alone would keep the target "running in place" — the limitation the
//! paper notes ("the constraint vertex is fixed in the same position through the entire
//! sequence"). [`TranslationMode::FollowMarkers`] (the default) goes beyond it: the result is
//! translated so that the centroid $\bar t$ of the target's anchor vertices (the markers; every
//! vertex for an identity correspondence) follows the source's anchor centroid $\bar s$:
//! $$\bar t(f) = \bar t(\text{ref}) + \frac{d_t}{d_s}\,\big(\bar s(f) - \bar s(\text{ref})\big),$$
//! $d_t, d_s$ the reference bounding-box diagonals. [`TranslationMode::FixedVertex`] keeps the
//! paper's convention. With several target components the translation is one rigid shift of
//! the whole result, so components keep the placement the constraint vertices give them.

use super::correspondence::{polar, Correspondence, GradientCombine};
use super::error::{Side, TransferError};
use super::fold_guard::{guarded_solve, FoldGuard, GuardOutcome, GuardedFrame};
use super::gradients::{FlipCheck, GradientOperator};
use super::solve::{SolverOptions, TransferSolver, TriangleWeighting};
use crate::mesh::{validate, Point, ShapeSet, ShapeSetError, Topology, TriMesh};
use nalgebra::{Matrix3, Vector3};

/// Where each transferred frame is placed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TranslationMode {
    /// The target's anchor centroid follows the source's, scaled by the size ratio. Default.
    #[default]
    FollowMarkers,
    /// The paper's convention: the constraint vertices stay at their reference positions.
    FixedVertex,
}

impl TranslationMode {
    /// The names the Python module (`translation=`) and recipes (`translation = …`) give
    /// [`TranslationMode::FollowMarkers`] and [`TranslationMode::FixedVertex`].
    pub const NAMES: [&'static str; 2] = ["follow", "fixed"];

    /// The name of this mode (one of [`TranslationMode::NAMES`]).
    pub fn name(self) -> &'static str {
        match self {
            Self::FollowMarkers => Self::NAMES[0],
            Self::FixedVertex => Self::NAMES[1],
        }
    }

    /// The mode named `name` (one of [`TranslationMode::NAMES`]), or `None`.
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::FollowMarkers, Self::FixedVertex]
            .into_iter()
            .find(|m| m.name() == name)
    }
}

/// In which frame a matched source gradient is carried onto its target triangle.
///
/// A source gradient splits into a rotation and a stretch, $G = R S$ (polar decomposition).
/// The rotation is a motion in the world, the same for both characters (a leg swinging
/// forward); the stretch is a deformation *of the surface*, defined relative to the source
/// triangle's own plane. Where a matched target triangle is oriented differently in its
/// reference (a camel's neck against a horse's), carrying $S$ unchanged in world coordinates
/// applies the source's in-plane stretch partly across the target's surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GradientFrame {
    /// Sumner & Popović as written: the matched gradients as they are, combined linearly
    /// ([`Correspondence::map_gradients`]). The default before issue 40.
    World,
    /// The rotations combined by their chordal mean (the projection of the weighted sum
    /// onto the rotations) and each match's stretch turned by the smallest rotation from its
    /// source triangle's reference normal onto the target triangle's, matches weighted also
    /// by how well their reference normals agree ([`Correspondence::map_gradients_local`]);
    /// each target triangle's term of the solve is weighted by the confidence of its matches
    /// ([`Correspondence::local_confidence`], Sumner & Popović 2004, Sec. 4: one term per
    /// matched pair). Default (issue 40): with the closest-point refinement, area-weighted
    /// solves and the fold guard ([`TransferOptions::fold_guard`]) it came closest in a
    /// leave-one-out study over four real pairs (docs/fidelity.md, "Transfer defaults"):
    /// mean cycle-consistency error 18.6–32.5 % lower than the world frame's, with fewer
    /// sharp folds on each pair (horse gallop onto the camel: 96 against 208 over 48 frames;
    /// 488 unguarded), but more triangles flipped against their wanted orientation (camel
    /// 593 against 320) and about 8× the per-frame solve time. Alone, without the fold guard,
    /// it makes more sharp folds than the world frame.
    #[default]
    LocalStretch,
}

/// Options of [`AnimationTransfer`].
#[derive(Clone, Debug)]
pub struct TransferOptions {
    /// Options of the prefactored solve (weights, constraint vertices). Default: area
    /// weights ([`TriangleWeighting::Area`], issue 40; `SolverOptions::default()` alone keeps
    /// the paper's uniform weights).
    pub solver: SolverOptions,
    /// How the gradients of several matched source triangles combine. Default: inverse
    /// distance.
    pub combine: GradientCombine,
    /// Translation convention. Default: follow the markers.
    pub translation: TranslationMode,
    /// Frame in which matched gradients are carried over. Default: local stretch (issue 40;
    /// [`GradientFrame::World`] is the paper's and the default before).
    pub frame: GradientFrame,
    /// With [`GradientFrame::LocalStretch`]: where a frame creases, its stretches are not
    /// turned there ([`FoldGuard`], module [`super::fold_guard`]). Default: on; `None` turns
    /// it off. No effect in the world frame.
    pub fold_guard: Option<FoldGuard>,
}

impl Default for TransferOptions {
    fn default() -> Self {
        Self {
            solver: SolverOptions {
                weighting: TriangleWeighting::Area,
                ..Default::default()
            },
            combine: GradientCombine::default(),
            translation: TranslationMode::default(),
            frame: GradientFrame::default(),
            fold_guard: Some(FoldGuard::default()),
        }
    }
}

/// A transfer set up once for a source reference, a target and their correspondence.
#[derive(Debug)]
pub struct AnimationTransfer {
    gradients: GradientOperator,
    correspondence: Correspondence,
    solver: TransferSolver,
    /// The source reference (for checking frames' connectivity).
    source_reference: TriMesh,
    /// The target reference's normals, for [`AnimationTransfer::flipped_triangles`].
    target_flips: FlipCheck,
    placement: Placement,
    combine: GradientCombine,
    /// Unit reference normals of the source and target triangles
    /// ([`GradientFrame::LocalStretch`] only).
    local_frames: Option<LocalFrames>,
    /// The fold guard with the target reference and its topology (local stretch only).
    guard: Option<(FoldGuard, TriMesh, Topology)>,
}

/// Unit reference normals of the source and the target triangles.
type LocalFrames = (Vec<Vector3<f64>>, Vec<Vector3<f64>>);

/// Unit normals of `m`'s triangles (zero for a degenerate one).
pub(crate) fn unit_normals(m: &TriMesh) -> Vec<Vector3<f64>> {
    (0..m.num_triangles())
        .map(|t| {
            let n = Vector3::from(m.triangle_normal(t));
            let l = n.norm();
            if l > 0.0 && l.is_finite() {
                n / l
            } else {
                Vector3::zeros()
            }
        })
        .collect()
}

/// The translation convention on its own ([`TranslationMode`], module doc), so that a caller
/// with its own prefactored [`TransferSolver`] (animation synthesis, which drives one target
/// from several sources) places frames exactly as [`AnimationTransfer`] does.
#[derive(Clone, Debug)]
pub struct Placement {
    anchors: Vec<[u32; 2]>,
    source_anchor_ref: Point,
    target_anchor_ref: Point,
    scale: f64,
    mode: TranslationMode,
}

impl Placement {
    /// The anchors of `correspondence` and their reference centroids on both meshes.
    pub fn new(
        source_reference: &TriMesh,
        target: &TriMesh,
        correspondence: &Correspondence,
        mode: TranslationMode,
    ) -> Self {
        let anchors = correspondence.anchor_pairs();
        let source_anchor_ref = centroid(&source_reference.positions, anchors.iter().map(|a| a[0]));
        let target_anchor_ref = centroid(&target.positions, anchors.iter().map(|a| a[1]));
        let ds = source_reference.bbox_diagonal();
        let scale = if ds > 0.0 {
            target.bbox_diagonal() / ds
        } else {
            1.0
        };
        Self {
            anchors,
            source_anchor_ref,
            target_anchor_ref,
            scale,
            mode,
        }
    }

    /// Size ratio $d_t / d_s$.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Translates a solved target frame `x` by the convention; `source_frame` supplies the
    /// source anchor centroid (`None`: the target's anchors stay at their reference centroid).
    /// [`TranslationMode::FixedVertex`] leaves `x` as the solve placed it.
    pub fn apply(&self, x: &mut [Point], source_frame: Option<&[Point]>) {
        if self.mode != TranslationMode::FollowMarkers {
            return;
        }
        let now = centroid(x, self.anchors.iter().map(|a| a[1]));
        let mut want = self.target_anchor_ref;
        if let Some(f) = source_frame {
            let s = centroid(f, self.anchors.iter().map(|a| a[0]));
            for k in 0..3 {
                want[k] += self.scale * (s[k] - self.source_anchor_ref[k]);
            }
        }
        let shift = [0, 1, 2].map(|k| want[k] - now[k]);
        for p in x.iter_mut() {
            for k in 0..3 {
                p[k] += shift[k];
            }
        }
    }
}

fn centroid(p: &[Point], idx: impl Iterator<Item = u32>) -> Point {
    let mut c = [0.0; 3];
    let mut n = 0usize;
    for i in idx {
        for k in 0..3 {
            c[k] += p[i as usize][k];
        }
        n += 1;
    }
    c.map(|x| x / n.max(1) as f64)
}

impl AnimationTransfer {
    /// Checks the meshes against the correspondence, precomputes the source reference's
    /// inverse frames and factors the target's transfer matrix.
    pub fn new(
        source_reference: &TriMesh,
        target: &TriMesh,
        correspondence: &Correspondence,
        opts: &TransferOptions,
    ) -> Result<Self, TransferError> {
        validate(source_reference).map_err(|source| TransferError::Mesh {
            side: Side::Source,
            source,
        })?;
        correspondence.check(source_reference, target)?;
        let local_frames = (opts.frame == GradientFrame::LocalStretch)
            .then(|| (unit_normals(source_reference), unit_normals(target)));
        let confidence = match &local_frames {
            Some((ns, nt)) => correspondence.local_confidence(ns, nt, opts.combine),
            None => Vec::new(),
        };
        let solver = TransferSolver::with_confidence(target, &opts.solver, &confidence)?;
        let placement = Placement::new(source_reference, target, correspondence, opts.translation);
        Ok(Self {
            gradients: GradientOperator::new(source_reference),
            correspondence: correspondence.clone(),
            solver,
            source_reference: source_reference.clone(),
            target_flips: FlipCheck::new(target),
            placement,
            combine: opts.combine,
            guard: match (&local_frames, opts.fold_guard) {
                (Some(_), Some(g)) => Some((
                    g,
                    target.clone(),
                    Topology::new(target.num_vertices(), &target.triangles),
                )),
                _ => None,
            },
            local_frames,
        })
    }

    /// The prefactored solver.
    pub fn solver(&self) -> &TransferSolver {
        &self.solver
    }

    /// The correspondence in use.
    pub fn correspondence(&self) -> &Correspondence {
        &self.correspondence
    }

    /// Size ratio $d_t / d_s$ used by the translation convention.
    pub fn scale(&self) -> f64 {
        self.placement.scale()
    }

    /// Gradients of every source triangle of `frame` relative to the source reference.
    /// Errors name frame 0; [`AnimationTransfer::source_gradients_at`] names another.
    pub fn source_gradients(&self, frame: &[Point]) -> Result<Vec<Matrix3<f64>>, TransferError> {
        self.gradients.gradients(frame)
    }

    /// [`AnimationTransfer::source_gradients`] of frame number `index`: errors name it.
    pub fn source_gradients_at(
        &self,
        index: usize,
        frame: &[Point],
    ) -> Result<Vec<Matrix3<f64>>, TransferError> {
        self.gradients.gradients_at(index, frame)
    }

    /// Target triangles of a transferred frame `x` that face against the orientation their
    /// wanted gradient (`target_gradients`) gives them ([`FlipCheck::flipped`] with the target
    /// reference's normals, computed once in [`AnimationTransfer::new`]).
    pub fn flipped_triangles(&self, x: &[Point], target_gradients: &[Matrix3<f64>]) -> Vec<usize> {
        self.target_flips.flipped(x, target_gradients)
    }

    /// Wanted gradient of every target triangle, from per-source-triangle gradients, carried
    /// over in the frame of [`TransferOptions::frame`] ([`GradientFrame`]).
    pub fn target_gradients(&self, source_gradients: &[Matrix3<f64>]) -> Vec<Matrix3<f64>> {
        match &self.local_frames {
            None => self
                .correspondence
                .map_gradients(source_gradients, self.combine),
            Some((ns, nt)) => {
                let pol: Vec<_> = source_gradients.iter().map(polar).collect();
                self.correspondence
                    .map_gradients_local(&pol, ns, nt, self.combine)
            }
        }
    }

    /// Solves for target positions from per-target-triangle gradients (from
    /// [`AnimationTransfer::target_gradients`], or blended by a synthesis step) and places the
    /// result by the translation convention; `source_frame` supplies the source anchor
    /// centroid (`None`: the target's anchors stay where they are in the reference).
    pub fn solve_gradients(
        &self,
        target_gradients: &[Matrix3<f64>],
        source_frame: Option<&[Point]>,
    ) -> Result<Vec<Point>, TransferError> {
        let mut x = self.solver.solve(target_gradients)?;
        self.placement.apply(&mut x, source_frame);
        Ok(x)
    }

    /// Solves for the target frame of per-source-triangle gradients `source_gradients`: their
    /// [`AnimationTransfer::target_gradients`], solved and placed as by
    /// [`AnimationTransfer::solve_gradients`], and with the local-stretch frame guarded
    /// against creases ([`TransferOptions::fold_guard`]). Returns the frame and the gradients
    /// it was solved with (for [`AnimationTransfer::flipped_triangles`]).
    pub fn transfer_gradients(
        &self,
        source_gradients: &[Matrix3<f64>],
        source_frame: Option<&[Point]>,
    ) -> Result<GuardedFrame, TransferError> {
        let (Some((guard, target, topology)), Some((ns, nt))) = (&self.guard, &self.local_frames)
        else {
            let wanted = self.target_gradients(source_gradients);
            let x = self.solve_gradients(&wanted, source_frame)?;
            return Ok((x, wanted, GuardOutcome::default()));
        };
        // The polar factors serve the turned gradients and, on a fold, the unturned ones.
        let pol: Vec<_> = source_gradients.iter().map(polar).collect();
        let wanted = self
            .correspondence
            .map_gradients_local(&pol, ns, nt, self.combine);
        let unturned = || {
            self.correspondence
                .map_gradients_local_unturned(&pol, ns, nt, self.combine)
        };
        let (mut x, used, outcome) =
            guarded_solve(guard, target, topology, wanted, unturned, |g| {
                self.solver.solve(g)
            })?;
        self.placement.apply(&mut x, source_frame);
        Ok((x, used, outcome))
    }

    /// Transfers one source frame (positions over the source reference's connectivity).
    /// Errors name frame 0; [`AnimationTransfer::transfer_frame_at`] names another.
    pub fn transfer_frame(&self, source_frame: &[Point]) -> Result<Vec<Point>, TransferError> {
        self.transfer_frame_at(0, source_frame)
    }

    /// [`AnimationTransfer::transfer_frame`] of frame number `index`: errors name it.
    pub fn transfer_frame_at(
        &self,
        index: usize,
        source_frame: &[Point],
    ) -> Result<Vec<Point>, TransferError> {
        let g = self.source_gradients_at(index, source_frame)?;
        Ok(self.transfer_gradients(&g, Some(source_frame))?.0)
    }

    /// Checks that `frames` share the source reference's connectivity (by
    /// [`ShapeSet::check_connectivity`]; a shape set's frames all share frame 0's, so a
    /// mismatch is reported for frame 0).
    pub fn check_frames(&self, frames: &ShapeSet) -> Result<(), TransferError> {
        check_frames(&self.source_reference, frames)
    }
}

/// [`ShapeSet::check_connectivity`] of the source reference against `frames`, with the
/// result phrased from the frames' side (`expected` is the reference's).
fn check_frames(reference: &TriMesh, frames: &ShapeSet) -> Result<(), TransferError> {
    let none = [u32::MAX; 3];
    match frames.check_connectivity("source reference", reference) {
        Ok(()) => Ok(()),
        Err(ShapeSetError::VertexCount {
            expected, found, ..
        }) => Err(TransferError::FrameVertexCount {
            frame: 0,
            expected: found,
            found: expected,
        }),
        Err(ShapeSetError::Connectivity {
            index,
            expected,
            found,
            ..
        }) => Err(TransferError::FrameConnectivity {
            frame: 0,
            triangle: index,
            expected: found,
            found: expected,
        }),
        Err(ShapeSetError::TriangleCount {
            expected, found, ..
        }) => {
            // `expected`: the frames' count, `found`: the reference's.
            let t = expected.min(found);
            Err(TransferError::FrameConnectivity {
                frame: 0,
                triangle: t,
                expected: reference.triangles.get(t).copied().unwrap_or(none),
                found: frames.triangles().get(t).copied().unwrap_or(none),
            })
        }
        Err(e) => Err(e.into()),
    }
}

/// One-shot transfer of every frame of `frames` (which must share `source_reference`'s
/// connectivity) onto `target`.
pub fn transfer_animation(
    source_reference: &TriMesh,
    frames: &ShapeSet,
    target: &TriMesh,
    correspondence: &Correspondence,
    opts: &TransferOptions,
) -> Result<Vec<Vec<Point>>, TransferError> {
    let tr = AnimationTransfer::new(source_reference, target, correspondence, opts)?;
    tr.check_frames(frames)?;
    frames
        .all_positions()
        .iter()
        .enumerate()
        .map(|(i, p)| tr.transfer_frame_at(i, p))
        .collect()
}

#[cfg(test)]
#[path = "animation_tests.rs"]
mod tests;
