//! What the fold guard ([`terms::orientation`](super::terms::orientation)) holds each triangle
//! to in a frame, and how firmly: two functions of the coefficients that are *continuous* in
//! them, so that the guard cannot make a frame jump (issue 54; docs/choices.md, "Continuity in
//! the weights").
//!
//! **Trust** $\gamma_t(c) \in [0, 1]$ scales triangle $t$'s guard. Where the rotation-aware
//! prediction and the linear blend disagree about a triangle's orientation (normals more than
//! 60° apart, [`AGREE_COS`]), neither is trusted, and the guard lets it go. Deciding that at
//! $c$ itself made the guarded set a step function of the weights: a triangle held at the
//! guard's wall was caught or released in one step (ICT jawOpen at 0.27, 16.8× the linear
//! step; jawLeft at 0.49). Instead the agreement $A_t$ (0 or 1) is taken at the corners of the
//! grid of step $1/$[`TRUST_GRID`] in $c_1, \dots, c_n$ (the base's $c_0 = 1 - \sum c_s$) and
//! interpolated over Freudenthal's simplices, the piecewise-linear interpolation through
//! $k + 1$ corners for $k$ nonzero coefficients:
//!
//! $$\gamma_t(c) = h\Big(\sum_{i=0}^{k} \lambda_i\, A_t(c^{(i)})\Big),
//! \qquad h(u) = u^2 (3 - 2u),$$
//!
//! with $c^{(0)} = \lfloor g c \rfloor / g$, $c^{(i)} = c^{(i-1)} + e_{\pi(i)}/g$ in the order
//! $\pi$ of decreasing fractional parts $f$ of $g c$, and $\lambda_0 = 1 - f_{\pi(1)}$,
//! $\lambda_i = f_{\pi(i)} - f_{\pi(i+1)}$. A zero coefficient adds no corner, so the trust
//! depends on the nonzero weights alone; at grid points it is the agreement itself. The
//! smoothstep $h$ makes a triangle's guard fade in and out with zero slope: measured, the
//! linear interpolation alone left 8.6× steps at jawLeft 0.5, where a guard of 1 % of its
//! stiffness already moves the mouth corner.
//!
//! **Reference.** The guard holds a triangle to its orientation in the predictor $P$, except
//! where $P$'s own triangle is turned against the shapes that make the frame (ICT
//! mouthSmile_L's mouth corner and cheekPuff_L near the rest, where $P$ is folded and the
//! linear blend $L$ is not). With $m_t$ the mean cosine between $P$'s normal and the active
//! shapes' (weighted by $|c_s|$), $\beta = h(\operatorname{clamp}(2 m_t + 1, 0, 1))$ (1 where
//! $P$ agrees with the shapes on average, 0 where it is turned more than about 120° from
//! them) and $a = \min(1, |n_L| / |n_P|)$ (how far $L$ keeps the triangle's area), the
//! reference direction is
//!
//! $$\big(1 - (1-\beta)\,a^2\big)\,\hat n_P + (1-\beta)\,a^2\,\hat n_L \quad\text{normalised}:$$
//!
//! $L$'s normal where $P$ is turned and $L$ keeps the triangle, $P$'s wherever $L$ collapses
//! it. A collapsing $L$ swings its normals fast (the kinking tube's end: turning fully to
//! $\hat n_L$ dragged two vertices at 4–8× the linear step over a whole key), and where a part
//! turns by half a turn it has none worth trusting.

use super::predictor;
use super::rig::Rig;
use super::terms::AGREE_COS;
use crate::mesh::{Point, ShapeSet};
use nalgebra::{Matrix3, Vector3};

/// The grid on which the guard's trust is decided and between whose corners it is
/// interpolated: steps of ¼ in each coefficient. Measured on ICT and the kinking tube
/// (docs/choices.md): ⅛ made the tube's snap a run of 30 steps of 5–14×; ½ and ⅓ passed
/// every sweep but took 33–63 Newton iterations a frame at the tube's snap.
pub const TRUST_GRID: f64 = 4.0;

fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

fn normal_of(p: &[Point], [a, b, c]: [u32; 3]) -> Vector3<f64> {
    let q = |v: u32| Vector3::from(p[v as usize]);
    (q(b) - q(a)).cross(&(q(c) - q(a)))
}

/// Whether normals `a` and `b` lie within 60° of each other (0 or 1; 0 where either is
/// degenerate).
fn agree(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    f64::from(u8::from(a.dot(b) > AGREE_COS * a.norm() * b.norm()))
}

