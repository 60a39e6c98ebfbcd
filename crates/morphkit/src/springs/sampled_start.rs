//! The sampled start: the predictor corrected by each target's equilibria at three sample
//! weights, so that a frame starts next to its equilibrium (see the
//! [module docs](super#the-canonical-equilibrium)).
//!
//! For target $s \ge 1$ and the two-shape coefficients $c^{s}(a) = (1-a)\,e_0 + a\,e_s$, the
//! *correction field* is $d_s(a) = x^*_0(c^{s}(a)) - P(c^{s}(a))$ (world positions, `#V`): how
//! far the equilibrium lies from the predictor. It is sampled at $a \in \{¼, ½, ¾\}$, once per
//! target, on the first solve that needs it:
//! - $x^*_0(c^s(½))$ is the Newton solve from the plain predictor $P$;
//! - $x^*_0(c^s(¼))$ and $x^*_0(c^s(¾))$ start from $P + 4a(1-a)\,d_s(½)$.
//!
//! A solve for coefficients $c$ then starts from
//!
//! $$\tilde P(c) = P(c) + \sum_{s \ge 1} q_s(c_s), \qquad
//! q_s(a) = a(1-a)\, g_s(\operatorname{clamp}(a, ¼, ¾)) \text{ for } 0 < a < 1,
//! \quad q_s(a) = 0 \text{ otherwise},$$
//!
//! where $g_s$ interpolates $d_s(a) / (a(1-a))$ linearly between the samples. $q_s$ vanishes
//! at $a = 0$ and $a = 1$, so endpoints still start (and stay) exactly at their shape; it
//! never extrapolates past a sample, which matters where the equilibrium path bends
//! (ICT jawOpen: a Lagrange polynomial through the three samples started frames near α = 0.1
//! and 0.9 farther from their equilibria than $P$ did).
//!
//! **Pairs.** Targets interact: where two or more targets are strictly between 0 and 1, the
//! start also adds, for every pair $s < t$ of them,
//!
//! $$\varphi(c_s)\,\varphi(c_t)\; r_{st}, \qquad \varphi(a) = 4a(1-a), \qquad
//! r_{st} = x^*_0(c^{st}) - \bigl(P(c^{st}) + q_s(½) + q_t(½)\bigr),$$
//!
//! with $c^{st} = ½\,e_s + ½\,e_t$: what the pair's equilibrium adds to the two targets' own
//! corrections, solved once per pair on first need, from $P + q_s + q_t$. $\varphi$ is 1 at
//! the sample and vanishes at 0 and 1, so a single target starts exactly as before, and the
//! pair's own sample starts at its equilibrium. Measured on the scrub bench's twelve ICT
//! combinations of three expressions (docs/performance.md, "Morning of 6 December").
//!
//! The samples are canonical solves themselves, so they, and every frame, depend on the
//! weights and the rig alone, whichever frame, thread or order first asks for them. A sample
//! that does not converge turns its target's correction off (deterministically).
//!
//! Measured (36 steps, per step, plain start → sampled start, samples not counted;
//! `morphkit bench --suite springs --steps 36 [--no-sampled-start]`): Newton iterations
//! horse ↔ horse-05 5.83 → 3.53, ICT ↔ jawOpen 10.0 → 5.72, bent tubes about 2 → 0.94;
//! factorizations 3.42 → 1.47 and 7.00 → 3.17. On the ten horse poses and ten ICT
//! expressions at α = 0.1, 0.4, 0.6, 0.9 both starts reach the same minimum within
//! 1e-8–1e-4 of the diagonal, except ICT eyeBlink_L/R at 0.6, where a thin eye strip had
//! two minima (measured before thin bands followed the predictor,
//! [`BlendOptions::thin_band_rings`](super::BlendOptions::thin_band_rings); see
//! docs/performance.md).

use crate::mesh::Point;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Sample weights $a$ of each target's correction field.
pub(crate) const SAMPLES: [f64; 3] = [0.25, 0.5, 0.75];

/// Each target's weight in a pair's sample: $c = ½ e_s + ½ e_t$.
pub(crate) const PAIR: f64 = 0.5;

/// One correction field $d_s(a)$ (`None`: its solve did not converge).
pub(crate) type Field = Option<Arc<Vec<Point>>>;

