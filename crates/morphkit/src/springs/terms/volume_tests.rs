use super::super::check::{
    bound_hessians_match, dense_hessian, fused_hessians_match, gradient_error, hessian_error,
};
use super::*;
use crate::mesh::{generate, Point, ShapeSet, TriMesh};
use rand::{Rng, SeedableRng};

/// Two tetrahedra sharing a face, in a base and a sheared target.
fn shapes(target: impl Fn(Point) -> Point) -> ShapeSet {
    let base: Vec<Point> = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
    ];
    let t: Vec<Point> = base.iter().map(|&p| target(p)).collect();
    let m = TriMesh::new(base.clone(), vec![[0, 1, 2]]);
    ShapeSet::new(m, vec![("a".into(), base), ("b".into(), t)]).unwrap()
}

const TETS: [[u32; 4]; 2] = [[0, 1, 2, 3], [1, 3, 2, 4]];

fn shear(p: Point) -> Point {
    [p[0] + 0.8 * p[2], p[1], p[2]]
}

#[test]
fn gradient_and_hessians_match_finite_differences() {
    let s = shapes(shear);
    let term = VolumeTerm::new(&s, &TETS, 2.0, 0.05);
    assert_eq!(term.tetrahedra().len(), 2);
    let p = term.prepare(&[0.4, 0.6]);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let x: Vec<f64> = s
        .positions(0)
        .iter()
        .flatten()
        .map(|v| 1.3 * v + rng.random_range(-0.1..0.1))
        .collect();
    let (err, gmax) = gradient_error(&term, &p, &x);
    assert!(gmax > 1e-3 && err < 1e-7 * gmax.max(1.0), "{err} {gmax}");
    let hm = dense_hessian(&term, &p, &x, HessianKind::Exact);
    assert!(hessian_error(&term, &p, &x, &hm) < 1e-6);
    assert!(fused_hessians_match(&term, &p, &x));
    let mut bound = term;
    assert!(bound_hessians_match(&mut bound, &p, &x));
    // The projected Hessian is positive semi-definite.
    let hp = dense_hessian(&bound, &p, &x, HessianKind::Projected);
    let m = nalgebra::DMatrix::from_fn(hp.len(), hp.len(), |r, c| hp[r][c]);
    assert!(m.symmetric_eigenvalues().min() > -1e-10);
}

#[test]
fn one_hot_weights_give_each_shapes_volumes_and_no_force() {
    let s = shapes(|p| [2.0 * p[0], p[1] + 0.3 * p[0], 0.7 * p[2]]);
    let term = VolumeTerm::new(&s, &TETS, 1.0, 0.05);
    for k in 0..2 {
        let mut c = [0.0; 2];
        c[k] = 1.0;
        let p = term.prepare(&c);
        let x: Vec<f64> = s.positions(k).iter().flatten().copied().collect();
        let mut g = vec![0.0; x.len()];
        assert_eq!(term.add_gradient(&p, &x, &mut g), 0.0);
        assert!(g.iter().all(|v| *v == 0.0));
    }
}

/// Under a similarity the blended volume is that of the blended scale: the springs'
/// equilibrium (the similarity at the blended scale) feels no force from the term.
#[test]
fn a_similarity_blend_feels_no_force() {
    let m = generate::tube(0.5, 2.0, 6, 3, true);
    let scaled: Vec<Point> = m.positions.iter().map(|p| p.map(|v| 2.0 * v)).collect();
    let s = ShapeSet::new(
        m.clone(),
        vec![("a".into(), m.positions.clone()), ("b".into(), scaled)],
    )
    .unwrap();
    let tets: Vec<[u32; 4]> = m
        .triangles
        .iter()
        .map(|t| [t[0], t[1], t[2], (m.num_vertices() - 1) as u32])
        .collect();
    let term = VolumeTerm::new(&s, &tets, 1.0, 0.05);
    let p = term.prepare(&[0.75, 0.25]);
    let x: Vec<f64> = m.positions.iter().flatten().map(|v| 1.25 * v).collect();
    let mut g = vec![0.0; x.len()];
    let e = term.add_gradient(&p, &x, &mut g);
    assert!(e < 1e-24, "{e}");
    assert!(g.iter().all(|v| v.abs() < 1e-12), "{g:?}");
}
