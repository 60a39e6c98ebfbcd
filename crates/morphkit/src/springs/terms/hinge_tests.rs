//! Tests of the parent module (kept apart so that the module itself stays one concept).
use super::super::check::{
    assert_projected_psd, bound_hessians_match, dense_hessian, fused_hessians_match,
    gradient_error, hessian_error,
};
use super::*;
use crate::mesh::generate;
use rand::{Rng, SeedableRng};

fn setup() -> (HingeTerm, ShapeSet) {
    let m = generate::tube(0.5, 2.0, 6, 4, false);
    let bent = generate::bend(&m.positions, 1.0, 1.0, 1.5);
    let set = ShapeSet::new(
        m.clone(),
        vec![("a".into(), m.positions.clone()), ("b".into(), bent)],
    )
    .unwrap();
    let topo = Topology::new(m.num_vertices(), &m.triangles);
    let term = HingeTerm::new(&set, &topo, &HingeOptions::default(), 1.0, 1.0);
    (term, set)
}

/// Shape `shape` of `set`, flattened, each coordinate moved by a uniform draw in
/// `[-amp, amp)` (seeded).
fn perturbed(set: &ShapeSet, shape: usize, seed: u64, amp: f64) -> Vec<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    set.positions(shape)
        .iter()
        .flatten()
        .map(|v| v + rng.random_range(-amp..amp))
        .collect()
}

#[test]
fn every_interior_edge_gets_a_hinge_and_each_shape_has_zero_energy() {
    let (term, set) = setup();
    let topo = Topology::new(set.num_vertices(), set.triangles());
    let interior = (0..topo.edges().len())
        .filter(|&e| topo.edge_faces(e).len() == 2)
        .count();
    assert_eq!(term.len(), interior);
    for s in 0..2 {
        let mut c = [0.0; 2];
        c[s] = 1.0;
        let p = term.prepare(&c);
        let x: Vec<f64> = set.positions(s).iter().flatten().copied().collect();
        let mut g = vec![0.0; x.len()];
        let e = term.add_gradient(&p, &x, &mut g);
        assert!(e < 1e-24, "energy {e}");
        assert!(g.iter().all(|v| v.abs() < 1e-12));
    }
}

#[test]
fn gradient_matches_finite_differences_and_hessians_are_right() {
    let (term, set) = setup();
    let p = term.prepare(&[0.5, 0.5]);
    let x = perturbed(&set, 0, 3, 0.05);
    let (err, gmax) = gradient_error(&term, &p, &x);
    assert!(err < 1e-7 * gmax.max(1.0), "FD error {err}, |g| {gmax}");
    assert!(fused_hessians_match(&term, &p, &x));
    let mut term = term;
    assert!(bound_hessians_match(&mut term, &p, &x));
    let exact = dense_hessian(&term, &p, &x, HessianKind::Exact);
    // The exact Hessian matches differences of the gradient.
    let worst = hessian_error(&term, &p, &x, &exact);
    let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        worst < 1e-5 * scale,
        "exact Hessian error {worst} (scale {scale})"
    );
    // Gauss–Newton: symmetric positive semi-definite.
    assert_projected_psd(&term, &p, &x);
}

#[test]
fn the_closed_form_hessian_holds_far_from_the_shapes() {
    // Large perturbations and extrapolated weights: every term of the second-order part
    // (ê's curvature, the mixed products, the triple products) is exercised.
    let (term, set) = setup();
    for (seed, amp, c) in [
        (5u64, 0.3, [-0.5, 1.5]),
        (6, 0.5, [1.0, 0.0]),
        (7, 0.2, [0.2, 0.8]),
    ] {
        let p = term.prepare(&c);
        let x = perturbed(&set, 1, seed, amp);
        let exact = dense_hessian(&term, &p, &x, HessianKind::Exact);
        let worst = hessian_error(&term, &p, &x, &exact);
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            worst < 1e-5 * scale,
            "seed {seed}: exact Hessian error {worst} (scale {scale})"
        );
    }
}

#[test]
fn the_closed_form_hessian_holds_on_a_twisted_box() {
    // Flat faces (θ = 0) and 90° box edges, twisted by 90° (180° would collapse the end's
    // cross-section to the axis at the linear midpoint: see the collapsed-edge test).
    let m = generate::bar(4.0, 0.6, 3, 24);
    let t: Vec<[f64; 3]> = m
        .positions
        .iter()
        .map(|&[x, y, z]| {
            let (s, c) = (std::f64::consts::FRAC_PI_2 * x / 4.0).sin_cos();
            [x, c * y - s * z, s * y + c * z]
        })
        .collect();
    let set = ShapeSet::new(
        m.clone(),
        vec![("a".into(), m.positions.clone()), ("b".into(), t.clone())],
    )
    .unwrap();
    let topo = Topology::new(m.num_vertices(), &m.triangles);
    let term = HingeTerm::new(&set, &topo, &HingeOptions::default(), 1.0, 1.0);
    let p = term.prepare(&[0.5, 0.5]);
    let x: Vec<f64> = m
        .positions
        .iter()
        .zip(&t)
        .flat_map(|(a, b)| (0..3).map(move |k| 0.5 * (a[k] + b[k])))
        .collect();
    let exact = dense_hessian(&term, &p, &x, HessianKind::Exact);
    let worst = hessian_error(&term, &p, &x, &exact);
    let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        worst < 1e-5 * scale,
        "exact Hessian error {worst} (scale {scale})"
    );
}

