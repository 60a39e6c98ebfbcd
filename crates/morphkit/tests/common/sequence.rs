//! Issue 7's whole-sequence properties of a physical blend, frame by frame: every frame
//! converged, no vertex steps more than [`STEP_BOUND`] × the linear blend's largest step
//! from the previous frame, no more folded triangles than the linear blend, and no vertex
//! farther from the linear blend than half the largest move between the shapes.

use morphkit::mesh::{Point, Topology};
use morphkit::springs::{fold_metrics, BlendResult, PhysicalBlend, Weights};

/// Consecutive frames may move a vertex by at most this multiple of the linear blend's largest
/// per-step move (as `springs_canonical::sequences_are_continuous_without_flying_parts`): a
/// vertex carried along an arc of angle θ ≤ π travels at most θ / (2 sin θ/2) ≤ π/2 times its
/// chord, and the equilibrium may move up to twice as fast in α as uniformly (rest lengths are
/// linear in α, positions are not): 2 · π/2 ≈ 3.1 < 4. A snap-through to another basin moves
/// a part by many steps at once (12.8× on the crumpling eye strip of ICT eyeBlink_L before thin
/// bands followed the predictor; 5.8–8.8× on three horse legs with the hinge weight at 0.01).
pub const STEP_BOUND: f64 = 4.0;

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
}

/// The largest vertex distance between two frames, and the vertex where it is.
pub fn max_step(a: &[Point], b: &[Point]) -> (f64, usize) {
    let d = |p: Point, q: Point| {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    a.iter()
        .zip(b)
        .enumerate()
        .map(|(v, (p, q))| (d(*p, *q), v))
        .fold((0.0, 0), |m, x| if x.0 > m.0 { x } else { m })
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
    let s = solver.shapes().clone();
    let topo = Topology::new(s.num_vertices(), s.triangles());
    let weights = ramp(targets, target, steps);
    let frames: Vec<BlendResult> = solver
        .solve_many(&weights, 2)
        .into_iter()
        .map(|r| r.expect("solve"))
        .collect();
    let linear_step = max_step(s.positions(0), s.positions(target + 1)).0 / (steps - 1) as f64;
    let mut rep = SequenceReport::default();
    for (k, r) in frames.iter().enumerate() {
        rep.newton += r.stats.newton_iterations;
        let q = fold_metrics(&s, &topo, &weights[k], &r.positions).unwrap();
        let far = q.max_from_linear / q.largest_move.max(f64::MIN_POSITIVE);
        let (step, at) = match k {
            0 => (0.0, 0),
            _ => max_step(&r.positions, &frames[k - 1].positions),
        };
        let ratio = step / linear_step;
        rep.worst_step = rep.worst_step.max(ratio);
        rep.worst_from_linear = rep.worst_from_linear.max(far);
        rep.worst_fold_excess = rep
            .worst_fold_excess
            .max(q.folds as i64 - q.folds_linear as i64);
        let finite = r.positions.iter().flatten().all(|c| c.is_finite());
        if !r.stats.converged
            || !finite
            || ratio > STEP_BOUND
            || q.folds > q.folds_linear
            || far > 0.5
        {
            rep.failures.push(format!(
                "{name} frame {k}: converged {} ({} Newton), finite {finite}, step {ratio:.2}× linear (vertex {at}), folds {} vs {} linear, from linear {far:.3} of the largest move",
                r.stats.converged, r.stats.newton_iterations, q.folds, q.folds_linear
            ));
        }
    }
    rep.frames = frames;
    rep
}
