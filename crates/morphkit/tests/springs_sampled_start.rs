//! The sampled start (`BlendOptions::sampled_start`): frames start from the predictor
//! corrected by each target's equilibria at ¼, ½, ¾, and where targets combine, by each pair's
//! equilibrium at (½, ½). It must reach the equilibrium the plain predictor reaches (within
//! the tolerance), with fewer iterations, and stay a function of the weights alone: samples
//! computed lazily by one solve or in parallel by `solve_many` give the same bits.

mod common;

use morphkit::mesh::{bbox_diagonal, generate, Point, ShapeSet};
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};

use common::max_dist;

fn options(sampled_start: bool) -> BlendOptions {
    BlendOptions {
        sampled_start,
        ..Default::default()
    }
}

/// A free (gauged) bar bent by 150° over its second half, and twisted by 90° as a second
/// target.
fn bar_rig() -> ShapeSet {
    let m = generate::bar(4.0, 0.6, 2, 24);
    let bent = generate::bend(&m.positions, 2.0, 2.0, 150f64.to_radians());
    let twisted: Vec<Point> = m
        .positions
        .iter()
        .map(|p| {
            let t = (p[0] / 4.0).clamp(0.0, 1.0) * std::f64::consts::FRAC_PI_2;
            let (s, c) = t.sin_cos();
            [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]]
        })
        .collect();
    ShapeSet::new(
        m.clone(),
        vec![
            ("straight".into(), m.positions.clone()),
            ("bent".into(), bent),
            ("twisted".into(), twisted),
        ],
    )
    .unwrap()
}

/// Solves every weight vector of `frames` with both blends: both converge, to the same
/// equilibrium, and the sampled start takes fewer Newton iterations over all of them.
fn same_equilibria_in_fewer_iterations(
    sampled: &mut PhysicalBlend,
    plain: &mut PhysicalBlend,
    frames: &[Vec<f64>],
    d: f64,
) {
    let (mut n_sampled, mut n_plain) = (0, 0);
    for w in frames {
        let weights = Weights::Delta(w.clone());
        let a = sampled.solve(&weights).unwrap();
        let b = plain.solve(&weights).unwrap();
        assert!(a.stats.converged && b.stats.converged, "{w:?}");
        // Two solves converged to the gradient tolerance (1e-6 · k0) from different starts
        // differ by up to that residual over the softest mode's stiffness: about 1e-6 of
        // the diagonal on this free bar (a different basin would be a large part of it).
        let gap = max_dist(&a.positions, &b.positions);
        assert!(gap <= 1e-5 * d, "{w:?}: {gap:e} of {d}");
        n_sampled += a.stats.newton_iterations;
        n_plain += b.stats.newton_iterations;
    }
    eprintln!("Newton iterations: sampled {n_sampled}, plain {n_plain}");
    assert!(n_sampled < n_plain, "{n_sampled} vs {n_plain}");
}

#[test]
fn reaches_the_plain_equilibrium_with_fewer_iterations() {
    let s = bar_rig();
    let d = bbox_diagonal(s.positions(0));
    let mut sampled = PhysicalBlend::new(&s, &options(true)).unwrap();
    let mut plain = PhysicalBlend::new(&s, &options(false)).unwrap();
    let frames: Vec<Vec<f64>> = (1..11).map(|k| vec![k as f64 / 11.0, 0.0]).collect();
    same_equilibria_in_fewer_iterations(&mut sampled, &mut plain, &frames, d);
    // Only the bent target's ¼, ½ and ¾ samples were solved.
    assert_eq!(sampled.start_samples_solved(), 3);
    assert_eq!(plain.start_samples_solved(), 0);
    // At a sample weight the start is that sample's equilibrium: no iteration left.
    let half = sampled.solve(&Weights::Delta(vec![0.5, 0.0])).unwrap();
    assert!(half.stats.converged && half.stats.newton_iterations == 0);
}

#[test]
fn lazy_and_prepared_samples_give_the_same_bits() {
    let s = bar_rig();
    let weights: Vec<Weights> = [(0.1, 0.0), (0.6, 0.3), (0.0, 0.9), (0.35, 0.35)]
        .iter()
        .map(|&(a, b)| Weights::Delta(vec![a, b]))
        .collect();
    // Prepared in parallel by solve_many.
    let mut many = PhysicalBlend::new(&s, &options(true)).unwrap();
    let frames: Vec<Vec<Point>> = many
        .solve_many(&weights, 2)
        .into_iter()
        .map(|r| r.unwrap().positions)
        .collect();
    // Computed lazily, in reverse order, each by the first solve that needs it.
    let mut one = PhysicalBlend::new(&s, &options(true)).unwrap();
    for (k, w) in weights.iter().enumerate().rev() {
        let r = one.solve(w).unwrap();
        assert!(r.stats.converged, "frame {k}");
        common::assert_same_frame(&r.positions, &frames[k], &format!("frame {k}"));
    }
    assert_eq!(many.start_samples_solved(), one.start_samples_solved());
    assert_eq!(
        many.start_samples_solved(),
        7,
        "both targets' three samples and their pair's field"
    );
}

/// Combinations of both targets read the pair's field: at (½, ½) the start is the pair's
/// equilibrium (no iteration left), and elsewhere the same equilibrium as the plain start's is
/// reached in fewer iterations.
#[test]
fn combinations_start_from_the_pairs_equilibrium() {
    let s = bar_rig();
    let d = bbox_diagonal(s.positions(0));
    let mut sampled = PhysicalBlend::new(&s, &options(true)).unwrap();
    let mut plain = PhysicalBlend::new(&s, &options(false)).unwrap();
    let half = sampled.solve(&Weights::Delta(vec![0.5, 0.5])).unwrap();
    assert!(half.stats.converged && half.stats.newton_iterations == 0);
    assert_eq!(
        sampled.start_samples_solved(),
        3,
        "two ½ samples and the pair"
    );
    let frames = [[0.3, 0.3], [0.6, 0.2], [0.2, 0.7], [0.45, 0.5]].map(|w| w.to_vec());
    same_equilibria_in_fewer_iterations(&mut sampled, &mut plain, &frames, d);
}

/// A sample that does not converge turns its target's correction off: the frame starts from
/// the plain predictor, bit for bit the solve without the sampled start.
#[test]
fn unconverged_samples_leave_the_plain_start() {
    let s = bar_rig();
    let limited = |sampled_start| BlendOptions {
        sampled_start,
        max_newton_iterations: 1,
        ..Default::default()
    };
    let w = Weights::Delta(vec![0.4, 0.0]);
    let mut a = PhysicalBlend::new(&s, &limited(true)).unwrap();
    let mut b = PhysicalBlend::new(&s, &limited(false)).unwrap();
    let (ra, rb) = (a.solve(&w).unwrap(), b.solve(&w).unwrap());
    assert!(
        !ra.stats.converged,
        "one iteration cannot converge this bend"
    );
    assert!(a.start_samples_solved() >= 1);
    common::assert_same_frame(&ra.positions, &rb.positions, "unconverged samples");
}
