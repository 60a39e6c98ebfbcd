//! Spring energy, gradient and projected Hessian (Ma et al. 2012, Eq. 2–5, with the corrected
//! Hessian of the math notes §1; the paper's Eq. 5 as printed is wrong).
//!
//! Positions are flattened, `x = [x₀, y₀, z₀, x₁, …]` (`3 #V`). For one spring $q = (i, j)$ with
//! $d = x_i - x_j$, $l = \lVert d\rVert$, $\hat d = d / l$, stiffness $k$ and rest length $r$:
//!
//! - energy $E_q = \tfrac12 k (l - r)^2$;
//! - gradient $\partial E_q / \partial x_i = k (l - r) \hat d = -\partial E_q / \partial x_j$
//!   (so the force of Eq. 2 is $-\nabla E$);
//! - Hessian block $K = k \left[(1 - r/l)(I - \hat d \hat d^\top) + \hat d \hat d^\top\right]$,
//!   entering as $H_{ii} \mathrel{+}= K$, $H_{jj} \mathrel{+}= K$, $H_{ij} = H_{ji} \mathrel{-}= K$.
//!
//! A compressed spring ($l < r$) makes $K$ indefinite; the *projected* block replaces
//! $(1 - r/l)$ by $\max(0, 1 - r/l)$, which makes every block, hence $H$, positive semi-definite.

use super::SpringSet;

/// A symmetric 3×3 block, row-major.
pub type Block = [[f64; 3]; 3];

#[inline]
fn diff(x: &[f64], i: usize, j: usize) -> [f64; 3] {
    [
        x[3 * i] - x[3 * j],
        x[3 * i + 1] - x[3 * j + 1],
        x[3 * i + 2] - x[3 * j + 2],
    ]
}

/// Total energy $E(x)$ for interpolated rest lengths `rest`.
pub fn energy(springs: &SpringSet, rest: &[f64], x: &[f64]) -> f64 {
    springs
        .springs()
        .iter()
        .enumerate()
        .map(|(q, s)| {
            let d = diff(x, s.i as usize, s.j as usize);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let k = springs.stiffness(q, rest[q]);
            0.5 * k * (l - rest[q]) * (l - rest[q])
        })
        .sum()
}

/// Writes $\nabla E(x)$ into `g` (`3 #V`) and returns $E(x)$.
pub fn gradient(springs: &SpringSet, rest: &[f64], x: &[f64], g: &mut [f64]) -> f64 {
    g.iter_mut().for_each(|v| *v = 0.0);
    let mut e = 0.0;
    for (q, s) in springs.springs().iter().enumerate() {
        let (i, j) = (s.i as usize, s.j as usize);
        let d = diff(x, i, j);
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let r = rest[q];
        let k = springs.stiffness(q, r);
        e += 0.5 * k * (l - r) * (l - r);
        if l > 0.0 {
            let f = k * (l - r) / l;
            for a in 0..3 {
                g[3 * i + a] += f * d[a];
                g[3 * j + a] -= f * d[a];
            }
        }
    }
    e
}

/// Hessian block of one spring with `d = x_i − x_j`; `projected` clamps the transverse
/// coefficient at zero (compressed springs). A zero-length spring gets $k I$, the limit of the
/// projected block's trace-average, so that no NaN can arise.
#[inline]
pub fn spring_block(d: [f64; 3], r: f64, k: f64, projected: bool) -> Block {
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if l <= 1e-300 {
        return [[k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k]];
    }
    let u = [d[0] / l, d[1] / l, d[2] / l];
    let mut t = 1.0 - r / l;
    if projected {
        t = t.max(0.0);
    }
    let mut b = [[0.0; 3]; 3];
    for a in 0..3 {
        for c in 0..3 {
            let uu = u[a] * u[c];
            let id = if a == c { 1.0 } else { 0.0 };
            b[a][c] = k * (t * (id - uu) + uu);
        }
    }
    b
}

