//! Issue 54 on the real ICT head, welded as every user-facing path welds it: eyeBlink_R swept
//! across 0.59 in steps of 0.005. Until the weld kept touching shells apart, the welded rig's
//! full solve jumped there by 0.91 % of the diagonal (48× the linear step, 55 Newton
//! iterations); now every step stays within the continuity bound and every frame takes at most
//! three Newton iterations, as on the unwelded rig.

mod common;

use morphkit::io::read_shape_set;
use morphkit::mesh::{bbox_diagonal, Weld, WELD_TOLERANCE};
use morphkit::springs::{linear_blend, BlendOptions, ContinuityCheck, PhysicalBlend, Weights};

#[test]
fn welded_ict_eye_blink_moves_continuously_across_0_59() {
    let Some(paths) = common::ict_rig_paths() else {
        return common::skip("welded_ict_eye_blink_moves_continuously_across_0_59");
    };
    let shapes = read_shape_set(&paths).unwrap();
    let weld = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let welded = weld.shapes(&shapes).unwrap();
    let mut solver = PhysicalBlend::new(&welded, &BlendOptions::default()).unwrap();
    let blink = common::ICT_EXPRESSIONS
        .iter()
        .position(|&e| e == "eyeBlink_R")
        .unwrap();
    let mut check = ContinuityCheck::new(4.0, bbox_diagonal(welded.positions(0)));
    for k in 0..=8 {
        let mut w = vec![0.0; common::ICT_EXPRESSIONS.len()];
        w[blink] = 0.57 + 0.005 * k as f64;
        let w = Weights::Delta(w);
        let r = solver.solve(&w).unwrap();
        assert!(r.stats.converged, "eyeBlink_R at {w:?}");
        assert!(
            r.stats.newton_iterations <= 3,
            "eyeBlink_R at {w:?}: {} Newton iterations",
            r.stats.newton_iterations
        );
        check
            .push(&r.positions, &linear_blend(&welded, &w).unwrap())
            .unwrap();
    }
    let c = check.finish();
    eprintln!(
        "welded eyeBlink_R 0.57..0.61: worst step {:.2}×",
        c.worst_ratio
    );
    assert!(c.jumps.is_empty(), "jumps: {:?}", c.jumps);
}
