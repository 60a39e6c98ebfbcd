//! Thin bands follow the predictor (`BlendOptions::thin_band_rings`): a free annular strip on
//! a spherical cap, like a face rig's eye-occlusion strip over the eyeball, squashed by its
//! target (an eye that closes) snaps between buckled states when solved as springs (6.8× the
//! linear blend's step in one frame); held at the rotation-aware predictor it moves smoothly
//! (1.1×) without folds, and the rest of the mesh is still solved.

mod common;

use common::sequence::{check_sequence, STEP_BOUND};
use morphkit::mesh::{generate, Point, ShapeSet, TriMesh};
use morphkit::springs::{linear_blend, BlendOptions, PhysicalBlend, Weights};

/// An annulus of 3 rings of 160 vertices (radii 0.85…1.15) on a sphere of radius 1.5, beside
/// a bar (a part that is solved); the target squashes the annulus to a twentieth of its
/// height on the sphere (the lids closing) and bends the bar by 100°.
fn strip_and_bar() -> ShapeSet {
    // The strip lies on a cap over an eyeball of radius 1.5.
    let cap = |x: f64, y: f64| (2.25 - x * x - y * y).sqrt();
    let (rows, around) = (3usize, 160usize);
    let mut p: Vec<Point> = Vec::new();
    for i in 0..rows {
        let r = 0.85 + 0.3 * i as f64 / (rows - 1) as f64;
        for j in 0..around {
            let t = std::f64::consts::TAU * j as f64 / around as f64;
            let (x, y) = (r * t.cos(), r * t.sin());
            p.push([x, y, cap(x, y)]);
        }
    }
    let id = |i: usize, j: usize| (i * around + j % around) as u32;
    let mut tris = Vec::new();
    for i in 0..rows - 1 {
        for j in 0..around {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let squashed: Vec<Point> = p
        .iter()
        .map(|q| [q[0], 0.05 * q[1], cap(q[0], 0.05 * q[1])])
        .collect();
    let bar = generate::bar(4.0, 0.6, 2, 24);
    let bent = generate::bend(&bar.positions, 2.0, 2.0, 100f64.to_radians());
    let off = p.len() as u32;
    let shift = |q: &Point| [q[0] - 2.0, q[1] + 3.0, q[2]];
    let mut base = p.clone();
    base.extend(bar.positions.iter().map(shift));
    let mut target = squashed;
    target.extend(bent.iter().map(shift));
    tris.extend(bar.triangles.iter().map(|t| t.map(|v| v + off)));
    let mesh = TriMesh::new(base.clone(), tris);
    ShapeSet::new(mesh, vec![("open".into(), base), ("closed".into(), target)]).unwrap()
}

#[test]
fn a_squashed_strip_follows_the_predictor_without_folds_or_jumps() {
    let s = strip_and_bar();
    let strip = 3 * 160;
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    // The 8 strip vertices on the x-axis do not move: fixed (`auto`), not counted as band.
    assert_eq!(solver.summary().band_vertices, strip - 6);
    let rep = check_sequence("strip", &mut solver, 1, 0, 36);
    for (k, f) in rep.frames.iter().enumerate() {
        let w = Weights::Delta(vec![k as f64 / 35.0]);
        let p = solver.predict(&w).unwrap();
        assert_eq!(
            &f.positions[..strip],
            &p[..strip],
            "frame {k}: the strip is the predictor"
        );
    }
    assert!(rep.failures.is_empty(), "{:#?}", rep.failures);

    let mut springs = PhysicalBlend::new(
        &s,
        &BlendOptions {
            thin_band_rings: 0,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(springs.summary().band_vertices, 0);
    let rep0 = check_sequence("strip as springs", &mut springs, 1, 0, 36);
    assert!(
        rep0.worst_step > STEP_BOUND,
        "solved as springs, the strip no longer snaps (worst step {:.2}× linear): the case no longer shows why bands are held",
        rep0.worst_step
    );
    assert!(
        rep.worst_step < 0.5 * rep0.worst_step,
        "{} vs {}",
        rep.worst_step,
        rep0.worst_step
    );
    // The bar is still solved: it is not the linear blend in the middle of its bend.
    let mid = &rep.frames[18].positions;
    let lin = linear_blend(&s, &Weights::Delta(vec![18.0 / 35.0])).unwrap();
    let off = mid[strip..]
        .iter()
        .zip(&lin[strip..])
        .map(|(p, q)| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(off > 0.05, "the bar follows the linear blend ({off})");
}
