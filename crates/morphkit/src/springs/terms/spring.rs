//! Distance springs with blended rest lengths (Ma et al. 2012, Eq. 1–5 and Sec. 3.5, with the
//! corrected Hessian of the math notes §1; the paper's Eq. 5 as printed is wrong).
//!
//! For spring $q = (i, j)$ with $d = x_i - x_j$, $l = \lVert d\rVert$, $\hat d = d / l$, rest
//! length $\bar r = \sum_s c_s r^s$ and stiffness $k$:
//!
//! - energy $E_q = \tfrac12 k (l - \bar r)^2$;
//! - gradient $\partial E_q / \partial x_i = k (l - \bar r) \hat d = -\partial E_q / \partial x_j$;
//! - Hessian block $K = k \left[(1 - \bar r/l)(I - \hat d \hat d^\top) + \hat d \hat d^\top\right]$
//!   at $(i,i)$ and $(j,j)$, $-K$ at $(i,j)$. The projected block clamps $(1 - \bar r/l)$ at 0.
//!
//! Stiffness is $k_q = k_0 s_q / \max(\bar r_q, f \max_s r^s_q)$ for the paper's
//! $k = k_0 / \bar r$ rule ($s_q$ = 1, or the bending multiplier; $f$ = `min_rest_fraction`),
//! so a spring that shrinks to nothing in some shape keeps a finite stiffness. The rest length
//! is clamped below at $f \min_s r^s_q$; convex weights never reach that floor, so a one-hot
//! weight vector reproduces that shape's rest lengths exactly. Only extrapolated weights clamp,
//! and the count is reported.

use super::{BlockHessian, EnergyTerm, HessianKind, PairSlots, TermParameters};
use crate::springs::{SpringSet, StiffnessRule};

/// The springs of a [`SpringSet`] as an energy term. Parameters: `[r̄ (m) | k (m)]`.
pub struct SpringTerm {
    set: SpringSet,
    rest_floor: Vec<f64>,
    stiffness_floor: Vec<f64>,
    /// The block of each spring in the solver's pattern.
    slots: PairSlots,
}

impl SpringTerm {
    /// Wraps `set`; `min_rest_fraction` is the `f` of the module doc.
    pub fn new(set: SpringSet, min_rest_fraction: f64) -> Self {
        let m = set.len();
        let mut lo = vec![f64::INFINITY; m];
        let mut hi = vec![0.0f64; m];
        for s in 0..set.num_shapes() {
            for (q, &r) in set.rest_lengths(s).iter().enumerate() {
                lo[q] = lo[q].min(r);
                hi[q] = hi[q].max(r);
            }
        }
        Self {
            rest_floor: lo.iter().map(|v| min_rest_fraction * v).collect(),
            stiffness_floor: hi
                .iter()
                .map(|v| (min_rest_fraction * v).max(f64::MIN_POSITIVE * 1e10))
                .collect(),
            set,
            slots: PairSlots::default(),
        }
    }

    /// The spring set.
    pub fn set(&self) -> &SpringSet {
        &self.set
    }
}

#[inline]
fn diff(x: &[f64], i: usize, j: usize) -> [f64; 3] {
    [
        x[3 * i] - x[3 * j],
        x[3 * i + 1] - x[3 * j + 1],
        x[3 * i + 2] - x[3 * j + 2],
    ]
}

/// Hessian block of one spring with `d = x_i − x_j`; `projected` clamps the transverse
/// coefficient at zero. A zero-length spring gets $k I$ (the limit of the projected block's
/// trace average), so that no NaN can arise.
#[inline]
pub fn spring_block(d: [f64; 3], r: f64, k: f64, projected: bool) -> super::Block {
    match direction(d, r) {
        None => k_identity(k),
        Some((u, t)) => block(u, k, if projected { t.max(0.0) } else { t }),
    }
}