#[test]
fn the_closed_form_hessian_holds_on_single_hinges() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut worst_rel: f64 = 0.0;
    for trial in 0..200 {
        let mut r = || -> [f64; 3] { std::array::from_fn(|_| rng.random_range(-1.0..1.0)) };
        let p0 = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.2],
        ];
        let p1: Vec<[f64; 3]> = (0..4).map(|_| r()).collect();
        let m = crate::mesh::TriMesh::new(p0.clone(), vec![[0, 1, 2], [1, 0, 3]]);
        let Ok(set) = ShapeSet::new(m.clone(), vec![("a".into(), p0.clone()), ("b".into(), p1)])
        else {
            continue;
        };
        let topo = Topology::new(4, &m.triangles);
        let opts = HingeOptions {
            min_fold_margin: 0.0,
            ..HingeOptions::default()
        };
        let term = HingeTerm::new(&set, &topo, &opts, 1.0, 1.0);
        if term.is_empty() {
            continue;
        }
        let p = term.prepare(&[0.3, 0.7]);
        let x: Vec<f64> = (0..4).flat_map(|_| r()).collect();
        let exact = dense_hessian(&term, &p, &x, HessianKind::Exact);
        let worst = hessian_error(&term, &p, &x, &exact);
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        worst_rel = worst_rel.max(worst / scale.max(1e-300));
        assert!(
            worst < 1e-4 * scale,
            "trial {trial}: error {worst} (scale {scale})"
        );
    }
    eprintln!("worst relative error {worst_rel:e}");
}

#[test]
fn a_collapsed_hinge_edge_gives_a_finite_hessian() {
    // A blend can pass through a state where a hinge's edge has zero length (a twisted
    // bar's axis); the Hessian must stay finite there (ê is undefined, its blocks vanish).
    let p0 = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 1.0, 0.0],
        [0.5, -1.0, 0.2],
    ];
    let m = crate::mesh::TriMesh::new(p0.clone(), vec![[0, 1, 2], [1, 0, 3]]);
    let set = ShapeSet::new(m.clone(), vec![("a".into(), p0.clone()), ("b".into(), p0)]).unwrap();
    let term = HingeTerm::new(
        &set,
        &Topology::new(4, &m.triangles),
        &HingeOptions::default(),
        1.0,
        1.0,
    );
    let p = term.prepare(&[1.0, 0.0]);
    let x = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.5, -1.0, 0.2];
    for kind in [HessianKind::Exact, HessianKind::Projected] {
        let h = dense_hessian(&term, &p, &x, kind);
        assert!(h.iter().flatten().all(|v| v.is_finite()), "{kind:?}");
    }
}

#[test]
fn a_mirror_flip_costs_energy_and_a_rotation_does_not() {
    // Two triangles folded by +60°; the same fold mirrored (-60°) has the same
    // 2-ring distance but a hinge energy of μ b |2 sin 60°|².
    let fold = |t: f64| {
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -t.cos(), t.sin()],
        ]
    };
    let m = crate::mesh::TriMesh::new(fold(0.5), vec![[0, 1, 2], [1, 0, 3]]);
    let set = ShapeSet::new(
        m.clone(),
        vec![("a".into(), fold(0.5)), ("b".into(), fold(0.5))],
    )
    .unwrap();
    let topo = Topology::new(4, &m.triangles);
    let term = HingeTerm::new(&set, &topo, &HingeOptions::default(), 100.0, 1.0);
    assert_eq!(term.len(), 1);
    let p = term.prepare(&[1.0, 0.0]);
    let flat = |q: Vec<[f64; 3]>| q.into_iter().flatten().collect::<Vec<f64>>();
    assert!(term.energy(&p, &flat(fold(0.5))) < 1e-20);
    assert!(term.energy(&p, &flat(fold(-0.5))) > 0.1);
    let turned = generate::rotate(&fold(0.5), [0.3, 0.2, 0.1], [1.0, 2.0, 3.0], 2.0);
    assert!(term.energy(&p, &flat(turned)) < 1e-20);
}

