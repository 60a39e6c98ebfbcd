use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random sparse SPD matrix: a graph Laplacian plus a positive diagonal shift.
pub(crate) fn random_spd(n: usize, seed: u64) -> Vec<(usize, usize, f64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut t = Vec::new();
    let mut diag = vec![0.1; n];
    for i in 0..n {
        for _ in 0..3 {
            let j = rng.random_range(0..n);
            if j != i {
                let w: f64 = rng.random_range(0.1..2.0);
                t.push((i.max(j), i.min(j), -w));
                diag[i] += w;
                diag[j] += w;
            }
        }
    }
    t.extend(diag.into_iter().enumerate().map(|(i, d)| (i, i, d)));
    t
}

fn residual(p: &SymmetricPattern, v: &[f64], x: &[f64], b: &[f64]) -> f64 {
    let ax = p.mul_vec(v, x);
    let r: f64 = ax
        .iter()
        .zip(b)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    r / b.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn residual_is_small_on_random_spd_systems() {
    for (n, seed) in [(1, 1), (10, 2), (200, 3), (3000, 4)] {
        let t = random_spd(n, seed);
        let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
        let mut chol = Cholesky::analyze(p.clone(), Ordering::Amd).unwrap();
        chol.factorize(&v).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 100);
        let b: Vec<f64> = (0..2 * n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x, 2).unwrap();
        for c in 0..2 {
            let r = residual(&p, &v, &x[c * n..(c + 1) * n], &b[c * n..(c + 1) * n]);
            assert!(r < 1e-10, "n = {n}: relative residual {r}");
        }
    }
}

/// A single-precision factor solves to f32 accuracy (a preconditioner), in half the
/// memory, with `solve_one` and `solve_in_place` agreeing, and shares its symbolic
/// analysis with a double factor of the same pattern.
#[test]
fn single_precision_factor_is_an_f32_accurate_solver() {
    let n = 2000;
    let t = random_spd(n, 5);
    let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
    let mut single = Cholesky::analyze_with(p.clone(), Ordering::Amd, Precision::Single).unwrap();
    assert_eq!(single.precision(), Precision::Single);
    single.factorize(&v).unwrap();
    let mut double = single.share_symbolic_with(Precision::Double).unwrap();
    double.factorize(&v).unwrap();
    assert_eq!(single.factor_nnz(), double.factor_nnz());
    let b: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
    let mut xs = b.clone();
    single.solve_one(&mut xs).unwrap();
    let xd = double.solve(&b).unwrap();
    let rs = residual(&p, &v, &xs, &b);
    assert!(rs < 1e-4 && rs > 1e-12, "single residual {rs}");
    assert!(residual(&p, &v, &xd, &b) < 1e-10);
    let mut xm = b.clone();
    single.solve_in_place(&mut xm, 1).unwrap();
    assert_eq!(xm, xs);
}

#[test]
fn a_frozen_factor_solves_its_own_matrix_on_another_solver() {
    let n = 400;
    let t = random_spd(n, 9);
    let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
    let v2: Vec<f64> = v
        .iter()
        .map(|x| if *x < 0.0 { 0.5 * x } else { x + 1.0 })
        .collect();
    for precision in [Precision::Single, Precision::Double] {
        let mut a = Cholesky::analyze_with(p.clone(), Ordering::Amd, precision).unwrap();
        assert!(a.freeze().is_err(), "nothing factored yet");
        a.factorize(&v).unwrap();
        let frozen = a.freeze().unwrap();
        assert_eq!(frozen.bytes() as u64, a.factor_bytes());
        let b: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).cos()).collect();
        let mut want = b.clone();
        a.solve_one(&mut want).unwrap();
        // Another solver sharing the analysis, factored with other values: the frozen
        // factor still solves the first matrix, bit for bit, and leaves the solver's own.
        let mut other = a.share_symbolic_with(precision).unwrap();
        other.factorize(&v2).unwrap();
        let mut got = b.clone();
        other.solve_one_with(&frozen, &mut got).unwrap();
        assert_eq!(got, want, "{precision:?}");
        let mut own = b.clone();
        other.solve_one(&mut own).unwrap();
        assert!(residual(&p, &v2, &own, &b) < 1e-4, "{precision:?}");
        // A solver of another analysis refuses it.
        let mut stranger = Cholesky::analyze_with(p.clone(), Ordering::Amd, precision).unwrap();
        assert!(stranger.solve_one_with(&frozen, &mut got).is_err());
    }
}

