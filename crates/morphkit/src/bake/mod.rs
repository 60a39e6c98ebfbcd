//! Physical correctives baked into ordinary blendshapes (issue 56): a rig that a DCC or an
//! engine plays live, at the cost of a linear blend, with the physical look.
//!
//! A [`BakedRig`] is what DCCs evaluate:
//! - **In-between shapes** per target: the physical equilibrium of the target alone at weights
//!   `k / (m + 1)`, `k = 1..=m`, and the target itself at 1 (exact: one-hot weights give the
//!   shape's own numbers). A target's delta at weight `w` is piecewise linear between them (as
//!   DCCs interpolate in-betweens), from 0 at `w = 0`; beyond `[0, 1]` the first and last
//!   segments extend linearly.
//! - **Combination shapes** per pair of targets that interact: the part of the pair's
//!   equilibrium at `(s, s)` that the two targets' in-betweens at `s` do not make,
//!   `C_ij(s) = P(s eᵢ + s eⱼ) − base − Dᵢ(s) − Dⱼ(s)`, for `s` = ½ and 1
//!   ([`BakeOptions::pair_samples`]), as in-betweens of one combination shape at combination
//!   weights `4 s²` (1 and 4), piecewise linear in the weight [`BakedRig::combination_weight`]
//!   `4 wᵢ wⱼ`, optionally damped where other targets are on:
//!   `4 wᵢ wⱼ · ((wᵢ + wⱼ) / Σₖ wₖ)^p` over the positive weights (`p` =
//!   [`BakeOptions::damping`], default 0).
//!
//! Why two pair samples and no damping (measured on the ICT head with ten expressions,
//! `examples/bake_accuracy.rs`, twelve random triples at 0.3–1): with one sample at `(½, ½)`
//! extrapolated bilinearly, the corrective of a pair whose weights are both high overshoots
//! (mouthSmile_L + jawOpen + jawLeft: 6.2e-2 of the diagonal from the solve, the linear blend
//! 1.8e-2); damping by the pair's share of the weights (`p` = 1, 2) only brought it to 3.5e-2
//! and 1.8e-2. The second sample at `(1, 1)` fixes the cause: the same triple is 2.7e-3 off,
//! the worst triple 2.7e-3 and the median 6.2e-4 (damping then makes it worse: 8.3e-3 and
//! 1.2e-2 at `p` = 1, 2), every state closer than the linear blend; single targets at any
//! weight within 8.1e-5 (the eighths' piecewise-linear error).
//!
//! `evaluate(w) = base + Σᵢ Dᵢ(wᵢ) + Σ_{pairs} φᵢⱼ(w) Cᵢⱼ`, `#V` positions: a linear blend of
//! stored shapes with weights computed from the sliders, which a glTF viewer (the mapping in
//! `extras`), USD (`UsdSkelInbetweenShape`s) or Blender (drivers) can play.

use crate::mesh::{Point, Weld};
use crate::springs::{BlendError, PhysicalBlend, Weights};
use crate::ShapeSet;

mod gltf;
mod refine;
#[cfg(test)]
mod tests;
mod usd;

pub use gltf::{add_to_gltf, check_gltf};
pub use usd::write_usd;

/// How to bake.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeOptions {
    /// In-between shapes per target, at `k / (inbetweens + 1)` (default 7: the eighths, which
    /// the interactive preparation also solves).
    pub inbetweens: usize,
    /// Pairs whose combination shape moves no vertex farther than this fraction of the base's
    /// bounding-box diagonal are left out (default 1e-4).
    pub pair_tolerance: f64,
    /// Most combination shapes kept (those that move a vertex farthest first; default 120, so
    /// that with 10 targets × 8 shapes a rig stays within the 200 targets WebGL2 plays).
    pub max_pairs: usize,
    /// The exponent `p` of the combination weights' damping (default 0: the plain product,
    /// which measured best with two pair samples; see the [module documentation](self)).
    pub damping: f64,
    /// The pair samples `s`: each pair is solved at `(s, s)` (default ½ and 1), which gives
    /// its combination shape an in-between at combination weight `4 s²`.
    pub pair_samples: Vec<f64>,
    /// More in-betweens where a target's interpolation is farther than this fraction of the
    /// base's bounding-box diagonal from its equilibrium (default 1e-3; 0 keeps the regular
    /// grid): see `refine.rs`.
    pub inbetween_tolerance: f64,
    /// Most in-betweens that tolerance adds, over all targets (default 64).
    pub max_refined: usize,
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            inbetweens: 7,
            pair_tolerance: 1e-4,
            max_pairs: 120,
            damping: 0.0,
            pair_samples: vec![0.5, 1.0],
            inbetween_tolerance: 1e-3,
            max_refined: 64,
        }
    }
}

