//! `morphkit blend --scene scene.toml`: a blend that collides with obstacles and follows pulled
//! vertices (Ma et al. 2012, Sec. 4). The scene file format is documented in
//! `morphkit::scene::Scene`; this file only runs it and writes the results.

use crate::outputs::{Kind, Plan};
use crate::util::progress;
use anyhow::{bail, Context};
use morphkit::io::{self, FramesOptions};
use morphkit::mesh::{ShapeSet, Weld, WELD_TOLERANCE};
use morphkit::scene::{Pull, Scene};
use morphkit::springs::FixedVertices;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// Runs the scene at `scene_path` on up to `threads` threads (frames are independent, so the
/// result does not depend on it), writing frames to `out` and an optional JSON report.
pub fn run(
    scene_path: &Path,
    out: &Path,
    report: Option<&Path>,
    threads: usize,
) -> anyhow::Result<()> {
    let start = Instant::now();
    let mut scene = Scene::load(scene_path)?;
    // Split seams and hard edges are one vertex for the solve (mesh::weld), with the pulled
    // and fixed vertex ids mapped; results go back in the input's layout.
    let input_base = scene.shapes.base().clone();
    let weld = weld_scene(&mut scene)?;
    let mut inputs = scene.inputs.clone();
    inputs.push(scene_path.to_path_buf());
    let mut outputs = Plan::new(&inputs)
        .output("--out", out, Kind::MeshOrAnimation)
        .output_opt(
            "--report",
            report.map(Path::to_path_buf).as_ref(),
            Kind::Json,
        )
        .check()?;
    let n = scene.weights.len();
    let single = io::Format::from_path(out).is_some_and(|f| f.is_single_mesh());
    if single && n != 1 {
        bail!("{}: a single-mesh output holds one frame, but the scene has {n} frames; use a directory, .glb or .pc2", out.display());
    }
    let t_setup = Instant::now();
    let mut solver = scene.build()?;
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let bar = progress(n as u64, "scene");
    let mut frames = Vec::with_capacity(n);
    let mut rows = Vec::with_capacity(n);
    let mut unresolved = Vec::new();
    let mut unconverged = Vec::new();
    let numbered: Vec<(f64, morphkit::springs::Weights)> = scene
        .weights
        .iter()
        .enumerate()
        .map(|(k, w)| (k as f64, w.clone()))
        .collect();
    let mut solved = Vec::with_capacity(n);
    // Chunks of a few frames per thread, so that the progress bar moves.
    for chunk in numbered.chunks(4 * threads.max(1)) {
        solved.extend(solver.solve_many(chunk, threads));
        bar.inc(chunk.len() as u64);
    }
    for (k, f) in solved.into_iter().enumerate() {
        let f = f.with_context(|| format!("frame {k}"))?;
        if !f.collision.resolved {
            unresolved.push(k);
        }
        if !f.solver.converged {
            unconverged.push(k);
        }
        if f.positions.iter().flatten().any(|c| !c.is_finite()) {
            bail!("frame {k}: the result has non-finite coordinates; nothing was written");
        }
        rows.push(json!({
            "frame": k,
            "collision": f.collision,
            "solver": f.solver,
            "contact_vertices": f.contacts.iter().map(|c| weld.representative()[c.vertex as usize]).collect::<Vec<_>>(),
        }));
        frames.push((format!("frame_{k:04}"), weld.scatter(&f.positions)));
    }
    bar.finish_and_clear();
    if !unresolved.is_empty() {
        eprintln!(
            "warning: {} of {n} frames still penetrate an obstacle by more than the tolerance after the allowed collision rounds (frames {:?}; see --report)",
            unresolved.len(),
            &unresolved[..unresolved.len().min(10)]
        );
    }
    if !unconverged.is_empty() {
        eprintln!(
            "warning: {} of {n} frames did not converge (frames {:?}; see --report)",
            unconverged.len(),
            &unconverged[..unconverged.len().min(10)]
        );
    }
    let out_set = ShapeSet::new(input_base.clone(), frames)?;
    let t_write = Instant::now();
    match io::Format::from_path(out) {
        Some(io::Format::Glb | io::Format::Gltf) => {
            let tracks: Vec<_> = scene
                .obstacles
                .iter()
                .map(|o| o.gltf_track(n, scene.fps))
                .collect();
            let opts = crate::outputs::frames_options(
                &FramesOptions {
                    fps: scene.fps,
                    inputs: inputs.clone(),
                    ..FramesOptions::default()
                },
                out_set.len(),
            );
            let rig = io::frames_to_gltf(&out_set, scene.fps);
            let mut summary = None;
            outputs.custom(out, false, |tmp| {
                summary = Some(io::write_gltf_scene_with(tmp, &rig, &tracks, &opts.gltf)?);
                Ok(())
            })?;
            if let Some(summary) = summary {
                crate::outputs::report_gltf(out, &summary, &opts.gltf);
            }
        }
        _ if single => outputs.mesh(out, &out_set.mesh(0))?,
        _ => outputs.frames(
            out,
            &out_set,
            &FramesOptions {
                fps: scene.fps,
                inputs: inputs.clone(),
                ..FramesOptions::default()
            },
            |_| {},
        )?,
    }
    let write_seconds = t_write.elapsed().as_secs_f64();
    if let Some(r) = report {
        let detection: f64 = rows
            .iter()
            .filter_map(|r| r["collision"]["detection_seconds"].as_f64())
            .sum();
        let solve: f64 = rows
            .iter()
            .filter_map(|r| r["collision"]["solve_seconds"].as_f64())
            .sum();
        let value = json!({
            "command": "blend",
            "method": "physical",
            "scene": scene_path.display().to_string(),
            "inputs": scene.inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "output": out.display().to_string(),
            "vertices": input_base.num_vertices(),
            "triangles": input_base.num_triangles(),
            "welded_vertices": weld.merged(),
            "obstacles": scene.obstacles.iter().map(|o| o.name().to_string()).collect::<Vec<_>>(),
            "pulls": scene.pulls.len(),
            "interior": solver.interior_report(),
            "penetration_tolerance": solver.tolerance(),
            "unresolved_frames": unresolved,
            "unconverged_frames": unconverged,
            "timings": {
                "setup_seconds": setup_seconds,
                "detection_seconds": detection,
                "solve_seconds": solve,
                "write_seconds": write_seconds,
                "total_seconds": start.elapsed().as_secs_f64(),
            },
            "frames": rows,
        });
        outputs.json(r, &value)?;
    }
    outputs.commit()?;
    eprintln!("wrote {n} frame(s) to {}", out.display());
    Ok(())
}

/// Welds the scene's shapes where their vertices coincide in every shape, with its fixed and
/// pulled vertex ids mapped, and returns the weld.
fn weld_scene(scene: &mut Scene) -> anyhow::Result<Weld> {
    let weld = Weld::of_shapes(&scene.shapes, WELD_TOLERANCE);
    if weld.is_identity() {
        return Ok(weld);
    }
    super::weld_util::announce(&weld, "the base");
    scene.shapes = weld.shapes(&scene.shapes)?;
    // Ids out of range stay out of range, for the solver's message.
    let map = |v: u32| weld.to_welded().get(v as usize).copied().unwrap_or(v);
    if let FixedVertices::Ids(ids) = &mut scene.blend.fixed {
        *ids = weld.welded_ids(ids);
    }
    let pulls = std::mem::take(&mut scene.pulls);
    for p in pulls {
        let v = map(p.vertex());
        scene
            .pulls
            .push(Pull::new(v, p.keys().to_vec(), p.kind()).context("pull")?);
    }
    Ok(weld)
}
