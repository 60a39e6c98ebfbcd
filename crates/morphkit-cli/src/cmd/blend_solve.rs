//! The surface frame solve of `morphkit blend`, shared by the modes that blend the surface
//! (plain frames, `--linear`, `--interactive`, and `--rig`): set up the solver once
//! ([`Surface::setup`]), solve every frame and hand each one on ([`Surface::solve`]), warn
//! about what went wrong and write the side regions ([`Solved::warn`]), write the `--report`
//! ([`Surface::report`]) and put everything in place ([`finish`]). A mode calls these in that
//! order around its own output step; the volumetric mode (`volume.rs`) has its own solve.
//!
//! It sits between the common input step ([`super::blend_inputs`]) and the modes in `blend`'s
//! one-way stack (see [`super::blend`]): it knows the frames, the report and the side outputs,
//! but not where the frames go. Frames leave through the mode's `emit` callback, in frame
//! order, so that a streamed output holds no more than [`FRAME_CHUNK`] of them and an output
//! that needs them all keeps only what it writes.

use super::blend_args::{BlendArgs, FRAME_CHUNK};
use super::blend_inputs::Input;
use super::blend_outputs::{
    mark_failed, report_jumps, unconverged_path, weights_json, write_region,
};
use crate::outputs::Outputs;
use crate::util::progress;
use anyhow::{bail, Context};
use morphkit::mesh::{Point, Topology};
use morphkit::springs::snaps::is_snap;
use morphkit::springs::{
    blend_metrics, fold_metrics, linear_blend, BlendResult, Continuity, ContinuityCheck,
    PhysicalBlend, Weights, JUMP_BOUND,
};
use serde_json::{json, Value};
use std::path::PathBuf;
use std::time::Instant;

/// Interactive frames whose error estimate exceeds this fraction of the diagonal (the issue's
/// 10⁻³) are named in a warning.
const INTERACTIVE_ESTIMATE_WARN: f64 = 1e-3;

/// The surface solver of a blend, set up once for all its frames.
pub(super) struct Surface {
    /// The physical blend of the welded shapes; `None` for `--linear`.
    solver: Option<PhysicalBlend>,
    /// The report's `interactive` object, when `--interactive` prepared its space.
    interactive: Option<Value>,
    /// Seconds the set-up took (the report's `setup_seconds`).
    setup_seconds: f64,
}

/// What the frames of a surface solve leave besides their positions (which went to the
/// mode's `emit`): the report's rows and what the warnings name. Frame ids are 0-based.
pub(super) struct Solved {
    /// Per frame: the report's row (`frame`, `weights`, and with `--report` the metrics).
    rows: Vec<Value>,
    /// Frames whose full solve did not converge.
    unconverged: Vec<usize>,
    /// Interactive frames with their error estimate over [`INTERACTIVE_ESTIMATE_WARN`].
    uncertain: Vec<(usize, f64)>,
    /// Per input vertex (`n`): true where some unconverged frame failed.
    failed: Vec<bool>,
    /// Frames with clamped springs, and how many.
    clamped: Vec<(usize, usize)>,
    /// Jumps between consecutive frames, against the linear blend's steps.
    continuity: Continuity,
    /// The jumps (their frames) that are snaps (`morphkit::springs::snaps`: halving the step
    /// keeps the move in one half), among the first [`CLASSIFIED_JUMPS`] of a full solve.
    snaps: Vec<[usize; 2]>,
}

/// Jumps of a sequence that are told apart as snaps or fast steps (three solves each).
const CLASSIFIED_JUMPS: usize = 32;

/// The side regions [`Solved::warn`] wrote beside the output, for the report.
pub(super) struct Regions {
    /// `OUT-unconverged.ply`, when a frame did not converge.
    failed_ply: Option<PathBuf>,
    /// `OUT-jumps.ply`, when a part jumped between frames.
    jumps_ply: Option<PathBuf>,
}

impl Surface {
    /// Sets up the solver of `input`'s welded shapes (none for `--linear`) and, with
    /// `--interactive`, prepares its interactive space.
    pub(super) fn setup(a: &BlendArgs, input: &Input) -> anyhow::Result<Surface> {
        if !a.linear {
            crate::util::announce_work(
                "setting up the physical blend",
                input.shapes.num_vertices(),
            );
        }
        let t_setup = Instant::now();
        let mut solver = if a.linear {
            None
        } else {
            Some(PhysicalBlend::new(
                &input.weld.shapes(&input.shapes)?,
                &input.options,
            )?)
        };
        let setup_seconds = t_setup.elapsed().as_secs_f64();
        let interactive = match solver.as_mut().filter(|_| a.interactive) {
            Some(s) => Some(super::blend_interactive::prepare(s, a, input.threads)?),
            None => None,
        };
        Ok(Surface {
            solver,
            interactive,
            setup_seconds,
        })
    }

