//! `morphkit blend --interior … --anchor …`: the physical blend with internal springs for
//! volume and the rigid anchor (Ma et al. 2012, Sec. 3.1 and 3.4), through
//! [`VolumetricBlend`]. The flags are parsed here; `blend.rs` only hands over.
//!
//! - `--interior none|lattice|tetgen[,density[,volume]]`: `lattice` fills each closed component with a
//!   BCC lattice (density 1: spacing two mean edges; 2: half that), small holes capped for
//!   the inside test; components with larger openings are blended with surface springs alone
//!   and listed in the report and on stderr. `tetgen` runs
//!   an external `tetgen` (Debian package; AGPL, only run as a separate process) on each closed
//!   component's surface for a constrained Delaunay tetrahedralization (largest tetrahedron a
//!   regular one of edge 2 mean edges / density; the surface is not split); without `tetgen`
//!   on the PATH it is a clear error. `volume` (default 10, 0: off) is the stiffness of the
//!   volume term on the interior's tetrahedra and the lattice's shell (issue 40).
//! - `--anchor auto|x,y,z[,size]`: a small stiff cube inside the base whose vertices are the
//!   boundary conditions; the result follows its slerp-interpolated rigid motion.
//!
//! A mode of `blend`'s one-way stack (see [`super::blend`]): inputs (an [`Input`], read by
//! the common step) → the volumetric solve → frames, with the side outputs of
//! [`super::blend_outputs`]; it imports nothing above those.

use super::blend_args::BlendArgs;
use super::blend_inputs::Input;
use super::blend_outputs::{
    mark_failed, report_jumps, unconverged_path, weights_json, write_region,
};
use crate::outputs::Outputs;
use crate::util::progress;
use anyhow::{bail, Context};
use morphkit::io::{self, FramesOptions};
use morphkit::mesh::{ShapeSet, Topology};
use morphkit::springs::interior::VolumeResult;
use morphkit::springs::{blend_metrics, AnchorOptions, InteriorOptions, VolumetricBlend};
use serde_json::json;
use std::time::Instant;

/// Parses `--interior none|lattice|tetgen[,density[,volume]]`.
pub fn parse_interior(spec: &str) -> anyhow::Result<InteriorOptions> {
    InteriorOptions::parse(spec).map_err(|e| anyhow::anyhow!("--interior: {e}"))
}

/// Parses `--anchor auto|x,y,z[,size]`.
pub fn parse_anchor(spec: Option<&str>) -> anyhow::Result<AnchorOptions> {
    match spec {
        None => Ok(AnchorOptions::default()),
        Some(s) => AnchorOptions::parse(s).map_err(|e| anyhow::anyhow!("--anchor: {e}")),
    }
}

/// True when the volumetric path is asked for.
pub fn requested(a: &BlendArgs) -> bool {
    a.anchor.is_some() || a.interior.trim() != "none"
}

