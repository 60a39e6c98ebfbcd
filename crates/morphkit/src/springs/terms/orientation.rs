//! The fold guard: a one-sided penalty on triangles that turn over against a trusted
//! orientation.
//!
//! Springs see only lengths and the signed hinges only dihedral angles, through a residual
//! whose pull vanishes when a hinge is half a turn from its blended angle. Where a target
//! crumples a region (ICT jawLeft presses the lips together at the mouth corner, with dihedral
//! angles of ±150° between small triangles), blended rest lengths that no surface realises can
//! squeeze a triangle through zero area, and the equilibrium keeps it turned over although
//! neither the shapes, the linear blend nor the predictor $P(w)$ fold it.
//!
//! Per frame, each triangle $t = (a, b, c)$ gets a reference $r_t = \hat u_t / |n_t|$: the
//! unit normal $\hat u_t$ it is held to (its normal in $P(w)$, turned towards the shapes'
//! mean normal where $P$'s own triangle is turned against the shapes) over its doubled area
//! $|n_t|$ in $P(w)$; and a trust $\gamma_t \in [0, 1]$, which fades the guard out where the
//! predictor and the linear blend disagree about the triangle (a part turning by about half a
//! turn, where either may be wrong). Both are continuous functions of the weights, computed
//! in `springs::guard_trust`. The signed area ratio
//! $s_t(x) = r_t \cdot \big((b - a) \times (c - a)\big)$ is 1 where the triangle keeps its
//! predicted area and orientation, 0 edge-on, negative turned over. The energy is
//!
//! $$E = \tfrac12\, \kappa \sum_t \gamma_t \min(0,\; s_t - s_0)^2,$$
//!
//! with $\kappa$ = `fold_guard` $\cdot\, \bar k\, \overline{l^2}$ (the hinges' unit) and
//! $s_0 =$ [`GUARD_FROM`]. It is zero wherever a triangle stays within about 84° of its
//! reference at its predicted area, so it leaves other equilibria as they were and the shapes
//! exact. $s$ is bilinear in the corners: $\partial s/\partial b = (c - a) \times r$,
//! $\partial s/\partial c = r \times (b - a)$, $\partial s/\partial a = -(\partial s/\partial b +
//! \partial s/\partial c)$; its second derivatives are the constant blocks $\partial^2
//! s/\partial a\,\partial b = \partial^2 s/\partial b\,\partial c = -[r]_\times$, $\partial^2
//! s/\partial a\,\partial c = [r]_\times$ (and transposes). The projected Hessian is
//! Gauss–Newton, $\kappa\,\gamma_t \nabla s\, \nabla s^\top$.

use super::{BlockHessian, EnergyTerm, HessianKind, TermParameters};
use nalgebra::{Matrix3, Vector3};

/// The signed area ratio below which the guard acts (a triangle turned about 84° from its
/// predicted orientation at its predicted area).
pub const GUARD_FROM: f64 = 0.1;

/// The predictor's and the linear blend's normals of a trusted triangle agree within this
/// cosine (60°), at the corners of the grid its trust is interpolated on.
pub const AGREE_COS: f64 = 0.5;

/// The fold guard of one frame (see the [module docs](self)).
pub(crate) struct OrientationTerm<'a> {
    triangles: &'a [[u32; 3]],
    /// Per triangle: $r = \hat u / |n|$ (zero where unguarded).
    reference: Vec<Vector3<f64>>,
    /// Per triangle: the trust $\gamma \in [0, 1]$.
    trust: Vec<f64>,
    /// κ in absolute units.
    weight: f64,
}

fn v3(x: &[f64], i: u32) -> Vector3<f64> {
    let i = 3 * i as usize;
    Vector3::new(x[i], x[i + 1], x[i + 2])
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

impl<'a> OrientationTerm<'a> {
    /// The guard of `triangles` with per-triangle `reference` $r_t$ (solver coordinates) and
    /// `trust` $\gamma_t$; absolute stiffness `weight`. A triangle with zero trust or reference
    /// is not guarded.
    pub fn new(
        triangles: &'a [[u32; 3]],
        reference: Vec<Vector3<f64>>,
        trust: Vec<f64>,
        weight: f64,
    ) -> Self {
        debug_assert_eq!(reference.len(), triangles.len());
        debug_assert_eq!(trust.len(), triangles.len());
        let reference = reference
            .into_iter()
            .zip(&trust)
            .map(|(r, &g)| if g > 0.0 { r } else { Vector3::zeros() })
            .collect();
        Self {
            triangles,
            reference,
            trust,
            weight,
        }
    }

    /// Per active triangle: its index, $s - s_0 < 0$ and $\nabla s$ at its corners.
    fn active<'b>(
        &'b self,
        x: &'b [f64],
    ) -> impl Iterator<Item = (usize, f64, [Vector3<f64>; 3])> + 'b {
        self.triangles
            .iter()
            .enumerate()
            .filter_map(move |(t, &[a, b, c])| {
                let r = self.reference[t];
                if r == Vector3::zeros() {
                    return None;
                }
                let (a, b, c) = (v3(x, a), v3(x, b), v3(x, c));
                let d = r.dot(&(b - a).cross(&(c - a))) - GUARD_FROM;
                (d < 0.0).then(|| {
                    let gb = (c - a).cross(&r);
                    let gc = r.cross(&(b - a));
                    (t, d, [-(gb + gc), gb, gc])
                })
            })
    }
}

