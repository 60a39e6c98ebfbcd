//! Issue 7's whole-sequence properties on every real rig under `MORPHKIT_DATA` (skipped when
//! unset, failing when set but a file is missing): each horse pose and each ICT expression
//! blended from the base over 36 steps, every frame checked by
//! `common::sequence::check_sequence` (converged, finite, no more folded triangles than the
//! linear blend, steps within `STEP_BOUND` × the linear blend's, no vertex farther from the
//! linear blend than half the largest move).
//!
//! Known failures, measured and reported in the README ("A known failure of issue 7's
//! properties"), are listed in [`KNOWN`]: on them only convergence, finiteness and the fold
//! count are asserted, and the test fails when one of them starts to pass, so that the list
//! is kept true.

mod common;

use common::sequence::{check_sequence, SequenceReport};
use morphkit::io::read_shape_set;
use morphkit::springs::{BlendOptions, PhysicalBlend};

/// Sequences that break the step bound with the default options: three horse legs snap
/// between two equilibria (a lower hind leg turns by a tenth of the body in one step,
/// 4.6–6.8× the linear step), and ICT jawOpen's lower gums, turning about a line of static
/// and kinematic vertices, swing through 4.1× the linear step (25× with Ma's bending
/// springs, which are off by default). horse-07, which used to end 0.51 of the largest move
/// from the linear blend because its seven kinematic vertices pinned the rearing body in the
/// world, passes since such a component is aligned as a whole.
const KNOWN: [&str; 4] = ["horse-02", "horse-04", "horse-06", "jawOpen"];

/// The part that jumps in each known jumping sequence, as the continuity check reports it:
/// `(name, lowest and highest vertex id allowed, most vertices)`. The horse legs are about
/// 500 vertices of the 8 431; the ICT jawOpen part lies in the 2 977-vertex gums and tongue
/// component (vertices 14 062–17 038).
const JUMPING: [(&str, u32, u32, usize); 4] = [
    ("horse-02", 0, 8430, 1000),
    ("horse-04", 0, 8430, 1000),
    ("horse-06", 0, 8430, 1000),
    ("jawOpen", 14062, 17038, 2977),
];

fn assert_holds(name: &str, rep: &SequenceReport) {
    let continuity = rep.continuity.as_ref().expect("checked");
    let region = continuity.jump_vertices();
    match JUMPING.iter().find(|j| j.0 == name) {
        Some(&(_, lo, hi, most)) => {
            assert!(!region.is_empty(), "{name}: the known jump is not found");
            assert!(
                region.len() <= most,
                "{name}: {} vertices jump",
                region.len()
            );
            assert!(
                region.iter().all(|&v| (lo..=hi).contains(&v)),
                "{name}: jump region outside {lo}..={hi}: {:?}",
                &region[..region.len().min(20)]
            );
        }
        None => assert!(region.is_empty(), "{name}: {:?}", continuity.jumps),
    }

    eprintln!(
        "{name}: worst step {:.2}× linear, fold excess {}, from linear {:.3}, {} Newton",
        rep.worst_step, rep.worst_fold_excess, rep.worst_from_linear, rep.newton
    );
    if KNOWN.contains(&name) {
        for (k, f) in rep.frames.iter().enumerate() {
            assert!(f.stats.converged, "{name} frame {k} did not converge");
            assert!(f.positions.iter().flatten().all(|c| c.is_finite()));
        }
        assert!(rep.worst_fold_excess <= 0, "{name}: {:#?}", rep.failures);
        assert!(
            !rep.failures.is_empty(),
            "{name} now passes: take it off the known failures"
        );
    } else {
        assert!(rep.failures.is_empty(), "{:#?}", rep.failures);
    }
}

#[test]
fn horse_pose_sequences() {
    for pose in 1..=10 {
        let name = format!("horse-{pose:02}");
        let paths: Option<Vec<_>> = ["horse-reference", name.as_str()]
            .iter()
            .map(|n| common::data_file(&format!("sumner-horse-camel/{n}.obj.gz")))
            .collect();
        let Some(paths) = paths else {
            return common::skip("horse_pose_sequences");
        };
        let s = read_shape_set(&paths).unwrap();
        let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
        assert_holds(&name, &check_sequence(&name, &mut solver, 1, 0, 36));
    }
}

#[test]
fn ict_expression_sequences() {
    let Some(paths) = common::ict_rig_paths() else {
        return common::skip("ict_expression_sequences");
    };
    let s = read_shape_set(&paths).unwrap();
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    // Bands: two eye-occlusion strips (152 vertices each), two tear films (204) and twelve
    // eyelash cards (114); the two 24-vertex eye pieces are bands too but move in no
    // expression, so they are fixed instead.
    assert_eq!(solver.summary().band_vertices, 2 * 152 + 2 * 204 + 12 * 114);
    let ict = common::ICT_EXPRESSIONS;
    for (k, e) in ict.iter().enumerate() {
        assert_holds(e, &check_sequence(e, &mut solver, ict.len(), k, 36));
    }
}