    /// Solves every frame of `input`, [`FRAME_CHUNK`] at a time, and hands frame `k`'s
    /// positions (the input's layout, `n` points) to `emit(k, positions)` in frame order: the
    /// physical equilibrium scattered back from the weld, or the linear blend `base +
    /// Σ wᵢ (targetᵢ − base)` with `--linear`. Refuses a frame with non-finite coordinates
    /// before it is emitted.
    pub(super) fn solve(
        &mut self,
        a: &BlendArgs,
        input: &Input,
        mut emit: impl FnMut(usize, Vec<Point>) -> anyhow::Result<()>,
    ) -> anyhow::Result<Solved> {
        let (shapes, weld, weights) = (&input.shapes, &input.weld, &input.weights);
        let topology = Topology::new(shapes.num_vertices(), shapes.triangles());
        let bar = progress(
            weights.len() as u64,
            if a.linear { "linear" } else { "physical" },
        );
        let mut rows = Vec::with_capacity(weights.len());
        let mut unconverged = Vec::new();
        let mut uncertain = Vec::new();
        let mut failed = vec![false; shapes.num_vertices()];
        let mut clamped = Vec::new();
        let mut steps = ContinuityCheck::new(JUMP_BOUND, shapes.base().bbox_diagonal());
        for (c, chunk) in weights.chunks(FRAME_CHUNK).enumerate() {
            let refine = a.interactive.then_some(a.refine);
            let results = solve_frames(self.solver.as_mut(), chunk, input.threads, refine, &bar)
                .with_context(|| format!("frames from {}", c * FRAME_CHUNK))?;
            for (i, (w, r)) in chunk.iter().zip(results).enumerate() {
                let k = c * FRAME_CHUNK + i;
                let linear = linear_blend(shapes, w)?;
                let mut row = json!({ "frame": k, "weights": weights_json(w) });
                if a.report.is_some() {
                    row["linear"] = json!(blend_metrics(shapes, &topology, w, &linear)?);
                }
                let positions = match r {
                    None => linear,
                    Some(r) => {
                        // An interactive shape is a reduced minimiser: its full gradient rarely
                        // meets the tolerance, and what it owes is its error estimate.
                        let estimate = r.stats.error_estimate.unwrap_or(f64::INFINITY);
                        if a.interactive && estimate > INTERACTIVE_ESTIMATE_WARN {
                            uncertain.push((k, estimate));
                        } else if !r.stats.converged && !a.interactive {
                            unconverged.push(k);
                            mark_failed(&mut failed, weld, &r.stats.unconverged_vertices);
                        }
                        if r.stats.clamped_springs > 0 {
                            clamped.push((k, r.stats.clamped_springs));
                        }
                        let c = w.coefficients(shapes.len())?;
                        let positions = weld.scatter_frame(&r.positions, &c);
                        if a.report.is_some() {
                            row["physical"] =
                                json!(blend_metrics(shapes, &topology, w, &positions)?);
                            row["folds"] = json!(fold_metrics(shapes, &topology, w, &positions)?);
                        }
                        row["solver"] = json!(r.stats);
                        steps.push(&positions, &linear)?;
                        positions
                    }
                };
                if positions.iter().flatten().any(|v| !v.is_finite()) {
                    bail!("frame {k}: the result has non-finite coordinates; nothing was written");
                }
                emit(k, positions)?;
                rows.push(row);
            }
        }
        bar.finish_and_clear();
        let continuity = steps.finish();
        let mut snaps = Vec::new();
        if let Some(solver) = self.solver.as_mut().filter(|_| !a.interactive) {
            for j in continuity.jumps.iter().take(CLASSIFIED_JUMPS) {
                let [p, q] = j.frames;
                if is_snap(solver, &weights[p], &weights[q], j.ratio)? {
                    snaps.push(j.frames);
                }
            }
        }
        Ok(Solved {
            rows,
            unconverged,
            uncertain,
            failed,
            clamped,
            continuity,
            snaps,
        })
    }

    /// Stages the `--report` JSON, if asked for: the run, the solver and every frame's row;
    /// `write_seconds` is the time the mode's output step took (streamed writes included).
    pub(super) fn report(
        &self,
        outputs: &mut Outputs,
        a: &BlendArgs,
        input: &Input,
        (solved, regions): (&Solved, &Regions),
        (write_seconds, clip): (f64, Option<Value>),
    ) -> anyhow::Result<()> {
        let Some(r) = &a.report else {
            return Ok(());
        };
        let (shapes, solver) = (&input.shapes, &self.solver);
        let report = json!({
            "command": "blend",
            "method": if a.linear { "linear" } else if a.interactive { "interactive" } else { "physical" },
            "interactive": self.interactive,
            "inputs": input.inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "output": a.out.display().to_string(),
            "vertices": shapes.num_vertices(),
            "triangles": shapes.triangles().len(),
            "welded_vertices": input.weld.merged(),
            "springs": solver.as_ref().map(|s| s.summary().springs),
            "rig": solver.as_ref().map(|s| s.summary().clone()),
            "free_dofs": solver.as_ref().map(|s| s.num_free_dofs()),
            "fixed_vertices": solver.as_ref().map(|s| s.constraints().fixed.len()),
            // Canonical solves the sampled start ran besides the frames (a one-frame blend
            // at ½ is such a sample, and its frame then takes no Newton iteration).
            "start_sample_solves": solver.as_ref().map(|s| s.start_samples_solved()),
            "threads": input.threads,
            "unconverged_frames": solved.unconverged,
            "interactive_uncertain_frames": solved.uncertain.iter().map(|u| u.0).collect::<Vec<_>>(),
            "unconverged_region": regions.failed_ply.as_ref().map(|p| p.display().to_string()),
            "continuity": (!a.linear).then_some(&solved.continuity),
            // Which jumps are snaps (the frames' equilibrium ends there) rather than fast
            // steps (a smooth motion over the bound), among the first CLASSIFIED_JUMPS.
            "snaps": (!a.linear && !a.interactive).then_some(&solved.snaps),
            "jump_region": regions.jumps_ply.as_ref().map(|p| p.display().to_string()),
            "timings": { "setup_seconds": self.setup_seconds, "write_seconds": write_seconds, "total_seconds": input.start.elapsed().as_secs_f64() },
            // How a rig's physical clip was written (blend_rig_out.rs), when one was.
            "clip": clip,
            "frames": solved.rows,
        });
        outputs.json(r, &report)
    }
}

