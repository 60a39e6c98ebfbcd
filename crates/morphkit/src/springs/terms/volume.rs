//! Volume of tetrahedra held near a blended value (issue 40, "Volume under twist"; an addition
//! to Ma et al. 2012, whose internal springs alone do not hold the volume under a large shear).
//!
//! For tetrahedron $t = (a, b, c, d)$ with signed volume
//! $V_t(x) = \tfrac16 (x_b - x_a) \cdot \big((x_c - x_a) \times (x_d - x_a)\big)$,
//! positive in the base, the energy is
//!
//! $$E_t = \tfrac12 k_t \big(V_t(x) - \bar V_t\big)^2, \qquad
//! \bar V_t = \rho_g(c) \sum_s c_s V^s_t, \qquad
//! k_t = \kappa\, k_0 \,/\, \ell_t^5,\quad \ell_t = \tfrac12 \max\Big(\sum_s c_s L^s_t,\ f \max_s L^s_t\Big),$$
//!
//! with $L^s_t$ the mean edge length of the tetrahedron in shape $s$: for a regular one
//! ($\sqrt[3]{V} = 0.49 L$) that is $\tfrac12 \kappa k_0 \ell_t (V_t / \bar V_t - 1)^2$, per unit
//! of relative volume change the energy of a spring of length $\ell_t$ per unit of strain
//! (Sec. 3.5's $k_0 / \bar r$). Edge lengths, not the volume, set the scale, so that a sliver
//! (a shell wedge flat in the base) is no stiffer against moving its vertices than a spring
//! of its size; with $\ell_t^3 \sim V_t$ a sliver's stiffness grows like $(L / \ell)^5$ and the
//! Newton iteration stalls (measured on a capped tube).
//! Each tetrahedron's volume is interpolated linearly, so that tetrahedra that tile a solid in
//! every shape have blended volumes summing to its interpolated volume, even where single
//! tetrahedra flatten or turn over between the shapes. The factor
//!
//! $$\rho_g(c) = \Big(\sum_s c_s \sqrt[3]{W^s_g}\Big)^3 \Big/ \sum_s c_s W^s_g, \qquad
//! W^s_g = \sum_{t \in g} V^s_t,$$
//!
//! per group $g$ of connected tetrahedra (a solid), makes the group's total follow its blended
//! length scale, as the springs interpolate lengths: under a similarity between the shapes
//! the springs' equilibrium already has that volume and the term exerts no force (without
//! $\rho$ a blend of a shape and its double would be pushed to $\tfrac92$ of the volume where the
//! springs give $\tfrac{27}{8}$). It acts where the interpolated rest lengths are not the
//! lengths of any shape of that volume: a shear, whose blended rest lengths are too long (see
//! docs/fidelity.md "Volume under twist"). For a twist $\rho = 1$. One-hot weights give
//! $\bar V_t = V^s_t$ exactly.
//!
//! Gradient: with $e_1 = x_b - x_a$, $e_2 = x_c - x_a$, $e_3 = x_d - x_a$,
//! $\partial V / \partial x_b = \tfrac16 e_2 \times e_3$, $\partial V/\partial x_c = \tfrac16
//! e_3 \times e_1$, $\partial V / \partial x_d = \tfrac16 e_1 \times e_2$, and $\partial V /
//! \partial x_a$ minus their sum. Hessian: $k_t \nabla V \nabla V^\top$ (the projected,
//! Gauss–Newton one) plus, exact only, $k_t (V - \bar V) \nabla^2 V$, whose blocks are
//! cross-product matrices (zero on the diagonal).

use super::{Block, BlockHessian, EnergyTerm, HessianKind, TermParameters};
use crate::mesh::{Point, ShapeSet};

