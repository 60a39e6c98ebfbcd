//! Collision handling during the blend (Ma et al. 2012, Sec. 4; math notes §1 "Physical
//! interaction"): after each equilibrium, surface vertices inside an obstacle are moved to its
//! surface and held there as boundary conditions, and the equilibrium is solved again.
//!
//! One frame, with weights $w$, pull targets $P$ and obstacles $O_k$ placed at the frame:
//! 1. round 0: $x^0$ = the equilibrium with the pulls, from the canonical predictor (so a frame
//!    with no pulls and no penetration is bit-for-bit the plain blend);
//! 2. detection: every candidate vertex $v$ (surface, free, not hard-pulled, on a component
//!    held by fixed vertices) inside some $O_k$ is projected to its closest surface point
//!    $q_v$ (the deepest obstacle wins); parry's BVH (mesh obstacles) or exact primitive
//!    projections answer, after a bounding-box rejection;
//! 3. if the largest penetration depth over **all** surface vertices is at most the tolerance
//!    (`tolerance` × the base's bounding-box diagonal), or `max_rounds` re-solves were done, or
//!    no new vertex can be held, stop; otherwise every newly penetrating candidate becomes a
//!    hard [`PointTarget`] at $q_v$ (contacts of earlier rounds of the same frame stay), and
//!    round $r + 1$ solves again from $x^r$ with every contact placed at its $q_v$ and held
//!    there exactly (a boundary condition, not a penalty; see [`PointTarget::is_hard`]).
//!    On the 18k-vertex benchmark (`morphkit bench --suite scene`) that round takes 6 Newton
//!    steps and 24 inner CG iterations; the stiff penalty used before took 7 and 96 (its
//!    residuals were dominated by the penalty's stiffness), and one penalized Newton step
//!    before holding (a smooth first displacement of each contact's neighbourhood) took 7.
//!
//! Contacts are found afresh for every frame and never carried over from another frame, so a
//! frame remains a function of its weights, its pulls and its obstacle poses alone (frame order
//! and scrubbing change nothing). The contacts are frictionless in the paper's sense: a contact
//! vertex is pinned where it first touched during the frame's rounds. Timings are measured and
//! reported only; no decision depends on them.

use super::obstacle::Placed;
use crate::geom::RigidTransform;
use crate::mesh::Point;
use crate::springs::interior::anchor::apply_inverse;
use crate::springs::{BlendError, BlendResult, FrameSolver, PointTarget, Weights};
use std::collections::BTreeMap;
use std::time::Instant;

/// Options of collision handling. Every field has a meaningful default.
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionOptions {
    /// Largest penetration accepted, relative to the base's bounding-box diagonal. Default
    /// `1e-4`.
    pub tolerance: f64,
    /// Re-solves allowed per frame after the first equilibrium. Default `10`.
    pub max_rounds: usize,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-4,
            max_rounds: 10,
        }
    }
}

/// A vertex held on an obstacle's surface.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Contact {
    /// The vertex.
    pub vertex: u32,
    /// Index of the obstacle.
    pub obstacle: usize,
    /// The surface point it is held at.
    pub position: Point,
    /// How deep it was when it was found.
    pub depth: f64,
}

/// What collision handling did in one frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CollisionStats {
    /// Vertices held on obstacle surfaces at the end.
    pub contacts: usize,
    /// Re-solves after the first equilibrium.
    pub rounds: usize,
    /// Largest remaining penetration depth of a surface vertex (absolute units).
    pub max_penetration: f64,
    /// The tolerance it is compared with (absolute units).
    pub tolerance: f64,
    /// Surface vertices still deeper than the tolerance.
    pub penetrating_vertices: usize,
    /// Whether nothing penetrates by more than the tolerance.
    pub resolved: bool,
    /// Newton iterations over all rounds.
    pub newton_iterations: usize,
    /// Wall time in collision detection (reported only).
    pub detection_seconds: f64,
    /// Wall time in the equilibrium solves (reported only).
    pub solve_seconds: f64,
}

