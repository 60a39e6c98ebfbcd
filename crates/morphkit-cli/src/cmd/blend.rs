//! `morphkit blend`: physical (or linear) blendshapes of a base and targets.
//!
//! Weights, in order of precedence of the flags (exactly one is required):
//! - `--alpha A`: two shapes, rest lengths `(1 − A) r_base + A r_target` (Ma et al. Eq. 1);
//! - `--weights w1,w2,…`: one weight per target, artist "delta" form `base + Σ wᵢ (targetᵢ − base)`
//!   (what glTF morph targets and DCC blendshape nodes use); with `--convex`, one weight per
//!   shape including the base, summing to 1 (the paper's Sec. 3.3);
//! - `--frames N`: `N` frames with α from 0 to 1 (`αₖ = k / (N − 1)`), one target only;
//! - `--weights-file F`: one weight vector per frame, JSON (`{"frames": [[…], …]}` or a bare
//!   array of arrays) or CSV (one row per frame; `#` comments and a non-numeric header skipped).
//!
//! With `--rig FILE.glb` instead of `--base`/`--target`, the file's mesh, morph targets and
//! weights animation (or `--weights-file`, its header naming targets) are the inputs, and a
//! .glb/.gltf output is that asset with the physical animation added (`blend_rig.rs`).

use crate::outputs::{is_frame_dir, Kind, Plan};
use crate::util::{check_fps, check_positive, progress};
use anyhow::{bail, Context};
use morphkit::io::{self, FramesOptions};
use morphkit::mesh::{ShapeSet, Topology, Weld, WELD_TOLERANCE};
use morphkit::springs::{
    blend_metrics, fold_metrics, linear_blend, BlendResult, ContinuityCheck, PhysicalBlend,
    Weights, JUMP_BOUND,
};
use serde_json::json;