/// Calls `f(q, i, j, K)` with the (projected) Hessian block of every spring.
pub fn for_each_block(
    springs: &SpringSet,
    rest: &[f64],
    x: &[f64],
    projected: bool,
    mut f: impl FnMut(usize, usize, usize, &Block),
) {
    for (q, s) in springs.springs().iter().enumerate() {
        let (i, j) = (s.i as usize, s.j as usize);
        let k = springs.stiffness(q, rest[q]);
        let b = spring_block(diff(x, i, j), rest[q], k, projected);
        f(q, i, j, &b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{generate, ShapeSet, Topology};
    use crate::springs::{SpringOptions, StiffnessRule};
    use rand::{Rng, SeedableRng};

    fn setup(rule: StiffnessRule) -> (SpringSet, Vec<f64>, Vec<f64>) {
        let m = generate::tube(0.5, 2.0, 6, 4, true);
        let bent = generate::bend(&m.positions, 1.0, 1.0, 1.5);
        let set = ShapeSet::new(
            m.clone(),
            vec![("a".into(), m.positions.clone()), ("b".into(), bent)],
        )
        .unwrap();
        let topo = Topology::new(m.num_vertices(), &m.triangles);
        let springs = SpringSet::new(
            &set,
            &topo,
            &SpringOptions {
                stiffness: rule,
                k0: 2.5,
                ..Default::default()
            },
        );
        let rest: Vec<f64> = springs
            .rest_lengths(0)
            .iter()
            .zip(springs.rest_lengths(1))
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let x: Vec<f64> = m
            .positions
            .iter()
            .flatten()
            .map(|v| v + rng.random_range(-0.05..0.05))
            .collect();
        (springs, rest, x)
    }

    #[test]
    fn gradient_matches_finite_differences() {
        for rule in [StiffnessRule::InverseRestLength, StiffnessRule::Uniform] {
            let (springs, rest, x) = setup(rule);
            let mut g = vec![0.0; x.len()];
            let e = gradient(&springs, &rest, &x, &mut g);
            assert!((e - energy(&springs, &rest, &x)).abs() < 1e-14 * e.abs().max(1.0));
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            for k in 0..x.len() {
                let mut xp = x.clone();
                let mut xm = x.clone();
                xp[k] += h;
                xm[k] -= h;
                let fd = (energy(&springs, &rest, &xp) - energy(&springs, &rest, &xm)) / (2.0 * h);
                worst = worst.max((fd - g[k]).abs());
            }
            let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                worst < 1e-7 * gmax.max(1.0),
                "gradient FD error {worst} (|g|∞ = {gmax})"
            );
        }
    }

    #[test]
    fn exact_hessian_matches_finite_differences_of_the_gradient() {
        let (springs, rest, x) = setup(StiffnessRule::InverseRestLength);
        let n = x.len();
        // Dense exact Hessian from the blocks.
        let mut hm = vec![vec![0.0; n]; n];
        for_each_block(&springs, &rest, &x, false, |_, i, j, b| {
            for a in 0..3 {
                for c in 0..3 {
                    hm[3 * i + a][3 * i + c] += b[a][c];
                    hm[3 * j + a][3 * j + c] += b[a][c];
                    hm[3 * i + a][3 * j + c] -= b[a][c];
                    hm[3 * j + a][3 * i + c] -= b[a][c];
                }
            }
        });
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        let mut gp = vec![0.0; n];
        let mut gm = vec![0.0; n];
        for k in 0..n {
            let mut xp = x.clone();
            let mut xm = x.clone();
            xp[k] += h;
            xm[k] -= h;
            gradient(&springs, &rest, &xp, &mut gp);
            gradient(&springs, &rest, &xm, &mut gm);
            for r in 0..n {
                let fd = (gp[r] - gm[r]) / (2.0 * h);
                worst = worst.max((fd - hm[r][k]).abs());
            }
        }
        assert!(worst < 1e-6, "Hessian FD error {worst}");
    }

    #[test]
    fn projected_block_is_positive_semidefinite() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            let d = [
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ];
            let r = rng.random_range(0.0..3.0);
            let b = spring_block(d, r, 1.3, true);
            let m = nalgebra::Matrix3::from_fn(|a, c| b[a][c]);
            let eig = m.symmetric_eigenvalues();
            assert!(eig.min() > -1e-12, "eigenvalues {eig}");
        }
        // Unprojected compressed spring is indefinite: the projection matters.
        let b = spring_block([0.5, 0.0, 0.0], 1.0, 1.0, false);
        assert!(b[1][1] < 0.0);
    }
}