/// One target's in-between shapes.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedTarget {
    /// Increasing weights in `(0, 1]`, the last 1.
    pub weights: Vec<f64>,
    /// Per weight, `#V` displacements from the base.
    pub deltas: Vec<Vec<Point>>,
}

/// A combination shape, with in-betweens of its own.
#[derive(Clone, Debug, PartialEq)]
pub struct Combination {
    /// The two targets (`i < j`, 0-based target indices).
    pub targets: (usize, usize),
    /// Its shapes: `weights` are combination weights (`4 s²` for the pair sample at
    /// `(s, s)`: 1 at `(½, ½)`, 4 at `(1, 1)`), `deltas` the `#V` corrections there; piecewise
    /// linear in [`BakedRig::combination_weight`] between them, from 0 at 0.
    pub shape: BakedTarget,
}

/// Baked physical correctives (see the [module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct BakedRig {
    /// `#V` base positions.
    pub base: Vec<Point>,
    /// Per target of the rig, its in-betweens.
    pub targets: Vec<BakedTarget>,
    /// The pairs that interact.
    pub combinations: Vec<Combination>,
    /// The damping exponent of the combination weights.
    pub damping: f64,
    /// The physical solves the bake took (regular in-betweens, pair samples and the tests of
    /// [`BakeOptions::inbetween_tolerance`]).
    pub solves: usize,
}

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// A solve failed.
    #[error("the solve at weights {weights:?}: {source}")]
    Solve {
        /// The delta weights.
        weights: Vec<f64>,
        /// Why.
        source: BlendError,
    },
    /// Options out of range.
    #[error("{0}")]
    Options(String),
}

/// The shapes of a piecewise-linear in-between curve through `(0, 0)` and
/// `(weights[k], shape k)` at `w`, extended linearly beyond its ends: up to two
/// `(shape, factor)` pairs (the segment's ends; the first segment starts at no shape).
fn hat(weights: &[f64], w: f64) -> [(usize, f64); 2] {
    if w == 0.0 || weights.is_empty() {
        return [(0, 0.0); 2];
    }
    // The segment [a, b] holding w (the first or last one outside [0, 1]).
    let k = weights
        .iter()
        .position(|&x| w <= x)
        .unwrap_or(weights.len() - 1);
    let a = if k == 0 { 0.0 } else { weights[k - 1] };
    let s = (w - a) / (weights[k] - a);
    let below = if k == 0 { (0, 0.0) } else { (k - 1, 1.0 - s) };
    [below, (k, s)]
}

/// Adds `f · d` to `out`.
fn add_scaled(out: &mut [Point], f: f64, d: &[Point]) {
    if f != 0.0 {
        for (o, p) in out.iter_mut().zip(d) {
            for c in 0..3 {
                o[c] += f * p[c];
            }
        }
    }
}

impl BakedRig {
    /// The weight of combination `c` at delta weights `w` (one per target): `4 wᵢ wⱼ ·
    /// ((wᵢ + wⱼ) / Σₖ max(wₖ, 0))^p`, 0 when `wᵢ` or `wⱼ` is not positive.
    pub fn combination_weight(&self, c: &Combination, w: &[f64]) -> f64 {
        let (i, j) = c.targets;
        let (a, b) = (w[i], w[j]);
        if a <= 0.0 || b <= 0.0 {
            return 0.0;
        }
        let total: f64 = w.iter().map(|x| x.max(0.0)).sum();
        let share = ((a + b) / total).min(1.0);
        4.0 * a * b * share.powf(self.damping)
    }