/// Both blocks of [`spring_block`] at once: `(projected, exact)`.
fn spring_blocks(d: [f64; 3], r: f64, k: f64) -> (super::Block, super::Block) {
    match direction(d, r) {
        None => (k_identity(k), k_identity(k)),
        Some((u, t)) => {
            let exact = block(u, k, t);
            let projected = if t >= 0.0 { exact } else { block(u, k, 0.0) };
            (projected, exact)
        }
    }
}

/// The unit direction of `d` and the transverse coefficient $1 - \bar r / l$; `None` for a
/// spring of zero length.
#[inline]
fn direction(d: [f64; 3], r: f64) -> Option<([f64; 3], f64)> {
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (l > 1e-300).then(|| ([d[0] / l, d[1] / l, d[2] / l], 1.0 - r / l))
}

#[inline]
fn k_identity(k: f64) -> super::Block {
    [[k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k]]
}

/// $k \left[t (I - u u^\top) + u u^\top\right]$.
#[inline]
fn block(u: [f64; 3], k: f64, t: f64) -> super::Block {
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

/// Adds spring block `b` at `(i, i)`, `(j, j)` and `−b` at `(i, j)` (whose block is `slot`
/// when known).
#[inline]
fn scatter(h: &mut BlockHessian, slot: Option<u32>, i: usize, j: usize, b: &super::Block) {
    h.add(i, i, b);
    h.add(j, j, b);
    h.add_pair(slot, i, j, &b.map(|row| row.map(|v| -v)));
}

impl EnergyTerm for SpringTerm {
    fn name(&self) -> &'static str {
        "springs"
    }

    fn couplings(&self, out: &mut Vec<[u32; 2]>) {
        out.extend(self.set.springs().iter().map(|s| [s.i, s.j]));
    }

    fn bind(&mut self, pattern: &std::sync::Arc<super::BlockPattern>) {
        self.slots = PairSlots::new(pattern, self.set.springs().iter().map(|s| [s.i, s.j]));
    }

    fn prepare(&self, c: &[f64]) -> TermParameters {
        let m = self.set.len();
        let mut values = vec![0.0; 2 * m];
        let (rest, k) = values.split_at_mut(m);
        for (s, &w) in c.iter().enumerate() {
            if w != 0.0 {
                for (v, r) in rest.iter_mut().zip(self.set.rest_lengths(s)) {
                    *v += w * r;
                }
            }
        }
        let mut clamped = 0;
        let inverse = self.set.options().stiffness == StiffnessRule::InverseRestLength;
        for q in 0..m {
            if rest[q] < self.rest_floor[q] {
                rest[q] = self.rest_floor[q];
                clamped += 1;
            }
            let scale = self.set.stiffness_scale(q);
            k[q] = if inverse {
                scale / rest[q].max(self.stiffness_floor[q])
            } else {
                scale
            };
        }
        TermParameters { values, clamped }
    }

    fn energy(&self, p: &TermParameters, x: &[f64]) -> f64 {
        let m = self.set.len();
        let (rest, k) = p.values.split_at(m);
        self.set
            .springs()
            .iter()
            .enumerate()
            .map(|(q, s)| {
                let d = diff(x, s.i as usize, s.j as usize);
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                0.5 * k[q] * (l - rest[q]) * (l - rest[q])
            })
            .sum()
    }

    fn add_gradient(&self, p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64 {
        let m = self.set.len();
        let (rest, k) = p.values.split_at(m);
        let mut e = 0.0;
        for (q, s) in self.set.springs().iter().enumerate() {
            let (i, j) = (s.i as usize, s.j as usize);
            let d = diff(x, i, j);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let r = rest[q];
            e += 0.5 * k[q] * (l - r) * (l - r);
            if l > 0.0 {
                let f = k[q] * (l - r) / l;
                for a in 0..3 {
                    g[3 * i + a] += f * d[a];
                    g[3 * j + a] -= f * d[a];
                }
            }
        }
        e
    }

    fn add_hessian(&self, p: &TermParameters, x: &[f64], kind: HessianKind, h: &mut BlockHessian) {
        let m = self.set.len();
        let (rest, k) = p.values.split_at(m);
        let projected = kind == HessianKind::Projected;
        let slots = self.slots.get(h);
        for (q, s) in self.set.springs().iter().enumerate() {
            let (i, j) = (s.i as usize, s.j as usize);
            let slot = slots.as_ref().map(|v| v[q]);
            let b = spring_block(diff(x, i, j), rest[q], k[q], projected);
            scatter(h, slot, i, j, &b);
        }
    }

    fn add_hessians(
        &self,
        p: &TermParameters,
        x: &[f64],
        projected: &mut BlockHessian,
        exact: &mut BlockHessian,
    ) {
        let m = self.set.len();
        let (rest, k) = p.values.split_at(m);
        let (sp, se) = (self.slots.get(projected), self.slots.get(exact));
        for (q, s) in self.set.springs().iter().enumerate() {
            let (i, j) = (s.i as usize, s.j as usize);
            let (bp, be) = spring_blocks(diff(x, i, j), rest[q], k[q]);
            scatter(projected, sp.as_ref().map(|v| v[q]), i, j, &bp);
            scatter(exact, se.as_ref().map(|v| v[q]), i, j, &be);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::check::{
        bound_hessians_match, dense_hessian, fused_hessians_match, gradient_error, hessian_error,
    };
    use super::*;
    use crate::mesh::{generate, ShapeSet, Topology};
    use crate::springs::SpringOptions;
    use rand::{Rng, SeedableRng};

    fn setup(rule: StiffnessRule) -> (SpringTerm, TermParameters, Vec<f64>) {
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
        let term = SpringTerm::new(springs, 0.05);
        let p = term.prepare(&[0.5, 0.5]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let x: Vec<f64> = m
            .positions
            .iter()
            .flatten()
            .map(|v| v + rng.random_range(-0.05..0.05))
            .collect();
        (term, p, x)
    }

    #[test]
    fn gradient_and_exact_hessian_match_finite_differences() {
        for rule in [StiffnessRule::InverseRestLength, StiffnessRule::Uniform] {
            let (term, p, x) = setup(rule);
            let (err, gmax) = gradient_error(&term, &p, &x);
            assert!(err < 1e-7 * gmax.max(1.0), "gradient FD error {err}");
        }
        let (term, p, x) = setup(StiffnessRule::InverseRestLength);
        // Both Hessians in one pass equal two separate passes, bit for bit.
        assert!(fused_hessians_match(&term, &p, &x));
        // Blocks placed by the slots of `bind` are the blocks placed by searching.
        let mut bound = term;
        assert!(bound_hessians_match(&mut bound, &p, &x));
        let term = bound;
        let hm = dense_hessian(&term, &p, &x, HessianKind::Exact);
        let worst = hessian_error(&term, &p, &x, &hm);
        assert!(worst < 1e-6, "Hessian FD error {worst}");
    }

    #[test]
    fn projected_block_is_positive_semidefinite_and_exact_is_not() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            let d = [
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ];
            let b = spring_block(d, rng.random_range(0.0..3.0), 1.3, true);
            let m = nalgebra::Matrix3::from_fn(|a, c| b[a][c]);
            assert!(m.symmetric_eigenvalues().min() > -1e-12);
        }
        let b = spring_block([0.5, 0.0, 0.0], 1.0, 1.0, false);
        assert!(b[1][1] < 0.0);
    }

    #[test]
    fn one_hot_weights_reproduce_each_shape_unclamped() {
        let (term, _, _) = setup(StiffnessRule::InverseRestLength);
        for s in 0..2 {
            let mut c = [0.0; 2];
            c[s] = 1.0;
            let p = term.prepare(&c);
            assert_eq!(p.clamped, 0);
            assert_eq!(&p.values[..term.set().len()], term.set().rest_lengths(s));
        }
        let p = term.prepare(&[40.0, -39.0]);
        assert!(p.values.iter().all(|v| *v > 0.0 && v.is_finite()));
    }
}