/// Computes field `k` of target `s` (`SAMPLES[k]`), given the ½ field for `k ≠ 1`; and the
/// field of targets `s < t`, given their own corrections at ½ (`singles`).
pub(crate) trait SampleSolver {
    fn field(&mut self, s: usize, k: usize, half: Option<&[Point]>) -> Option<Vec<Point>>;
    fn pair_field(&mut self, s: usize, t: usize, singles: Option<&[Point]>) -> Option<Vec<Point>>;
}

/// Each target's correction fields and each pair's, computed on first use and then shared by
/// every thread.
pub(crate) struct StartSamples {
    /// Index `s - 1` for target `s`, then the sample.
    cells: Vec<[OnceLock<Field>; 3]>,
    /// The pair fields $r_{st}$, `s < t`, at [`pair_index`]`(s, t)`.
    pairs: Vec<OnceLock<Field>>,
    /// Sample solves run so far.
    solved: AtomicUsize,
}

/// Where the field of targets `s < t` (both ≥ 1) lies among the pairs: by `t`, then `s`.
pub(crate) fn pair_index(s: usize, t: usize) -> usize {
    debug_assert!(1 <= s && s < t);
    (t - 1) * (t - 2) / 2 + (s - 1)
}

/// Pairs among `targets` targets.
pub(crate) fn pair_count(targets: usize) -> usize {
    targets * targets.saturating_sub(1) / 2
}

impl StartSamples {
    /// Room for `targets` targets, none computed.
    pub fn new(targets: usize) -> Self {
        Self {
            cells: (0..targets).map(|_| Default::default()).collect(),
            pairs: (0..pair_count(targets)).map(|_| OnceLock::new()).collect(),
            solved: AtomicUsize::new(0),
        }
    }

    /// Bytes of every field of `targets` targets and their pairs over `n` vertices (none when
    /// `enabled` is false), for the memory check.
    pub fn bytes(n: usize, targets: usize, enabled: bool) -> u64 {
        if enabled {
            let fields = SAMPLES.len() * targets + pair_count(targets);
            (fields * n * std::mem::size_of::<Point>()) as u64
        } else {
            0
        }
    }

    /// Whether field `k` of target `s` has been computed (converged or not).
    pub fn is_computed(&self, s: usize, k: usize) -> bool {
        self.computed(s, k).is_some()
    }

    /// Field `k` of target `s` where it has been computed (`None` where not yet).
    pub fn computed(&self, s: usize, k: usize) -> Option<&Field> {
        self.cells[s - 1][k].get()
    }

    /// Sets field `k` of target `s` to `field` where it has not been computed yet (a saved
    /// preparation restoring what its solves gave: the same field, bit for bit, that the
    /// solve would give again, since every field is a function of the rig alone).
    pub fn restore(&self, s: usize, k: usize, field: Field) {
        let _ = self.cells[s - 1][k].set(field);
    }

    /// The field of targets `s < t` where it has been computed (`None` where not yet).
    pub fn pair_computed(&self, s: usize, t: usize) -> Option<&Field> {
        self.pairs[pair_index(s, t)].get()
    }

    /// Sets the field of targets `s < t` where it has not been computed yet (as
    /// [`restore`](Self::restore)).
    pub fn restore_pair(&self, s: usize, t: usize, field: Field) {
        let _ = self.pairs[pair_index(s, t)].set(field);
    }

    /// Sample solves run so far (target and pair fields).
    pub fn solved(&self) -> usize {
        self.solved.load(Ordering::Relaxed)
    }

    /// Field `k` of target `s`, computed with `solver` unless it already is (the ½ field
    /// first for the others, which start from it).
    pub fn field(&self, s: usize, k: usize, solver: &mut dyn SampleSolver) -> Field {
        let half = if k == 1 {
            None
        } else {
            Some(self.field(s, 1, solver)?)
        };
        self.cells[s - 1][k]
            .get_or_init(|| {
                self.solved.fetch_add(1, Ordering::Relaxed);
                solver
                    .field(s, k, half.as_deref().map(|h| h.as_slice()))
                    .map(Arc::new)
            })
            .clone()
    }

    /// The field of targets `s < t`, $r_{st}$, computed with `solver` unless it already is
    /// (their ½ fields first: the pair's solve starts from them).
    pub fn pair(&self, s: usize, t: usize, solver: &mut dyn SampleSolver) -> Field {
        self.pairs[pair_index(s, t)]
            .get_or_init(|| {
                let mut c = vec![0.0; self.cells.len() + 1];
                c[s] = PAIR;
                c[t] = PAIR;
                let singles = self.single_correction(&c, solver);
                self.solved.fetch_add(1, Ordering::Relaxed);
                solver.pair_field(s, t, singles.as_deref()).map(Arc::new)
            })
            .clone()
    }

