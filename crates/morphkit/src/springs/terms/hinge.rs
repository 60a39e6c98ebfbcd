//! Signed hinges: a bending term that tells a fold up from a fold down.
//!
//! Distance springs see only lengths; a 2-ring spring across an edge sees only $\cos\theta$ of
//! the dihedral angle, so a thin, weakly coupled region can mirror itself at no cost and the
//! blend crumples (the project's blend-design notes, §2). Following discrete shells (Grinspun et
//! al. 2003) and the dihedral-angle interpolation of Fröhlich & Botsch 2011, each interior edge
//! gets a hinge whose rest angle is the blended *signed* dihedral angle.
//!
//! For an edge $e = (a, b)$ with opposite vertices $c$ and $d$, define
//! $n_1 = (b - a) \times (c - a)$ and $n_2 = (d - a) \times (b - a)$ (the two face normals of a
//! consistently oriented mesh, unnormalised; the definition is geometric, so it does not depend
//! on the file's face orientation), $\hat e = (b - a)/\lVert b - a\rVert$, and the signed angle
//! $\theta = \operatorname{atan2}(\hat e \cdot (n_1 \times n_2),\, n_1 \cdot n_2)$.
//! Per shape $s$ this gives $\theta^s$ (unwrapped to within $\pi$ of $\theta^0$) and normal
//! lengths $\lVert n^s_{1,2}\rVert$; blending gives $\bar\Theta = \sum_s c_s \theta^s$ and
//! $\beta_{1,2} = \sum_s c_s \lVert n^s_{1,2}\rVert$. The residual
//!
//! $$\rho = n_2/\beta_2 - (\cos\bar\Theta\, n_1 + \sin\bar\Theta\, \hat e \times n_1)/\beta_1$$
//!
//! is zero exactly when the current hinge has angle $\bar\Theta$ and the blended normal lengths,
//! is invariant under rigid motions, penalises mirror flips ($|\rho|^2 \approx 2 - 2\cos(\theta -
//! \bar\Theta)$) and has no singularity at degenerate triangles (unlike a raw `atan2` penalty).
//! The energy is $E_h = \mu\, b_h \lVert\rho\rVert^2$ with $b_h = \lVert e\rVert^2/(A_1 + A_2)$ on
//! the base (capped at `max_shape_factor`) and $\mu = c\, \overline{k}\, \overline{l^2}$ (mean
//! structure-spring stiffness and squared length on the base), so `weight` $= c$ is unit-free.
//! The projected Hessian is Gauss–Newton, $2 \mu b_h J^\top J$ (positive semi-definite); the
//! exact one adds the second-order part in closed form.
//!
//! A hinge is left out where its dihedral angle is ill defined in the base: a face of (nearly)
//! zero area, an edge of zero length, or a fold within `min_fold_margin` of ±π. Where it is ill
//! defined only in some targets, it fades out with their largest weight $m$ (issue 40: a frame
//! must not depend on targets at weight 0): its energy is scaled by $((r - m)/r)^2$ for
//! $m < r$ and is zero from $m = r$ on, $r$ the rig's hold ramp ([`HingeTerm::fading`]); such
//! a target's angle and normal lengths are the measured ones at a fold, the base's at a
//! degenerate face.

use super::{
    Block, BlockHessian, BlockPattern, EnergyTerm, HessianKind, PairSlots, TermParameters,
};
use crate::mesh::{ShapeSet, Topology};
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::PI;

/// Options of the signed-hinge term.
#[derive(Clone, Debug, PartialEq)]
pub struct HingeOptions {
    /// Hinge weight $c$ relative to the springs (unit-free). `0` disables hinges. Default
    /// `0.01`: enough to break the mirror symmetry that lets thin regions crumple, small
    /// enough to leave the spring equilibrium otherwise unchanged (blend-design §2).
    pub weight: f64,
    /// Hinges whose fold comes within this angle (radians) of ±π in some shape are left out.
    /// Default `0.17` (about 10°).
    pub min_fold_margin: f64,
    /// Cap on the shape factor $b_h = \lVert e\rVert^2/(A_1+A_2)$ (about 1.15 for equilateral
    /// triangles). Default `10`.
    pub max_shape_factor: f64,
}

