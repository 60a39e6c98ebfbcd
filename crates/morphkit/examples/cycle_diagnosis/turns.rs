//! Variants of how the local-stretch frame turns each matched stretch (`TURN` of the
//! `heldout` study), with their own combine and the cycle measure that uses it.

use super::*;
use morphkit::mesh::Topology;
use morphkit::transfer::correspondence::rotation_between;
use morphkit::transfer::{normal_agreement, CorrespondenceResult};

/// How each match's stretch is turned onto its target triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Turn {
    /// Not at all (world-frame stretch, chordal-mean rotation).
    None,
    /// The smallest rotation between the reference normals (the library).
    Smallest,
    /// The rotation field of the warps: $R_{t,j}^\top R_{s,i}$ (polar factors of the warps'
    /// deformation gradients; $R_t = I$ when refined).
    Warp,
    /// [`Turn::Warp`] followed by the smallest rotation from the turned source normal onto
    /// the target normal (the stretch exactly in the target plane, its twist from the warp).
    WarpAligned,
    /// The target triangle's chordal mean of its matches' smallest rotations, smoothed over
    /// neighbouring target triangles this many times.
    Smooth(usize),
    /// [`Turn::Smooth`] followed by the smallest rotation onto the target normal.
    SmoothAligned(usize),
    /// The smallest rotation only where the reference normals' cosine is above this.
    Cut(f64),
    /// The smallest rotation's angle scaled by $((1 + c)/2)^p$.
    Partial(f64),
    /// The smallest rotation's angle scaled by $\kappa_j^g$, $\kappa_j$ the concentration
    /// (mean singular value of the weighted mean) of the smallest rotations of target
    /// triangle $j$'s and its neighbours' matches: 1 where they agree.
    Coherent(f64),
    /// The smallest rotation's angle scaled by $(\sigma_2/\sigma_1)^g$, the in-plane
    /// singular values of the warp's gradient on the source triangle: turned fully where the
    /// warp is conformal, little where it squashes the source triangle.
    Conformal(f64),
}

/// The rotation about the axis of the smallest rotation from `a` onto `b`, by `f(c)` times
/// its angle.
fn partial_rotation(a: Vector3<f64>, b: Vector3<f64>, f: impl Fn(f64) -> f64) -> Matrix3<f64> {
    let k = a.cross(&b);
    let c = a.dot(&b);
    let sn = k.norm();
    if sn < 1e-12 {
        return Matrix3::identity();
    }
    let theta = sn.atan2(c) * f(c);
    *nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(k), theta).matrix()
}

/// Everything the custom combine needs for one direction.
pub struct Dir<'a> {
    c: &'a Correspondence,
    pub ns: Vec<Vector3<f64>>,
    pub nt: Vec<Vector3<f64>>,
    /// Warp rotations of the source / target triangles.
    pub ws: Vec<Matrix3<f64>>,
    pub wt: Vec<Matrix3<f64>>,
    /// Target triangle neighbours.
    nbr: Topology,
    /// In-plane singular value ratio of the warp of each source triangle.
    conformality: Vec<f64>,
}

impl<'a> Dir<'a> {
    pub fn new(a: &TriMesh, b: &TriMesh, r: &'a CorrespondenceResult) -> Self {
        Self {
            c: &r.correspondence,
            ns: unit_normals(a),
            nt: unit_normals(b),
            ws: warp_rotations(a, &r.warped_source),
            wt: warp_rotations(b, &r.warped_target),
            nbr: Topology::new(b.num_vertices(), &b.triangles),
            conformality: GradientOperator::new(a)
                .gradients(&r.warped_source)
                .unwrap()
                .iter()
                .zip(&a.triangles)
                .map(|(d, tri)| {
                    let p = |k: usize| v(a.positions[tri[k] as usize]);
                    let e1 = p(1) - p(0);
                    let n = e1.cross(&(p(2) - p(0)));
                    if n.norm() == 0.0 || e1.norm() == 0.0 {
                        return 1.0;
                    }
                    let u1 = e1.normalize();
                    let u2 = n.normalize().cross(&u1);
                    let m = nalgebra::Matrix3x2::from_columns(&[d * u1, d * u2]);
                    let sv = m.svd(false, false).singular_values;
                    let (hi, lo) = (sv[0].max(sv[1]), sv[0].min(sv[1]));
                    if hi > 0.0 {
                        lo / hi
                    } else {
                        0.0
                    }
                })
                .collect(),
        }
    }

