//! Per-frame holds: a frame is a function of its nonzero weights (issue 40).
//!
//! Two boundary conditions used to be chosen once per rig from *all* its targets, so a target
//! at weight 0 still changed every frame (ICT: the neutral and jawLeft at ½ on their own and
//! in the 10-expression rig were 3.7e-3 of the diagonal apart):
//!
//! - **automatic fixed vertices**, those that move in no target: a vertex moved only by an
//!   unused target was free in the big rig and fixed in a rig without that target;
//! - **kinematic vertices**, those of triangles stretched past
//!   [`kinematic_stretch`](super::BlendOptions::kinematic_stretch) by *any* target: jawOpen's
//!   mouth interior was held at the linear blend while only jawLeft and the smiles moved.
//!
//! The rig keeps as boundary conditions only what holds in every frame (vertices no target
//! moves, explicit ids, thin bands, and the kinematic vertices of components that nothing
//! else holds, which need them as their frame). The rest is decided per frame from the
//! weights $w$, as a point target towards the linear blend $L(w)$ whose stiffness fades with
//! the weights, so that frames stay continuous as a weight leaves 0. With $r$ =
//! [`hold_ramp`](super::BlendOptions::hold_ramp) and the stiffness in units of the mean
//! spring:
//!
//! - a vertex whose moving targets have largest weight $m = \max_{i \text{ moves } v} |w_i|$,
//!   where the other targets have largest weight $o$, is held with
//!   $\kappa = \big((r - m)/m\big)^2 \big(o/(o + m)\big)^2$ for $m < r$: exactly (a
//!   boundary condition) at $m = 0$, as in a rig without those targets, and not at all from
//!   $m = r$ on. The factor in $o$ (issue 54) frees the vertex where only its own targets
//!   act ($o = 0$): nothing else moves the mesh then, so the equilibrium leaves the base
//!   continuously by itself, and a hold towards the linear blend's chord only delayed a part
//!   that turns, which then snapped onto its turn as the hold let go (a head turning 180°:
//!   8.8× the linear step between 0.045 and 0.05, 107 Newton iterations; none with the
//!   factor). As $o \to 0$ with $m$ fixed the hold fades to 0, so frames stay continuous
//!   in every weight;
//! - a vertex of triangles over-stretched by targets whose largest weight is
//!   $k = \max_{i \text{ stretches } v} |w_i|$ is held with $\kappa = \big(k/(r - k)\big)^2$
//!   for $k < r$, exactly from $k = r$ on: free as in a rig without those targets at $k = 0$.
//!
//! A stiffness past [`HARD_FROM`] becomes a boundary condition. The step that leaves is the
//! hold's residual $f/\kappa$, with $f$ the force of the neighbours, which is below the
//! solver's tolerance there; both functions are smooth and monotone in between.
//!
//! Only vertices of components anchored by fixed vertices take part: a component held by a
//! gauge is solved in its own frame, where a hold towards the world's linear blend would
//! pull it; such components keep the rig-wide rule.

use super::constraints::Moves;
use super::terms::PointTarget;
use super::Constraints;
use crate::mesh::{Point, ShapeSet};

/// Stiffness (units of the mean spring) from which a hold is a boundary condition: the step
/// it leaves, the neighbours' force over this stiffness, is a millionth of a spring's pull.
pub(super) const HARD_FROM: f64 = 1e6;

/// The gain of an over-stretched vertex's hold, `G (k/(r − k))²`: how early in the ramp the
/// hold takes the vertex onto the linear blend (see the module documentation). With G = 1 the
/// hold only took hold in the last tenth of the ramp, where it then pulled the mouth interior
/// of ICT's jawLeft back onto the linear blend within 0.003 of weight (15× the linear step
/// at 0.049 → 0.05); with G = 100 it holds from the first fifth on, while the frame is still
/// near the base.
pub(super) const STRETCH_HOLD_GAIN: f64 = 100.0;

/// Vertices with the targets that concern each (compressed rows; target indices are shape
/// indices, `1..#shapes`).
#[derive(Default)]
struct Rows {
    vertices: Vec<u32>,
    offsets: Vec<u32>,
    targets: Vec<u32>,
}

impl Rows {
    fn push(&mut self, v: u32, targets: impl IntoIterator<Item = u32>) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        let before = self.targets.len();
        self.targets.extend(targets);
        if self.targets.len() > before {
            self.vertices.push(v);
            self.offsets.push(self.targets.len() as u32);
        }
    }

    /// Each vertex with its targets' largest absolute weight in `c`.
    fn largest<'a>(&'a self, c: &'a [f64]) -> impl Iterator<Item = (u32, f64)> + 'a {
        self.largest_and_other(c, &[]).map(|(v, m, _)| (v, m))
    }

    /// Per vertex: its largest weight as [`largest`](Self::largest), and the largest weight
    /// of the *other* targets (those not in its row), from `active`: the targets with a
    /// nonzero weight, largest weight first.
    fn largest_and_other<'a>(
        &'a self,
        c: &'a [f64],
        active: &'a [(f64, u32)],
    ) -> impl Iterator<Item = (u32, f64, f64)> + 'a {
        self.vertices.iter().enumerate().map(move |(i, &v)| {
            let row = &self.targets[self.offsets[i] as usize..self.offsets[i + 1] as usize];
            let m = row.iter().map(|&s| c[s as usize].abs()).fold(0.0, f64::max);
            let o = active
                .iter()
                .find(|(_, s)| !row.contains(s))
                .map_or(0.0, |&(w, _)| w);
            (v, m, o)
        })
    }
}