/// Runs the volumetric blend of `morphkit blend` on `input` and writes its outputs.
pub(super) fn run(a: &BlendArgs, input: &Input, mut outputs: Outputs) -> anyhow::Result<()> {
    let (shapes, weld, weights) = (&input.shapes, &input.weld, &input.weights[..]);
    let (options, threads, start) = (&input.options, input.threads, input.start);
    if a.linear {
        bail!("--linear blends without springs; it cannot be combined with --interior or --anchor");
    }
    let interior = parse_interior(&a.interior)?;
    let anchor = parse_anchor(a.anchor.as_deref())?;
    let mut inputs: Vec<std::path::PathBuf> = a.base.iter().cloned().collect();
    inputs.extend(a.targets.iter().cloned());
    let t_setup = Instant::now();
    let mut solver = VolumetricBlend::new(&weld.shapes(shapes)?, options, &interior, &anchor)?;
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let rep = solver.report().clone();
    for s in &rep.skipped {
        eprintln!(
            "note: component {} (vertex {}) has no interior ({}); it is blended with surface springs only",
            s.component, s.example_vertex, s.reason
        );
    }
    let bar = progress(weights.len() as u64, "volumetric");
    let mut results: Vec<VolumeResult> = Vec::with_capacity(weights.len());
    for (c, chunk) in weights.chunks(4 * threads).enumerate() {
        for (k, r) in solver.solve_many(chunk, threads).into_iter().enumerate() {
            results.push(r.with_context(|| format!("frame {}", c * 4 * threads + k))?);
        }
        bar.inc(chunk.len() as u64);
    }
    bar.finish_and_clear();
    let topology = Topology::new(shapes.num_vertices(), shapes.triangles());
    let mut frames = Vec::with_capacity(results.len());
    let mut rows = Vec::with_capacity(results.len());
    let mut unconverged = Vec::new();
    let mut failed = vec![false; shapes.num_vertices()];
    let mut steps = morphkit::springs::ContinuityCheck::new(
        morphkit::springs::JUMP_BOUND,
        shapes.base().bbox_diagonal(),
    );
    let (mut worst_tets, mut worst_tris) = (0, 0);
    for (k, (w, mut r)) in weights.iter().zip(results).enumerate() {
        r.positions = weld.scatter(&r.positions);
        if !r.stats.converged {
            unconverged.push(k);
            mark_failed(&mut failed, weld, &r.stats.unconverged_vertices);
        }
        worst_tets = worst_tets.max(r.inversions.tetrahedra);
        worst_tris = worst_tris.max(r.inversions.triangles);
        let mut row = json!({
            "frame": k, "weights": weights_json(w), "solver": r.stats,
            "inversions": r.inversions,
        });
        let lin = morphkit::springs::linear_blend(shapes, w)?;
        steps.push(&r.positions, &lin)?;
        if a.report.is_some() {
            row["linear"] = json!(blend_metrics(shapes, &topology, w, &lin)?);
            row["physical"] = json!(blend_metrics(shapes, &topology, w, &r.positions)?);
            if let Some(t) = &r.anchor_motion {
                row["anchor_rotation"] = json!(t.rotation.as_slice());
                row["anchor_translation"] = json!(t.translation.as_slice());
            }
        }
        if r.positions.iter().flatten().any(|v| !v.is_finite()) {
            bail!("frame {k}: the result has non-finite coordinates; nothing was written");
        }
        frames.push((format!("frame_{k:04}"), r.positions));
        rows.push(row);
    }
    if worst_tets + worst_tris > 0 {
        eprintln!("note: element inversion (Ma et al. Sec. 5): up to {worst_tets} interior tetrahedra and {worst_tris} surface triangles flipped against the linear blend in a frame (see --report)");
    }
    let continuity = steps.finish();
    let jumps_ply = report_jumps(&mut outputs, &a.out, shapes.base(), &continuity, None)?;
    let failed_ply = (!unconverged.is_empty()).then(|| unconverged_path(&a.out));
    if let Some(path) = &failed_ply {
        outputs.warn_after_commit(format!(
            "warning: {} of {} frames did not converge; failing vertices in red in {}",
            unconverged.len(),
            weights.len(),
            path.display()
        ));
        write_region(&mut outputs, path, shapes.base(), &failed)?;
    }
    let out_set = ShapeSet::new(shapes.base().clone(), frames)?;
    let single = io::Format::from_path(&a.out).is_some_and(|f| f.is_single_mesh());
    if single {
        outputs.mesh(&a.out, &out_set.mesh(0))?;
    } else {
        let fo = FramesOptions {
            fps: a.fps,
            inputs: inputs.clone(),
            ..FramesOptions::default()
        };
        outputs.frames(&a.out, &out_set, &fo, |_| {})?;
    }
    if let Some(r) = &a.report {
        let report = json!({
            "command": "blend",
            "method": "physical-volumetric",
            "inputs": inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "output": a.out.display().to_string(),
            "vertices": shapes.num_vertices(),
            "welded_vertices": weld.merged(),
            "triangles": shapes.triangles().len(),
            "interior": rep,
            "rig": solver.physical().summary(),
            "threads": threads,
            "unconverged_frames": unconverged,
            "unconverged_region": failed_ply.as_ref().map(|p| p.display().to_string()),
            "continuity": continuity,
            "jump_region": jumps_ply.as_ref().map(|p| p.display().to_string()),
            "timings": { "setup_seconds": setup_seconds, "total_seconds": start.elapsed().as_secs_f64() },
            "frames": rows,
        });
        outputs.json(r, &report)?;
    }
    outputs.commit()?;
    eprintln!("wrote {} frame(s) to {}", weights.len(), a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use morphkit::springs::{AnchorPlacement, InteriorMode};

    #[test]
    fn flags_parse_and_bad_ones_are_refused() {
        assert_eq!(parse_interior("none").unwrap().mode, InteriorMode::None);
        let o = parse_interior("lattice,2.5").unwrap();
        assert_eq!((o.mode, o.density), (InteriorMode::Lattice, 2.5));
        assert_eq!(parse_interior("tetgen").unwrap().mode, InteriorMode::Tetgen);
        assert!(parse_interior("voxels").is_err());
        assert!(parse_interior("lattice,-1").is_err());
        assert_eq!(parse_interior("lattice,1,2").unwrap().volume, 2.0);
        assert_eq!(parse_interior("lattice,1,0").unwrap().volume, 0.0);
        assert!(parse_interior("lattice,1,-2").is_err());
        assert!(parse_interior("lattice,1,2,3").is_err());
        assert_eq!(
            parse_anchor(Some("auto")).unwrap().placement,
            AnchorPlacement::Auto
        );
        assert_eq!(
            parse_anchor(Some("1,2,3,0.5")).unwrap().placement,
            AnchorPlacement::At {
                center: [1.0, 2.0, 3.0],
                size: Some(0.5)
            }
        );
        assert!(parse_anchor(Some("1,2")).is_err());
        assert!(parse_anchor(Some("a,b,c")).is_err());
    }
}
