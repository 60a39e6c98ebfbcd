//! Issue 40: a frame is a function of its nonzero weights, and stays continuous as a weight
//! leaves 0 (`BlendOptions::hold_ramp`, module `springs::holds`). A tube bent by target A is
//! blended alone and in a rig that also has B, a bulge where A moves nothing (so A alone
//! leaves those vertices fixed), and C, which stretches one band of triangles twelvefold
//! (kinematic) and carries the rest along: with B and C at weight 0 the frames are the same
//! shape, and a weight of 1e-6 on B or C moves no vertex by more than 1e-6 of the diagonal.

mod common;

use common::max_dist;
use morphkit::mesh::{bbox_diagonal, generate, Point, ShapeSet};
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};

const AROUND: usize = 16;
const ALONG: usize = 40;

/// The straight tube (x ∈ [0, 4]), A, B and C.
fn shapes() -> (morphkit::mesh::TriMesh, [Vec<Point>; 3]) {
    let m = generate::tube(0.5, 4.0, AROUND, ALONG, false);
    let a = generate::bend(&m.positions, 2.0, 2.0, 90f64.to_radians());
    let b = m
        .positions
        .iter()
        .map(|&[x, y, z]| {
            let s = if (0.5..=1.5).contains(&x) {
                1.0 + 0.3 * (std::f64::consts::PI * (x - 0.5)).sin()
            } else {
                1.0
            };
            [x, s * y, s * z]
        })
        .collect();
    // Rings past x = 0.55 move 1.1 along the axis: the band between x = 0.5 and 0.6
    // stretches from 0.1 to 1.2.
    let c = m
        .positions
        .iter()
        .map(|&[x, y, z]| [if x > 0.55 { x + 1.1 } else { x }, y, z])
        .collect();
    (m, [a, b, c])
}

fn rig(m: &morphkit::mesh::TriMesh, targets: &[(&str, &Vec<Point>)]) -> ShapeSet {
    let mut all = vec![("straight".to_string(), m.positions.clone())];
    all.extend(targets.iter().map(|(n, p)| (n.to_string(), (*p).clone())));
    ShapeSet::new(m.clone(), all).unwrap()
}

#[test]
fn unused_targets_change_no_frame_and_a_weight_leaves_zero_continuously() {
    let (m, [a, b, c]) = shapes();
    let d = bbox_diagonal(&m.positions);
    let small = rig(&m, &[("a", &a)]);
    let big = rig(&m, &[("a", &a), ("b", &b), ("c", &c)]);
    let o = BlendOptions::default();
    let mut alone = PhysicalBlend::new(&small, &o).unwrap();
    let mut all = PhysicalBlend::new(&big, &o).unwrap();
    // The rig-wide rules would free the vertices B moves and hold C's band: both differ.
    assert!(all.summary().fixed_vertices < alone.summary().fixed_vertices);
    assert!(all.summary().kinematic_vertices > 0);
    for alpha in [0.3, 0.6] {
        let r0 = alone.solve(&Weights::Delta(vec![alpha])).unwrap();
        let r1 = all.solve(&Weights::Delta(vec![alpha, 0.0, 0.0])).unwrap();
        assert!(r0.stats.converged && r1.stats.converged);
        let gap = max_dist(&r0.positions, &r1.positions);
        assert!(
            gap <= 1e-9 * d,
            "A at {alpha}: {:e} of the diagonal apart",
            gap / d
        );
        for (k, name) in [(1, "B"), (2, "C")] {
            let mut w = vec![alpha, 0.0, 0.0];
            w[k] = 1e-6;
            let r = all.solve(&Weights::Delta(w.clone())).unwrap();
            assert!(r.stats.converged, "{name} at 1e-6");
            let step = max_dist(&r.positions, &r1.positions);
            assert!(
                step <= 1e-6 * d,
                "A at {alpha}, {name} at 1e-6: {:e} of the diagonal from {name} at 0",
                step / d
            );
            // Past the ramp the weight acts as a weight: B bulges, C stretches.
            w[k] = 0.2;
            let r = all.solve(&Weights::Delta(w)).unwrap();
            assert!(r.stats.converged, "{name} at 0.2");
            assert!(
                max_dist(&r.positions, &r1.positions) > 2e-3 * d,
                "{name} at 0.2"
            );
        }
    }
}

#[test]
fn frames_through_the_ramp_move_in_small_steps() {
    let (m, [a, b, c]) = shapes();
    let d = bbox_diagonal(&m.positions);
    let big = rig(&m, &[("a", &a), ("b", &b), ("c", &c)]);
    let mut all = PhysicalBlend::new(&big, &BlendOptions::default()).unwrap();
    for k in [1, 2] {
        // B or C from 0 through the ramp (0.05) in steps of 1/400: no step is a jump.
        let frames: Vec<Vec<Point>> = (0..=40)
            .map(|i| {
                let mut w = vec![0.5, 0.0, 0.0];
                w[k] = i as f64 / 400.0;
                let r = all.solve(&Weights::Delta(w)).unwrap();
                assert!(r.stats.converged);
                r.positions
            })
            .collect();
        let steps: Vec<f64> = frames.windows(2).map(|f| max_dist(&f[0], &f[1])).collect();
        let total = max_dist(&frames[0], &frames[40]);
        let worst = steps.iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "target {k}: total {:e}, worst step {:e} (of the diagonal)",
            total / d,
            worst / d
        );
        assert!(
            worst <= 0.2 * total.max(1e-9 * d),
            "target {k}: a step of {worst:e} in {total:e}"
        );
    }
}