impl Default for HingeOptions {
    fn default() -> Self {
        Self {
            weight: 0.01,
            min_fold_margin: 0.17,
            max_shape_factor: 10.0,
        }
    }
}

/// The signed hinges of a shape set. Parameters: per hinge `[cos Θ̄, sin Θ̄, 1/β₁, 1/β₂]`.
pub struct HingeTerm {
    /// `[a, b, c, d]` per hinge.
    hinges: Vec<[u32; 4]>,
    /// `μ b_h` per hinge.
    weight: Vec<f64>,
    /// Per shape, per hinge: unwrapped angle, |n₁|, |n₂|.
    angle: Vec<Vec<f64>>,
    len1: Vec<Vec<f64>>,
    len2: Vec<Vec<f64>>,
    /// Floors for extrapolated normal lengths.
    floor1: Vec<f64>,
    floor2: Vec<f64>,
    /// The blocks of each hinge's six pairs (`PAIRS` order) in the solver's pattern.
    slots: PairSlots,
    /// `(hinge, shape)`: the targets in which a hinge's angle is ill defined, by hinge.
    ill: Vec<(u32, u32)>,
    /// The weight over which a hinge fades out with such a target.
    ramp: f64,
}

/// The corner pairs `(u, v)`, `u < v`, of a hinge `[a, b, c, d]`, in the order of its slots:
/// `(u, v)` is at `u (7 − u) / 2 + v − u − 1`.
const PAIRS: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