    /// The `(target, sample)` fields that the correction for coefficients `c` reads.
    pub fn needed(c: &[f64]) -> impl Iterator<Item = (usize, usize)> + '_ {
        c.iter().enumerate().skip(1).flat_map(|(s, &a)| {
            let w = sample_weights(a).unwrap_or([0.0; 3]);
            (0..3).filter(move |&k| w[k] != 0.0).map(move |k| (s, k))
        })
    }

    /// The pairs `(s, t)`, `s < t`, whose fields the correction for coefficients `c` reads:
    /// those of the targets strictly between 0 and 1.
    pub fn needed_pairs(c: &[f64]) -> Vec<(usize, usize)> {
        let inner: Vec<usize> = (1..c.len()).filter(|&s| pair_weight(c[s]) > 0.0).collect();
        let mut out = Vec::new();
        for (i, &t) in inner.iter().enumerate() {
            for &s in &inner[..i] {
                out.push((s, t));
            }
        }
        out
    }

    /// The correction for coefficients `c` over all shapes,
    /// $\sum_s q_s(c_s) + \sum_{s<t} \varphi(c_s)\,\varphi(c_t)\, r_{st}$, or `None` where
    /// every term is zero. A target or pair whose fields did not converge adds nothing.
    pub fn correction(&self, c: &[f64], solver: &mut dyn SampleSolver) -> Option<Vec<Point>> {
        let mut out = self.single_correction(c, solver);
        for (s, t) in Self::needed_pairs(c) {
            let Some(field) = self.pair(s, t, solver) else {
                continue;
            };
            let w = pair_weight(c[s]) * pair_weight(c[t]);
            add(&mut out, w, &field);
        }
        out
    }

    /// $\sum_s q_s(c_s)$: the targets' own corrections, without the pairs'.
    pub fn single_correction(
        &self,
        c: &[f64],
        solver: &mut dyn SampleSolver,
    ) -> Option<Vec<Point>> {
        let mut out: Option<Vec<Point>> = None;
        for (s, &a) in c.iter().enumerate().skip(1) {
            let Some(w) = sample_weights(a) else {
                continue;
            };
            let fields: Option<Vec<(f64, Arc<Vec<Point>>)>> = (0..3)
                .filter(|&k| w[k] != 0.0)
                .map(|k| Some((w[k], self.field(s, k, solver)?)))
                .collect();
            let Some(fields) = fields else {
                continue;
            };
            for (wk, field) in fields {
                add(&mut out, wk, &field);
            }
        }
        out
    }
}

/// `out += w d` ([`shifted`]), starting from zeros.
fn add(out: &mut Option<Vec<Point>>, w: f64, d: &[Point]) {
    let acc = out.take().unwrap_or_else(|| vec![[0.0; 3]; d.len()]);
    *out = Some(shifted(acc, d, w));
}

/// The weight of a pair field in one target's coefficient $a$: $\varphi(a) = 4a(1-a)$ for
/// $0 < a < 1$ (1 at the sample, ½), 0 otherwise, so that a pair adds nothing where either
/// target is at 0 or 1 and single targets start exactly as without pairs.
fn pair_weight(a: f64) -> f64 {
    if a > 0.0 && a < 1.0 {
        4.0 * a * (1.0 - a)
    } else {
        0.0
    }
}

/// The weights of the three sample fields in $q_s(a)$, or `None` outside $0 < a < 1$.
fn sample_weights(a: f64) -> Option<[f64; 3]> {
    if !(a > 0.0 && a < 1.0) {
        return None;
    }
    let b = a.clamp(SAMPLES[0], SAMPLES[2]);
    let k = usize::from(b > SAMPLES[1]);
    let t = (b - SAMPLES[k]) / (SAMPLES[k + 1] - SAMPLES[k]);
    let mut w = [0.0; 3];
    w[k] = 1.0 - t;
    w[k + 1] = t;
    for (wk, &x) in w.iter_mut().zip(&SAMPLES) {
        *wk *= a * (1.0 - a) / (x * (1.0 - x));
    }
    Some(w)
}

/// The start of the side samples: $4a(1-a)$, the weight of $d_s(½)$ at sample $a$.
pub(crate) fn half_weight(a: f64) -> f64 {
    4.0 * a * (1.0 - a)
}