impl Solved {
    /// Warns about unconverged frames, uncertain interactive frames, jumps and clamped
    /// springs, and stages the regions of failing and jumping vertices beside `--out` (red on
    /// the base). Warnings that name a region print once the outputs are in place.
    pub(super) fn warn(
        &self,
        outputs: &mut Outputs,
        a: &BlendArgs,
        input: &Input,
    ) -> anyhow::Result<Regions> {
        let (unconverged, uncertain, clamped) = (&self.unconverged, &self.uncertain, &self.clamped);
        let (frames, base) = (input.weights.len(), input.shapes.base());
        let failed_ply = (!unconverged.is_empty()).then(|| unconverged_path(&a.out));
        if let Some(path) = &failed_ply {
            let count = self.failed.iter().filter(|f| **f).count();
            outputs.warn_after_commit(format!(
                "warning: {} of {} frames did not converge (frames {:?}{}); {count} vertices fail, shown red in {}",
                unconverged.len(),
                frames,
                &unconverged[..unconverged.len().min(10)],
                if unconverged.len() > 10 { ", …" } else { "" },
                path.display()
            ));
            write_region(outputs, path, base, &self.failed)?;
        }
        if let Some(&(_, worst)) = uncertain.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
            let first: Vec<usize> = uncertain.iter().take(10).map(|u| u.0).collect();
            eprintln!(
                "warning: {} of {} interactive frames have an error estimate over {INTERACTIVE_ESTIMATE_WARN} of the diagonal (frames {first:?}{}; largest {worst:.2e}); without --interactive (or with --refine) they are the equilibrium",
                uncertain.len(),
                frames,
                if uncertain.len() > 10 { ", …" } else { "" },
            );
        }
        let snaps = (!a.interactive).then_some(self.snaps.as_slice());
        let jumps_ply = report_jumps(outputs, &a.out, base, &self.continuity, snaps)?;
        if let Some(&(_, most)) = clamped.iter().max_by_key(|c| c.1) {
            eprintln!(
                "warning: extreme weights clamped the rest lengths of up to {most} springs in {} of {} frames (first: frame {}); see --report",
                clamped.len(),
                frames,
                clamped[0].0
            );
        }
        Ok(Regions {
            failed_ply,
            jumps_ply,
        })
    }
}

/// Puts every staged output in place, prints the warnings that name them, and says what was
/// written (and what of a glTF input an output of another format leaves out).
pub(super) fn finish(outputs: Outputs, a: &BlendArgs, input: &Input) -> anyhow::Result<()> {
    outputs.commit()?;
    eprintln!(
        "wrote {} frame(s) to {}",
        input.weights.len(),
        a.out.display()
    );
    crate::util::note_not_carried(&input.inputs[0], &a.out, a.mesh.as_deref());
    Ok(())
}

/// Solves every frame (`None` per frame for the linear blend), in parallel chunks so that the
/// progress bar moves.
fn solve_frames(
    solver: Option<&mut PhysicalBlend>,
    weights: &[Weights],
    threads: usize,
    interactive: Option<usize>,
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<Vec<Option<BlendResult>>> {
    let Some(solver) = solver else {
        bar.inc(weights.len() as u64);
        return Ok(weights.iter().map(|_| None).collect());
    };
    let mut out = Vec::with_capacity(weights.len());
    for (c, chunk) in weights.chunks(4 * threads).enumerate() {
        let results = match interactive {
            Some(refine) => super::blend_interactive::solve(solver, chunk, refine),
            None => solver
                .solve_many(chunk, threads)
                .into_iter()
                .map(|r| r.map_err(anyhow::Error::from))
                .collect(),
        };
        for (k, r) in results.into_iter().enumerate() {
            let frame = c * 4 * threads + k;
            out.push(Some(r.with_context(|| format!("frame {frame}"))?));
        }
        bar.inc(chunk.len() as u64);
    }
    Ok(out)
}