#[test]
fn pattern_reuse_matches_a_fresh_factorization() {
    let n = 500;
    let t = random_spd(n, 7);
    let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
    let mut reused = Cholesky::analyze(p.clone(), Ordering::Amd).unwrap();
    reused.factorize(&v).unwrap();
    // New values, same pattern: scale off-diagonals, bump the diagonal.
    let v2: Vec<f64> = v
        .iter()
        .map(|x| if *x < 0.0 { 0.5 * x } else { x + 1.0 })
        .collect();
    reused.factorize(&v2).unwrap();
    let mut fresh = Cholesky::analyze(p.clone(), Ordering::Amd).unwrap();
    fresh.factorize(&v2).unwrap();
    let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let (x1, x2) = (reused.solve(&b).unwrap(), fresh.solve(&b).unwrap());
    assert_eq!(
        x1, x2,
        "the same symbolic analysis and values give bitwise the same result"
    );
    assert!(residual(&p, &v2, &x1, &b) < 1e-12);
}

#[test]
fn orderings_agree() {
    let n = 300;
    let t = random_spd(n, 9);
    let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
    let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
    let rev: Vec<usize> = (0..n).rev().collect();
    let mut xs = Vec::new();
    for ord in [Ordering::Amd, Ordering::Identity, Ordering::Custom(rev)] {
        let mut c = Cholesky::analyze(p.clone(), ord).unwrap();
        c.factorize(&v).unwrap();
        xs.push(c.solve(&b).unwrap());
    }
    for x in &xs[1..] {
        let d = x
            .iter()
            .zip(&xs[0])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-10);
    }
}

#[test]
fn singular_and_indefinite_matrices_are_errors_not_nans() {
    // Path-graph Laplacian: singular (constant null space).
    let t = vec![
        (0, 0, 1.0),
        (1, 0, -1.0),
        (1, 1, 2.0),
        (2, 1, -1.0),
        (2, 2, 1.0),
    ];
    let (p, v) = SymmetricPattern::from_triplets(3, &t).unwrap();
    let mut c = Cholesky::analyze(p, Ordering::Amd).unwrap();
    assert!(matches!(
        c.factorize(&v),
        Err(SolveError::NotPositiveDefinite { .. })
    ));
    assert!(
        c.solve(&[1.0, 0.0, 0.0]).is_err(),
        "no solve after a failed factorization"
    );
    let (p, v) = SymmetricPattern::from_triplets(2, &[(0, 0, 1.0), (1, 1, -1.0)]).unwrap();
    let mut c = Cholesky::analyze(p, Ordering::Amd).unwrap();
    assert!(c.factorize(&v).is_err());
    let (p, v) = SymmetricPattern::from_triplets(1, &[(0, 0, f64::NAN)]).unwrap();
    let mut c = Cholesky::analyze(p, Ordering::Amd).unwrap();
    assert!(matches!(c.factorize(&v), Err(SolveError::NonFinite { .. })));
}

#[test]
fn symmetric_product_equals_the_dense_one() {
    let t = random_spd(40, 3);
    let (p, v) = SymmetricPattern::from_triplets(40, &t).unwrap();
    let mut dense = vec![vec![0.0; 40]; 40];
    for &(i, j, a) in &t {
        dense[i][j] += a;
        if i != j {
            dense[j][i] += a;
        }
    }
    let x: Vec<f64> = (0..40).map(|k| (k as f64 * 0.37).sin()).collect();
    let y = p.mul_vec(&v, &x);
    for i in 0..40 {
        let want: f64 = (0..40).map(|j| dense[i][j] * x[j]).sum();
        assert!(
            (y[i] - want).abs() <= 1e-12 * want.abs().max(1.0),
            "row {i}"
        );
    }
}