/// The per-frame hold rules of a rig (see the [module docs](self)).
#[derive(Default)]
pub(super) struct FrameHolds {
    ramp: f64,
    /// Vertices free in the rig that some targets move, with those targets.
    moved: Rows,
    /// Kinematic vertices released from the rig's boundary conditions, with the targets that
    /// over-stretch their triangles.
    stretched: Rows,
    /// Vertices of thin bands that some targets move, with those targets: held at the
    /// predictor as every band, which places its component onto them where no active target
    /// moves them, as onto fixed vertices.
    bands: Rows,
}

impl FrameHolds {
    /// The rules for `shapes` under `constraints` (after
    /// [`Constraints::release_kinematic`] gave `released`), with `stretched_by[s - 1]` the
    /// vertices target `s` over-stretches. `automatic`: whether fixed vertices are the
    /// automatic ones (explicit ids and no fixed vertices have no automatic hold).
    pub(super) fn new(
        shapes: &ShapeSet,
        constraints: &Constraints,
        released: &[u32],
        stretched_by: &[Vec<u32>],
        automatic: bool,
        ramp: f64,
    ) -> Self {
        let n = shapes.num_vertices();
        let mut anchored = vec![true; n];
        let gauged = constraints.gauges.iter().map(|g| &g.vertices);
        for comp in gauged.chain(constraints.aligned.iter().map(|a| &a.vertices)) {
            for &v in comp {
                anchored[v as usize] = false;
            }
        }
        let mut is_fixed = vec![false; n];
        for &v in &constraints.fixed {
            is_fixed[v as usize] = true;
        }
        let mut holds = Self {
            ramp,
            ..Default::default()
        };
        if automatic && shapes.len() > 1 {
            let rule = Moves::new(shapes);
            let rule = &rule;
            let moves =
                |v: usize| (1..shapes.len() as u32).filter(move |&s| rule.in_shape(s as usize, v));
            for v in 0..n {
                if anchored[v] && !is_fixed[v] {
                    holds.moved.push(v as u32, moves(v));
                }
            }
            for &v in &constraints.bands {
                holds.bands.push(v, moves(v as usize));
            }
        }
        let mut by_vertex: Vec<Vec<u32>> = vec![Vec::new(); released.len()];
        for (s, verts) in stretched_by.iter().enumerate() {
            for v in verts {
                if let Ok(i) = released.binary_search(v) {
                    by_vertex[i].push(s as u32 + 1);
                }
            }
        }
        for (&v, targets) in released.iter().zip(by_vertex) {
            holds.stretched.push(v, targets);
        }
        holds
    }

    /// The holds of coefficients `c` (`c[s]` the weight of shape `s`) towards the linear
    /// blend `lin`, sorted by vertex: hard targets where held exactly, soft ones while fading.
    /// (The hard targets on band vertices only anchor the predictor: the solve holds bands
    /// already.)
    ///
    /// At a shape itself (one-hot weights) there are none: the equilibrium is that shape with
    /// or without them, and a reference factor made there must not have them masked out.
    pub(super) fn targets(&self, c: &[f64], lin: &[Point]) -> Vec<PointTarget> {
        if super::weights::one_hot(c).is_some() {
            return Vec::new();
        }
        let r = self.ramp;
        let mut active: Vec<(f64, u32)> = (1..c.len())
            .filter(|&s| c[s] != 0.0)
            .map(|s| (c[s].abs(), s as u32))
            .collect();
        active.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut kappa: Vec<(u32, f64)> = Vec::new();
        for (v, m, o) in self.moved.largest_and_other(c, &active) {
            if m < r {
                let k = if m == 0.0 {
                    f64::INFINITY
                } else {
                    ((r - m) / m).powi(2) * (o / (o + m)).powi(2)
                };
                if k > 0.0 {
                    kappa.push((v, k));
                }
            }
        }
        for (v, m) in self.stretched.largest(c) {
            if m > 0.0 {
                let k = if m >= r {
                    f64::INFINITY
                } else {
                    STRETCH_HOLD_GAIN * (m / (r - m)).powi(2)
                };
                kappa.push((v, k));
            }
        }
        for (v, m) in self.bands.largest(c) {
            if m == 0.0 {
                kappa.push((v, f64::INFINITY));
            }
        }
        kappa.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        kappa.dedup_by_key(|h| h.0);
        kappa
            .into_iter()
            .map(|(v, k)| {
                let p = lin[v as usize];
                if k >= HARD_FROM {
                    PointTarget::hard(v, p)
                } else {
                    PointTarget {
                        vertex: v,
                        position: p,
                        stiffness: k,
                    }
                }
            })
            .collect()
    }
}