    /// The weight of every stored shape at delta weights `w` (one per target): each target's
    /// in-betweens in order, then each combination's, in [`BakedRig::shapes`]' order. A
    /// target's weight `x` falls in one segment of its in-between weights (the first from 0,
    /// the last extended beyond 1): the segment's upper shape weighs `s = (x − a) / (b − a)`,
    /// its lower one `1 − s`; a combination does the same with its combination weight. This
    /// is the whole mapping a client computes (docs/bake.md has it in JavaScript).
    pub fn shape_weights(&self, w: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.num_shapes());
        let mut put = |weights: &[f64], x: f64| {
            let start = out.len();
            out.resize(start + weights.len(), 0.0);
            for (k, f) in hat(weights, x) {
                if f != 0.0 {
                    out[start + k] += f;
                }
            }
        };
        for (t, &x) in self.targets.iter().zip(w) {
            put(&t.weights, x);
        }
        for c in &self.combinations {
            put(&c.shape.weights, self.combination_weight(c, w));
        }
        out
    }

    /// Every stored shape's `#V` displacement, in [`BakedRig::shape_weights`]' order.
    pub fn shapes(&self) -> impl Iterator<Item = &Vec<Point>> {
        self.targets
            .iter()
            .flat_map(|t| &t.deltas)
            .chain(self.combinations.iter().flat_map(|c| &c.shape.deltas))
    }

    /// The baked shape at delta weights `w` (one per target): `#V` positions, base + Σ
    /// [`BakedRig::shape_weights`] × [`BakedRig::shapes`], as a client evaluates it.
    pub fn evaluate(&self, w: &[f64]) -> Vec<Point> {
        let mut out = self.base.clone();
        for (f, d) in self.shape_weights(w).into_iter().zip(self.shapes()) {
            add_scaled(&mut out, f, d);
        }
        out
    }

    /// The bake of a welded rig in its input's layout (`#V_in` vertices): every delta
    /// scattered to the copies of its welded vertex, and the base and each target at weight 1
    /// the input's own numbers (copies keep their own positions at the shapes themselves, as
    /// [`Weld::scatter_frame`] gives them). `welded` is the rig the bake was made on (the
    /// solver's shapes, `weld.shapes(input)`).
    pub fn unweld(&self, weld: &Weld, welded: &ShapeSet) -> BakedRig {
        if weld.is_identity() {
            return self.clone();
        }
        let n = welded.len();
        let own = |s: usize| {
            let mut c = vec![0.0; n];
            c[s] = 1.0;
            weld.scatter_frame(welded.positions(s), &c)
        };
        let base = own(0);
        let targets = self
            .targets
            .iter()
            .enumerate()
            .map(|(t, bt)| {
                let last = bt.deltas.len() - 1;
                let deltas = bt
                    .deltas
                    .iter()
                    .enumerate()
                    .map(|(k, d)| {
                        if k == last && bt.weights[k] == 1.0 {
                            sub(&own(t + 1), &base)
                        } else {
                            weld.scatter(d)
                        }
                    })
                    .collect();
                BakedTarget {
                    weights: bt.weights.clone(),
                    deltas,
                }
            })
            .collect();
        let combinations = self
            .combinations
            .iter()
            .map(|c| Combination {
                targets: c.targets,
                shape: BakedTarget {
                    weights: c.shape.weights.clone(),
                    deltas: c.shape.deltas.iter().map(|d| weld.scatter(d)).collect(),
                },
            })
            .collect();
        BakedRig {
            base,
            targets,
            combinations,
            damping: self.damping,
            solves: self.solves,
        }
    }

    /// Shapes a client holds: in-betweens (the targets' own included) plus combinations.
    pub fn num_shapes(&self) -> usize {
        let shapes = |t: &BakedTarget| t.weights.len();
        self.targets.iter().map(shapes).sum::<usize>()
            + self
                .combinations
                .iter()
                .map(|c| shapes(&c.shape))
                .sum::<usize>()
    }
}

fn sub(a: &[Point], b: &[Point]) -> Vec<Point> {
    a.iter()
        .zip(b)
        .map(|(p, q)| [p[0] - q[0], p[1] - q[1], p[2] - q[2]])
        .collect()
}

