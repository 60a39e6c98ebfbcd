//! `morphkit blend --interactive` (issue 38): every frame from the rig's prepared interactive
//! space (`morphkit::springs::interactive`) instead of the full canonical solve, as a slider
//! preview would be, with each frame's error estimate in the report.

use super::blend_args::BlendArgs;
use anyhow::Context;
use morphkit::springs::{BlendResult, InteractiveCacheUse, PhysicalBlend, Weights};
use serde_json::{json, Value};
use std::time::Instant;

/// Prepares the space (from `--interactive-cache` where it holds this rig), on `threads`
/// threads; returns the report's `interactive` object.
pub fn prepare(solver: &mut PhysicalBlend, a: &BlendArgs, threads: usize) -> anyhow::Result<Value> {
    let started = Instant::now();
    crate::util::announce_work(
        "preparing the interactive space",
        solver.shapes().num_vertices(),
    );
    let used = match &a.interactive_cache {
        Some(path) => solver
            .prepare_interactive_cached(threads, path)
            .with_context(|| format!("--interactive-cache {}", path.display()))?,
        None => {
            solver.prepare_interactive(threads);
            InteractiveCacheUse {
                loaded: false,
                replaced: None,
            }
        }
    };
    if let Some(why) = &used.replaced {
        // `why` names the file.
        eprintln!(
            "note: the interactive cache was not a preparation of this rig ({why}); prepared again and replaced it"
        );
    }
    let space = solver.interactive_space().expect("prepared above");
    Ok(json!({
        "snapshots": space.len(),
        "unconverged_snapshots": space.unconverged,
        "seconds": started.elapsed().as_secs_f64(),
        "loaded": used.loaded,
        "replaced": used.replaced,
        "cache": a.interactive_cache.as_ref().map(|p| p.display().to_string()),
        "refine": a.refine,
    }))
}

/// The interactive shapes of `weights`, one after the other (each takes milliseconds; the
/// space does not change, so they are the same on any split of the frames).
pub fn solve(
    solver: &mut PhysicalBlend,
    weights: &[Weights],
    refine: usize,
) -> Vec<anyhow::Result<BlendResult>> {
    weights
        .iter()
        .map(|w| Ok(solver.solve_interactive(w, refine)?))
        .collect()
}
