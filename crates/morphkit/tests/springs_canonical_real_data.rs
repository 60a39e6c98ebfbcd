//! The canonical physical blend on every real rig under `MORPHKIT_DATA` (skipped when unset,
//! failing when set but a file is missing): exact endpoints on all horse poses, all ICT
//! expressions, the cylinders and a bent armadillo; convergence, no flying parts and no more
//! folds than the linear blend at α = ¼, ½, ¾; frames independent of their order.

mod common;

use morphkit::io::{read_mesh, read_shape_set};
use morphkit::mesh::{bbox_diagonal, generate, Point, ShapeSet, Topology};
use morphkit::springs::{fold_metrics, BlendOptions, PhysicalBlend, Weights};
use std::path::PathBuf;

use common::ICT_EXPRESSIONS as ICT;

use common::max_dist;

/// Every one-hot delta weight vector (and all zeros) reproduces its shape within 1e-6 × diag.
fn check_endpoints(name: &str, solver: &mut PhysicalBlend) {
    let s = solver.shapes().clone();
    let d = bbox_diagonal(s.positions(0));
    let n = s.len() - 1;
    for shape in 0..=n {
        let mut w = vec![0.0; n];
        if shape > 0 {
            w[shape - 1] = 1.0;
        }
        let r = solver.solve(&Weights::Delta(w)).unwrap();
        let err = max_dist(&r.positions, s.positions(shape));
        assert!(
            err <= 1e-6 * d,
            "{name}: shape {} reproduced {err:e} away ({:e} of the diagonal)",
            s.name(shape),
            err / d
        );
    }
}

/// Convergence, no flying parts and no more folds than linear at the given delta weights.
fn check_quality(name: &str, solver: &mut PhysicalBlend, weights: &[Weights]) {
    let s = solver.shapes().clone();
    let topo = Topology::new(s.num_vertices(), s.triangles());
    for (w, r) in weights.iter().zip(solver.solve_many(weights, 2)) {
        let r = r.unwrap();
        assert!(
            r.stats.converged,
            "{name} {w:?}: not converged ({:e} > {:e}), {} vertices failing",
            r.stats.gradient_norm,
            r.stats.gradient_tolerance,
            r.stats.unconverged_vertices.len()
        );
        assert!(r.positions.iter().flatten().all(|v| v.is_finite()));
        let q = fold_metrics(&s, &topo, w, &r.positions).unwrap();
        eprintln!("{name} {w:?}: {q:?}, {} Newton", r.stats.newton_iterations);
        assert!(
            q.max_from_linear <= 0.5 * q.largest_move,
            "{name} {w:?}: a part flies away: {q:?}"
        );
        assert!(q.folds <= q.folds_linear, "{name} {w:?}: {q:?}");
    }
}

fn quarter_weights(targets: usize, target: usize) -> Vec<Weights> {
    [0.25, 0.5, 0.75]
        .iter()
        .map(|&a| {
            let mut w = vec![0.0; targets];
            w[target] = a;
            Weights::Delta(w)
        })
        .collect()
}

fn files(dir: &str, names: &[String]) -> Option<Vec<PathBuf>> {
    names
        .iter()
        .map(|n| common::data_file(&format!("{dir}/{n}")))
        .collect()
}

#[test]
fn horse_poses_endpoints_and_quality() {
    for pose in 1..=10 {
        let names = [
            "horse-reference.obj.gz".to_string(),
            format!("horse-{pose:02}.obj.gz"),
        ];
        let Some(paths) = files("sumner-horse-camel", &names) else {
            return common::skip("horse_poses_endpoints_and_quality");
        };
        let s = read_shape_set(&paths).unwrap();
        let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
        let name = format!("horse-{pose:02}");
        check_endpoints(&name, &mut solver);
        check_quality(&name, &mut solver, &quarter_weights(1, 0));
    }
}

fn ict_rig() -> Option<ShapeSet> {
    Some(read_shape_set(&common::ict_rig_paths()?).unwrap())
}

#[test]
fn ict_expressions_endpoints() {
    let Some(s) = ict_rig() else {
        return common::skip("ict_expressions_endpoints");
    };
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    check_endpoints("ict", &mut solver);
}

#[test]
fn ict_expressions_quality() {
    let Some(s) = ict_rig() else {
        return common::skip("ict_expressions_quality");
    };
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    for (k, e) in ICT.iter().enumerate() {
        check_quality(e, &mut solver, &quarter_weights(ICT.len(), k));
    }
}

#[test]
fn cylinders_and_bent_armadillo_endpoints() {
    let mut names = vec!["cylinder-rest.obj".to_string()];
    for k in 1..=4 {
        names.push(format!("cylinder-bend-{k}.obj"));
        names.push(format!("cylinder-pose1-{k}.obj"));
    }
    let Some(paths) = files("cragl-bending-cylinder", &names) else {
        return common::skip("cylinders_and_bent_armadillo_endpoints");
    };
    let s = read_shape_set(&paths).unwrap();
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    check_endpoints("cylinders", &mut solver);

    let arm = read_mesh(&common::data_file("generic-meshes/armadillo.obj.gz").unwrap()).unwrap();
    let (lo, hi) = arm.bounding_box();
    let mid = 0.5 * (lo[0] + hi[0]);
    let bent = generate::bend(&arm.positions, mid, hi[0] - mid, 60f64.to_radians());
    let s = common::two_shapes(&arm, "armadillo", ("bent", bent));
    let mut solver = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    check_endpoints("armadillo", &mut solver);
}

#[test]
fn horse_frames_do_not_depend_on_their_order() {
    let names = [
        "horse-reference.obj.gz".to_string(),
        "horse-05.obj.gz".to_string(),
    ];
    let Some(paths) = files("sumner-horse-camel", &names) else {
        return common::skip("horse_frames_do_not_depend_on_their_order");
    };
    let s = read_shape_set(&paths).unwrap();
    let w = |a: f64| Weights::Delta(vec![a]);
    let mut a = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    let forward: Vec<Vec<Point>> = [0.0, 0.5, 1.0]
        .iter()
        .map(|&t| a.solve(&w(t)).unwrap().positions)
        .collect();
    let mut b = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    let reversed = b.solve_many(&[w(1.0), w(0.5), w(0.0)], 2);
    for (k, r) in reversed.iter().enumerate() {
        common::assert_same_frame(
            &r.as_ref().unwrap().positions,
            &forward[2 - k],
            &format!("reversed frame {k}"),
        );
    }
    common::assert_same_frame(&a.solve(&w(0.5)).unwrap().positions, &forward[1], "again");
}
