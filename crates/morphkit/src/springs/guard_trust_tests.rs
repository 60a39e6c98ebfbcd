use super::*;
use crate::mesh::generate;
use crate::springs::{BlendOptions, PhysicalBlend, Weights};

/// A deterministic value per grid corner, to interpolate.
fn corner_value(corner: &[f64]) -> f64 {
    corner
        .iter()
        .enumerate()
        .map(|(s, &x)| ((s + 1) as f64 * 1.7 * x + 0.3).sin())
        .sum()
}

fn interpolate(c: &[f64], g: f64) -> f64 {
    freudenthal_corners(c, g)
        .iter()
        .map(|(corner, l)| l * corner_value(corner))
        .sum()
}

#[test]
fn corners_reproduce_the_coefficients_and_skip_zero_ones() {
    let c = [0.0, 0.3, 0.0, 0.71, -0.2, 1.0];
    let corners = freudenthal_corners(&c, 4.0);
    // Four nonzero coefficients, one of them on the grid: at most five corners.
    assert!(corners.len() <= 5 && corners.len() >= 2, "{corners:?}");
    let total: f64 = corners.iter().map(|(_, l)| l).sum();
    assert!((total - 1.0).abs() < 1e-12);
    for s in 1..c.len() {
        let back: f64 = corners.iter().map(|(k, l)| l * k[s]).sum();
        assert!((back - c[s]).abs() < 1e-12, "coefficient {s}: {back}");
        for (k, _) in &corners {
            assert_eq!((k[s] * 4.0).fract(), 0.0, "corner {k:?} off the grid");
            if c[s] == 0.0 {
                assert_eq!(k[s], 0.0, "zero coefficient {s} moved");
            }
        }
    }
    for (k, _) in &corners {
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    // A grid point is its own single corner.
    let on = freudenthal_corners(&[0.25, 0.5, 0.25], 4.0);
    assert_eq!(on, vec![(vec![0.25, 0.5, 0.25], 1.0)]);
}

#[test]
fn the_interpolation_is_continuous_across_cells() {
    // A path through many cells in three coefficients, in steps of 1e-4: no step changes the
    // interpolant by more than its Lipschitz bound (g · the largest corner difference · the
    // step's l1 length), while the nearest corner's value (a cut) jumps.
    let (g, n) = (4.0, 10_000);
    let at = |t: f64| vec![0.0, 1.3 * t, 0.9 - 1.1 * t, 0.37 * t + 0.05];
    let bound = g * 6.0 * (1.3 + 1.1 + 0.37) / n as f64;
    let mut prev = interpolate(&at(0.0), g);
    let (mut worst, mut cut_worst) = (0.0f64, 0.0f64);
    let cut = |c: &[f64]| corner_value(&c.iter().map(|x| (x * g).round() / g).collect::<Vec<_>>());
    let mut prev_cut = cut(&at(0.0));
    for k in 1..=n {
        let c = at(k as f64 / n as f64);
        let v = interpolate(&c, g);
        worst = worst.max((v - prev).abs());
        prev = v;
        let vc = cut(&c);
        cut_worst = cut_worst.max((vc - prev_cut).abs());
        prev_cut = vc;
    }
    assert!(worst <= bound, "step {worst} over {bound}");
    assert!(
        cut_worst > 100.0 * bound,
        "the cut should jump: {cut_worst}"
    );
}

#[test]
fn trust_is_the_agreement_on_the_grid_and_continuous_between() {
    // The neck whose head turns by 180°: the rotation-aware prediction and the linear blend
    // disagree about the neck's triangles in mid-turn.
    let shapes = generate::turning_head_rig(180.0, 20.0);
    let blend = PhysicalBlend::new(&shapes, &BlendOptions::default()).unwrap();
    let rig = &blend.rig;
    let n = 400;
    let coefficients = |k: usize| Weights::Alpha(k as f64 / n as f64).coefficients(2).unwrap();
    let mut prev = rig.guard_trust(&coefficients(0));
    assert!(
        prev.iter().all(|&g| g == 1.0),
        "the base agrees with itself"
    );
    let (mut partial, mut worst) = (0, 0.0f64);
    for k in 1..=n {
        let c = coefficients(k);
        let trust = rig.guard_trust(&c);
        assert!(trust.iter().all(|g| (0.0..=1.0).contains(g)));
        if k % (n / 4) == 0 {
            assert_eq!(trust, rig.agreement(&c), "at {}", k as f64 / n as f64);
        }
        partial += trust.iter().filter(|&&g| g > 0.0 && g < 1.0).count();
        for (a, b) in trust.iter().zip(&prev) {
            worst = worst.max((a - b).abs());
        }
        prev = trust;
    }
    // The smoothstep's slope is at most 3/2, the interpolation's g per unit weight.
    let bound = 1.5 * TRUST_GRID / n as f64 * (1.0 + 1e-9);
    assert!(partial > 0, "some triangle should be partly trusted");
    assert!(
        worst <= bound,
        "trust moved {worst} in one step (bound {bound})"
    );
    // A zero weight adds nothing: the same trust with a third shape at zero.
    let mut three = shapes.clone();
    three
        .push("copy".into(), shapes.positions(1).to_vec())
        .unwrap();
    let blend3 = PhysicalBlend::new(&three, &BlendOptions::default()).unwrap();
    let c2 = Weights::Delta(vec![0.4]).coefficients(2).unwrap();
    let c3 = Weights::Delta(vec![0.4, 0.0]).coefficients(3).unwrap();
    assert_eq!(rig.guard_trust(&c2), blend3.rig.guard_trust(&c3));
}

/// A flat 3 × 3 grid as both shapes and the linear blend; the predictor turns triangle 0 over (its first corner
/// reflected across the opposite edge), and all of it is rotated into solver coordinates.
#[test]
fn references_follow_the_predictor_unless_it_is_turned_against_the_shapes() {
    let m = generate::grid(3, 3, 1.0, 1.0);
    let shapes = ShapeSet::new(
        m.clone(),
        vec![
            ("base".into(), m.positions.clone()),
            ("same".into(), m.positions.clone()),
        ],
    )
    .unwrap();
    let c = [0.5, 0.5];
    let mut world = m.positions.clone();
    let [a, b, cc] = m.triangles[0];
    // Reflect corner a across the opposite edge: triangle 0 turns over.
    let (pb, pc) = (
        Vector3::from(world[b as usize]),
        Vector3::from(world[cc as usize]),
    );
    let pa = Vector3::from(world[a as usize]);
    let e = (pc - pb).normalize();
    let foot = pb + e * (pa - pb).dot(&e);
    world[a as usize] = (2.0 * foot - pa).into();
    let turn = nalgebra::Rotation3::from_euler_angles(0.3, -0.5, 1.1);
    let solver: Vec<f64> = world
        .iter()
        .flat_map(|p| {
            let q = turn * Vector3::from(*p);
            [q.x, q.y, q.z]
        })
        .collect();
    let refs = guard_references(&shapes, &c, &solver, &world, &m.positions);
    let up = turn * Vector3::z();
    for (t, r) in refs.iter().enumerate() {
        let pn = normal_of(&world, m.triangles[t]);
        // Magnitude: one over P's doubled area.
        assert!((r.norm() * pn.norm() - 1.0).abs() < 1e-9, "triangle {t}");
        // Direction: the shapes' (turned into solver coordinates) everywhere, since where P
        // agrees with them it is P's own, and where P is turned over it is L's (which keeps
        // the triangle's area).
        assert!(
            (r.normalize() - up).norm() < 1e-9,
            "triangle {t}: {r:?} against {up:?}"
        );
    }
    assert!(pa != Vector3::from(world[a as usize]));
    assert!(normal_of(&world, m.triangles[0]).dot(&Vector3::z()) < 0.0);
}
