//! Issue 38: the interactive mode (`PhysicalBlend::solve_interactive`, module
//! `springs::interactive`) on a generated rig. A tube is bent 90° by target A and bulged by
//! target B. Checked: one-hot and zero weights give the full solve's bits; between them the
//! interactive shape is closer to the full solve than the predictor and within its own error
//! estimate; a refinement step does not move it away; and the shape is a function of the
//! weights alone, whatever the preparation's thread count.

mod common;

use common::{assert_same_frame, max_dist};
use morphkit::mesh::{bbox_diagonal, generate, ShapeSet};
use morphkit::springs::{BlendError, BlendOptions, PhysicalBlend, Weights};

fn rig() -> ShapeSet {
    let m = generate::tube(0.5, 4.0, 12, 32, false);
    let a = generate::bend(&m.positions, 2.0, 2.0, 90f64.to_radians());
    let b = m
        .positions
        .iter()
        .map(|&[x, y, z]| {
            let s = 1.0 + 0.3 * (std::f64::consts::PI * x / 4.0).sin();
            [x, s * y, s * z]
        })
        .collect();
    let targets = vec![
        ("base".to_string(), m.positions.clone()),
        ("A".to_string(), a),
        ("B".to_string(), b),
    ];
    ShapeSet::new(m, targets).unwrap()
}

fn prepared(threads: usize) -> PhysicalBlend {
    let mut blend = PhysicalBlend::new(&rig(), &BlendOptions::default()).unwrap();
    let space = blend.prepare_interactive(threads);
    // 2 targets: one snapshot at every eighth each and 2 for the pair.
    assert_eq!(space.len() + space.unconverged, 16);
    assert_eq!(space.unconverged, 0);
    blend
}

#[test]
fn one_hot_and_zero_weights_are_the_full_solve() {
    let mut blend = prepared(1);
    for w in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] {
        let weights = Weights::Delta(w.to_vec());
        let full = blend.solve(&weights).unwrap();
        let fast = blend.solve_interactive(&weights, 0).unwrap();
        assert_same_frame(&fast.positions, &full.positions, &format!("{w:?}"));
        assert_eq!(fast.stats.error_estimate, Some(0.0), "{w:?}");
        assert_eq!(full.stats.error_estimate, None);
    }
}

#[test]
fn between_the_ends_it_is_closer_than_the_predictor_and_within_its_estimate() {
    let mut blend = prepared(2);
    let diag = bbox_diagonal(blend.shapes().positions(0));
    for w in [
        [0.3, 0.0],
        [0.6, 0.0],
        [0.0, 0.45],
        [0.4, 0.3],
        [0.7, 0.2],
        [0.9, 0.8],
        [0.5, 0.5],
        [0.25, 0.6],
    ] {
        let weights = Weights::Delta(w.to_vec());
        let full = blend.solve(&weights).unwrap();
        assert!(full.stats.converged);
        let predicted = blend.predict(&weights).unwrap();
        let fast = blend.solve_interactive(&weights, 0).unwrap();
        let error = max_dist(&fast.positions, &full.positions) / diag;
        let before = max_dist(&predicted, &full.positions) / diag;
        let estimate = fast.stats.error_estimate.expect("an estimate");
        assert!(
            error <= 0.5 * before,
            "{w:?}: interactive {error:.2e}, predictor {before:.2e}"
        );
        assert!(
            error <= estimate,
            "{w:?}: error {error:.2e} over its estimate {estimate:.2e}"
        );
        // Inside the snapshots' range (weights summing to at most 1) the space is close;
        // beyond it (0.9 + 0.8) only the estimate and the predictor bound it.
        if w[0] + w[1] <= 1.0 {
            assert!(error < 2e-3, "{w:?}: error {error:.2e}");
        }
        let refined = blend.solve_interactive(&weights, 1).unwrap();
        let closer = max_dist(&refined.positions, &full.positions) / diag;
        // (Below 1e-5 of the diagonal both are equilibria to the gradient tolerance, and
        // differ by its round-off: 1e-6 here.)
        assert!(
            closer <= error.max(1e-5),
            "{w:?}: refined {closer:.2e} > {error:.2e}"
        );
        // A refinement step factorizes, unless the shape already met the tolerance.
        assert!(
            refined.stats.factorizations >= 1 || refined.stats.converged,
            "{w:?}: {:?}",
            refined.stats
        );
    }
}