fn v3(x: &[f64], i: u32) -> Vector3<f64> {
    let i = 3 * i as usize;
    Vector3::new(x[i], x[i + 1], x[i + 2])
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Normals and signed angle of hinge `h` at positions `x` (flattened).
fn measure(x: &[f64], h: [u32; 4]) -> (f64, f64, f64, f64) {
    let [a, b, c, d] = h.map(|v| v3(x, v));
    let e = b - a;
    let n1 = e.cross(&(c - a));
    let n2 = (d - a).cross(&e);
    let le = e.norm();
    let theta = if le > 0.0 {
        (e.dot(&n1.cross(&n2)) / le).atan2(n1.dot(&n2))
    } else {
        0.0
    };
    (theta, n1.norm(), n2.norm(), le)
}

impl HingeTerm {
    /// Builds the hinges of every interior manifold edge of `topology`, measured in every
    /// shape. `mean_stiffness` and `mean_square_length` give $\mu$ (module doc).
    pub fn new(
        shapes: &ShapeSet,
        topology: &Topology,
        options: &HingeOptions,
        mean_stiffness: f64,
        mean_square_length: f64,
    ) -> Self {
        let tris = shapes.triangles();
        let flat: Vec<Vec<f64>> = shapes
            .all_positions()
            .iter()
            .map(|p| p.iter().flatten().copied().collect())
            .collect();
        let diag = crate::mesh::bbox_diagonal(shapes.positions(0)).max(f64::MIN_POSITIVE);
        let area_eps = 1e-12 * diag * diag;
        let mu = options.weight * mean_stiffness * mean_square_length;
        let mut out = Self {
            hinges: Vec::new(),
            weight: Vec::new(),
            angle: vec![Vec::new(); shapes.len()],
            len1: vec![Vec::new(); shapes.len()],
            len2: vec![Vec::new(); shapes.len()],
            floor1: Vec::new(),
            floor2: Vec::new(),
            slots: PairSlots::default(),
            ill: Vec::new(),
            ramp: 0.05,
        };
        if mu <= 0.0 {
            return out;
        }
        'edges: for (k, &[a, b]) in topology.edges().iter().enumerate() {
            let faces = topology.edge_faces(k);
            if faces.len() != 2 {
                continue;
            }
            let opposite = |f: u32| tris[f as usize].iter().copied().find(|&v| v != a && v != b);
            let (Some(c), Some(d)) = (opposite(faces[0]), opposite(faces[1])) else {
                continue;
            };
            if c == d {
                continue;
            }
            let h = [a, b, c, d];
            let mut m = Vec::with_capacity(shapes.len());
            let mut ill = Vec::new();
            for (s, x) in flat.iter().enumerate() {
                let (theta, l1, l2, le) = measure(x, h);
                let degenerate = l1 <= area_eps || l2 <= area_eps || le <= 1e-12 * diag;
                if degenerate || theta.abs() > PI - options.min_fold_margin {
                    if s == 0 {
                        continue 'edges;
                    }
                    ill.push(s as u32);
                }
                m.push(if degenerate { m[0] } else { (theta, l1, l2) });
            }
            let theta0 = m[0].0;
            let (_, l1, l2, le) = measure(&flat[0], h);
            let shape_factor = (2.0 * le * le / (l1 + l2)).min(options.max_shape_factor);
            let k = out.hinges.len() as u32;
            out.ill.extend(ill.iter().map(|&s| (k, s)));
            out.hinges.push(h);
            out.weight.push(mu * shape_factor);
            let (mut lo1, mut lo2) = (f64::INFINITY, f64::INFINITY);
            for (s, &(theta, l1, l2)) in m.iter().enumerate() {
                let mut d = theta - theta0;
                d -= (2.0 * PI) * (d / (2.0 * PI)).round();
                out.angle[s].push(theta0 + d);
                out.len1[s].push(l1);
                out.len2[s].push(l2);
                if !ill.contains(&(s as u32)) {
                    lo1 = lo1.min(l1);
                    lo2 = lo2.min(l2);
                }
            }
            out.floor1.push(0.05 * lo1);
            out.floor2.push(0.05 * lo2);
        }
        out
    }

    /// Hinges ill defined in a target fade out as its weight goes from 0 to `ramp` (module
    /// doc). Default `0.05`.
    pub fn fading(mut self, ramp: f64) -> Self {
        self.ramp = ramp;
        self
    }

    /// Whether hinge `k`'s angle is well defined in every shape with a nonzero coefficient
    /// in `c` (it always is in the base).
    pub fn defined_at(&self, k: usize, c: &[f64]) -> bool {
        let from = self.ill.partition_point(|&(h, _)| (h as usize) < k);
        self.ill[from..]
            .iter()
            .take_while(|&&(h, _)| h as usize == k)
            .all(|&(_, s)| c.get(s as usize).is_none_or(|&w| w == 0.0))
    }

    /// Number of hinges.
    pub fn len(&self) -> usize {
        self.hinges.len()
    }
    /// True when there are no hinges.
    pub fn is_empty(&self) -> bool {
        self.hinges.is_empty()
    }
    /// The hinges `[a, b, c, d]` (edge `ab`, opposite vertices `c`, `d`).
    pub fn hinges(&self) -> &[[u32; 4]] {
        &self.hinges
    }
    /// Blended signed dihedral angle of every hinge for coefficients `c`.
    pub fn blended_angles(&self, c: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.hinges.len()];
        for (s, &w) in c.iter().enumerate() {
            if w != 0.0 {
                for (o, t) in out.iter_mut().zip(&self.angle[s]) {
                    *o += w * t;
                }
            }
        }
        out
    }
    /// Signed dihedral angle of hinge `k` at positions `x`.
    pub fn angle_at(&self, x: &[f64], k: usize) -> f64 {
        measure(x, self.hinges[k]).0
    }
}

type P3 = [f64; 3];

#[inline(always)]
fn p3(x: &[f64], i: u32) -> P3 {
    let i = 3 * i as usize;
    [x[i], x[i + 1], x[i + 2]]
}

#[inline(always)]
fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `f` applied to each coordinate.
#[inline(always)]
fn each(f: impl Fn(usize) -> f64) -> P3 {
    [f(0), f(1), f(2)]
}