    /// Matches of `t` with their combine weights (inverse distance) times the agreement.
    fn weights(&self, t: usize) -> Vec<(usize, f64)> {
        let c = self.c;
        let (o0, o1) = (c.offsets[t] as usize, c.offsets[t + 1] as usize);
        let m = &c.matches[o0..o1];
        let d = &c.distances[o0..o1];
        let base: Vec<(usize, f64)> = if std::env::var("COMBINE").as_deref() == Ok("mean") {
            m.iter().map(|&i| (i as usize, 1.0)).collect()
        } else if let (Ok(soft), false) = (std::env::var("SOFT"), d[0] == 0.0) {
            let soft: f64 = soft.parse().unwrap();
            m.iter()
                .zip(d)
                .map(|(&i, &di)| (i as usize, 1.0 / (f64::from(di) + soft * c.radius)))
                .collect()
        } else if d[0] == 0.0 {
            m.iter()
                .zip(d)
                .take_while(|x| *x.1 == 0.0)
                .map(|(&i, _)| (i as usize, 1.0))
                .collect()
        } else {
            m.iter()
                .zip(d)
                .map(|(&i, &di)| (i as usize, 1.0 / f64::from(di)))
                .collect()
        };
        let agreed: Vec<(usize, f64)> = base
            .iter()
            .map(|&(i, w)| (i, w * normal_agreement(self.ns[i].dot(&self.nt[t]))))
            .collect();
        if agreed.iter().any(|x| x.1 > 0.0) {
            agreed.into_iter().filter(|x| x.1 > 0.0).collect()
        } else {
            base
        }
    }

    /// Per-target-triangle turning rotation for the smoothed variants.
    fn smooth_rotations(&self, iters: usize) -> Vec<Matrix3<f64>> {
        let nf = self.nt.len();
        let mut q: Vec<Matrix3<f64>> = (0..nf)
            .map(|t| {
                let mut s = Matrix3::zeros();
                for (i, w) in self.weights(t) {
                    s += rotation_between(self.ns[i], self.nt[t]) * w;
                }
                project_rotation(&s)
            })
            .collect();
        for _ in 0..iters {
            q = (0..nf)
                .map(|t| {
                    let mut s = q[t];
                    for &n in self.nbr.face_neighbors(t) {
                        s += q[n as usize];
                    }
                    project_rotation(&s)
                })
                .collect();
        }
        q
    }

    /// κ of [`Turn::Coherent`] per target triangle (in `smooth[t][(0, 0)]`).
    fn coherence(&self) -> Vec<Matrix3<f64>> {
        let nf = self.nt.len();
        let sums: Vec<(Matrix3<f64>, f64)> = (0..nf)
            .map(|t| {
                let (mut s, mut ws) = (Matrix3::zeros(), 0.0);
                for (i, w) in self.weights(t) {
                    s += rotation_between(self.ns[i], self.nt[t]) * w;
                    ws += w;
                }
                (s / ws, 1.0)
            })
            .collect();
        (0..nf)
            .map(|t| {
                let mut s = sums[t].0;
                let mut n = 1.0;
                for &k in self.nbr.face_neighbors(t) {
                    s += sums[k as usize].0;
                    n += 1.0;
                }
                let k = (s / n).svd(false, false).singular_values.sum() / 3.0;
                Matrix3::identity() * k
            })
            .collect()
    }

    fn map(&self, g: &[Matrix3<f64>], turn: Turn, smooth: &[Matrix3<f64>]) -> Vec<Matrix3<f64>> {
        let pol: Vec<(Matrix3<f64>, Matrix3<f64>)> = g.iter().map(polar).collect();
        (0..self.nt.len())
            .map(|t| {
                let (mut r, mut s, mut ws) = (Matrix3::zeros(), Matrix3::zeros(), 0.0);
                for (i, w) in self.weights(t) {
                    let q = match turn {
                        Turn::None => Matrix3::identity(),
                        Turn::Smallest => rotation_between(self.ns[i], self.nt[t]),
                        Turn::Warp => self.wt[t].transpose() * self.ws[i],
                        Turn::WarpAligned => {
                            let q = self.wt[t].transpose() * self.ws[i];
                            rotation_between(q * self.ns[i], self.nt[t]) * q
                        }
                        Turn::Smooth(_) => smooth[t],
                        Turn::Conformal(g) => {
                            let k = self.conformality[i].powf(g);
                            partial_rotation(self.ns[i], self.nt[t], |_| k)
                        }
                        Turn::Coherent(g) => {
                            let k = smooth[t][(0, 0)].clamp(0.0, 1.0).powf(g);
                            partial_rotation(self.ns[i], self.nt[t], |_| k)
                        }
                        Turn::Cut(c0) => {
                            if self.ns[i].dot(&self.nt[t]) > c0 {
                                rotation_between(self.ns[i], self.nt[t])
                            } else {
                                Matrix3::identity()
                            }
                        }
                        Turn::Partial(e) => {
                            partial_rotation(self.ns[i], self.nt[t], |c| (0.5 * (1.0 + c)).powf(e))
                        }
                        Turn::SmoothAligned(_) => {
                            rotation_between(smooth[t] * self.ns[i], self.nt[t]) * smooth[t]
                        }
                    };
                    r += pol[i].0 * w;
                    let st = match std::env::var("SHRINK") {
                        Ok(e) => {
                            let h = (0.5 * (1.0 + self.ns[i].dot(&self.nt[t])))
                                .clamp(0.0, 1.0)
                                .powf(e.parse().unwrap());
                            Matrix3::identity() + (pol[i].1 - Matrix3::identity()) * h
                        }
                        Err(_) => pol[i].1,
                    };
                    s += q * st * q.transpose() * w;
                    ws += w;
                }
                project_rotation(&r) * (s / ws)
            })
            .collect()
    }
}

