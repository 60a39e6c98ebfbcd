//! [`VolumetricBlend`]: the physical blend with internal springs and an optional anchor
//! (Ma et al. 2012, Sec. 3.1 and 3.4), built once, then solved per weight vector.

use super::anchor::{self, apply_inverse, AnchorMotion};
use super::lattice::{self, Interior, SkippedComponent};
use super::reverse::{self, Neighbourhoods};
use super::tetgen;
use super::{
    count_inversions, AnchorOptions, InteriorError, InteriorMode, InteriorOptions, Inversions,
};
use crate::geom::RigidTransform;
use crate::mesh::{Point, ShapeSet, TriMesh};
use crate::springs::terms::{EnergyTerm, SpringTerm, VolumeTerm};
use crate::springs::{
    BlendError, BlendOptions, BlendPredictor, FixedVertices, FrameStats, PhysicalBlend, Spring,
    SpringKind, SpringSet, Weights,
};
use std::time::Instant;

/// What the volumetric set-up built.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct InteriorReport {
    /// Surface vertices.
    pub surface_vertices: usize,
    /// Interior vertices (lattice points or tetgen's Steiner points).
    pub interior_vertices: usize,
    /// Anchor vertices (0 or 8).
    pub anchor_vertices: usize,
    /// Internal springs (lattice edges and surface ties, or tetgen's tetrahedron edges that
    /// are not surface edges).
    pub internal_springs: usize,
    /// Anchor springs (its edges and ties).
    pub anchor_springs: usize,
    /// Interior tetrahedra (lattice or tetgen).
    pub tetrahedra: usize,
    /// Tetrahedra of the volume term: the interior's, plus the lattice's shell cones (one per
    /// surface triangle that has one); 0 when the term is off.
    pub volume_elements: usize,
    /// Lattice spacing, or tetgen's edge length $L$ of the volume bound, per filled component
    /// `(component, h)`.
    pub spacing: Vec<(usize, f64)>,
    /// Components without interior and why (open meshes: every component).
    pub skipped: Vec<SkippedComponent>,
    /// Anchor centre and edge length in the base.
    pub anchor: Option<(Point, f64)>,
    /// Newton iterations of each target's reverse solve.
    pub reverse_iterations: Vec<usize>,
    /// Seconds spent building (interior, reverse solves, symbolic analysis).
    pub setup_seconds: f64,
}

/// One volumetric frame.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeResult {
    /// Surface positions, `#V` of the input.
    pub positions: Vec<Point>,
    /// Interior then anchor positions, world coordinates.
    pub extra: Vec<Point>,
    /// Solver statistics (unconverged vertices: surface ids only).
    pub stats: FrameStats,
    /// Inverted elements (Sec. 5).
    pub inversions: Inversions,
    /// The anchor's blended motion $T(c)$, when there is an anchor.
    pub anchor_motion: Option<RigidTransform>,
}

/// The predictor of a blend on its input surface, in world coordinates: that of a
/// [`PhysicalBlend`] ([`BlendPredictor`]), or of a [`VolumetricBlend`] (or a scene built on
/// one), whose prediction of the extended system is mapped out of the anchor's frame and cut
/// to the surface. The interior is predicted too (carried with its surface neighbourhood), so
/// this previews the volumetric blend's start, not the surface blend's. Cheap to clone,
/// `Send + Sync`, usable while the blend solves on another thread.
#[derive(Clone)]
pub struct SurfacePredictor {
    inner: BlendPredictor,
    motion: Option<AnchorMotion>,
    surface: usize,
}

impl std::fmt::Debug for SurfacePredictor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfacePredictor")
            .field("surface", &self.surface)
            .finish()
    }
}

impl SurfacePredictor {
    /// The predictor of `inner` (a blend whose first `surface` vertices are the input's),
    /// mapped to the world by the anchor's `motion` when there is one.
    pub(crate) fn new(inner: BlendPredictor, motion: Option<AnchorMotion>, surface: usize) -> Self {
        Self {
            inner,
            motion,
            surface,
        }
    }