/// One hinge's quantities that ρ and its adjoint share, with parameters `q`
/// $= [\cos\bar\Theta, \sin\bar\Theta, \beta_1^{-1}, \beta_2^{-1}]$ at corners `[a, b, c, d]`:
/// $e = b - a$, $u_1 = c - a$, $u_2 = d - a$, $\lVert e\rVert$ and its inverse, $\hat e$,
/// $n_1 = e \times u_1$.
struct Geometry {
    q: [f64; 4],
    e: P3,
    u1: P3,
    u2: P3,
    le: f64,
    il: f64,
    eh: P3,
    n1: P3,
}

impl Geometry {
    #[inline(always)]
    fn new(q: &[f64], [a, b, c, d]: [P3; 4]) -> Self {
        let e = each(|i| b[i] - a[i]);
        let le = dot(e, e).sqrt().max(f64::MIN_POSITIVE);
        let il = 1.0 / le;
        let u1 = each(|i| c[i] - a[i]);
        Self {
            q: [q[0], q[1], q[2], q[3]],
            e,
            u1,
            u2: each(|i| d[i] - a[i]),
            le,
            il,
            eh: each(|i| e[i] * il),
            n1: cross(e, u1),
        }
    }

    /// $\rho = \beta_2^{-1} n_2 - \beta_1^{-1}(\cos\bar\Theta\, n_1 + \sin\bar\Theta\, \hat e
    /// \times n_1)$ with $n_2 = u_2 \times e$.
    #[inline(always)]
    fn rho(&self) -> P3 {
        let [cs, sn, ib1, ib2] = self.q;
        let n2 = cross(self.u2, self.e);
        let t = cross(self.eh, self.n1);
        each(|i| n2[i] * ib2 - (self.n1[i] * cs + t[i] * sn) * ib1)
    }

    /// $J_u^\top r$ per corner $u$ (the Jacobian of ρ transposed, applied to `r`), by
    /// reverse-mode differentiation of [`Self::rho`]: the adjoints are
    /// $\bar n_2 = \beta_2^{-1} r$, $\bar m = -\beta_1^{-1} r$,
    /// $\bar n_1 = \cos\bar\Theta\, \bar m + \sin\bar\Theta\, \bar m \times \hat e$,
    /// $\bar{\hat e} = \sin\bar\Theta\, n_1 \times \bar m$, then
    /// $\bar e = (I - \hat e \hat e^\top)\bar{\hat e} / \lVert e\rVert + \bar n_2 \times u_2 +
    /// u_1 \times \bar n_1$, $\bar u_1 = \bar n_1 \times e$, $\bar u_2 = e \times \bar n_2$;
    /// the corners get $(-\bar e - \bar u_1 - \bar u_2,\ \bar e,\ \bar u_1,\ \bar u_2)$. It
    /// equals the Jacobian's 3×3 blocks written out (the tests' oracle) applied to `r`, in
    /// about half the arithmetic (ICT's 80k hinges: 5.7 → 3.6 ms per gradient).
    #[inline(always)]
    fn pull(&self, r: P3) -> [P3; 4] {
        let [cs, sn, ib1, ib2] = self.q;
        let (e, eh) = (self.e, self.eh);
        let gn2 = each(|i| r[i] * ib2);
        let gm = each(|i| -r[i] * ib1);
        let gme = cross(gm, eh);
        let gn1 = each(|i| gm[i] * cs + gme[i] * sn);
        let geh = cross(self.n1, gm);
        let along = dot(eh, geh);
        let (x2, x1) = (cross(gn2, self.u2), cross(self.u1, gn1));
        let ge = each(|i| (geh[i] - eh[i] * along) * (sn * self.il) + x2[i] + x1[i]);
        let gu1 = cross(gn1, e);
        let gu2 = cross(e, gn2);
        let ga = each(|i| -(ge[i] + gu1[i] + gu2[i]));
        [ga, ge, gu1, gu2]
    }

    /// The Jacobian's rows: `rows[i][u]` is $J_u^\top e_i$.
    #[inline(always)]
    fn jacobian_rows(&self) -> [[P3; 4]; 3] {
        std::array::from_fn(|i| self.pull(each(|k| if k == i { 1.0 } else { 0.0 })))
    }
}

