//! One interactive solve: the reduced quasi-Newton iteration in the active snapshots' span,
//! optional projected-Newton refinement steps, and the error estimate (see the
//! [module docs](super)).

use super::InteractiveSpace;
use crate::springs::options::{BlendResult, FrameStats};
use crate::springs::predictor;
use crate::springs::rig::Rig;
use crate::springs::solve::Start;
use crate::springs::system::FreeSystem;
use crate::springs::terms::{
    total_energy, total_gradient, EnergyTerm, Held, HessianKind, TermParameters,
};
use crate::springs::workspace::Workspace;
use crate::springs::BlendError;
use nalgebra::{DMatrix, DMatrixView, DVector, DVectorView, DVectorViewMut, Dyn};
use std::time::Instant;

/// Most quasi-Newton iterations of one interactive solve.
pub const MAX_ITERATIONS: usize = 20;

/// A change stops once a step moves no coordinate by more than this fraction of the diagonal.
pub const STEP_STOP: f64 = 1e-4;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Columns $D$ (free coordinates, zero on held ones) and `T` with $D T$ orthonormal.
///
/// $D$ is stored transposed (`m × nf`, so that the `m` column values of one coordinate are
/// contiguous): every product with it is one pass over `nf` coordinates, and the projected
/// Hessian's products with all columns read the matrix once. Measured on the ICT rig (15
/// columns, 80k coordinates, probe runs): products 26 → 17 ms per slider change.
struct Subspace {
    d: DMatrix<f64>,
    t: DMatrix<f64>,
}

impl Subspace {
    fn reduce(&self, gf: &[f64]) -> DVector<f64> {
        let raw = &self.d * DVectorView::from_slice(gf, gf.len());
        self.t.tr_mul(&raw)
    }

    fn expand(&self, y: &DVector<f64>, out: &mut [f64]) {
        let raw = &self.t * y;
        let n = out.len();
        DVectorViewMut::from_slice(out, n).gemv_tr(1.0, &self.d, &raw, 0.0);
    }

    /// The reduced matrix $T^\top (D^\top H D)\, T$ (symmetrized), given `hessian` $= D^\top H D$.
    fn matrix(&self, hessian: &DMatrix<f64>) -> DMatrix<f64> {
        let k = self.t.transpose() * hessian * &self.t;
        (&k + k.transpose()) * 0.5
    }

    /// The space of `space`'s snapshots `cols`, zero on the free coordinates `held`: their
    /// Gram matrix is the prepared one less the held coordinates' products. `buffer` becomes
    /// $D$'s storage ([`Self::into_buffer`] gives it back).
    fn new(space: &InteractiveSpace, cols: &[usize], held: &[usize], buffer: Vec<f64>) -> Self {
        let m = cols.len();
        let nf = space.snapshots.first().map_or(0, |s| s.d.len());
        let columns: Vec<&[f64]> = cols.iter().map(|&k| &space.snapshots[k].d[..]).collect();
        let mut values = buffer;
        values.clear();
        values.extend((0..nf).flat_map(|i| columns.iter().map(move |c| c[i])));
        let mut d = DMatrix::from_vec(m, nf, values);
        let mut gram = DMatrix::from_fn(m, m, |i, j| space.gram[(cols[i], cols[j])]);
        for &h in held {
            let row = d.column(h).clone_owned();
            gram -= &row * row.transpose();
            d.column_mut(h).fill(0.0);
        }
        let t = orthonormalizer(&gram);
        Self { d, t }
    }

    /// $D$'s storage, for the next change.
    fn into_buffer(self) -> Vec<f64> {
        self.d.data.into()
    }

    /// $D^\top H D$ for the matrix `h` (values over `system`'s pattern), with `scratch` for
    /// $H D$.
    fn products(&self, system: &FreeSystem, h: &[f64], scratch: &mut Vec<f64>) -> DMatrix<f64> {
        let (m, nf) = self.d.shape();
        scratch.resize(m * nf, 0.0);
        system
            .pattern
            .mul_rows_into(h, m, self.d.as_slice(), scratch);
        // (H D)ᵀ read in place (a strided view): a transposed copy took 4 of the 6 ms of
        // this product on the ICT rig.
        let hd_t =
            DMatrixView::from_slice_with_strides_generic(scratch, Dyn(nf), Dyn(m), Dyn(m), Dyn(1));
        let mut out = DMatrix::zeros(m, m);
        out.gemm(1.0, &self.d, &hd_t, 0.0);
        out
    }
}