/// Tetrahedra whose volumes are held near their blended value. Parameters:
/// `[V̄ (m) | k (m)]`.
pub struct VolumeTerm {
    tets: Vec<[u32; 4]>,
    /// Group (connected tetrahedra) of each tetrahedron.
    group: Vec<u32>,
    /// Per shape, per group: $W^s_g$.
    totals: Vec<Vec<f64>>,
    /// Per shape, per tetrahedron: its signed volume.
    volumes: Vec<Vec<f64>>,
    /// Per shape, per tetrahedron: its mean edge length $L^s_t$.
    edges: Vec<Vec<f64>>,
    /// $f \max_s L^s_t$.
    floor: Vec<f64>,
    /// $\kappa k_0$.
    stiffness: f64,
}

impl VolumeTerm {
    /// The tetrahedra `tets` (vertex ids of `shapes`, any orientation) with stiffness
    /// `stiffness` ($\kappa k_0$); `min_fraction` is the $f$ of the module doc. Tetrahedra flat
    /// in every shape are left out.
    pub fn new(shapes: &ShapeSet, tets: &[[u32; 4]], stiffness: f64, min_fraction: f64) -> Self {
        let all: Vec<Vec<f64>> = shapes
            .all_positions()
            .iter()
            .map(|p| tets.iter().map(|&t| signed_volume(p, t)).collect())
            .collect();
        let diag = crate::mesh::bbox_diagonal(shapes.positions(0)).max(f64::MIN_POSITIVE);
        let eps = 1e-12 * diag * diag * diag;
        // Left out: tetrahedra flat in every shape, and those turned over in some shape
        // against the base (a reverse-solved interior can hold such; interpolating a signed
        // volume through zero would turn them over in the blend too).
        let keep: Vec<usize> = (0..tets.len())
            .filter(|&t| all.iter().any(|v| v[t].abs() > eps))
            .filter(|&t| all.iter().all(|v| v[t] * all[0][t] >= 0.0))
            .collect();
        // Positive in the base.
        let sign: Vec<f64> = keep
            .iter()
            .map(|&t| if all[0][t] < 0.0 { -1.0 } else { 1.0 })
            .collect();
        let tets: Vec<[u32; 4]> = keep
            .iter()
            .zip(&sign)
            .map(|(&t, &s)| {
                let [a, b, c, d] = tets[t];
                if s < 0.0 {
                    [a, b, d, c]
                } else {
                    [a, b, c, d]
                }
            })
            .collect();
        let volumes: Vec<Vec<f64>> = all
            .iter()
            .map(|v| keep.iter().zip(&sign).map(|(&t, &s)| s * v[t]).collect())
            .collect();
        let (group, groups) = groups(&tets);
        let totals = volumes
            .iter()
            .map(|v| {
                let mut w = vec![0.0; groups];
                for (t, x) in v.iter().enumerate() {
                    w[group[t] as usize] += x;
                }
                w
            })
            .collect();
        let edges: Vec<Vec<f64>> = shapes
            .all_positions()
            .iter()
            .map(|p| tets.iter().map(|&t| mean_edge(p, t)).collect())
            .collect();
        let floor = (0..tets.len())
            .map(|t| {
                let m = edges.iter().fold(0.0f64, |m, v| m.max(v[t]));
                (min_fraction * m).max(f64::MIN_POSITIVE)
            })
            .collect();
        Self {
            tets,
            group,
            totals,
            volumes,
            edges,
            floor,
            stiffness,
        }
    }

    /// The tetrahedra, positively oriented in the base.
    pub fn tetrahedra(&self) -> &[[u32; 4]] {
        &self.tets
    }
}