/// The corners of the Freudenthal simplex holding `c[1..]` on the grid of step `1/g`, with
/// their barycentric weights (only those above zero); each corner's `c[0]` is `1 − Σ c[1..]`.
pub(crate) fn freudenthal_corners(c: &[f64], g: f64) -> Vec<(Vec<f64>, f64)> {
    let mut dims: Vec<(usize, f64, f64)> = (1..c.len())
        .filter(|&s| c[s] != 0.0)
        .map(|s| {
            let b = (c[s] * g).floor();
            (s, b, c[s] * g - b)
        })
        .collect();
    dims.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
    let mut corner = vec![0.0; c.len()];
    for &(s, b, _) in &dims {
        corner[s] = b / g;
    }
    let frac = |i: usize| dims.get(i).map_or(0.0, |d| d.2);
    let mut out = Vec::with_capacity(dims.len() + 1);
    let mut push = |corner: &[f64], lambda: f64| {
        if lambda > 0.0 {
            let mut at = corner.to_vec();
            at[0] = 1.0 - at[1..].iter().sum::<f64>();
            out.push((at, lambda));
        }
    };
    push(&corner, 1.0 - frac(0));
    for i in 0..dims.len() {
        corner[dims[i].0] += 1.0 / g;
        push(&corner, frac(i) - frac(i + 1));
    }
    out
}

impl Rig {
    /// Per triangle: whether the rotation-aware prediction and the linear blend at `c` agree
    /// about its orientation (1) or not (0).
    fn agreement(&self, c: &[f64]) -> Vec<f64> {
        let lin = predictor::linear(&self.shapes, c);
        let holds = self.holds.targets(c, &lin);
        let rotated = self.rotation_prediction(c, &lin, &holds);
        let world = rotated.as_deref().unwrap_or(&lin);
        self.shapes
            .triangles()
            .iter()
            .map(|&t| agree(&normal_of(world, t), &normal_of(&lin, t)))
            .collect()
    }

    /// The guard's trust $\gamma_t(c)$ of every triangle (see the [module docs](self)).
    pub(super) fn guard_trust(&self, c: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.shapes.triangles().len()];
        for (corner, lambda) in freudenthal_corners(c, TRUST_GRID) {
            for (o, a) in out.iter_mut().zip(self.agreement(&corner)) {
                *o += lambda * a;
            }
        }
        out.iter_mut().for_each(|g| *g = smoothstep(*g));
        out
    }
}

/// The rigid rotation taking triangle `t` of `from` onto its place in `to` (the identity where
/// the triangle is degenerate): solver coordinates differ from world ones by a rotation per
/// gauged component.
fn rotation_of(from: &[Point], to: &[Point], t: [u32; 3]) -> Matrix3<f64> {
    let frame = |p: &[Point]| {
        let q = |v: u32| Vector3::from(p[v as usize]);
        let (e1, e2) = (q(t[1]) - q(t[0]), q(t[2]) - q(t[0]));
        Matrix3::from_columns(&[e1, e2, e1.cross(&e2)])
    };
    frame(from)
        .try_inverse()
        .map(|inv| frame(to) * inv)
        .filter(|r| r.iter().all(|x| x.is_finite()))
        .unwrap_or_else(Matrix3::identity)
}

/// Per triangle, the guard's reference $r = \hat u / |n_P|$ in solver coordinates (see the
/// [module docs](self)), zero where $P$'s triangle is degenerate. `predicted`: $P$ in solver
/// coordinates (`3 #V`); `predicted_world`: the same in world coordinates; `c`: the
/// coefficients of `shapes`.
pub(super) fn guard_references(
    shapes: &ShapeSet,
    c: &[f64],
    predicted: &[f64],
    predicted_world: &[Point],
    lin: &[Point],
) -> Vec<Vector3<f64>> {
    let solver: Vec<Point> = predicted
        .chunks_exact(3)
        .map(|v| [v[0], v[1], v[2]])
        .collect();
    shapes
        .triangles()
        .iter()
        .map(|&t| {
            let n = normal_of(&solver, t);
            let l2 = n.norm_squared();
            if !(l2 > 0.0 && l2.is_finite()) {
                return Vector3::zeros();
            }
            let np = normal_of(predicted_world, t);
            let (mut num, mut den) = (0.0, 0.0);
            for (s, &cs) in c.iter().enumerate().filter(|(_, &cs)| cs != 0.0) {
                let ns = normal_of(shapes.positions(s), t);
                let cos = np.dot(&ns) / (np.norm() * ns.norm());
                if cos.is_finite() {
                    num += cs.abs() * cos;
                    den += cs.abs();
                }
            }
            let beta = if den > 0.0 {
                smoothstep(2.0 * num / den + 1.0)
            } else {
                1.0
            };
            let unit = n / l2.sqrt();
            let dir = if beta < 1.0 {
                // m: L's unit normal (in solver coordinates) times a = min(1, |n_L| / |n_P|).
                let nl = rotation_of(predicted_world, &solver, t) * normal_of(lin, t);
                let a = (nl.norm() / np.norm()).min(1.0);
                match nl.try_normalize(0.0) {
                    Some(m) if a.is_finite() => {
                        let tau = (1.0 - beta) * a;
                        ((1.0 - tau * a) * unit + tau * a * m)
                            .try_normalize(0.0)
                            .unwrap_or(unit)
                    }
                    _ => unit,
                }
            } else {
                unit
            };
            dir / l2.sqrt()
        })
        .collect()
}

#[cfg(test)]
#[path = "guard_trust_tests.rs"]
mod tests;