/// `T` (`m × r`) such that $D T$ is orthonormal, for columns $D$ with Gram matrix `g`
/// (eigenvectors, directions under $10^{-10}$ of the largest eigenvalue dropped).
fn orthonormalizer(g: &DMatrix<f64>) -> DMatrix<f64> {
    let m = g.nrows();
    let eig = g.clone().symmetric_eigen();
    let top = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut keep: Vec<usize> = (0..m)
        .filter(|&k| eig.eigenvalues[k] > 1e-10 * top)
        .collect();
    // A fixed order (eigenvalues descending, ties by index): a function of the inputs.
    keep.sort_by(|&a, &b| {
        eig.eigenvalues[b]
            .total_cmp(&eig.eigenvalues[a])
            .then(a.cmp(&b))
    });
    DMatrix::from_fn(m, keep.len(), |i, j| {
        eig.eigenvectors[(i, keep[j])] / eig.eigenvalues[keep[j]].sqrt()
    })
}

/// Largest per-vertex length of a free-coordinate vector.
pub(super) fn max_vertex(system: &FreeSystem, z: &[f64]) -> f64 {
    let dof = &system.dof_index;
    (0..dof.len() / 3)
        .map(|v| {
            (0..3)
                .filter_map(|a| {
                    let i = dof[3 * v + a];
                    (i != u32::MAX).then(|| z[i as usize].powi(2))
                })
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
}

impl Rig {
    /// The interactive shape for coefficients `c` after `refine` projected-Newton steps (see
    /// the [module docs](super)). Its statistics count quasi-Newton iterations as Newton
    /// iterations and carry the error estimate; `converged` says whether the full gradient
    /// reached the tolerance, which a reduced space rarely allows.
    pub(in crate::springs) fn solve_interactive(
        &self,
        ws: &mut Workspace,
        space: &InteractiveSpace,
        c: &[f64],
        refine: usize,
    ) -> Result<BlendResult, BlendError> {
        Ok(self.interactive_state(ws, space, c, refine, &[])?.0)
    }

    /// [`solve_interactive`](Self::solve_interactive) with the snapshots `exclude` left out
    /// of the space, also giving the final iterate in solver coordinates (`3 #V`).
    pub(super) fn interactive_state(
        &self,
        ws: &mut Workspace,
        space: &InteractiveSpace,
        c: &[f64],
        refine: usize,
        exclude: &[usize],
    ) -> Result<(BlendResult, Vec<f64>), BlendError> {
        let started = Instant::now();
        let frame = self.frame_energy(c, &[], true, false);
        // The affine start without the pairs' fields: the space holds the pairs' equilibria
        // as columns, and the left-out estimate must see them there.
        let mut x = self.start_of(ws, c, Start::Singles, &frame)?;
        let cols = space.columns(c, exclude);
        let mut stats = FrameStats {
            gradient_tolerance: self.tolerance,
            clamped_springs: frame.clamped(),
            error_estimate: space.estimate(c, &cols),
            ..Default::default()
        };
        let system = &self.system;
        let nf = system.num_free();
        frame.with_terms(|terms, params| {
            let gradient = |x: &[f64], g: &mut [f64], gf: &mut [f64]| {
                let e = total_gradient(terms, params, x, g);
                frame.held.mask_gradient(g);
                system.gather(g, gf);
                e
            };
            let mut g = vec![0.0; x.len()];
            let mut gf = vec![0.0; nf];
            let mut e = gradient(&x, &mut g, &mut gf);
            let norm = |gf: &[f64]| gf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            stats.gradient_norm = norm(&gf);
            stats.energy = e;
            if stats.gradient_norm <= self.tolerance {
                return;
            }
            let held_free = self.held_free(&frame.held);
            let mut trial = x.clone();
            if !cols.is_empty() {
                // Held coordinates do not move.
                let buffer = std::mem::take(&mut ws.reduced[0]);
                let sub = Subspace::new(space, &cols, &held_free, buffer);
                // The first quasi-Newton matrix: the projected Hessian at the start.
                self.projected_hessian(ws, terms, params, &frame.held, &x);
                let hd = sub.products(system, &ws.projected, &mut ws.reduced[1]);
                let mut b = sub.matrix(&hd);
                let mut step = vec![0.0; nf];
                let mut gr = sub.reduce(&gf);
                while stats.newton_iterations < MAX_ITERATIONS && sub.t.ncols() > 0 {
                    let Some(chol) = b.clone().cholesky() else {
                        break;
                    };
                    let dy = -chol.solve(&gr);
                    let slope = gr.dot(&dy);
                    if slope >= 0.0 {
                        break;
                    }
                    sub.expand(&dy, &mut step);
                    stats.newton_iterations += 1;
                    // Each trial point's energy comes with its gradient (one pass over the
                    // terms): the first step is nearly always taken, and its gradient is
                    // the next iteration's.
                    let mut e_new = e;
                    let found = line_search(|a| {
                        trial.copy_from_slice(&x);
                        system.add_step(&mut trial, a, &step);
                        e_new = gradient(&trial, &mut g, &mut gf);
                        e_new <= e + 1e-4 * a * slope
                    });
                    let Some(a) = found else {
                        gradient(&x, &mut g, &mut gf);
                        break;
                    };
                    stats.rejected_steps += a.1;
                    let a = a.0;
                    x.copy_from_slice(&trial);
                    let gn = sub.reduce(&gf);
                    let s = &dy * a;
                    let yv = &gn - &gr;
                    let sy = s.dot(&yv);
                    if sy > 1e-12 * s.norm() * yv.norm() {
                        let bs = &b * &s;
                        b += &yv * yv.transpose() / sy - &bs * bs.transpose() / s.dot(&bs);
                    }
                    gr = gn;
                    let decrease = e - e_new;
                    e = e_new;
                    // Done when a step moves no coordinate by more than 10⁻⁴ of the
                    // diagonal (a tenth of the 10⁻³ the shape is held to) or the energy
                    // stops decreasing beyond round-off. Horse: 10⁻⁹ → 10⁻⁶ took 7–8
                    // iterations to 4–5. ICT, the twelve three-expression changes of the scrub
                    // bench: 10⁻⁶ → 10⁻⁵ took the median from 11.5 to 8.5 iterations and from
                    // 174 to 147 ms; 10⁻⁵ → 3·10⁻⁵ from 8.5 to 6.5 iterations and 136 to
                    // 110 ms (probe runs), every distance from the full solve the same to
                    // 0.013 % of the diagonal (horse: to 0.001 %); 3·10⁻⁵ → 10⁻⁴ from 84 to
                    // 67 iterations in all (horse: 54 to 47), distances the same to 0.007 %
                    // (horse: 0.004 %).
                    let moved = step.iter().fold(0.0f64, |m, v| m.max(v.abs())) * a;
                    if moved <= STEP_STOP * space.diagonal || decrease <= 1e-13 * e.abs() {
                        break;
                    }
                }
                ws.reduced[0] = sub.into_buffer();
            }
            for _ in 0..refine {
                // A projected-Newton step with this frame's own factor: its length is the
                // estimate of the distance left before it.
                self.projected_hessian(ws, terms, params, &frame.held, &x);
                let values = ws.projected.clone();
                stats.factorizations += 1;
                let mut z = gf.clone();
                let Ok(factor) = ws.factor() else { break };
                if factor.factorize(&values).is_err() || factor.solve_one(&mut z).is_err() {
                    break;
                }
                z.iter_mut().for_each(|v| *v = -*v);
                held_free.iter().for_each(|&i| z[i] = 0.0);
                let slope = dot(&gf, &z);
                let Some((a, rejected)) = line_search(|a| {
                    trial.copy_from_slice(&x);
                    system.add_step(&mut trial, a, &z);
                    total_energy(terms, params, &trial) <= e + 1e-4 * a * slope
                }) else {
                    break;
                };
                stats.rejected_steps += rejected;
                stats.newton_iterations += 1;
                stats.error_estimate = Some(a * max_vertex(system, &z) / space.diagonal);
                x.copy_from_slice(&trial);
                e = gradient(&x, &mut g, &mut gf);
            }
            stats.gradient_norm = norm(&gf);
            stats.energy = e;
        });
        // A start that already meets the tolerance is where the full solve stops too.
        if stats.gradient_norm <= self.tolerance && stats.newton_iterations == 0 {
            stats.error_estimate = Some(0.0);
        }
        stats.converged = stats.gradient_norm <= self.tolerance;
        stats.seconds = started.elapsed().as_secs_f64();
        let positions = predictor::output(&self.constraints, &x, &frame.lin);
        let mut r = BlendResult { positions, stats };
        self.own_numbers_at_a_shape(c, &mut r);
        Ok((r, x))
    }

    /// The free coordinates of the vertices `held` holds.
    fn held_free(&self, held: &Held) -> Vec<usize> {
        let dof = &self.system.dof_index;
        held.vertices()
            .flat_map(|v| (0..3).map(move |a| dof[3 * v + a]))
            .filter(|&i| i != u32::MAX)
            .map(|i| i as usize)
            .collect()
    }

    /// Assembles the projected Hessian at `x` into `ws.projected`, held vertices decoupled,
    /// with a shift of 10⁻⁸ of its mean diagonal so that flat regions factorize.
    fn projected_hessian(
        &self,
        ws: &mut Workspace,
        terms: &[&dyn EnergyTerm],
        params: &[TermParameters],
        held: &Held,
        x: &[f64],
    ) {
        ws.blocks.clear();
        for (term, p) in terms.iter().zip(params) {
            term.add_hessian(p, x, HessianKind::Projected, &mut ws.blocks);
        }
        held.mask_hessian(&mut ws.blocks);
        let system = &self.system;
        ws.ensure_projected();
        let values = &mut ws.projected;
        system.assemble(&ws.blocks, values);
        let slots = &system.diag_slots;
        let mean =
            slots.iter().map(|&d| values[d as usize]).sum::<f64>() / slots.len().max(1) as f64;
        for &d in slots {
            values[d as usize] += 1e-8 * mean;
        }
    }
}

/// Backtracking from a full step: the first step fraction `a` (halving down to 10⁻⁸) for
/// which `accept(a)` holds, with the number of rejected fractions. (A quadratic
/// interpolation of the rejected energy instead of halving, tried on the twelve
/// three-expression ICT changes of the scrub bench: 89 → 87 gradient evaluations in all,
/// one change 6 → 11 iterations; not kept.)
fn line_search(mut accept: impl FnMut(f64) -> bool) -> Option<(f64, usize)> {
    let mut a = 1.0;
    let mut rejected = 0;
    while a >= 1e-8 {
        if accept(a) {
            return Some((a, rejected));
        }
        rejected += 1;
        a *= 0.5;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::super::{InteractiveSpace, Snapshot};
    use super::Subspace;
    use nalgebra::DMatrix;

    #[test]
    fn the_pairs_held_apart_count_only_in_frames_of_three_or_more_targets() {
        // Targets 1–3; a snapshot per target at ½ (and target 1's at ⅛, a fine one), one per
        // pair (1, 2) and (2, 3), with made-up left-out and held-apart errors.
        let snap = |active: Vec<usize>, a: f64, left_out: f64, apart: f64| {
            let mut c = vec![0.0; 4];
            active.iter().for_each(|&s| c[s] = a);
            Snapshot {
                c,
                active,
                d: vec![1.0; 4],
                left_out,
                apart,
            }
        };
        let snapshots = vec![
            snap(vec![1], 0.5, 0.0, 0.0),
            snap(vec![2], 0.5, 0.0, 0.0),
            snap(vec![3], 0.5, 0.0, 0.0),
            snap(vec![1, 2], 0.5, 0.002, 0.009),
            snap(vec![2, 3], 0.5, 0.001, 0.004),
            snap(vec![1], 0.125, 0.0, 0.0),
        ];
        let checked = [vec![0.003, 0.001, 0.002], vec![0.0035, 0.0012, 0.0025]];
        let space = InteractiveSpace::new(snapshots, checked, 0, 1.0, 0.0);
        let estimate = |c: [f64; 4]| {
            let cols = space.columns(&c, &[]);
            space.estimate(&c, &cols).unwrap()
        };
        // One target: its checked error of frames of one target, with every snapshot of it.
        assert_eq!(estimate([0.5, 0.0, 0.5, 0.0]), 0.001);
        assert_eq!(estimate([0.5, 0.5, 0.0, 0.0]), 0.003);
        assert_eq!(space.columns(&[0.5, 0.5, 0.0, 0.0], &[]), vec![0, 5]);
        // Two: the checked errors of frames of several targets, their pair's left-out error,
        // and no fine single-target snapshot.
        assert_eq!(estimate([0.0, 0.5, 0.5, 0.0]), 0.0035);
        assert_eq!(estimate([0.0, 0.0, 0.5, 0.5]), 0.0025);
        assert_eq!(space.columns(&[0.0, 0.5, 0.5, 0.0], &[]), vec![0, 1, 3]);
        // Three: each of their pairs also held apart, scaled by the product of the pair's
        // weights over ¼ where that is above 1.
        assert_eq!(estimate([-0.5, 0.5, 0.5, 0.5]), 0.009);
        assert_eq!(estimate([-0.3, 0.4, 0.5, 0.4]), 0.009);
        assert!((estimate([-1.7, 0.9, 0.9, 0.9]) - 0.009 * 4.0 * 0.81).abs() < 1e-15);
        // A left-out snapshot is not counted.
        assert_eq!(
            space.columns(&[-0.5, 0.5, 0.5, 0.5], &[3, 4]),
            vec![0, 1, 2]
        );
    }

    #[test]
    fn subspace_from_prepared_gram_is_orthonormal_without_held_coordinates() {
        // Five made-up snapshots over 2600 coordinates (more than one Gram block), one a
        // combination of two others, so that one direction is dropped.
        let nf = 2600;
        let wave = |k: usize| -> Vec<f64> {
            (0..nf)
                .map(|i| ((i * (k + 2)) as f64 * 0.013).sin() + 0.1 * k as f64)
                .collect()
        };
        let mut ds: Vec<Vec<f64>> = (0..4).map(wave).collect();
        ds.push(ds[0].iter().zip(&ds[2]).map(|(a, b)| 2.0 * a - b).collect());
        let snapshots = ds
            .into_iter()
            .map(|d| Snapshot {
                c: vec![1.0],
                active: vec![1],
                d,
                left_out: 0.0,
                apart: 0.0,
            })
            .collect();
        let space = InteractiveSpace::new(snapshots, [vec![0.0], vec![0.0]], 0, 1.0, 0.0);
        let cols = [0, 1, 2, 4];
        let held: Vec<usize> = (0..nf).step_by(97).collect();
        let sub = Subspace::new(&space, &cols, &held, Vec::new());
        assert_eq!(sub.t.ncols(), 3, "the combination adds no direction");
        // D is the snapshots' values, zero on held coordinates.
        for (j, &k) in cols.iter().enumerate() {
            for i in 0..nf {
                let expected = if held.contains(&i) {
                    0.0
                } else {
                    space.snapshots[k].d[i]
                };
                assert_eq!(sub.d[(j, i)], expected);
            }
        }
        // (D T)ᵀ (D T) = I.
        let q = sub.d.transpose() * &sub.t;
        let gram = q.transpose() * &q;
        let error = (gram - DMatrix::identity(3, 3)).abs().max();
        assert!(error < 1e-9, "orthonormality error {error}");
    }
}
