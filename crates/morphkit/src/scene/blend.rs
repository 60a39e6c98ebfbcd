//! [`SceneBlend`]: a prefactored [`PhysicalBlend`] with obstacles and pulls, solving one frame
//! at a time with the collision rounds of [`super::collide`]; [`blend_scene`] for one-off use.

use super::collide::{solve_frame, Candidates, CollisionOptions, CollisionStats, Contact};
use super::obstacle::Obstacle;
use super::pulls::{Pull, PullKind};
use super::SceneError;
use crate::mesh::{bbox_diagonal, Point, ShapeSet};
use crate::springs::interior::anchor::targets_in_frame;
use crate::springs::interior::{AnchorMotion, InteriorReport, SurfacePredictor};
use crate::springs::{
    AnchorOptions, AnchorPlacement, BlendOptions, BlendPredictor, FrameSolver, FrameStats,
    InteriorMode, InteriorOptions, PhysicalBlend, VolumetricBlend, Weights,
};

/// One blended frame of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFrame {
    /// Vertex positions, `#V` (the surface).
    pub positions: Vec<Point>,
    /// Interior then anchor vertex positions, world coordinates (empty without an interior or
    /// an anchor).
    pub extra: Vec<Point>,
    /// Solver statistics of the last equilibrium solve of the frame.
    pub solver: FrameStats,
    /// The vertices held on obstacles, by vertex id.
    pub contacts: Vec<Contact>,
    /// Collision rounds, penetration and timings.
    pub collision: CollisionStats,
}

/// Physical blendshapes interacting with a scene (Ma et al. 2012, Sec. 4): the springs, the
/// constraints and the symbolic analysis are built once; each [`solve`](Self::solve) is one
/// frame. Pulls and contacts only add diagonal blocks, so no frame needs a new analysis.
#[derive(Debug)]
pub struct SceneBlend {
    solver: PhysicalBlend,
    /// Surface vertices (the input's); the solver's interior and anchor vertices follow.
    surface_vertices: usize,
    /// The anchor's blended motion (solver frame → world), when anchored.
    motion: Option<AnchorMotion>,
    /// What the volumetric set-up built, when there is an interior or an anchor.
    interior: Option<InteriorReport>,
    obstacles: Vec<Obstacle>,
    pulls: Vec<Pull>,
    options: CollisionOptions,
    candidates: Candidates,
    tolerance: f64,
}

impl std::fmt::Debug for Candidates {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Candidates")
            .field("surface", &self.surface.len())
            .finish()
    }
}

impl SceneBlend {
    /// Builds the physical blend and checks the pulls against it: each pulled vertex must
    /// exist, must not be fixed, must lie on a component held by fixed vertices, and may be
    /// pulled once.
    pub fn new(
        shapes: &ShapeSet,
        blend: &BlendOptions,
        obstacles: Vec<Obstacle>,
        pulls: Vec<Pull>,
        options: &CollisionOptions,
    ) -> Result<Self, SceneError> {
        let none = (InteriorOptions::default(), AnchorOptions::default());
        Self::with_interior(shapes, blend, &none.0, &none.1, obstacles, pulls, options)
    }