/// The connected groups of `tets` (sharing a vertex): each one's group and the count.
fn groups(tets: &[[u32; 4]]) -> (Vec<u32>, usize) {
    let n = tets
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut v: usize) -> usize {
        while p[v] != v {
            p[v] = p[p[v]];
            v = p[v];
        }
        v
    }
    for t in tets {
        for k in 1..4 {
            let (a, b) = (
                root(&mut parent, t[0] as usize),
                root(&mut parent, t[k] as usize),
            );
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut id = vec![u32::MAX; n];
    let mut count = 0;
    let group = tets
        .iter()
        .map(|t| {
            let r = root(&mut parent, t[0] as usize);
            if id[r] == u32::MAX {
                id[r] = count;
                count += 1;
            }
            id[r]
        })
        .collect();
    (group, count as usize)
}

/// Mean length of the six edges of `t` at positions `p`.
fn mean_edge(p: &[Point], t: [u32; 4]) -> f64 {
    let mut sum = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            sum += crate::mesh::norm(crate::mesh::sub(p[t[i] as usize], p[t[j] as usize]));
        }
    }
    sum / 6.0
}

/// Signed volume of tetrahedron `t` at positions `p`.
fn signed_volume(p: &[Point], t: [u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(|v| p[v as usize]);
    let e = |q: Point| [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
    crate::mesh::dot(e(b), crate::mesh::cross(e(c), e(d))) / 6.0
}

#[inline]
fn corner(x: &[f64], v: u32) -> [f64; 3] {
    let i = 3 * v as usize;
    [x[i], x[i + 1], x[i + 2]]
}

/// Volume and its gradient per corner.
#[inline]
fn volume_gradient(x: &[f64], t: [u32; 4]) -> (f64, [[f64; 3]; 4], [[f64; 3]; 3]) {
    let a = corner(x, t[0]);
    let e = [1, 2, 3].map(|k| {
        let q = corner(x, t[k]);
        [q[0] - a[0], q[1] - a[1], q[2] - a[2]]
    });
    let cr = crate::mesh::cross;
    let gb = cr(e[1], e[2]).map(|v| v / 6.0);
    let gc = cr(e[2], e[0]).map(|v| v / 6.0);
    let gd = cr(e[0], e[1]).map(|v| v / 6.0);
    let ga = [0, 1, 2].map(|k| -(gb[k] + gc[k] + gd[k]));
    // As in `signed_volume`, so that a shape's own volume is reproduced to the bit.
    let v = crate::mesh::dot(e[0], cr(e[1], e[2])) / 6.0;
    (v, [ga, gb, gc, gd], e)
}

/// $s [u]_\times$.
#[inline]
fn skew(u: [f64; 3], s: f64) -> Block {
    [
        [0.0, -s * u[2], s * u[1]],
        [s * u[2], 0.0, -s * u[0]],
        [-s * u[1], s * u[0], 0.0],
    ]
}

impl VolumeTerm {
    fn hessian(&self, p: &TermParameters, x: &[f64], exact: bool, h: &mut BlockHessian) {
        let m = self.tets.len();
        let (target, k) = p.values.split_at(m);
        for (q, &t) in self.tets.iter().enumerate() {
            let (v, g, e) = volume_gradient(x, t);
            for i in 0..4 {
                for j in i..4 {
                    let mut b = [[0.0; 3]; 3];
                    for r in 0..3 {
                        for c in 0..3 {
                            b[r][c] = k[q] * g[i][r] * g[j][c];
                        }
                    }
                    if exact && i != j {
                        // ∂²V/∂x_i∂x_j (times 6): [x_l − x_k]× for the other two corners (k, l)
                        // in the orientation of (i, j, k, l) even.
                        let s = k[q] * (v - target[q]) / 6.0;
                        let w = cross_block(&e, i, j);
                        let c = skew(w, s);
                        for r in 0..3 {
                            for cc in 0..3 {
                                b[r][cc] += c[r][cc];
                            }
                        }
                    }
                    h.add(t[i] as usize, t[j] as usize, &b);
                }
            }
        }
    }
}

/// The vector $w$ with $6\, \partial^2 V / \partial x_i \partial x_j = [w]_\times$, $i < j$.
#[inline]
fn cross_block(e: &[[f64; 3]; 3], i: usize, j: usize) -> [f64; 3] {
    let d = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let z = [0.0; 3];
    let x = [z, e[0], e[1], e[2]]; // corners relative to corner 0
    match (i, j) {
        (0, 1) => d(x[2], x[3]),
        (0, 2) => d(x[3], x[1]),
        (0, 3) => d(x[1], x[2]),
        (1, 2) => d(z, x[3]),
        (1, 3) => x[2],
        (2, 3) => d(z, x[1]),
        _ => z,
    }
}

impl EnergyTerm for VolumeTerm {
    fn name(&self) -> &'static str {
        "volume"
    }

    fn couplings(&self, out: &mut Vec<[u32; 2]>) {
        for t in &self.tets {
            for i in 0..4 {
                for j in i + 1..4 {
                    out.push([t[i], t[j]]);
                }
            }
        }
    }

    fn prepare(&self, c: &[f64]) -> TermParameters {
        let m = self.tets.len();
        let mut values = vec![0.0; 2 * m];
        let (target, k) = values.split_at_mut(m);
        let nonzero: Vec<usize> = (0..c.len()).filter(|&s| c[s] != 0.0).collect();
        if let [s] = nonzero[..] {
            // One shape (c_s = 1, the weights being affine): its volumes, exactly.
            let w = c[s];
            target
                .iter_mut()
                .zip(&self.volumes[s])
                .for_each(|(v, x)| *v = w * x);
        } else {
            for &s in &nonzero {
                for (v, x) in target.iter_mut().zip(&self.volumes[s]) {
                    *v += c[s] * x;
                }
            }
            let groups = self.totals[0].len();
            let rho: Vec<f64> = (0..groups)
                .map(|g| {
                    let (mut lin, mut root) = (0.0, 0.0);
                    for &s in &nonzero {
                        lin += c[s] * self.totals[s][g];
                        root += c[s] * self.totals[s][g].cbrt();
                    }
                    let r = root * root * root / lin;
                    if r.is_finite() && r > 0.0 {
                        r
                    } else {
                        1.0
                    }
                })
                .collect();
            for (v, g) in target.iter_mut().zip(&self.group) {
                *v *= rho[*g as usize];
            }
        }
        for (q, k) in k.iter_mut().enumerate() {
            let mut l = 0.0;
            for &s in &nonzero {
                l += c[s] * self.edges[s][q];
            }
            let l = 0.5 * l.max(self.floor[q]);
            *k = self.stiffness / (l * l * l * l * l);
        }
        TermParameters { values, clamped: 0 }
    }

    fn energy(&self, p: &TermParameters, x: &[f64]) -> f64 {
        let m = self.tets.len();
        let (target, k) = p.values.split_at(m);
        self.tets
            .iter()
            .enumerate()
            .map(|(q, &t)| {
                let a = corner(x, t[0]);
                let e = [1, 2, 3].map(|j| {
                    let b = corner(x, t[j]);
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
                });
                let v = crate::mesh::dot(e[0], crate::mesh::cross(e[1], e[2])) / 6.0;
                0.5 * k[q] * (v - target[q]) * (v - target[q])
            })
            .sum()
    }

    fn add_gradient(&self, p: &TermParameters, x: &[f64], g: &mut [f64]) -> f64 {
        let m = self.tets.len();
        let (target, k) = p.values.split_at(m);
        let mut e = 0.0;
        for (q, &t) in self.tets.iter().enumerate() {
            let (v, dv, _) = volume_gradient(x, t);
            let r = v - target[q];
            e += 0.5 * k[q] * r * r;
            let f = k[q] * r;
            for (corner, d) in t.iter().zip(&dv) {
                let i = 3 * *corner as usize;
                for a in 0..3 {
                    g[i + a] += f * d[a];
                }
            }
        }
        e
    }

    fn add_hessian(&self, p: &TermParameters, x: &[f64], kind: HessianKind, h: &mut BlockHessian) {
        self.hessian(p, x, kind == HessianKind::Exact, h);
    }
}

#[cfg(test)]
#[path = "volume_tests.rs"]
mod tests;