#[test]
fn the_shape_depends_on_the_weights_alone() {
    let mut one = prepared(1);
    let mut two = prepared(2);
    let order = [[0.4, 0.3], [0.2, 0.0], [0.4, 0.3]];
    let mut first = None;
    for w in order {
        let weights = Weights::Delta(w.to_vec());
        let a = one.solve_interactive(&weights, 0).unwrap();
        let b = two.solve_interactive(&weights, 0).unwrap();
        assert_same_frame(&a.positions, &b.positions, &format!("{w:?} over threads"));
        assert_eq!(a.stats.error_estimate, b.stats.error_estimate);
        if w == [0.4, 0.3] {
            match &first {
                None => first = Some(a.positions),
                Some(p) => assert_same_frame(&a.positions, p, "again after another frame"),
            }
        }
    }
}

#[test]
fn a_saved_preparation_gives_the_same_bits_and_is_refused_for_another_rig() {
    let mut fresh = prepared(1);
    let bytes = fresh.interactive_bytes().expect("prepared");
    let mut reopened = PhysicalBlend::new(&rig(), &BlendOptions::default()).unwrap();
    assert!(reopened.interactive_bytes().is_none());
    let space = reopened.load_interactive(&bytes).unwrap();
    assert_eq!(space.len(), 16);
    assert_eq!(reopened.interactive_bytes().unwrap(), bytes);
    for w in [[0.4, 0.3], [0.7, 0.0], [0.0, 0.2], [1.0, 0.0]] {
        let weights = Weights::Delta(w.to_vec());
        let a = fresh.solve_interactive(&weights, 0).unwrap();
        let b = reopened.solve_interactive(&weights, 0).unwrap();
        assert_same_frame(&a.positions, &b.positions, &format!("{w:?} loaded"));
        assert_eq!(a.stats.error_estimate, b.stats.error_estimate);
    }
    // The sampled start's fields came with the file: the reopened rig solved nothing, also
    // for the full solves of the weights it now moves through.
    assert_eq!(reopened.start_samples_solved(), 0);
    let full = reopened.solve(&Weights::Delta(vec![0.4, 0.3])).unwrap();
    assert_eq!(reopened.start_samples_solved(), 0);
    let fresh_full = fresh.solve(&Weights::Delta(vec![0.4, 0.3])).unwrap();
    assert_same_frame(&full.positions, &fresh_full.positions, "full solve, loaded");
    // Damaged, truncated or foreign bytes are refused, and leave the blend unprepared.
    let mut other = PhysicalBlend::new(&rig(), &BlendOptions::default()).unwrap();
    for (what, bad) in [
        ("truncated", bytes[..bytes.len() - 5].to_vec()),
        ("empty", Vec::new()),
        ("not ours", b"MKINTER9".repeat(8)),
        ("trailing", [bytes.clone(), vec![0; 8]].concat()),
        ("bad field tag", {
            // The last target's last field tag sits 8 (3 #V + 1) bytes before the 8-byte
            // checksum (which refuses it first).
            let mut b = bytes.clone();
            let at = b.len() - 8 - 8 * (3 * rig().num_vertices() + 1);
            b[at..at + 8].copy_from_slice(&7u64.to_le_bytes());
            b
        }),
    ] {
        let e = other.load_interactive(&bad).unwrap_err();
        assert!(
            matches!(e, BlendError::InteractiveCache { .. }),
            "{what}: {e}"
        );
        assert!(other.interactive_space().is_none(), "{what}");
    }
    let stiffer = BlendOptions {
        fold_guard: 2.0,
        ..BlendOptions::default()
    };
    let mut changed = PhysicalBlend::new(&rig(), &stiffer).unwrap();
    let e = changed.load_interactive(&bytes).unwrap_err();
    assert!(e.to_string().contains("another rig"), "{e}");
    let original = rig();
    let mut shapes: Vec<(String, Vec<_>)> = (0..original.len())
        .map(|s| (format!("s{s}"), original.positions(s).to_vec()))
        .collect();
    shapes[2].1[7][0] += 1e-9;
    let moved = ShapeSet::new(original.base().clone(), shapes).unwrap();
    let mut other_target = PhysicalBlend::new(&moved, &BlendOptions::default()).unwrap();
    assert!(other_target.load_interactive(&bytes).is_err());
}

