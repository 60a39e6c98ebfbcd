//! A rotation-aware predictor: Poisson shape interpolation of the shapes' deformation
//! gradients (Alexa et al. 2000; Xu et al. 2005, "Poisson shape interpolation").
//!
//! Per triangle $t$ and shape $s$, the deformation gradient from the base, $D_{s,t}$
//! ([`GradientOperator`]), is split by polar decomposition into $R_{s,t} S_{s,t}$
//! ([`polar_decomposition`]). For coefficients $c$ the blended gradient is
//!
//! $$\bar D_t = \exp\Big(\sum_s c_s \log R_{s,t}\Big)\, \Big(c_0 I + \sum_{s \ge 1} c_s S_{s,t}\Big),$$
//!
//! rotations blended in the log map (on one branch along the surface, below), stretches
//! linearly, and one prefactored Poisson solve ([`TransferSolver`], the same system as
//! deformation transfer) gives positions whose gradients best match $\bar D$. Each connected
//! component is then placed rigidly: onto its fixed vertices where it has some, else onto the
//! linear blend. At one-hot weights $\bar D$ is the shape's own gradient and the solve
//! reproduces the shape exactly (up to round-off), so endpoints stay exact; in between, a jaw
//! or a leg that turns by θ is predicted turned by about αθ instead of cut short along the
//! chord as by the linear blend.
//!
//! **The branch of each log.** A rotation by θ about $a$ is also one by $θ - 2π$ about $a$
//! (and by $θ + 2πk$ for every $k$), and the blend depends on the choice: by ½ it turns by
//! $θ/2$ one way or $π - θ/2$ the other. Taking each triangle's principal log (angle ≤ π) on
//! its own splits a part that turns by about π, as a tail curled over the back does, where
//! neighbouring triangles land on different sides of π: the blended gradients then disagree
//! by up to π across an edge and the prediction is twisted (a curled tube at ½: up to 25
//! triangles facing against both shapes and 130° of twist between two rings, where the
//! linear blend has 0–2). So the logs of each shape are put on one branch along the surface
//! ([`consistent_logs`]): flooded over triangle adjacency from the triangles that turn least
//! (the fixed or still region), each triangle takes the $θ + 2πk$ nearest to the mean of its
//! already assigned neighbours, the way phase unwrapping follows the most reliable pixels
//! first. A part that turns by 190° is then predicted turned by 95° at ½, the same way round
//! as the parts it hangs from. Every branch has the same exponential, so one-hot weights
//! still give each shape's own gradients.
//!
//! Vertices that no triangle uses (the interior and anchor vertices of a volumetric blend,
//! issue 11) have no gradient. The Poisson solve runs on the triangulated surface alone, and
//! each such vertex $y$ is carried by the weighted Kabsch motion $K$ of its nearest surface
//! vertices from the base to the predicted surface (the reverse solve's guess,
//! [`Neighbourhoods`]), plus the blend of what that guess misses in each shape:
//! $y(c) = K_{P(c)}(y^0) + \sum_s c_s \big(y^s - K_{x^s}(y^0)\big)$. At one-hot weights this
//! is $y^s$ (the reverse-solved position), so endpoints stay exact; a bent interior follows the
//! bend instead of the linear blend's chord.

use super::constraints::Components;
use super::interior::reverse::Neighbourhoods;
use crate::geom::{kabsch, polar_decomposition};
use crate::mesh::{sub, Point, ShapeSet, Topology, TriMesh};
use crate::transfer::{GradientOperator, SolverOptions, TransferSolver};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Prefactored Poisson interpolation of a shape set.
pub(crate) struct RotationPredictor {
    solver: TransferSolver,
    /// Per shape ≥ 1, per triangle: log-rotation vector (on one branch along the surface,
    /// [`consistent_logs`]) and stretch.
    logs: Vec<Vec<Vector3<f64>>>,
    stretches: Vec<Vec<Matrix3<f64>>>,
    members: Vec<Vec<u32>>,
    /// The triangulated vertices, in the order of the Poisson solve's unknowns.
    surface: Vec<u32>,
    /// The other vertices, carried by their surface neighbourhoods (module doc).
    carried: Option<Carried>,
}

/// Vertices without triangles and how they follow the surface.
struct Carried {
    vertices: Vec<u32>,
    near: Neighbourhoods,
    /// Base positions: the surface (solve order), then the carried vertices.
    surface_base: Vec<Point>,
    carried_base: Vec<Point>,
    /// Per shape: each carried vertex's offset from its guess, $y^s - K_{x^s}(y^0)$.
    residuals: Vec<Vec<Point>>,
}