/// One penetrating vertex.
#[derive(Clone, Copy, Debug)]
struct Hit {
    obstacle: usize,
    surface: Point,
    depth: f64,
}

/// The deepest obstacle that contains each vertex of `vertices` (absent: outside all).
fn detect(placed: &[Placed<'_>], vertices: &[u32], x: &[Point]) -> Vec<(u32, Hit)> {
    let mut out = Vec::new();
    for &v in vertices {
        let mut best: Option<Hit> = None;
        for (k, o) in placed.iter().enumerate() {
            if let Some((surface, depth)) = o.penetration(x[v as usize]) {
                if best.is_none_or(|b| depth > b.depth) {
                    best = Some(Hit {
                        obstacle: k,
                        surface,
                        depth,
                    });
                }
            }
        }
        if let Some(h) = best {
            out.push((v, h));
        }
    }
    out
}

/// The vertex sets collision handling looks at.
pub(crate) struct Candidates {
    /// Vertices of some triangle: their penetration is measured.
    pub surface: Vec<u32>,
    /// Surface vertices that may become contacts (free, not hard-pulled, held component).
    pub movable: Vec<bool>,
}

/// Solves one frame with pulls `pulls` and the obstacles `placed`; see the [module docs](self).
/// `frame` maps the solver's coordinates to the world (an anchored blend solves in the
/// anchor's frame): `pulls` and the returned positions are in solver coordinates, obstacles
/// and contacts in the world.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_frame(
    solver: &mut FrameSolver<'_>,
    weights: &Weights,
    pulls: &[PointTarget],
    placed: &[Placed<'_>],
    candidates: &Candidates,
    options: &CollisionOptions,
    tolerance: f64,
    frame: Option<&RigidTransform>,
) -> Result<(BlendResult, Vec<Contact>, CollisionStats), BlendError> {
    let mut stats = CollisionStats {
        tolerance,
        ..Default::default()
    };
    let t = Instant::now();
    let mut result = solver.solve_with(weights, pulls, None)?;
    stats.solve_seconds += t.elapsed().as_secs_f64();
    stats.newton_iterations += result.stats.newton_iterations;
    let mut contacts: BTreeMap<u32, Contact> = BTreeMap::new();
    let mut targets = pulls.to_vec();
    loop {
        let t = Instant::now();
        let hits = match (placed.is_empty(), frame) {
            (true, _) => Vec::new(),
            (false, None) => detect(placed, &candidates.surface, &result.positions),
            (false, Some(t)) => {
                let world: Vec<Point> = result.positions.iter().map(|&p| t.apply(p)).collect();
                detect(placed, &candidates.surface, &world)
            }
        };
        stats.detection_seconds += t.elapsed().as_secs_f64();
        stats.max_penetration = hits.iter().map(|(_, h)| h.depth).fold(0.0, f64::max);
        stats.penetrating_vertices = hits.iter().filter(|(_, h)| h.depth > tolerance).count();
        if stats.max_penetration <= tolerance || stats.rounds >= options.max_rounds {
            break;
        }
        let mut added = 0;
        for (v, h) in hits {
            if !candidates.movable[v as usize] || contacts.contains_key(&v) {
                continue;
            }
            contacts.insert(
                v,
                Contact {
                    vertex: v,
                    obstacle: h.obstacle,
                    position: h.surface,
                    depth: h.depth,
                },
            );
            let held = frame.map_or(h.surface, |t| apply_inverse(t, h.surface));
            targets.push(PointTarget::hard(v, held));
            added += 1;
        }
        if added == 0 {
            break; // what still penetrates cannot be held (fixed, pulled or already held)
        }
        stats.rounds += 1;
        let t = Instant::now();
        result = solver.solve_with(weights, &targets, Some(&result.positions))?;
        stats.solve_seconds += t.elapsed().as_secs_f64();
        stats.newton_iterations += result.stats.newton_iterations;
    }
    stats.contacts = contacts.len();
    stats.resolved = stats.max_penetration <= tolerance;
    Ok((result, contacts.into_values().collect(), stats))
}