#[test]
fn with_the_aggregation_cycle_interactive_frames_leave_full_solves_unchanged() {
    // The cycle's workspace lends the projected Hessian's values to the interactive mode and
    // has no factor for its refinement: neither may change a later full solve's bits.
    let options = BlendOptions {
        preconditioner: morphkit::springs::Preconditioner::Aggregation,
        ..Default::default()
    };
    let weights = Weights::Delta(vec![0.4, 0.3]);
    let mut fresh = PhysicalBlend::new(&rig(), &options).unwrap();
    assert!(fresh.summary().aggregates > 0);
    let full = fresh.solve(&weights).unwrap();
    assert!(full.stats.converged, "{:?}", full.stats);
    let mut used = PhysicalBlend::new(&rig(), &options).unwrap();
    let space = used.prepare_interactive(1);
    assert_eq!(space.unconverged, 0);
    for refine in [0, 1] {
        let fast = used.solve_interactive(&weights, refine).unwrap();
        let diag = bbox_diagonal(used.shapes().positions(0));
        let d = max_dist(&fast.positions, &full.positions) / diag;
        let estimate = fast.stats.error_estimate.unwrap();
        assert!(
            d.is_finite() && d <= estimate.max(1e-3),
            "refine {refine}: {d} vs {estimate}"
        );
    }
    let again = used.solve(&weights).unwrap();
    assert_same_frame(
        &again.positions,
        &full.positions,
        "after interactive frames",
    );
}

/// The tube of [`rig`] with a third target: the tube's far half twisted 60° about its axis.
fn rig3() -> ShapeSet {
    let two = rig();
    let twisted = two
        .positions(0)
        .iter()
        .map(|&[x, y, z]| {
            let a = 60f64.to_radians() * ((x - 2.0) / 2.0).clamp(0.0, 1.0);
            [x, a.cos() * y - a.sin() * z, a.sin() * y + a.cos() * z]
        })
        .collect();
    let mut shapes: Vec<(String, Vec<_>)> = (0..two.len())
        .map(|s| (format!("s{s}"), two.positions(s).to_vec()))
        .collect();
    shapes.push(("C".to_string(), twisted));
    ShapeSet::new(two.base().clone(), shapes).unwrap()
}

#[test]
fn with_three_targets_the_estimate_counts_the_pairs_held_apart_and_bounds_the_error() {
    let mut blend = PhysicalBlend::new(&rig3(), &BlendOptions::default()).unwrap();
    let space = blend.prepare_interactive(2);
    // 3 targets: 7 each, 2 per pair.
    assert_eq!(space.len(), 27);
    let diag = bbox_diagonal(blend.shapes().positions(0));
    let bytes = blend.interactive_bytes().unwrap();
    let mut reopened = PhysicalBlend::new(&rig3(), &BlendOptions::default()).unwrap();
    reopened.load_interactive(&bytes).unwrap();
    for w in [
        [0.4, 0.3, 0.3],
        [0.6, 0.5, 0.4],
        [0.2, 0.7, 0.5],
        [0.8, 0.8, 0.8],
    ] {
        let weights = Weights::Delta(w.to_vec());
        let full = blend.solve(&weights).unwrap();
        assert!(full.stats.converged, "{w:?}");
        let fast = blend.solve_interactive(&weights, 0).unwrap();
        let error = max_dist(&fast.positions, &full.positions) / diag;
        let estimate = fast.stats.error_estimate.expect("an estimate");
        assert!(
            error <= estimate,
            "{w:?}: error {error:.2e} over its estimate {estimate:.2e}"
        );
        // The estimate's data came with the saved preparation.
        let again = reopened.solve_interactive(&weights, 0).unwrap();
        assert_eq!(
            again.stats.error_estimate, fast.stats.error_estimate,
            "{w:?}"
        );
        assert_same_frame(&again.positions, &fast.positions, &format!("{w:?} loaded"));
    }
}