impl RotationPredictor {
    /// Gradients, polar factors and the factorization of the triangulated vertices, and the
    /// neighbourhoods of the others (module doc); `None` when the base surface cannot carry a
    /// Poisson solve (no triangles, say), and the linear blend is used instead.
    /// `topology` is that of `shapes`' triangles.
    pub fn new(shapes: &ShapeSet, topology: &Topology, components: &Components) -> Option<Self> {
        let n = shapes.num_vertices();
        let mut used = vec![false; n];
        shapes
            .triangles()
            .iter()
            .flatten()
            .for_each(|&v| used[v as usize] = true);
        let (surface, vertices): (Vec<u32>, Vec<u32>) =
            (0..n as u32).partition(|&v| used[v as usize]);
        let mut local = vec![u32::MAX; n];
        for (k, &v) in surface.iter().enumerate() {
            local[v as usize] = k as u32;
        }
        let restrict =
            |p: &[Point]| -> Vec<Point> { surface.iter().map(|&v| p[v as usize]).collect() };
        let tris: Vec<[u32; 3]> = shapes
            .triangles()
            .iter()
            .map(|t| t.map(|v| local[v as usize]))
            .collect();
        let base = TriMesh::new(restrict(shapes.positions(0)), tris);
        let solver = TransferSolver::new(&base, &SolverOptions::default()).ok()?;
        let op = GradientOperator::new(&base);
        let (mut logs, mut stretches) = (Vec::new(), Vec::new());
        for s in 1..shapes.len() {
            let grads = op.gradients(&restrict(shapes.positions(s))).ok()?;
            let (mut l, mut st) = (
                Vec::with_capacity(grads.len()),
                Vec::with_capacity(grads.len()),
            );
            for d in &grads {
                let (r, sm) = polar_decomposition(d);
                let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
                l.push(q.scaled_axis());
                st.push(sm);
            }
            consistent_logs(&mut l, |t| topology.face_neighbors(t));
            logs.push(l);
            stretches.push(st);
        }
        let mut members = vec![Vec::new(); components.count];
        for (v, &c) in components.label.iter().enumerate() {
            members[c as usize].push(v as u32);
        }
        let carried = (!vertices.is_empty()).then(|| {
            let pick =
                |p: &[Point]| -> Vec<Point> { vertices.iter().map(|&v| p[v as usize]).collect() };
            let surface_base = base.positions.clone();
            let carried_base = pick(shapes.positions(0));
            let near = Neighbourhoods::new(&surface_base, &carried_base);
            let residuals = (0..shapes.len())
                .map(|s| {
                    let guess =
                        near.guess(&surface_base, &restrict(shapes.positions(s)), &carried_base);
                    let own = pick(shapes.positions(s));
                    own.iter().zip(&guess).map(|(&y, &g)| sub(y, g)).collect()
                })
                .collect();
            Carried {
                vertices,
                near,
                surface_base,
                carried_base,
                residuals,
            }
        });
        Some(Self {
            solver,
            logs,
            stretches,
            members,
            surface,
            carried,
        })
    }

    /// The predicted world positions for coefficients `c`; `lin` is the linear blend, whose
    /// values the `fixed` vertices take.
    pub fn predict(&self, c: &[f64], lin: &[Point], fixed: &[bool]) -> Option<Vec<Point>> {
        let nt = self.solver.num_triangles();
        let mut grads = Vec::with_capacity(nt);
        for t in 0..nt {
            let mut w = Vector3::zeros();
            let mut st = Matrix3::identity() * c[0];
            for s in 1..c.len() {
                if c[s] != 0.0 {
                    w += self.logs[s - 1][t] * c[s];
                    st += self.stretches[s - 1][t] * c[s];
                }
            }
            let r = UnitQuaternion::from_scaled_axis(w).to_rotation_matrix();
            grads.push(r.matrix() * st);
        }
        let solved = self.solver.solve(&grads).ok()?;
        let mut p = lin.to_vec();
        for (&v, &x) in self.surface.iter().zip(&solved) {
            p[v as usize] = x;
        }
        if let Some(k) = &self.carried {
            let guess = k.near.guess(&k.surface_base, &solved, &k.carried_base);
            for (i, (&v, g)) in k.vertices.iter().zip(guess).enumerate() {
                let mut y = g;
                for (s, &w) in c.iter().enumerate() {
                    if w != 0.0 {
                        let r = k.residuals[s][i];
                        y = [y[0] + w * r[0], y[1] + w * r[1], y[2] + w * r[2]];
                    }
                }
                p[v as usize] = y;
            }
        }
        for comp in &self.members {
            let anchor: Vec<u32> = comp
                .iter()
                .copied()
                .filter(|&v| fixed[v as usize])
                .collect();
            let use_fixed = anchor.len() >= 3;
            let verts = if use_fixed { &anchor } else { comp };
            let from: Vec<Point> = verts.iter().map(|&v| p[v as usize]).collect();
            let to: Vec<Point> = verts.iter().map(|&v| lin[v as usize]).collect();
            let fit = kabsch(&from, &to, &[]);
            for &v in comp {
                p[v as usize] = if fixed[v as usize] {
                    lin[v as usize]
                } else {
                    fit.apply(p[v as usize])
                };
            }
        }
        p.iter().flatten().all(|v| v.is_finite()).then_some(p)
    }
}