/// Cycle measures of one setting.
#[derive(Debug, Default, Clone)]
pub struct Measure {
    pub mean: f64,
    pub max: f64,
    pub folds: usize,
    pub flipped: usize,
}

/// Cycle consistency with the custom combine `turn` in both directions, solves set up by
/// `topts` (local stretch: the confidence-weighted solve); `None`: the library's combine.
/// Also returns the forward frames.
pub fn cycle_turn(
    p: &Pair,
    rf: &CorrespondenceResult,
    rb: &CorrespondenceResult,
    topts: &TransferOptions,
    turn: Option<Turn>,
) -> (Measure, Vec<Vec<Point>>) {
    let tf = AnimationTransfer::new(&p.a_ref, &p.b, &rf.correspondence, topts).unwrap();
    let tb = AnimationTransfer::new(&p.b, &p.a_ref, &rb.correspondence, topts).unwrap();
    let df = Dir::new(&p.a_ref, &p.b, rf);
    let db = Dir::new(&p.b, &p.a_ref, rb);
    let (sf, sb) = match turn {
        Some(Turn::Smooth(k) | Turn::SmoothAligned(k)) => {
            (df.smooth_rotations(k), db.smooth_rotations(k))
        }
        Some(Turn::Coherent(_)) => (df.coherence(), db.coherence()),
        _ => (Vec::new(), Vec::new()),
    };
    let topo_b = Topology::new(p.b.num_vertices(), &p.b.triangles);
    let d = p.a_ref.bbox_diagonal();
    let mut m = Measure::default();
    let mut ys = Vec::new();
    for f in &p.frames {
        let gs = tf.source_gradients(f).unwrap();
        let (y, g) = match turn {
            // The library, fold guard included.
            None => {
                let (y, g, _) = tf.transfer_gradients(&gs, Some(f)).unwrap();
                (y, g)
            }
            // The variants, unguarded.
            Some(t) => {
                let g = df.map(&gs, t, &sf);
                (tf.solve_gradients(&g, Some(f)).unwrap(), g)
            }
        };
        let nf = morphkit::transfer::sharp_folds(&p.b, &topo_b, &y);
        if std::env::var("PER_FRAME").is_ok() {
            eprint!("{nf} ");
        }
        m.folds += nf;
        m.flipped += tf.flipped_triangles(&y, &g).len();
        let gb = tb.source_gradients(&y).unwrap();
        let z = match turn {
            None => tb.transfer_gradients(&gb, Some(&y)).unwrap().0,
            Some(t) => tb.solve_gradients(&db.map(&gb, t, &sb), Some(&y)).unwrap(),
        };
        let e = errs(&z, f, d);
        m.mean += mean(&e);
        m.max = e.iter().copied().fold(m.max, f64::max);
        ys.push(y);
    }
    m.mean /= p.frames.len() as f64;
    (m, ys)
}

pub fn corr_pair(
    p: &Pair,
    o: &CorrespondenceOptions,
) -> (CorrespondenceResult, CorrespondenceResult) {
    (
        correspond(&p.a_corr, &p.b, &p.markers, o).unwrap(),
        correspond(&p.b, &p.a_corr, &p.markers.reversed(), o).unwrap(),
    )
}

pub fn parse_turn(s: &str) -> Turn {
    let k = |p: &str| s.strip_prefix(p).map(|x| x.parse().unwrap());
    match s {
        "none" => Turn::None,
        "smallest" => Turn::Smallest,
        "warp" => Turn::Warp,
        "warpal" => Turn::WarpAligned,
        _ => {
            if let Some(x) = s.strip_prefix("cut") {
                Turn::Cut(x.parse().unwrap())
            } else if let Some(x) = s.strip_prefix("conformal") {
                Turn::Conformal(x.parse().unwrap())
            } else if let Some(x) = s.strip_prefix("coherent") {
                Turn::Coherent(x.parse().unwrap())
            } else if let Some(x) = s.strip_prefix("partial") {
                Turn::Partial(x.parse().unwrap())
            } else if let Some(n) = k("smoothal") {
                Turn::SmoothAligned(n)
            } else if let Some(n) = k("smooth") {
                Turn::Smooth(n)
            } else {
                panic!("unknown turn {s}")
            }
        }
    }
}