impl EnergyTerm for OrientationTerm<'_> {
    fn name(&self) -> &'static str {
        "fold guard"
    }

    /// The triangles' edges, which the structure springs declare already.
    fn couplings(&self, out: &mut Vec<[u32; 2]>) {
        for &[a, b, c] in self.triangles {
            out.extend([[a, b], [b, c], [c, a]]);
        }
    }

    fn prepare(&self, _c: &[f64]) -> TermParameters {
        TermParameters::default()
    }

    fn energy(&self, _p: &TermParameters, x: &[f64]) -> f64 {
        self.active(x)
            .map(|(t, d, _)| 0.5 * self.weight * self.trust[t] * d * d)
            .sum()
    }

    fn add_gradient(&self, _p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64 {
        let mut e = 0.0;
        for (t, d, grad) in self.active(x) {
            let w = self.weight * self.trust[t];
            e += 0.5 * w * d * d;
            for (&v, gv) in self.triangles[t].iter().zip(&grad) {
                let i = 3 * v as usize;
                for k in 0..3 {
                    g[i + k] += w * d * gv[k];
                }
            }
        }
        e
    }

    fn add_hessian(&self, _p: &TermParameters, x: &[f64], kind: HessianKind, h: &mut BlockHessian) {
        for (t, d, grad) in self.active(x) {
            let tri = self.triangles[t];
            let rx = skew(&self.reference[t]);
            let w = self.weight * self.trust[t];
            for i in 0..3 {
                for j in i..3 {
                    let mut m = grad[i] * grad[j].transpose() * w;
                    if kind == HessianKind::Exact {
                        // ∂²s/∂(corner i)∂(corner j), i < j: a–b and b–c −[r]×, a–c [r]×.
                        let sign = match (i, j) {
                            (0, 1) | (1, 2) => -1.0,
                            (0, 2) => 1.0,
                            _ => 0.0,
                        };
                        m += rx * (sign * w * d);
                    }
                    let b: [[f64; 3]; 3] =
                        std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
                    h.add(tri[i] as usize, tri[j] as usize, &b);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::check::{assert_projected_psd, dense_hessian, gradient_error, hessian_error};
    use super::*;
    use crate::mesh::generate;

    /// A flat grid (the predictor) with each triangle's own reference, and the same grid with
    /// interior vertex 5, at (⅓, ⅓), pushed across its neighbours: the triangles around it
    /// turn over.
    type Setup = (Vec<[u32; 3]>, Vec<Vector3<f64>>, Vec<f64>, Vec<f64>);

    fn setup() -> Setup {
        let m = generate::grid(3, 3, 1.0, 1.0);
        let flat: Vec<f64> = m.positions.iter().flatten().copied().collect();
        let mut x = flat.clone();
        x[15] += 0.9;
        x[16] += 0.7;
        x[17] += 0.05;
        let reference = m
            .triangles
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a, b, c].map(|v| Vector3::from(m.positions[v as usize]));
                let n = (b - a).cross(&(c - a));
                n / n.norm_squared()
            })
            .collect();
        (m.triangles, reference, flat, x)
    }

    #[test]
    fn zero_on_the_predictor_and_positive_where_triangles_turn_over() {
        let (tris, reference, flat, x) = setup();
        let n = tris.len();
        let term = OrientationTerm::new(&tris, reference.clone(), vec![1.0; n], 2.0);
        let p = TermParameters::default();
        assert_eq!(term.energy(&p, &flat), 0.0);
        let full = term.energy(&p, &x);
        assert!(full > 0.0);
        assert!(term.active(&x).count() >= 1);
        // The trust scales each triangle's share; with none, nothing is guarded.
        let half = OrientationTerm::new(&tris, reference.clone(), vec![0.5; n], 2.0);
        assert!((half.energy(&p, &x) - 0.5 * full).abs() <= 1e-12 * full);
        let off = OrientationTerm::new(&tris, reference, vec![0.0; n], 2.0);
        assert_eq!(off.energy(&p, &x), 0.0);
        assert_eq!(off.active(&x).count(), 0);
    }

    #[test]
    fn gradient_and_exact_hessian_match_finite_differences() {
        let (tris, reference, _, x) = setup();
        let trust = (0..tris.len()).map(|t| 0.25 + 0.04 * t as f64).collect();
        let term = OrientationTerm::new(&tris, reference, trust, 2.0);
        let p = TermParameters::default();
        let (err, gmax) = gradient_error(&term, &p, &x);
        assert!(
            gmax > 0.0 && err < 1e-7 * gmax.max(1.0),
            "FD error {err}, |g| {gmax}"
        );
        let exact = dense_hessian(&term, &p, &x, HessianKind::Exact);
        let worst = hessian_error(&term, &p, &x, &exact);
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            scale > 0.0 && worst < 1e-5 * scale,
            "Hessian error {worst} of {scale}"
        );
        // Gauss–Newton: symmetric positive semi-definite.
        assert_projected_psd(&term, &p, &x);
    }
}