pub(super) use super::blend_inputs::{
    check_frames_memory, frame_weights, read_fixed, welded_fixed,
};
pub(super) use super::blend_outputs::{
    jumps_path, mark_failed, report_jumps, unconverged_path, weights_json, write_region,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use super::blend_args::BlendArgs;
use super::blend_args::{blend_options, threads, FRAME_CHUNK};

/// Interactive frames whose error estimate exceeds this fraction of the diagonal (the issue's
/// 10⁻³) are named in a warning.
const INTERACTIVE_ESTIMATE_WARN: f64 = 1e-3;

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

/// Runs `morphkit blend`.
pub fn run(a: &BlendArgs) -> anyhow::Result<()> {
    if let Some(scene) = &a.scene {
        return super::scene::run(scene, &a.out, a.report.as_deref(), threads(a));
    }
    let start = Instant::now();
    let mut inputs = match (&a.rig, &a.base) {
        (Some(rig), _) => vec![rig.clone()],
        (None, Some(base)) => vec![base.clone()],
        _ => bail!("give --base and --target, --rig, or --scene"),
    };
    inputs.extend(a.targets.iter().cloned());
    let mut protected = inputs.clone();
    protected.extend(a.weights_file.iter().cloned());
    if !matches!(a.fixed.as_str(), "auto" | "none") {
        protected.push(PathBuf::from(&a.fixed));
    }
    super::blend_inputs::check_dependent_flags(a)?;
    check_positive("--k0", a.k0)?;
    check_positive("--tolerance", a.tolerance)?;
    check_fps(a.fps)?;
    let mut outputs = Plan::new(&protected)
        .force(a.force)
        .output("--out", &a.out, Kind::MeshOrAnimation)
        .output_opt("--report", a.report.as_ref(), Kind::Json)
        .output_opt(
            "--interactive-cache",
            a.interactive_cache.as_ref(),
            Kind::Json,
        )
        .output_sometimes("OUT-unconverged.ply", &unconverged_path(&a.out), Kind::Mesh)
        .output_sometimes("OUT-jumps.ply", &jumps_path(&a.out), Kind::Mesh)
        .check()?;
    crate::util::announce_reading(&inputs);
    let (rig, shapes) = match &a.rig {
        Some(r) => {
            let (rig, shapes) = super::blend_rig::read(a, r)?;
            (Some(rig), shapes)
        }
        None => (None, io::read_shape_set(&inputs)?),
    };
    crate::util::warn_carried(&inputs[0], shapes.base());
    // An OBJ or PLY base comes back as the artist's own file: texture coordinates, normals'
    // hard edges, materials, groups, colours and custom properties kept (io::MeshTemplate).
    let template = crate::util::template(&inputs[0], shapes.num_vertices())?;
    let weights = match &rig {
        Some(r) => r.weights.clone(),
        None => frame_weights(a, shapes.len())?,
    };
    for (k, w) in weights.iter().enumerate() {
        w.coefficients(shapes.len())
            .with_context(|| format!("frame {k}: invalid weights"))?;
    }
    let single_mesh =
        !is_frame_dir(&a.out) && io::Format::from_path(&a.out).is_some_and(|f| f.is_single_mesh());
    if single_mesh && weights.len() != 1 {
        bail!("{}: a single-mesh output holds one frame, but {} frames were asked for; use a directory, .glb or .pc2", a.out.display(), weights.len());
    }
    if !(a.max_memory.is_finite() && a.max_memory > 0.0) {
        bail!("--max-memory must be a finite positive number of GiB");
    }
    check_frames_memory(&a.out, weights.len(), shapes.num_vertices(), a.max_memory)?;
    let topology = Topology::new(shapes.num_vertices(), shapes.triangles());
    // Split seams and hard edges are one vertex for the solve (mesh::weld); results go back in
    // the input's layout.
    let weld = (!a.linear).then(|| Weld::of_shapes(&shapes, WELD_TOLERANCE));
    let weld = weld.unwrap_or_else(|| Weld::identity(shapes.num_vertices()));
    if !weld.is_identity() {
        eprintln!(
            "welded {} split vertices (seams, hard edges) into the {} they share a position with in every shape; the result keeps the input's {} vertices",
            weld.merged(),
            weld.num_welded(),
            weld.num_input()
        );
    }
    let fixed = welded_fixed(read_fixed(&a.fixed)?, &weld, Path::new(&a.fixed))?;
    let options = blend_options(a, fixed, weights.len());
    let threads = threads(a);
    // A .glb/.gltf output of --rig is the rig's asset with the physical animation added.
    let carry = rig.is_some() && super::blend_rig::carries(&a.out) && !single_mesh;
    if carry && super::volume::requested(a) {
        bail!("--rig with --interior writes frames, not the asset: give a directory or .pc2 --out");
    }
    if a.interactive && super::volume::requested(a) {
        bail!("--interactive is for surface blends: leave out --interior");
    }
    if super::volume::requested(a) {
        return super::volume::run(
            a,
            (&shapes, &weld),
            &weights,
            &options,
            threads,
            start,
            outputs,
        );
    }
    if !a.linear {
        crate::util::announce_work("setting up the physical blend", shapes.num_vertices());
    }
    let t_setup = Instant::now();
    let mut solver = if a.linear {
        None
    } else {
        Some(PhysicalBlend::new(&weld.shapes(&shapes)?, &options)?)
    };
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let interactive = match solver.as_mut().filter(|_| a.interactive) {
        Some(s) => Some(super::blend_interactive::prepare(s, a, threads)?),
        None => None,
    };

    let bar = progress(
        weights.len() as u64,
        if a.linear { "linear" } else { "physical" },
    );
    // A frame directory or .pc2 receives each chunk of frames as it is solved; other formats
    // need every frame before the file.
    let dir_out = is_frame_dir(&a.out);
    let mut stream = if !single_mesh && io::FrameStream::supports(&a.out, dir_out) {
        Some(outputs.stream(
            &a.out,
            dir_out,
            shapes.base(),
            weights.len(),
            template.clone(),
        )?)
    } else {
        None
    };
    let mut frames = Vec::new();
    let mut rows = Vec::with_capacity(weights.len());
    let mut unconverged = Vec::new();
    let mut uncertain = Vec::new();
    let mut failed = vec![false; shapes.num_vertices()];
    let mut clamped = Vec::new();
    let mut steps = ContinuityCheck::new(JUMP_BOUND, shapes.base().bbox_diagonal());
    let mut write_seconds = 0.0;
    for (c, chunk) in weights.chunks(FRAME_CHUNK).enumerate() {
        let refine = a.interactive.then_some(a.refine);
        let results = solve_frames(solver.as_mut(), chunk, threads, refine, &bar)
            .with_context(|| format!("frames from {}", c * FRAME_CHUNK))?;
        for (i, (w, r)) in chunk.iter().zip(results).enumerate() {
            let k = c * FRAME_CHUNK + i;
            let linear = linear_blend(&shapes, w)?;
            let mut row = json!({ "frame": k, "weights": weights_json(w) });
            if a.report.is_some() {
                row["linear"] = json!(blend_metrics(&shapes, &topology, w, &linear)?);
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
                        mark_failed(&mut failed, &weld, &r.stats.unconverged_vertices);
                    }
                    if r.stats.clamped_springs > 0 {
                        clamped.push((k, r.stats.clamped_springs));
                    }
                    let c = w.coefficients(shapes.len())?;
                    let positions = weld.scatter_frame(&r.positions, &c);
                    if a.report.is_some() {
                        row["physical"] = json!(blend_metrics(&shapes, &topology, w, &positions)?);
                        row["folds"] = json!(fold_metrics(&shapes, &topology, w, &positions)?);
                    }
                    row["solver"] = json!(r.stats);
                    steps.push(&positions, &linear)?;
                    positions
                }
            };
            if positions.iter().flatten().any(|v| !v.is_finite()) {
                bail!("frame {k}: the result has non-finite coordinates; nothing was written");
            }
            match &mut stream {
                Some(s) => {
                    let t = Instant::now();
                    s.push(&positions)?;
                    write_seconds += t.elapsed().as_secs_f64();
                }
                None => frames.push((format!("frame_{k:04}"), positions)),
            }
            rows.push(row);
        }
    }
    bar.finish_and_clear();
    let failed_ply = (!unconverged.is_empty()).then(|| unconverged_path(&a.out));
    if let Some(path) = &failed_ply {
        let count = failed.iter().filter(|f| **f).count();
        outputs.warn_after_commit(format!(
            "warning: {} of {} frames did not converge (frames {:?}{}); {count} vertices fail, shown red in {}",
            unconverged.len(),
            weights.len(),
            &unconverged[..unconverged.len().min(10)],
            if unconverged.len() > 10 { ", …" } else { "" },
            path.display()
        ));
        write_region(&mut outputs, path, shapes.base(), &failed)?;
    }
    if let Some(&(_, worst)) = uncertain.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        let first: Vec<usize> = uncertain.iter().take(10).map(|u| u.0).collect();
        eprintln!(
            "warning: {} of {} interactive frames have an error estimate over {INTERACTIVE_ESTIMATE_WARN} of the diagonal (frames {first:?}{}; largest {worst:.2e}); without --interactive (or with --refine) they are the equilibrium",
            uncertain.len(),
            weights.len(),
            if uncertain.len() > 10 { ", …" } else { "" },
        );
    }
    let continuity = steps.finish();
    let jumps_ply = report_jumps(&mut outputs, &a.out, shapes.base(), &continuity)?;
    if let Some(&(_, most)) = clamped.iter().max_by_key(|c| c.1) {
        eprintln!(
            "warning: extreme weights clamped the rest lengths of up to {most} springs in {} of {} frames (first: frame {}); see --report",
            clamped.len(),
            weights.len(),
            clamped[0].0
        );
    }
    let t_write = Instant::now();
    if let Some(s) = stream {
        s.finish()?;
    } else if let Some(r) = rig.filter(|_| carry) {
        super::blend_rig::write(&mut outputs, &a.out, r, frames, &inputs)?;
    } else {
        let out_set = ShapeSet::new(shapes.base().clone(), frames)?;
        if single_mesh {
            outputs.mesh_like(&a.out, &out_set.mesh(0), template.as_ref())?;
        } else {
            let mut opts = FramesOptions {
                fps: a.fps,
                inputs: inputs.clone(),
                ..FramesOptions::default()
            };
            opts.gltf.extras =
                Some(json!({ "weights": weights.iter().map(weights_json).collect::<Vec<_>>() }));
            outputs.frames(&a.out, &out_set, &opts, |_| {})?;
        }
    }
    write_seconds += t_write.elapsed().as_secs_f64();
    if let Some(r) = &a.report {
        let report = json!({
            "command": "blend",
            "method": if a.linear { "linear" } else if a.interactive { "interactive" } else { "physical" },
            "interactive": interactive,
            "inputs": inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "output": a.out.display().to_string(),
            "vertices": shapes.num_vertices(),
            "triangles": shapes.triangles().len(),
            "welded_vertices": weld.merged(),
            "springs": solver.as_ref().map(|s| s.summary().springs),
            "rig": solver.as_ref().map(|s| s.summary().clone()),
            "free_dofs": solver.as_ref().map(|s| s.num_free_dofs()),
            "fixed_vertices": solver.as_ref().map(|s| s.constraints().fixed.len()),
            // Canonical solves the sampled start ran besides the frames (a one-frame blend
            // at ½ is such a sample, and its frame then takes no Newton iteration).
            "start_sample_solves": solver.as_ref().map(|s| s.start_samples_solved()),
            "threads": threads,
            "unconverged_frames": unconverged,
            "interactive_uncertain_frames": uncertain.iter().map(|u| u.0).collect::<Vec<_>>(),
            "unconverged_region": failed_ply.as_ref().map(|p| p.display().to_string()),
            "continuity": (!a.linear).then_some(&continuity),
            "jump_region": jumps_ply.as_ref().map(|p| p.display().to_string()),
            "timings": { "setup_seconds": setup_seconds, "write_seconds": write_seconds, "total_seconds": start.elapsed().as_secs_f64() },
            "frames": rows,
        });
        outputs.json(r, &report)?;
    }
    outputs.commit()?;
    eprintln!("wrote {} frame(s) to {}", weights.len(), a.out.display());
    crate::util::note_not_carried(&inputs[0], &a.out, a.mesh.as_deref());
    Ok(())
}