/// A 40 × 40 grid Laplacian: the natural (identity) order fills the band, AMD much less; the
/// cheapest of the two is AMD, whichever comes first, and it solves.
#[test]
fn the_cheapest_ordering_is_kept() {
    let side = 40;
    let n = side * side;
    let mut t = Vec::new();
    for r in 0..side {
        for c in 0..side {
            let i = r * side + c;
            t.push((i, i, 4.5));
            if c + 1 < side {
                t.push((i + 1, i, -1.0));
            }
            if r + 1 < side {
                t.push((i + side, i, -1.0));
            }
        }
    }
    let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
    let p = Arc::new(p);
    let flops = |o: Ordering| {
        Cholesky::analyze_shared(p.clone(), o, Precision::Double)
            .unwrap()
            .factor_flops()
    };
    let (identity, amd) = (flops(Ordering::Identity), flops(Ordering::Amd));
    assert!(
        identity > 0.0 && amd < 0.7 * identity,
        "{identity:e} vs {amd:e}"
    );
    for (orders, want) in [
        (vec![Ordering::Identity, Ordering::Amd], 1),
        (vec![Ordering::Amd, Ordering::Identity], 0),
    ] {
        let (mut c, k) = Cholesky::analyze_cheapest(p.clone(), &orders, Precision::Double).unwrap();
        assert_eq!(k, want);
        assert_eq!(c.factor_flops(), amd);
        c.factorize(&v).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i % 7) as f64).collect();
        let mut x = b.clone();
        c.solve_one(&mut x).unwrap();
        assert!(residual(&p, &v, &x, &b) < 1e-12);
    }
    assert!(Cholesky::analyze_cheapest(p, &[], Precision::Double).is_err());
}

#[test]
fn the_cheapest_ordering_never_has_more_entries_than_the_first() {
    // Among random orderings of a random sparse matrix, find one pair where the second
    // ordering takes fewer multiply-adds but stores more entries than the first: the first is
    // the memory reference, so it is kept; swapped, the cheaper one is the reference and wins.
    let n = 60;
    let (p, _) = SymmetricPattern::from_triplets(n, &random_spd(n, 5)).unwrap();
    let p = Arc::new(p);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let measure = |perm: &[usize]| {
        let c = Cholesky::analyze_shared(
            p.clone(),
            Ordering::Custom(perm.to_vec()),
            Precision::Double,
        )
        .unwrap();
        (c.factor_flops(), c.factor_nnz())
    };
    let random_perm = |rng: &mut ChaCha8Rng| {
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            perm.swap(i, rng.random_range(0..=i));
        }
        perm
    };
    let perms: Vec<Vec<usize>> = (0..60).map(|_| random_perm(&mut rng)).collect();
    let costs: Vec<(f64, usize)> = perms.iter().map(|q| measure(q)).collect();
    let pair = (0..perms.len())
        .flat_map(|i| (0..perms.len()).map(move |j| (i, j)))
        .find(|&(i, j)| costs[j].0 < costs[i].0 && costs[j].1 > costs[i].1);
    let (i, j) = pair.expect("no pair of orderings trades flops against entries");
    let orders = |a: usize, b: usize| {
        vec![
            Ordering::Custom(perms[a].clone()),
            Ordering::Custom(perms[b].clone()),
        ]
    };
    let (c, k) = Cholesky::analyze_cheapest(p.clone(), &orders(i, j), Precision::Double).unwrap();
    assert_eq!((k, c.factor_nnz()), (0, costs[i].1));
    let (c, k) = Cholesky::analyze_cheapest(p.clone(), &orders(j, i), Precision::Double).unwrap();
    assert_eq!((k, c.factor_flops()), (0, costs[j].0));
}

#[test]
fn a_symbolic_analysis_allocates_and_factors_nothing_until_given_buffers() {
    let n = 400;
    let (p, v) = SymmetricPattern::from_triplets(n, &random_spd(n, 11)).unwrap();
    let p = Arc::new(p);
    let (mut symbolic, k) =
        Cholesky::analyze_cheapest_symbolic(p.clone(), &[Ordering::Amd], Precision::Single)
            .unwrap();
    assert_eq!(k, 0);
    assert!(!symbolic.is_numeric());
    assert!(symbolic.factorize(&v).is_err());
    // A thread's share of a symbolic analysis has no buffers either.
    assert!(!symbolic.share_symbolic().unwrap().is_numeric());
    let (full, _) = Cholesky::analyze_cheapest(p, &[Ordering::Amd], Precision::Single).unwrap();
    assert_eq!(symbolic.factor_nnz(), full.factor_nnz());
    assert_eq!(symbolic.factor_flops(), full.factor_flops());
    assert_eq!(symbolic.numeric_bytes(), full.numeric_bytes());
    // The factor, the f32 matrix and the scratch are all counted.
    assert!(full.numeric_bytes() > full.factor_bytes() + 4 * full.pattern().nnz() as u64);
    let mut numeric = symbolic.with_numeric().unwrap();
    assert!(numeric.is_numeric());
    numeric.factorize(&v).unwrap();
    let mut x = vec![1.0; n];
    numeric.solve_one(&mut x).unwrap();
    assert!(x.iter().all(|x| x.is_finite()));
}
