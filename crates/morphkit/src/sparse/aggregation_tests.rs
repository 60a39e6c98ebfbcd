use super::*;
use crate::sparse::{Ordering, SymmetricPattern};

/// A spring lattice `nx × ny × nz` (every pair of points within √3 spacings), bent about the
/// z axis so that the rigid modes vary over the body, its `z = 0` layer fixed. Returns the
/// pattern and lower values of the spring Hessian Σ k d dᵀ over free coordinates, the point
/// and axis of each unknown, and the bent positions.
#[allow(clippy::type_complexity)]
fn lattice(
    nx: usize,
    ny: usize,
    nz: usize,
) -> (
    Arc<SymmetricPattern>,
    Vec<f64>,
    Vec<(u32, u8)>,
    Vec<[f64; 3]>,
) {
    let id = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let mut pos = vec![[0.0; 3]; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                // Bend: the z axis curls around a centre at x = -R.
                let (r, t) = (6.0 + i as f64, k as f64 / 6.0 * 0.5);
                pos[id(i, j, k)] = [r * t.cos() - 6.0, j as f64, r * t.sin()];
            }
        }
    }
    let mut dof = vec![u32::MAX; 3 * pos.len()];
    let mut node_axis = Vec::new();
    for k in 1..nz {
        for j in 0..ny {
            for i in 0..nx {
                for a in 0..3 {
                    dof[3 * id(i, j, k) + a] = node_axis.len() as u32;
                    node_axis.push((id(i, j, k) as u32, a as u8));
                }
            }
        }
    }
    let mut trip = Vec::new();
    let pts: Vec<(usize, usize, usize)> = (0..nz)
        .flat_map(|k| (0..ny).flat_map(move |j| (0..nx).map(move |i| (i, j, k))))
        .collect();
    for &(i, j, k) in &pts {
        for di in -1i64..=1 {
            for dj in -1i64..=1 {
                for dk in -1i64..=1 {
                    let (a, b, c) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                    if (di, dj, dk) <= (0, 0, 0)
                        || a < 0
                        || b < 0
                        || c < 0
                        || a >= nx as i64
                        || b >= ny as i64
                        || c >= nz as i64
                    {
                        continue;
                    }
                    let (p, q) = (id(i, j, k), id(a as usize, b as usize, c as usize));
                    let d: Vec<f64> = (0..3).map(|x| pos[q][x] - pos[p][x]).collect();
                    let l = d.iter().map(|v| v * v).sum::<f64>().sqrt();
                    let kk = 1.0 / l;
                    for x in 0..3 {
                        for y in 0..3 {
                            let h = kk * d[x] * d[y] / (l * l);
                            for (u, w, s) in [(p, p, h), (q, q, h), (p, q, -h), (q, p, -h)] {
                                let (r, cc) = (dof[3 * u + x], dof[3 * w + y]);
                                if r != u32::MAX && cc != u32::MAX && r >= cc {
                                    trip.push((r as usize, cc as usize, s));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    let (pattern, values) = SymmetricPattern::from_triplets(node_axis.len(), &trip).unwrap();
    (Arc::new(pattern), values, node_axis, pos)
}

/// Preconditioned CG on `A x = b` from zero to a relative residual of `tol`; returns the
/// solution and the iteration count.
fn pcg(
    p: &SymmetricPattern,
    a: &[f64],
    b: &[f64],
    tol: f64,
    pre: &mut dyn FnMut(&mut [f64]),
) -> (Vec<f64>, usize) {
    let n = b.len();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
    let (mut x, mut r) = (vec![0.0; n], b.to_vec());
    let mut z = r.clone();
    pre(&mut z);
    let mut d = z.clone();
    let mut rz = dot(&r, &z);
    let bn = dot(b, b).sqrt();
    for it in 1..=2000 {
        let ad = p.mul_vec(a, &d);
        let alpha = rz / dot(&d, &ad);
        for k in 0..n {
            x[k] += alpha * d[k];
            r[k] -= alpha * ad[k];
        }
        if dot(&r, &r).sqrt() <= tol * bn {
            return (x, it);
        }
        z.copy_from_slice(&r);
        pre(&mut z);
        let rz2 = dot(&r, &z);
        for k in 0..n {
            d[k] = z[k] + rz2 / rz * d[k];
        }
        rz = rz2;
    }
    (x, usize::MAX)
}

fn rhs(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

#[test]
fn pcg_with_the_two_level_cycle_converges_in_few_iterations_to_the_direct_solution() {
    let (p, a, na, pos) = lattice(6, 6, 30);
    let levels = Arc::new(AggregationLevels::new(p.clone(), &na).unwrap());
    let nodes = pos.len() - 36;
    // Aggregates of a point and its 26 neighbours, and fewer leftovers.
    assert!(
        levels.num_aggregates() * 4 < nodes && levels.num_aggregates() * 40 > nodes,
        "{} aggregates of {nodes} points",
        levels.num_aggregates()
    );
    let mut m = AggregationPreconditioner::new(levels).unwrap();
    m.refresh(&a, &pos).unwrap();
    let b = rhs(p.n(), 7);
    let (x, its) = pcg(&p, &a, &b, 1e-10, &mut |r| m.apply(r).unwrap());
    let (_, plain) = pcg(&p, &a, &b, 1e-10, &mut |_| {});
    assert!(its <= 40, "{its} iterations");
    assert!(plain > 4 * its, "plain CG {plain} vs two-level {its}");
    let mut chol = Cholesky::analyze((*p).clone(), Ordering::Amd).unwrap();
    chol.factorize(&a).unwrap();
    let direct = chol.solve(&b).unwrap();
    let err = x
        .iter()
        .zip(&direct)
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f64::max);
    let scale = direct.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(err <= 1e-7 * scale, "{err} vs {scale}");
}

#[test]
fn the_cycle_is_a_symmetric_positive_definite_operator() {
    let (p, a, na, pos) = lattice(4, 5, 9);
    let levels = Arc::new(AggregationLevels::new(p.clone(), &na).unwrap());
    let mut m = AggregationPreconditioner::new(levels).unwrap();
    m.refresh(&a, &pos).unwrap();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
    for seed in 0..4 {
        let (u, v) = (rhs(p.n(), 2 * seed + 1), rhs(p.n(), 2 * seed + 2));
        let (mut mu, mut mv) = (u.clone(), v.clone());
        m.apply(&mut mu).unwrap();
        m.apply(&mut mv).unwrap();
        let (uv, vu) = (dot(&u, &mv), dot(&v, &mu));
        assert!(
            (uv - vu).abs() <= 1e-12 * (uv.abs() + vu.abs()),
            "{uv} vs {vu}"
        );
        assert!(dot(&u, &mu) > 0.0 && dot(&v, &mv) > 0.0);
    }
    // The same bits on a second application and a second instance.
    let b = rhs(p.n(), 99);
    let (mut once, mut twice) = (b.clone(), b.clone());
    m.apply(&mut once).unwrap();
    m.apply(&mut twice).unwrap();
    assert_eq!(once, twice);
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let (p, a, na, pos) = lattice(3, 3, 4);
    assert!(matches!(
        AggregationLevels::new(p.clone(), &na[1..]),
        Err(SolveError::Dimension { .. })
    ));
    let levels = Arc::new(AggregationLevels::new(p.clone(), &na).unwrap());
    let mut m = AggregationPreconditioner::new(levels).unwrap();
    let mut r = vec![1.0; p.n()];
    assert!(m.apply(&mut r).is_err(), "applied before it was built");
    assert!(matches!(
        m.refresh(&a[1..], &pos),
        Err(SolveError::Dimension { .. })
    ));
    assert!(matches!(
        m.refresh(&a, &pos[..3]),
        Err(SolveError::Dimension { .. })
    ));
    let mut nan = a.clone();
    nan[5] = f64::NAN;
    assert!(matches!(
        m.refresh(&nan, &pos),
        Err(SolveError::NonFinite { .. })
    ));
    let mut neg = a.clone();
    neg[p.diag_slot(4)] = -1.0;
    assert!(matches!(
        m.refresh(&neg, &pos),
        Err(SolveError::NotPositiveDefinite { column: 4, .. })
    ));
    m.refresh(&a, &pos).unwrap();
    assert!(matches!(
        m.apply(&mut r[1..]),
        Err(SolveError::Dimension { .. })
    ));
}

#[test]
fn refresh_from_takes_the_buffer_and_gives_the_same_bits_as_refresh() {
    let (p, a, na, pos) = lattice(4, 4, 6);
    let levels = Arc::new(AggregationLevels::new(p.clone(), &na).unwrap());
    let mut copied = AggregationPreconditioner::new(levels.clone()).unwrap();
    copied.refresh(&a, &pos).unwrap();
    let mut owned = AggregationPreconditioner::new(levels).unwrap();
    // The cycle's own buffer, filled by the caller and handed back.
    let mut values = owned.take_values();
    assert_eq!(values.len(), a.len());
    let mut r = rhs(p.n(), 3);
    assert!(
        owned.apply(&mut r).is_err(),
        "applied while its values are out"
    );
    // A refused refresh leaves the caller's values where they were.
    values.copy_from_slice(&a);
    values[p.diag_slot(2)] = -1.0;
    assert!(matches!(
        owned.refresh_from(&mut values, &pos),
        Err(SolveError::NotPositiveDefinite { column: 2, .. })
    ));
    assert_eq!(values.len(), a.len());
    values[p.diag_slot(2)] = a[p.diag_slot(2)];
    owned.refresh_from(&mut values, &pos).unwrap();
    assert!(values.is_empty(), "the cycle holds the only copy");
    let b = rhs(p.n(), 7);
    let (mut x, mut y) = (b.clone(), b.clone());
    copied.apply(&mut x).unwrap();
    owned.apply(&mut y).unwrap();
    assert_eq!(x, y);
    // Taken again, the buffer has the pattern's length (its old values are the caller's to
    // overwrite).
    assert_eq!(owned.take_values().len(), a.len());
}