    /// The predicted surface for `weights` ([`BlendPredictor::predict`]): exact at one-hot
    /// weights, one prefactored solve.
    pub fn predict(&self, weights: &Weights) -> Result<Vec<Point>, BlendError> {
        let mut p = self.inner.predict(weights)?;
        if let Some(m) = &self.motion {
            let t = m.at(&weights.coefficients(self.inner.num_shapes())?);
            p.iter_mut().for_each(|x| *x = t.apply(*x));
        }
        p.truncate(self.surface);
        Ok(p)
    }
}

impl From<BlendPredictor> for SurfacePredictor {
    fn from(inner: BlendPredictor) -> Self {
        let surface = inner.num_vertices();
        Self::new(inner, None, surface)
    }
}

/// Physical blend with internal springs and an anchor: build once, solve many.
pub struct VolumetricBlend {
    blend: PhysicalBlend,
    surface: ShapeSet,
    extended: ShapeSet,
    tets: Vec<[u32; 4]>,
    motion: Option<AnchorMotion>,
    report: InteriorReport,
}

impl std::fmt::Debug for VolumetricBlend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VolumetricBlend")
            .field("report", &self.report)
            .finish()
    }
}

impl VolumetricBlend {
    /// Builds the interior and the anchor in the base, places them in every target by the
    /// reverse solve, and sets up the blend of the extended shape set.
    ///
    /// With an anchor, its 8 vertices are the boundary conditions: [`FixedVertices::Auto`]
    /// and [`FixedVertices::None`] then fix nothing else (every surface vertex moves freely,
    /// as Sec. 3.4 intends); explicit ids are fixed as well, interpolated linearly in the
    /// anchor's frame.
    pub fn new(
        shapes: &ShapeSet,
        options: &BlendOptions,
        interior: &InteriorOptions,
        anchor: &AnchorOptions,
    ) -> Result<Self, InteriorError> {
        let t0 = Instant::now();
        interior.check()?;
        anchor.check()?;
        let n = shapes.num_vertices();
        let base = shapes.positions(0);
        let k0 = options.springs.k0;
        let (solids, skipped) = lattice::solids(base, shapes.triangles());
        let inner = match interior.mode {
            InteriorMode::Lattice => lattice::build_in(base, &solids, skipped, interior),
            InteriorMode::Tetgen => {
                tetgen::build_in(base, shapes.triangles(), &solids, skipped, interior)?
            }
            InteriorMode::None => Interior::default(),
        };
        let mut body = base.to_vec();
        body.extend_from_slice(&inner.points);
        let placed = anchor::place(&body, n, &solids, anchor, k0)?;
        let mut springs: Vec<(Spring, f64)> = inner
            .springs
            .iter()
            .map(|&[i, j]| {
                let s = Spring {
                    i,
                    j,
                    kind: SpringKind::Internal,
                };
                (s, interior.stiffness * k0)
            })
            .collect();
        let mut extra_base = inner.points.clone();
        if let Some(a) = &placed {
            springs.extend_from_slice(&a.springs);
            extra_base.extend_from_slice(&a.points);
        }
        let mut base_ext = base.to_vec();
        base_ext.extend_from_slice(&extra_base);
        // Reverse solve (Sec. 3.4 step 3): the extra vertices in every target.
        let near = Neighbourhoods::new(base, &extra_base);
        let mut per_shape = vec![base_ext.clone()];
        let mut reverse_iterations = Vec::new();
        for s in 1..shapes.len() {
            let guess = near.guess(base, shapes.positions(s), &extra_base);
            let extra = if springs.is_empty() {
                guess
            } else {
                let (mut e, its) = reverse::solve(shapes, s, &base_ext, &springs, &guess, options)?;
                reverse_iterations.push(its);
                if let Some(a) = &placed {
                    keep_anchor_upright(&mut e, &guess, a.vertices.len());
                }
                e
            };
            let mut p = shapes.positions(s).to_vec();
            p.extend(extra);
            per_shape.push(p);
        }
        let names: Vec<String> = shapes.names().to_vec();
        let mesh = TriMesh::new(base_ext.clone(), shapes.triangles().to_vec());
        let extended = ShapeSet::new(
            mesh.clone(),
            names
                .iter()
                .cloned()
                .zip(per_shape.iter().cloned())
                .collect(),
        )?;
        // Steps 4–5: the anchor's motions, and the shapes in the anchor's frame.
        let mut o = options.clone();
        let (motion, local) = match &placed {
            None => (None, extended.clone()),
            Some(a) => {
                let anchors: Vec<Vec<Point>> = per_shape
                    .iter()
                    .map(|p| a.vertices.iter().map(|&v| p[v as usize]).collect())
                    .collect();
                let motion = AnchorMotion::new(&a.points, &anchors);
                let local: Vec<(String, Vec<Point>)> = per_shape
                    .iter()
                    .enumerate()
                    .map(|(s, p)| {
                        let t = motion.shape(s);
                        let q = p.iter().map(|&x| apply_inverse(&t, x)).collect();
                        (names[s].clone(), q)
                    })
                    .collect();
                let mut ids = a.vertices.clone();
                if let FixedVertices::Ids(user) = &options.fixed {
                    ids.extend_from_slice(user);
                }
                o.fixed = FixedVertices::Ids(ids);
                (Some(motion), ShapeSet::new(mesh, local)?)
            }
        };
        let mut terms: Vec<Box<dyn EnergyTerm>> = Vec::new();
        if !springs.is_empty() {
            let set = SpringSet::from_pairs(&local, &springs, &o.springs);
            terms.push(Box::new(SpringTerm::new(set, o.min_rest_fraction)));
        }
        let mut volume_elements = 0;
        if interior.volume > 0.0 {
            let mut elements = inner.tets.clone();
            if interior.mode == InteriorMode::Lattice {
                elements.extend(super::shell::cones(
                    base,
                    shapes.triangles(),
                    &inner.points,
                    &inner.springs,
                ));
            }
            if !elements.is_empty() {
                let term =
                    VolumeTerm::new(&local, &elements, interior.volume * k0, o.min_rest_fraction);
                volume_elements = term.tetrahedra().len();
                terms.push(Box::new(term));
            }
        }
        let blend = PhysicalBlend::with_terms(&local, &o, terms)?;
        let anchor_springs = springs
            .iter()
            .filter(|s| s.0.kind == SpringKind::Anchor)
            .count();
        let report = InteriorReport {
            surface_vertices: n,
            interior_vertices: inner.points.len(),
            anchor_vertices: placed.as_ref().map_or(0, |a| a.vertices.len()),
            internal_springs: springs.len() - anchor_springs,
            anchor_springs,
            tetrahedra: inner.tets.len(),
            volume_elements,
            spacing: inner.spacing.clone(),
            skipped: inner.skipped.clone(),
            anchor: placed.as_ref().map(|a| (a.center, a.size)),
            reverse_iterations,
            setup_seconds: t0.elapsed().as_secs_f64(),
        };
        Ok(Self {
            blend,
            surface: shapes.clone(),
            extended,
            tets: inner.tets,
            motion,
            report,
        })
    }