/// Bakes `solver`'s rig: `n × inbetweens` single-target solves and one solve per pair at
/// `(½, ½)`, spread over `threads` threads (the result does not depend on the count). Positions
/// are those of the solver's shapes (a welded rig's welded vertices).
///
/// Errors: a failed solve (naming its weights), `inbetweens` of 0 or a negative tolerance or
/// damping.
pub fn bake(
    solver: &mut PhysicalBlend,
    options: &BakeOptions,
    threads: usize,
) -> Result<BakedRig, BakeError> {
    let increasing = options.pair_samples.windows(2).all(|p| p[0] < p[1]);
    if options.inbetweens == 0
        || options.pair_samples.is_empty()
        || !increasing
        || options
            .pair_samples
            .iter()
            .any(|&s| !(s > 0.0 && s.is_finite()))
        || options.pair_tolerance.is_nan()
        || options.pair_tolerance < 0.0
        || !(options.damping >= 0.0 && options.damping.is_finite())
        || !(options.inbetween_tolerance >= 0.0 && options.inbetween_tolerance.is_finite())
    {
        return Err(BakeError::Options(format!(
            "in-betweens must be at least 1, the pair samples positive and increasing, the pair \
             and in-between tolerances and the damping finite and not negative: {options:?}"
        )));
    }
    let shapes = solver.shapes();
    let n = shapes.len() - 1;
    let base = shapes.positions(0).to_vec();
    let diagonal = shapes.base().bbox_diagonal();
    let m = options.inbetweens;
    let steps: Vec<f64> = (1..=m).map(|k| k as f64 / (m + 1) as f64).collect();
    let mut weights = Vec::new();
    for t in 0..n {
        for &a in &steps {
            let mut w = vec![0.0; n];
            w[t] = a;
            weights.push(w);
        }
    }
    let pairs: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .collect();
    let samples = &options.pair_samples;
    for &(i, j) in &pairs {
        for &s in samples {
            let mut w = vec![0.0; n];
            w[i] = s;
            w[j] = s;
            weights.push(w);
        }
    }
    let as_weights: Vec<Weights> = weights.iter().map(|w| Weights::Delta(w.clone())).collect();
    let mut solved = Vec::with_capacity(weights.len());
    for (w, r) in weights.iter().zip(solver.solve_many(&as_weights, threads)) {
        let r = r.map_err(|source| BakeError::Solve {
            weights: w.clone(),
            source,
        })?;
        solved.push(r.positions);
    }
    let shapes = solver.shapes();
    let mut targets = Vec::with_capacity(n);
    for t in 0..n {
        let mut ws = steps.clone();
        let mut deltas: Vec<Vec<Point>> = solved[t * m..(t + 1) * m]
            .iter()
            .map(|p| sub(p, &base))
            .collect();
        ws.push(1.0);
        deltas.push(sub(shapes.positions(t + 1), &base));
        targets.push(BakedTarget {
            weights: ws,
            deltas,
        });
    }
    let mut refine_solves = 0;
    if options.inbetween_tolerance > 0.0 {
        let tolerance = options.inbetween_tolerance * diagonal;
        let most = options.max_refined;
        refine_solves = refine::refine(solver, &mut targets, &base, tolerance, most, threads)?;
    }
    let mut rig = BakedRig {
        base,
        targets,
        combinations: Vec::new(),
        damping: options.damping,
        solves: weights.len() + refine_solves,
    };
    let mut combos: Vec<(f64, Combination)> = Vec::new();
    for (k, &(i, j)) in pairs.iter().enumerate() {
        let mut deltas = Vec::with_capacity(samples.len());
        let mut size: f64 = 0.0;
        for (q, &s) in samples.iter().enumerate() {
            // What the in-betweens alone make at (s, s), without combinations.
            let mut singles = rig.base.clone();
            for t in [&rig.targets[i], &rig.targets[j]] {
                for (k, f) in hat(&t.weights, s) {
                    add_scaled(&mut singles, f, &t.deltas[k]);
                }
            }
            let delta = sub(&solved[n * m + k * samples.len() + q], &singles);
            let largest = delta
                .iter()
                .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
                .fold(0.0, f64::max);
            size = size.max(largest);
            deltas.push(delta);
        }
        if size > options.pair_tolerance * diagonal {
            let weights = samples.iter().map(|s| 4.0 * s * s).collect();
            combos.push((
                size,
                Combination {
                    targets: (i, j),
                    shape: BakedTarget { weights, deltas },
                },
            ));
        }
    }
    // The pairs that move a vertex farthest, then in pair order (a stable, total order).
    combos.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.targets.cmp(&b.1.targets)));
    combos.truncate(options.max_pairs);
    combos.sort_by_key(|c| c.1.targets);
    rig.combinations = combos.into_iter().map(|c| c.1).collect();
    Ok(rig)
}