/// `w m` as a block (`m` scaled first, then copied: the rounding of every caller is the same).
fn weighted(m: &Matrix3<f64>, w: f64) -> Block {
    let m = m * w;
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

/// A Hessian and, when known, the slots of one hinge's six pairs in it (`PAIRS` order).
type Target<'a, 'b> = (&'a mut BlockHessian, Option<&'b [u32]>);

/// Adds block `b` of corners `(u, v)`, `u ≤ v`, of hinge `hv` to `h`.
#[inline]
fn add_corner_block(h: &mut Target<'_, '_>, hv: [u32; 4], u: usize, v: usize, b: &Block) {
    let (i, j) = (hv[u] as usize, hv[v] as usize);
    if u == v {
        return h.0.add(i, i, b);
    }
    // Index of (u, v) in PAIRS.
    let slot = h.1.map(|s| s[u * (7 - u) / 2 + v - u - 1]);
    h.0.add_pair(slot, i, j, b);
}

/// $J_u^\top J_v$ of one hinge from its Jacobian's rows ([`Geometry::jacobian_rows`]); the
/// projected Hessian and the fused one take it from here, so that both have the same bits.
#[inline(always)]
fn jtj(rows: &[[P3; 4]; 3], u: usize, v: usize) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| {
        rows[0][u][r] * rows[0][v][c]
            + rows[1][u][r] * rows[1][v][c]
            + rows[2][u][r] * rows[2][v][c]
    })
}

/// Adds $w (J^\top J + M^\top H_y M)$ of one hinge to `exact` (`hy` holds the second-order
/// blocks in the edge variables $(e, u_1, u_2) = (b - a, c - a, d - a)$, mapped to the corners
/// by $M$) and, when given, the Gauss–Newton blocks $w J^\top J$ alone to `projected`.
fn add_block_pairs(
    mut projected: Option<Target<'_, '_>>,
    mut exact: Target<'_, '_>,
    hv: [u32; 4],
    rows: &[[P3; 4]; 3],
    hy: &[[Matrix3<f64>; 3]; 3],
    w: f64,
) {
    // M^T H_y M at the corners: b, c, d are the edge variables e, u1, u2, and a is minus
    // their sum, so the (a, ·) blocks are minus column sums of H_y and (a, a) is its total.
    let col: [Matrix3<f64>; 3] = std::array::from_fn(|q| hy[0][q] + hy[1][q] + hy[2][q]);
    let total = col[0] + col[1] + col[2];
    for u in 0..4 {
        for v in u..4 {
            let jtj = jtj(rows, u, v);
            if let Some(ph) = projected.as_mut() {
                add_corner_block(ph, hv, u, v, &weighted(&jtj, w));
            }
            let second = match (u, v) {
                (0, 0) => total,
                (0, v) => -col[v - 1],
                (u, v) => hy[u - 1][v - 1],
            };
            add_corner_block(&mut exact, hv, u, v, &weighted(&(jtj + second), w));
        }
    }
}