    /// As [`new`](Self::new), on the [`VolumetricBlend`] with internal springs and an anchor
    /// (Ma et al. Sec. 3.1, 3.4) when `interior` or `anchor` asks for one. Only surface
    /// vertices can be pulled or become contacts; with an anchor the solve runs in the
    /// anchor's frame, and obstacles and pulls are mapped into it.
    pub fn with_interior(
        shapes: &ShapeSet,
        blend: &BlendOptions,
        interior: &InteriorOptions,
        anchor: &AnchorOptions,
        obstacles: Vec<Obstacle>,
        pulls: Vec<Pull>,
        options: &CollisionOptions,
    ) -> Result<Self, SceneError> {
        if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
            return Err(crate::springs::BlendError::InvalidOption(format!(
                "the collision tolerance must be finite and positive, got {}",
                options.tolerance
            ))
            .into());
        }
        let volumetric =
            interior.mode != InteriorMode::None || anchor.placement != AnchorPlacement::None;
        let (solver, motion, report) = if volumetric {
            let (s, m, r) = VolumetricBlend::new(shapes, blend, interior, anchor)?.into_parts();
            (s, m, Some(r))
        } else {
            (PhysicalBlend::new(shapes, blend)?, None, None)
        };
        let n = shapes.num_vertices();
        let constraints = solver.constraints();
        // Over the solver's vertices: the surface, then any interior and anchor vertices.
        let n_all = solver.shapes().num_vertices();
        let mut fixed = vec![false; n_all];
        for &v in &constraints.fixed {
            fixed[v as usize] = true;
        }
        let mut gauged = vec![false; n_all];
        let free = constraints.gauges.iter().map(|g| &g.vertices);
        for comp in free.chain(constraints.aligned.iter().map(|a| &a.vertices)) {
            for &v in comp {
                gauged[v as usize] = true;
            }
        }
        let mut pulled = vec![None; n];
        for (index, p) in pulls.iter().enumerate() {
            let v = p.vertex() as usize;
            let why = if v >= n {
                Some(format!(
                    "is out of range: the mesh has {n} vertices (ids are 0-based)"
                ))
            } else if constraints.bands.binary_search(&(v as u32)).is_ok() {
                Some("lies on a thin band, which follows the predictor (blend.thin_band_rings = 0 solves it as springs)".to_string())
            } else if fixed[v] {
                Some("is a fixed vertex; a pull cannot move it".to_string())
            } else if gauged[v] {
                Some("lies on a component with no fixed vertices: fix at least 3 non-collinear vertices of it so that it has a place in the world to be pulled against".to_string())
            } else {
                pulled[v]
                    .replace(index)
                    .map(|other| format!("is already pulled by pull {other}"))
            };
            if let Some(why) = why {
                return Err(SceneError::PullVertex {
                    index,
                    vertex: p.vertex(),
                    why,
                });
            }
        }
        let mut on_surface = vec![false; n];
        for t in shapes.triangles() {
            for &v in t {
                on_surface[v as usize] = true;
            }
        }
        let surface: Vec<u32> = (0..n as u32).filter(|&v| on_surface[v as usize]).collect();
        let movable = (0..n)
            .map(|v| {
                let hard_pull = pulled[v].is_some_and(|i| pulls[i].kind() == PullKind::Hard);
                on_surface[v] && !fixed[v] && !gauged[v] && !hard_pull
            })
            .collect();
        let tolerance = options.tolerance * bbox_diagonal(shapes.positions(0));
        Ok(Self {
            solver,
            surface_vertices: n,
            motion,
            interior: report,
            obstacles,
            pulls,
            options: options.clone(),
            candidates: Candidates { surface, movable },
            tolerance,
        })
    }

    /// The frame at frame number `frame` (it places the obstacles and the pulls) with
    /// `weights`. Frames do not depend on each other.
    pub fn solve(&mut self, frame: f64, weights: &Weights) -> Result<SceneFrame, SceneError> {
        let (ctx, solver) = self.split();
        ctx.solve(&mut solver.frame_solver(), frame, weights)
    }

    /// Frames `(frame number, weights)`, spread over up to `threads` threads (each with its own
    /// numeric workspace), in input order. Each equals [`solve`](Self::solve) of the same
    /// frame bit for bit, whatever the thread count: frames never share contacts or starts.
    pub fn solve_many(
        &mut self,
        frames: &[(f64, Weights)],
        threads: usize,
    ) -> Vec<Result<SceneFrame, SceneError>> {
        let (ctx, solver) = self.split();
        crate::springs::report_lost(
            solver.map_frames(frames, threads, |s, (f, w)| ctx.solve(s, *f, w)),
        )
    }

    /// The read-only part of the scene beside the solver, borrowed apart.
    fn split(&mut self) -> (FrameContext<'_>, &mut PhysicalBlend) {
        let shapes = self.solver.shapes().len();
        (
            FrameContext {
                shapes,
                surface_vertices: self.surface_vertices,
                motion: self.motion.as_ref(),
                obstacles: &self.obstacles,
                pulls: &self.pulls,
                options: &self.options,
                candidates: &self.candidates,
                tolerance: self.tolerance,
            },
            &mut self.solver,
        )
    }

    /// What the interior and anchor set-up built ([`with_interior`](Self::with_interior)).
    pub fn interior_report(&self) -> Option<&InteriorReport> {
        self.interior.as_ref()
    }

    /// The predictor of the underlying blend (no obstacles, no pulls): a preview for UIs. With
    /// an interior or an anchor it is that of the extended system, in the anchor's frame.
    pub fn predictor(&self) -> BlendPredictor {
        self.solver.predictor()
    }

    /// The predictor on the input surface in world coordinates (no obstacles, no pulls; with
    /// an interior or an anchor, the volumetric blend's, mapped out of the anchor's frame).
    pub fn surface_predictor(&self) -> SurfacePredictor {
        SurfacePredictor::new(
            self.solver.predictor(),
            self.motion.clone(),
            self.surface_vertices,
        )
    }

    /// The underlying physical blend.
    pub fn physical_blend(&mut self) -> &mut PhysicalBlend {
        &mut self.solver
    }
    /// The obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }
    /// The pulls.
    pub fn pulls(&self) -> &[Pull] {
        &self.pulls
    }
    /// The absolute penetration tolerance.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }
}