/// Puts the per-triangle rotation logs `logs` (principal: angle ≤ π) on one branch along the
/// surface (module doc): in each connected part (over `neighbours`, the triangles sharing an
/// edge), starting from the triangle that turns least, triangles are taken in the order of
/// their own angle among those next to an assigned one, and each becomes the
/// $(θ + 2πk)\,a$ nearest to the mean of its assigned neighbours. Deterministic: ties go to
/// the lower index. The exponential of every log is unchanged.
pub(crate) fn consistent_logs<'a>(
    logs: &mut [Vector3<f64>],
    neighbours: impl Fn(usize) -> &'a [u32],
) {
    use std::f64::consts::TAU;
    let n = logs.len();
    // Angles are ≥ 0, so their bit patterns sort like the angles.
    let key = |t: usize, logs: &[Vector3<f64>]| Reverse((logs[t].norm().to_bits(), t as u32));
    let mut seeds: Vec<(u64, u32)> = (0..n).map(|t| key(t, logs).0).collect();
    seeds.sort_unstable();
    let mut assigned = vec![false; n];
    let mut heap = BinaryHeap::new();
    for (_, seed) in seeds {
        if assigned[seed as usize] {
            continue;
        }
        // The seed keeps its principal log.
        heap.push(Reverse((0, seed)));
        while let Some(Reverse((_, t))) = heap.pop() {
            let t = t as usize;
            if assigned[t] {
                continue;
            }
            let (mut mean, mut count) = (Vector3::zeros(), 0usize);
            for &m in neighbours(t) {
                if assigned[m as usize] {
                    mean += logs[m as usize];
                    count += 1;
                }
            }
            if count > 0 {
                mean /= count as f64;
                let w = logs[t];
                let angle = w.norm();
                // Near the identity the axis is the neighbours' (a whole turn about any axis
                // is the identity too).
                let axis = if angle > 1e-9 {
                    w / angle
                } else if mean.norm() > 0.0 {
                    mean.normalize()
                } else {
                    Vector3::zeros()
                };
                // argmin over k of |(θ + 2πk) a − mean|: θ + 2πk nearest to a · mean.
                let k = ((axis.dot(&mean) - angle) / TAU).round();
                if k != 0.0 {
                    logs[t] = axis * (angle + TAU * k);
                }
            }
            assigned[t] = true;
            for &m in neighbours(t) {
                if !assigned[m as usize] {
                    heap.push(key(m as usize, logs));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A strip of triangles in a row, triangle t turning by `turn(t)` about z.
    fn strip(turns: &[f64]) -> (Vec<Vector3<f64>>, Vec<Vec<u32>>) {
        let n = turns.len();
        let logs = turns
            .iter()
            .map(|&a| {
                let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a);
                q.scaled_axis()
            })
            .collect();
        let adj = (0..n)
            .map(|t| {
                let mut v = Vec::new();
                if t > 0 {
                    v.push(t as u32 - 1);
                }
                if t + 1 < n {
                    v.push(t as u32 + 1);
                }
                v
            })
            .collect();
        (logs, adj)
    }

    #[test]
    fn a_strip_turning_past_pi_keeps_one_way_round() {
        // 0° … 380° in steps of 20°: past π the principal logs flip to the other way round.
        let turns: Vec<f64> = (0..20).map(|k| (20.0 * k as f64).to_radians()).collect();
        let (mut logs, adj) = strip(&turns);
        assert!(logs[10].z < 0.0, "principal log of 200° is −160°");
        consistent_logs(&mut logs, |t| &adj[t]);
        for (t, (w, &a)) in logs.iter().zip(&turns).enumerate() {
            assert!(
                (w - Vector3::new(0.0, 0.0, a)).norm() < 1e-9,
                "{t}: {w:?} for {a}"
            );
        }
    }

    #[test]
    fn branches_keep_the_rotation_and_do_not_depend_on_the_start_order() {
        // Exactly π at the middle triangle, whose principal axis sign is round-off.
        let turns = [0.0, 0.5 * PI, PI, 0.5 * PI, 0.0];
        let (mut logs, adj) = strip(&turns);
        let before = logs.clone();
        consistent_logs(&mut logs, |t| &adj[t]);
        for (w, b) in logs.iter().zip(&before) {
            let (rw, rb) = (
                UnitQuaternion::from_scaled_axis(*w).to_rotation_matrix(),
                UnitQuaternion::from_scaled_axis(*b).to_rotation_matrix(),
            );
            assert!((rw.matrix() - rb.matrix()).norm() < 1e-12);
        }
        let mut again = before.clone();
        consistent_logs(&mut again, |t| &adj[t]);
        assert_eq!(logs, again);
    }
}
