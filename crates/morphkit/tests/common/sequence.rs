//! Issue 7's whole-sequence properties of a physical blend, frame by frame: every frame
//! converged, no vertex steps more than [`STEP_BOUND`] × the linear blend's largest step
//! from the previous frame, no more folded triangles than the linear blend, and no vertex
//! farther from the linear blend than half the largest move between the shapes.

use morphkit::mesh::{bbox_diagonal, Topology};
use morphkit::springs::{
    fold_metrics, linear_blend, BlendResult, Continuity, ContinuityCheck, PhysicalBlend, Weights,
    JUMP_BOUND,
};

/// Consecutive frames may move a vertex by at most this multiple of the linear blend's step
/// (the library's bound; its justification is in [`morphkit::springs::continuity`]).
pub const STEP_BOUND: f64 = JUMP_BOUND;

/// What [`check_sequence`] found.
#[derive(Debug, Default)]
pub struct SequenceReport {
    /// Largest vertex step between consecutive frames / the linear blend's largest step.
    pub worst_step: f64,
    /// Largest count of folded triangles over the linear blend's, over the frames.
    pub worst_fold_excess: i64,
    /// Largest distance from the linear blend / the largest move between the shapes.
    pub worst_from_linear: f64,
    /// Newton iterations over all frames.
    pub newton: usize,
    /// One line per frame that breaks a property.
    pub failures: Vec<String>,
    /// The frames, in order.
    pub frames: Vec<BlendResult>,
    /// The jumps between consecutive frames.
    pub continuity: Option<Continuity>,
}

/// Delta weights `α e_target` over `targets` targets, α = k / (steps − 1).
pub fn ramp(targets: usize, target: usize, steps: usize) -> Vec<Weights> {
    (0..steps)
        .map(|k| {
            let mut w = vec![0.0; targets];
            w[target] = k as f64 / (steps - 1) as f64;
            Weights::Delta(w)
        })
        .collect()
}

/// Solves the sequence `ramp(targets, target, steps)` (on two threads) and checks every
/// frame.
pub fn check_sequence(
    name: &str,
    solver: &mut PhysicalBlend,
    targets: usize,
    target: usize,
    steps: usize,
) -> SequenceReport {
    check_sequence_allowing(name, solver, targets, target, steps, 0)
}

/// [`check_sequence`], with frames allowed `fold_excess` more folded triangles than the
/// linear blend (a known, documented case; every other property as strict).
pub fn check_sequence_allowing(
    name: &str,
    solver: &mut PhysicalBlend,
    targets: usize,
    target: usize,
    steps: usize,
    fold_excess: usize,
) -> SequenceReport {
    let s = solver.shapes().clone();
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let weights = ramp(targets, target, steps);
    let frames: Vec<BlendResult> = solver
        .solve_many(&weights, 2)
        .into_iter()
        .map(|r| r.expect("solve"))
        .collect();
    let mut rep = SequenceReport::default();
    let mut steps = ContinuityCheck::new(STEP_BOUND, bbox_diagonal(s.positions(0)));
    for (k, r) in frames.iter().enumerate() {
        rep.newton += r.stats.newton_iterations;
        let q = fold_metrics(&s, &topo, &weights[k], &r.positions).unwrap();
        let far = q.max_from_linear / q.largest_move.max(f64::MIN_POSITIVE);
        steps
            .push(&r.positions, &linear_blend(&s, &weights[k]).unwrap())
            .unwrap();
        rep.worst_from_linear = rep.worst_from_linear.max(far);
        rep.worst_fold_excess = rep
            .worst_fold_excess
            .max(q.folds as i64 - q.folds_linear as i64);
        let finite = r.positions.iter().flatten().all(|c| c.is_finite());
        if !r.stats.converged || !finite || q.folds > q.folds_linear + fold_excess || far > 0.5 {
            rep.failures.push(format!(
                "{name} frame {k}: converged {} ({} Newton), finite {finite}, folds {} vs {} linear, from linear {far:.3} of the largest move",
                r.stats.converged, r.stats.newton_iterations, q.folds, q.folds_linear
            ));
        }
    }
    let continuity = steps.finish();
    rep.worst_step = continuity.worst_ratio;
    for j in &continuity.jumps {
        rep.failures.push(format!(
            "{name} frames {}→{}: step {:.2}× linear (vertex {}, {} vertices over the bound)",
            j.frames[0],
            j.frames[1],
            j.ratio,
            j.vertex,
            j.vertices.len()
        ));
    }
    rep.continuity = Some(continuity);
    rep.frames = frames;
    rep
}