/// `p + w d`, pointwise.
pub(crate) fn shifted(mut p: Vec<Point>, d: &[Point], w: f64) -> Vec<Point> {
    for (p, d) in p.iter_mut().zip(d) {
        for k in 0..3 {
            p[k] += w * d[k];
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_reproduce_each_sample_and_vanish_at_the_ends() {
        for (k, &a) in SAMPLES.iter().enumerate() {
            let w = sample_weights(a).unwrap();
            for (j, &wj) in w.iter().enumerate() {
                let want = if j == k { 1.0 } else { 0.0 };
                assert!((wj - want).abs() < 1e-15, "a = {a}: {w:?}");
            }
        }
        for a in [0.0, 1.0, -0.5, 1.5, f64::NAN] {
            assert!(sample_weights(a).is_none(), "a = {a}");
        }
        let near = sample_weights(1e-9).unwrap();
        assert!(near.iter().all(|w| w.abs() < 1e-8), "{near:?}");
        // Between samples the weights interpolate; never negative (no extrapolation).
        for i in 1..100 {
            let w = sample_weights(i as f64 / 100.0).unwrap();
            assert!(w.iter().all(|&x| x >= 0.0), "{w:?}");
        }
    }

    /// Field `k` of target `s`: `s` in coordinate `k`; the pair field of `s < t`: 100 s + t
    /// in coordinate 2 (the pair's start must hold both targets' ½ fields: `[0, s + t, 0]`).
    struct Fake(Vec<(usize, usize)>);
    impl SampleSolver for Fake {
        fn field(&mut self, s: usize, k: usize, half: Option<&[Point]>) -> Option<Vec<Point>> {
            assert_eq!(half.is_some(), k != 1, "the ½ field comes first");
            self.0.push((s, k));
            let mut p = [0.0; 3];
            p[k] = s as f64;
            Some(vec![p])
        }
        fn pair_field(
            &mut self,
            s: usize,
            t: usize,
            singles: Option<&[Point]>,
        ) -> Option<Vec<Point>> {
            assert_eq!(singles, Some(&[[0.0, (s + t) as f64, 0.0]][..]));
            self.0.push((100 + s, t));
            Some(vec![[0.0, 0.0, (100 * s + t) as f64]])
        }
    }

    #[test]
    fn correction_sums_the_targets_and_pairs_and_computes_each_field_once() {
        let s = StartSamples::new(2);
        let mut f = Fake(Vec::new());
        assert!(s.correction(&[1.0, 0.0, 0.0], &mut f).is_none());
        // A single target: its own fields only.
        let d = s.correction(&[0.5, 0.5, 0.0], &mut f).unwrap();
        assert_eq!(d, vec![[0.0, 1.0, 0.0]]);
        // Both at ½: the pair's field at full weight.
        let d = s.correction(&[0.0, 0.5, 0.5], &mut f).unwrap();
        assert_eq!(d, vec![[0.0, 3.0, 102.0]]);
        // Both at ¼: φ(¼)² = (3/4)².
        let d = s.correction(&[0.5, 0.25, 0.25], &mut f).unwrap();
        assert_eq!(d, vec![[3.0, 0.0, 0.5625 * 102.0]]);
        // One of them at 1: no pair term.
        let d = s.correction(&[-0.25, 1.0, 0.25], &mut f).unwrap();
        assert_eq!(d, vec![[2.0, 0.0, 0.0]]);
        assert_eq!(f.0, vec![(1, 1), (2, 1), (101, 2), (1, 0), (2, 0)]);
        assert_eq!(s.solved(), 5);
        let needed: Vec<_> = StartSamples::needed(&[0.2, 0.6, 0.2, 1.0]).collect();
        assert_eq!(needed, vec![(1, 1), (1, 2), (2, 0)]);
        assert_eq!(
            StartSamples::needed_pairs(&[-0.6, 0.5, 1.0, 0.3, 0.8]),
            vec![(1, 3), (1, 4), (3, 4)]
        );
        assert!(StartSamples::needed_pairs(&[0.5, 0.5, 0.0]).is_empty());
    }

    #[test]
    fn pair_indices_cover_every_pair_once() {
        let targets = 7;
        let mut seen = vec![false; pair_count(targets)];
        for t in 2..=targets {
            for s in 1..t {
                let i = pair_index(s, t);
                assert!(!seen[i], "({s}, {t})");
                seen[i] = true;
            }
        }
        assert!(seen.iter().all(|&x| x));
        assert_eq!(pair_count(1), 0);
        assert_eq!(pair_count(0), 0);
    }
}