/// One-shot scene blend: builds a [`SceneBlend`] and solves frame `k` with `weights[k]`.
pub fn blend_scene(
    shapes: &ShapeSet,
    blend: &BlendOptions,
    obstacles: Vec<Obstacle>,
    pulls: Vec<Pull>,
    options: &CollisionOptions,
    weights: &[Weights],
) -> Result<Vec<SceneFrame>, SceneError> {
    let mut s = SceneBlend::new(shapes, blend, obstacles, pulls, options)?;
    weights
        .iter()
        .enumerate()
        .map(|(k, w)| s.solve(k as f64, w))
        .collect()
}

/// What one frame of a scene reads besides the solver.
struct FrameContext<'a> {
    shapes: usize,
    surface_vertices: usize,
    motion: Option<&'a AnchorMotion>,
    obstacles: &'a [Obstacle],
    pulls: &'a [Pull],
    options: &'a CollisionOptions,
    candidates: &'a Candidates,
    tolerance: f64,
}

impl FrameContext<'_> {
    /// One frame: pulls and obstacles placed at `frame`, mapped into the anchor's frame when
    /// anchored, the collision rounds, and the result back in the world.
    fn solve(
        &self,
        solver: &mut FrameSolver<'_>,
        frame: f64,
        weights: &Weights,
    ) -> Result<SceneFrame, SceneError> {
        let motion = match self.motion {
            Some(m) => Some(m.at(&weights.coefficients(self.shapes)?)),
            None => None,
        };
        let world = self.pulls.iter().map(|p| p.target_at(frame)).collect();
        let targets = targets_in_frame(motion.as_ref(), world);
        let placed: Vec<_> = self.obstacles.iter().map(|o| o.placed(frame)).collect();
        let (result, contacts, collision) = solve_frame(
            solver,
            weights,
            &targets,
            &placed,
            self.candidates,
            self.options,
            self.tolerance,
            motion.as_ref(),
        )?;
        let mut positions = result.positions;
        if let Some(m) = &motion {
            positions.iter_mut().for_each(|p| *p = m.apply(*p));
        }
        let extra = positions.split_off(self.surface_vertices);
        let mut solver_stats = result.stats;
        solver_stats
            .unconverged_vertices
            .retain(|&v| (v as usize) < self.surface_vertices);
        Ok(SceneFrame {
            positions,
            extra,
            solver: solver_stats,
            contacts,
            collision,
        })
    }
}