#[test]
fn the_gradient_pass_equals_the_jacobian_transposed_times_the_residual() {
    // `residual_pullback` applies the transposed blocks of `residual_at` to ρ without forming
    // them; both must agree, and so must the energy pass, on every hinge of a perturbed,
    // half-blended tube.
    let (term, set) = setup();
    let p = term.prepare(&[0.3, 0.7]);
    let x = perturbed(&set, 1, 11, 0.1);
    let mut energy = 0.0;
    for k in 0..term.len() {
        let (rho, j) = term.residual(&p.values, &x, k);
        let (r, g) = term.residual_pullback(&p.values, &x, k);
        assert!((rho - r).norm() <= 1e-14 * rho.norm().max(1.0), "hinge {k}");
        assert!(rho.norm() > 1e-6, "hinge {k}: the test needs a residual");
        for u in 0..4 {
            let want = j[u].transpose() * rho;
            let err = (want - g[u]).norm();
            assert!(
                err <= 1e-12 * want.norm().max(1e-300).max(rho.norm()),
                "hinge {k}, corner {u}: {err}"
            );
        }
        energy += term.weight[k] * rho.norm_squared();
    }
    let e = term.energy(&p, &x);
    assert!((e - energy).abs() <= 1e-12 * energy, "{e} vs {energy}");
}

/// The Jacobian of ρ in matrix form, block by block, written out independently of the
/// adjoint pass ([`Geometry::pull`]) that the term uses: the oracle it is checked against.
impl HingeTerm {
    /// Residual ρ and its Jacobian blocks (∂ρ/∂a, ∂ρ/∂b, ∂ρ/∂c, ∂ρ/∂d).
    fn residual(&self, p: &[f64], x: &[f64], k: usize) -> (Vector3<f64>, [Matrix3<f64>; 4]) {
        self.residual_at(p, k, self.hinges[k].map(|v| v3(x, v)))
    }

    /// The quantities of hinge `k` at corner positions `pos` that ρ and its derivatives share.
    fn local(&self, p: &[f64], k: usize, [a, b, c, _]: [Vector3<f64>; 4]) -> Local {
        let (cs, sn, ib1, ib2) = (p[4 * k], p[4 * k + 1], p[4 * k + 2], p[4 * k + 3]);
        let e = b - a;
        let le = e.norm().max(f64::MIN_POSITIVE);
        Local {
            cs,
            sn,
            ib1,
            ib2,
            e,
            le,
            eh: e / le,
            n1: e.cross(&(c - a)),
        }
    }

    /// Residual and Jacobian of hinge `k` at corner positions `[a, b, c, d]`.
    fn residual_at(
        &self,
        p: &[f64],
        k: usize,
        pos: [Vector3<f64>; 4],
    ) -> (Vector3<f64>, [Matrix3<f64>; 4]) {
        let [a, b, c, d] = pos;
        let l = self.local(p, k, pos);
        let (cs, sn, ib1, ib2, e, eh, n1) = (l.cs, l.sn, l.ib1, l.ib2, l.e, l.eh, l.n1);
        let rho = l.rho(d - a);
        // R(Θ̄)[w]× with R = cos Θ̄ I + sin Θ̄ [ê]×, using [ê]×[w]× = w êᵀ − (ê·w) I.
        let rot_skew = |w: Vector3<f64>| {
            skew(&w) * cs + (w * eh.transpose() - Matrix3::identity() * eh.dot(&w)) * sn
        };
        // sin Θ̄ [n₁]× ∂ê/∂b, with ∂ê/∂b = (I − ê êᵀ)/‖e‖ = −∂ê/∂a.
        let np = (skew(&n1) - n1.cross(&eh) * eh.transpose()) * (sn / l.le);
        let j = [
            skew(&(b - d)) * ib2 - (rot_skew(c - b) + np) * ib1,
            skew(&(d - a)) * ib2 + (rot_skew(c - a) + np) * ib1,
            -rot_skew(e) * ib1,
            -skew(&e) * ib2,
        ];
        (rho, j)
    }

    /// Residual ρ of hinge `k` at `x` and the gradient blocks $J_u^\top \rho$ of
    /// $\lVert\rho\rVert^2 / 2$ per corner ([`pullback`]).
    fn residual_pullback(
        &self,
        p: &[f64],
        x: &[f64],
        k: usize,
    ) -> (Vector3<f64>, [Vector3<f64>; 4]) {
        let h = Geometry::new(&p[4 * k..4 * k + 4], self.hinges[k].map(|v| p3(x, v)));
        let r = h.rho();
        (r.into(), h.pull(r).map(Vector3::from))
    }
}

/// What ρ of one hinge and its derivatives share: the blended parameters (cos Θ̄, sin Θ̄,
/// 1/β̄₁, 1/β̄₂), the hinge edge `e = b − a`, its length and direction, and $n_1 = e \times (c - a)$.
#[derive(Clone, Copy)]
struct Local {
    cs: f64,
    sn: f64,
    ib1: f64,
    ib2: f64,
    e: Vector3<f64>,
    le: f64,
    eh: Vector3<f64>,
    n1: Vector3<f64>,
}

impl Local {
    /// $\rho = \beta_2^{-1} n_2 - \beta_1^{-1} R(\bar\Theta) n_1$ with $n_2 = u_2 \times e$.
    fn rho(&self, u2: Vector3<f64>) -> Vector3<f64> {
        let n2 = u2.cross(&self.e);
        n2 * self.ib2 - (self.n1 * self.cs + self.eh.cross(&self.n1) * self.sn) * self.ib1
    }
}