impl EnergyTerm for HingeTerm {
    fn name(&self) -> &'static str {
        "hinges"
    }

    fn couplings(&self, out: &mut Vec<[u32; 2]>) {
        for h in &self.hinges {
            out.extend(PAIRS.iter().map(|&(u, v)| [h[u], h[v]]));
        }
    }

    fn bind(&mut self, pattern: &std::sync::Arc<BlockPattern>) {
        let pairs = self
            .hinges
            .iter()
            .flat_map(|h| PAIRS.iter().map(move |&(u, v)| [h[u], h[v]]));
        self.slots = PairSlots::new(pattern, pairs);
    }

    fn prepare(&self, c: &[f64]) -> TermParameters {
        let m = self.hinges.len();
        let theta = self.blended_angles(c);
        let (mut b1, mut b2) = (vec![0.0; m], vec![0.0; m]);
        for (s, &w) in c.iter().enumerate() {
            if w != 0.0 {
                for k in 0..m {
                    b1[k] += w * self.len1[s][k];
                    b2[k] += w * self.len2[s][k];
                }
            }
        }
        // √ of each hinge's fade: ρ is linear in (1/β₁, 1/β₂), so scaling both scales E by
        // the fade.
        let mut fade = vec![1.0; m];
        for &(k, s) in &self.ill {
            let w = c.get(s as usize).map_or(0.0, |w| w.abs());
            let f = ((self.ramp - w) / self.ramp).max(0.0);
            fade[k as usize] = f64::min(fade[k as usize], f);
        }
        let mut values = Vec::with_capacity(4 * m);
        let mut clamped = 0;
        for k in 0..m {
            if b1[k] < self.floor1[k] || b2[k] < self.floor2[k] {
                clamped += 1;
            }
            values.extend_from_slice(&[
                theta[k].cos(),
                theta[k].sin(),
                fade[k] / b1[k].max(self.floor1[k]),
                fade[k] / b2[k].max(self.floor2[k]),
            ]);
        }
        TermParameters { values, clamped }
    }

    fn energy(&self, p: &TermParameters, x: &[f64]) -> f64 {
        let terms = self.hinges.iter().zip(p.values.chunks_exact(4));
        terms
            .zip(&self.weight)
            .map(|((h, q), w)| {
                let rho = Geometry::new(q, h.map(|v| p3(x, v))).rho();
                w * dot(rho, rho)
            })
            .sum()
    }

    fn add_gradient(&self, p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64 {
        let mut e = 0.0;
        for (k, (h, q)) in self.hinges.iter().zip(p.values.chunks_exact(4)).enumerate() {
            let hinge = Geometry::new(q, h.map(|v| p3(x, v)));
            let rho = hinge.rho();
            let jt_rho = hinge.pull(rho);
            let w = self.weight[k];
            e += w * dot(rho, rho);
            for (v, jv) in h.iter().zip(&jt_rho) {
                let i = 3 * *v as usize;
                g[i] += jv[0] * (2.0 * w);
                g[i + 1] += jv[1] * (2.0 * w);
                g[i + 2] += jv[2] * (2.0 * w);
            }
        }
        e
    }

    fn add_hessian(&self, p: &TermParameters, x: &[f64], kind: HessianKind, h: &mut BlockHessian) {
        if kind == HessianKind::Exact {
            return self.add_exact_hessian(p, x, h);
        }
        let slots = self.slots.get(h);
        for (k, (&hv, q)) in self.hinges.iter().zip(p.values.chunks_exact(4)).enumerate() {
            let rows = Geometry::new(q, hv.map(|v| p3(x, v))).jacobian_rows();
            let w = 2.0 * self.weight[k];
            let mut target = (&mut *h, slots.map(|s| &s[6 * k..6 * k + 6]));
            for u in 0..4 {
                for v in u..4 {
                    add_corner_block(&mut target, hv, u, v, &weighted(&jtj(&rows, u, v), w));
                }
            }
        }
    }

    fn add_hessians(
        &self,
        p: &TermParameters,
        x: &[f64],
        projected: &mut BlockHessian,
        exact: &mut BlockHessian,
    ) {
        let (sp, se) = (self.slots.get(projected), self.slots.get(exact));
        for (k, (&hv, q)) in self.hinges.iter().zip(p.values.chunks_exact(4)).enumerate() {
            let geometry = Geometry::new(q, hv.map(|v| p3(x, v)));
            let hy = Self::second_order(&geometry, &geometry.rho().into());
            add_block_pairs(
                Some((&mut *projected, sp.map(|s| &s[6 * k..6 * k + 6]))),
                (&mut *exact, se.map(|s| &s[6 * k..6 * k + 6])),
                hv,
                &geometry.jacobian_rows(),
                &hy,
                2.0 * self.weight[k],
            );
        }
    }
}

#[path = "hinge_exact.rs"]
mod exact;

#[cfg(test)]
#[path = "hinge_tests.rs"]
mod tests;