    /// The pieces a scene blend builds on: the blend of the extended set (in the anchor's
    /// frame when anchored), the anchor's motion, and the report.
    pub(crate) fn into_parts(self) -> (PhysicalBlend, Option<AnchorMotion>, InteriorReport) {
        (self.blend, self.motion, self.report)
    }

    /// What was built.
    pub fn report(&self) -> &InteriorReport {
        &self.report
    }
    /// The underlying blend of the extended set (in the anchor's frame when anchored).
    pub fn physical(&self) -> &PhysicalBlend {
        &self.blend
    }
    /// The extended shapes in world coordinates: surface then extra vertices, every target
    /// with its reverse-solved extra vertices.
    pub fn extended_shapes(&self) -> &ShapeSet {
        &self.extended
    }
    /// The interior tetrahedra (extended ids), positively oriented in the base.
    pub fn tetrahedra(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// The shape every solve for `weights` starts from, on the input surface in world
    /// coordinates (a preview, see [`SurfacePredictor`]).
    pub fn predict(&self, weights: &Weights) -> Result<Vec<Point>, BlendError> {
        self.predictor().predict(weights)
    }

    /// A handle on [`predict`](Self::predict) that does not borrow the blend.
    pub fn predictor(&self) -> SurfacePredictor {
        SurfacePredictor::new(
            self.blend.predictor(),
            self.motion.clone(),
            self.surface.num_vertices(),
        )
    }

    /// The canonical equilibrium of the extended system for `weights`, surface returned.
    pub fn solve(&mut self, weights: &Weights) -> Result<VolumeResult, BlendError> {
        let r = self.blend.solve(weights)?;
        self.finish(weights, r)
    }

    /// The equilibrium with point targets on surface vertices (pulls, Ma et al. Sec. 4), given
    /// in world coordinates; with an anchor they are mapped into its blended frame for the
    /// solve. Without targets this is [`solve`](Self::solve), bit for bit.
    pub fn solve_with(
        &mut self,
        weights: &Weights,
        targets: &[crate::springs::PointTarget],
    ) -> Result<VolumeResult, BlendError> {
        let n = self.surface.num_vertices();
        if let Some(t) = targets.iter().find(|t| t.vertex as usize >= n) {
            return Err(BlendError::TargetOutOfRange {
                vertex: t.vertex,
                num_vertices: n,
            });
        }
        let frame = match &self.motion {
            Some(m) if !targets.is_empty() => {
                Some(m.at(&weights.coefficients(self.surface.len())?))
            }
            _ => None,
        };
        let local = anchor::targets_in_frame(frame.as_ref(), targets.to_vec());
        let r = self.blend.solve_with(weights, &local, None)?;
        self.finish(weights, r)
    }

    /// Every weight vector on up to `threads` threads; bit-for-bit [`solve`](Self::solve).
    pub fn solve_many(
        &mut self,
        weights: &[Weights],
        threads: usize,
    ) -> Vec<Result<VolumeResult, BlendError>> {
        let rs = self.blend.solve_many(weights, threads);
        rs.into_iter()
            .zip(weights)
            .map(|(r, w)| r.and_then(|r| self.finish(w, r)))
            .collect()
    }

    fn finish(
        &self,
        weights: &Weights,
        r: crate::springs::BlendResult,
    ) -> Result<VolumeResult, BlendError> {
        let n = self.surface.num_vertices();
        let c = weights.coefficients(self.surface.len())?;
        let mut p = r.positions;
        let motion = self.motion.as_ref().map(|m| m.at(&c));
        if let Some(t) = &motion {
            p.iter_mut().for_each(|x| *x = t.apply(*x));
        }
        let linear = crate::springs::linear_blend(&self.surface, weights)?;
        let inversions = count_inversions(&p, self.surface.triangles(), &self.tets, &linear);
        let mut stats = r.stats;
        stats.unconverged_vertices.retain(|&v| (v as usize) < n);
        let extra = p.split_off(n);
        Ok(VolumeResult {
            positions: p,
            extra,
            stats,
            inversions,
            anchor_motion: motion,
        })
    }
}

/// A cube tied to a nearly flat patch (an open mesh) has turned-over equilibria: the same
/// vertex set with permuted labels, i.e. the cube rotated by up to 180°. When the reverse
/// solve ends in one, its anchor (the last `anchor` entries of `extra`) turns by more than 90°
/// against the guess, which carries it rigidly with its surface neighbourhood; the blend would
/// then turn the whole shape by the slerp towards that rotation. Such an anchor is replaced by
/// its guess.
fn keep_anchor_upright(extra: &mut [Point], guess: &[Point], anchor: usize) {
    let k = extra.len() - anchor;
    let fit = crate::geom::kabsch(&guess[k..], &extra[k..], &[]);
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(
        &nalgebra::Rotation3::from_matrix_unchecked(fit.rotation),
    );
    if q.angle() > std::f64::consts::FRAC_PI_2 {
        extra[k..].copy_from_slice(&guess[k..]);
    }
}
