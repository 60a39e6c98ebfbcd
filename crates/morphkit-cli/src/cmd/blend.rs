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
//! .glb/.gltf output is that asset with the physical animation added (`blend_rig.rs` reads
//! it, `blend_rig_out.rs` writes it).
//!
//! # Layout: a one-way stack
//!
//! Every mode reads the same arguments and starts from the same inputs, and the surface modes
//! share one frame solve; each module imports only modules below it, so that a mode can be
//! changed (or one added) without touching the others:
//!
//! ```text
//! blend.rs              dispatcher: common checks, then one mode
//! ├ blend_frames.rs     mode: surface frames → stream / animation / single mesh
//! ├ blend_rig_out.rs    mode: --rig into its own .glb/.gltf → the asset with clips added
//! ├ volume.rs           mode: --interior / --anchor, the volumetric solve → frames
//! ├ scene.rs            mode: --scene (reads its own TOML; imports no blend module)
//! │ blend_solve.rs      the surface frame solve, warnings, --report (frames leave by `emit`)
//! │ blend_interactive.rs  --interactive's preparation and reduced solves
//! │ blend_inputs.rs     the common input step: Input (shapes, weights, weld, options)
//! │ blend_rig.rs        --rig's reader (called by the input step)
//! │ blend_outputs.rs    side outputs: OUT-unconverged.ply, OUT-jumps.ply, weights as JSON
//! └ blend_args.rs       BlendArgs, MAX_FRAMES, FRAME_CHUNK, threads, BlendOptions from flags
//! ```
//!
//! A mode is a short pipeline, inputs → solve → outputs, and each output is a function of
//! its own: a new output is a new function (or mode), not a branch in the shared loop.

use anyhow::bail;
use std::time::Instant;

pub use super::blend_args::BlendArgs;

/// Runs `morphkit blend`: `--scene` on its own; otherwise the checks every mode shares (flags,
/// then the common input step), the checks on combinations of modes, and the mode.
pub fn run(a: &BlendArgs) -> anyhow::Result<()> {
    if let Some(scene) = &a.scene {
        let threads = super::blend_args::threads(a);
        return super::scene::run(scene, &a.out, a.report.as_deref(), threads);
    }
    let start = Instant::now();
    let inputs = super::blend_inputs::input_paths(a)?;
    super::blend_inputs::check_flags(a)?;
    let (input, rig, outputs) = super::blend_inputs::read(a, inputs, start)?;
    let volume = super::volume::requested(a);
    // A .glb/.gltf output of --rig is the rig's asset with the physical animation added.
    let carry = rig.is_some() && super::blend_rig::carries(&a.out) && !input.single_mesh;
    if carry && volume {
        bail!("--rig with --interior writes frames, not the asset: give a directory or .pc2 --out");
    }
    if a.interactive && volume {
        bail!("--interactive is for surface blends: leave out --interior");
    }
    if volume {
        return super::volume::run(a, &input, outputs);
    }
    match rig.filter(|_| carry) {
        Some(rig) => super::blend_rig_out::run(a, rig, input, outputs),
        None => super::blend_frames::run(a, input, outputs),
    }
}
