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
    blend_metrics, fold_metrics, linear_blend, BlendOptions, BlendResult, ContinuityCheck,
    HingeOptions, PhysicalBlend, Precision, SpringOptions, Weights, JUMP_BOUND,
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

/// Interactive frames whose error estimate exceeds this fraction of the diagonal (the issue's
/// 10⁻³) are named in a warning.
const INTERACTIVE_ESTIMATE_WARN: f64 = 1e-3;

const EXAMPLES: &str = "\
Examples:
  morphkit blend --base straight.obj --target bent.obj --alpha 0.5 --out half.obj
  morphkit blend --base rest.obj --target bend.obj --frames 36 --out bend.glb --report bend.json
  morphkit blend --base neutral.obj --target jawOpen.obj --target smile.obj --weights 0.7,0.3 --out face.obj
  morphkit blend --base a.obj --target b.obj --target c.obj --weights 0.2,0.3,0.5 --convex --out mix.ply
  morphkit blend --base rest.obj --target bend.obj --weights-file keys.csv --fixed pinned.json --out anim.pc2
  morphkit blend --base rest.obj --target bend.obj --frames 36 --linear --out linear.glb
  morphkit blend --scene examples/bend-around-cylinder/scene.toml --out wrap.glb --report wrap.json
  morphkit blend --rig character.glb --animation Talk --out character-physical.glb
  morphkit blend --rig character.glb --mesh Face --weights-file keys.csv --out physical.glb

OUT: a directory (no extension) gets frame_0000.obj, …; .glb/.gltf gets an animation (frame k
at k/fps seconds; more than --max-targets frames are split into meshes shown in turn); .pc2 a
point cache; .usda a USD Mesh with time-sampled points; .obj/.ply/.off a single mesh (one frame
only). --fixed FILE.json holds
{\"fixed\": [vertex ids]} (0-based) or a bare array. Without fixed vertices, each connected
component keeps only its rigid motion free and is aligned to the linear blend.

Each frame is the canonical equilibrium of its weights, solved from the linear blend: frames
do not depend on each other, so --threads, frame order and repeated runs give the same bytes.
A frame that does not converge is reported on stderr and in --report, and its failing
vertices are written, coloured red, to OUT-unconverged.ply beside the output.

--rig FILE.glb blends a user's asset: its mesh (--mesh NAME|INDEX when several have morph targets),
named morph targets and weights animation (--animation NAME|INDEX when several; or --weights-file,
whose CSV header row names targets) drive the blend, and a .glb/.gltf OUT is the same asset
(materials, textures, skins, other meshes, transforms, animations kept) with one more
animation, NAME-physical, keying one new morph target per frame at the keys' times. More frames
than --max-targets (default 200, what WebGL2 viewers play) is refused before any solve.";

/// Fewest frames for which a blend computes reference factors (fewer never pay them back).
const REFERENCE_MIN_FRAMES: usize = 4;

/// Most frames one call produces.
pub(super) const MAX_FRAMES: usize = 100_000;

/// Frames solved before they are handed on: a streamed output (frame directory, .pc2) holds
/// no more than this many at a time.
pub(super) const FRAME_CHUNK: usize = 256;

/// Arguments of `morphkit blend`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct BlendArgs {
    /// A TOML scene (base, targets, weights, obstacles, pulls; see `morphkit::scene::Scene`)
    /// instead of --base/--target and the weight flags: the blend collides with the obstacles.
    #[arg(long, conflicts_with_all = ["base", "targets", "w", "rig"])]
    pub scene: Option<PathBuf>,
    /// A .glb/.gltf asset instead of --base/--target: its mesh, morph targets and weights
    /// animation drive the blend; a .glb/.gltf --out is that asset with the physical animation
    /// added.
    #[arg(long, value_name = "GLB", conflicts_with_all = ["base", "targets", "alpha", "weights", "frames", "convex"])]
    pub rig: Option<PathBuf>,
    /// The weights animation of --rig to blend, by name or index in the file's animations
    /// (needed when several drive the mesh; an index where they share a name).
    #[arg(
        long,
        value_name = "NAME|INDEX",
        requires = "rig",
        conflicts_with = "weights_file"
    )]
    pub animation: Option<String>,
    /// The mesh of --rig, by name or index (needed when several meshes have morph targets;
    /// an index where they share a name).
    #[arg(long, value_name = "NAME|INDEX", requires = "rig")]
    pub mesh: Option<String>,
    /// The base shape (shape 0).
    #[arg(long, required_unless_present_any = ["scene", "rig"])]
    pub base: Option<PathBuf>,
    /// A target shape; repeat for several. All must share the base's connectivity.
    #[arg(long = "target", required_unless_present_any = ["scene", "rig"])]
    pub targets: Vec<PathBuf>,
    /// Blend factor between the base and a single target.
    #[arg(long, group = "w")]
    pub alpha: Option<f64>,
    /// Comma-separated weights (one per target, or one per shape with --convex).
    #[arg(long, group = "w", value_delimiter = ',', allow_hyphen_values = true)]
    pub weights: Option<Vec<f64>>,
    /// Number of frames with α from 0 to 1 (single target).
    #[arg(long, group = "w")]
    pub frames: Option<usize>,
    /// File of per-frame weight vectors (JSON or CSV).
    #[arg(long, group = "w")]
    pub weights_file: Option<PathBuf>,
    /// Weights are convex over all shapes (base first) instead of per-target deltas.
    #[arg(long)]
    pub convex: bool,
    /// Boundary conditions: auto (vertices static in all shapes), none, or a JSON file of ids.
    #[arg(long, default_value = "auto")]
    pub fixed: String,
    /// Classic linear blendshapes instead of the physical blend.
    #[arg(long)]
    pub linear: bool,
    /// Base spring stiffness k0 (only ratios matter).
    #[arg(long, default_value_t = 1.0)]
    pub k0: f64,
    /// Add Ma et al.'s bending springs between vertices two edges apart (off by default: the
    /// signed hinge is the bending term; see docs/choices.md).
    #[arg(long)]
    pub bending_springs: bool,
    /// Without bending springs: the default now, accepted for older scripts.
    #[arg(long, hide = true, conflicts_with = "bending_springs")]
    pub no_bending: bool,
    /// Convergence tolerance on the gradient, in units of k0 × strain.
    #[arg(long, default_value_t = 1e-6)]
    pub tolerance: f64,
    /// Weight of the signed-hinge bending term relative to the springs (0 turns it off).
    #[arg(long, default_value_t = 0.01)]
    pub hinge_weight: f64,
    /// Stiffness, relative to the mean spring, of the zero-length springs that tie every
    /// solved vertex to the rotation-aware predictor; they keep parts that can swing either
    /// way from snapping between frames (0 turns them off).
    #[arg(long, default_value_t = 1e-5)]
    pub tether: f64,
    /// Triangles stretched more than this factor between the base and a target follow the
    /// linear blend (kinematic); `inf` turns this off.
    #[arg(long, default_value_t = 10.0)]
    pub kinematic_stretch: f64,
    /// Connected parts whose every vertex lies within N edges of the mesh boundary and that
    /// are at least twice as long as wide (eye strips, eyelash and hair cards) follow the
    /// rotation-aware predictor instead of being solved for; 0 turns this off.
    #[arg(long, default_value_t = 4)]
    pub thin_band_rings: usize,
    /// Refresh the Newton preconditioner every N iterations (0: only when it stalls). A speed
    /// knob; results agree within the tolerance.
    #[arg(long, default_value_t = 1)]
    pub refactor_every: usize,
    /// …but keep it while the last inner solve converged within N CG iterations (0: never
    /// keep). A speed knob; results agree within the tolerance.
    #[arg(long, default_value_t = 8)]
    pub keep_factor_cg: usize,
    /// Start every frame from the plain predictor instead of the predictor corrected by each
    /// target's equilibria at α = ¼, ½, ¾ (three extra solves per target, done once): cheaper
    /// for one or two frames, slower for an animation. The frames agree within the tolerance
    /// where both starts reach the same equilibrium.
    #[arg(long)]
    pub no_sampled_start: bool,
    /// Factorize every frame's own Hessians instead of preconditioning frames near a
    /// target's equilibria at α = 0, ¼, ½, ¾, 1 with those equilibria's factors, turned by
    /// each vertex's rotation (on by default where a probe frame at α = ⅜ converges on them;
    /// up to five factors of memory per target, 1 GiB in all; never for fewer than 4 frames,
    /// which do not pay them back). A speed knob; the frames agree within the tolerance.
    #[arg(long)]
    pub no_reference_factors: bool,
    /// Preconditioner of the Newton steps' inner CG: `cholesky` (a sparse factor), `aggregation`
    /// (a two-level cycle on vertex aggregates, no fine factor: for large volumetric systems,
    /// `--interior`), or `auto` (aggregation where the factor would cost more than 10⁴
    /// multiply-adds per Hessian entry; counts, never timings). The equilibrium is the same
    /// to the tolerance.
    #[arg(long, default_value = "auto", value_parser = super::bench::parse_preconditioner)]
    pub preconditioner: morphkit::springs::Preconditioner,
    /// Arithmetic of the Newton preconditioner's factor: `single` (half the memory, faster;
    /// the equilibrium is the same to the gradient tolerance) or `double`.
    #[arg(long, default_value = "single", value_parser = ["single", "double"])]
    pub factor_precision: String,
    /// Refuse meshes whose solver would need more than this many GiB, and animations whose
    /// frames would (frames × vertices, estimated before any solve).
    #[arg(long, default_value_t = 8.0)]
    pub max_memory: f64,
    /// Threads solving frames in parallel (default: the machine's cores). Results do not
    /// depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Frames per second of a .glb/.gltf or .usda animation output: N frames play as an
    /// (N − 1)/fps second clip (9 frames at the default 24 fps last 0.33 s).
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Output: directory of OBJ frames, .glb/.gltf, .pc2, .usda, or a single .obj/.ply/.off.
    #[arg(long)]
    pub out: PathBuf,
    /// Write per-frame solver statistics, timings and quality metrics as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Replace the frame_*.obj files of an existing output directory.
    #[arg(long)]
    pub force: bool,
    /// Rigid anchor (Ma et al. Sec. 3.4): `auto`, or `x,y,z[,size]` in base coordinates.
    #[arg(long)]
    pub anchor: Option<String>,
    /// Interior for volume (Sec. 3.1): `none`, `lattice` (BCC lattice, spacing 2 mean edges /
    /// density) or `tetgen` (constrained Delaunay tetrahedralization by an external `tetgen`
    /// on the PATH, tetrahedra up to a regular one of that edge), optionally `,density` and
    /// `,volume`: the stiffness of the volume term on the interior's tetrahedra and shell
    /// (default 10; 0 turns it off, springs only as in Ma et al.).
    #[arg(long, default_value = "none")]
    pub interior: String,
    /// The interactive mode (a slider preview): each frame is a small solve in the rig's
    /// space of equilibria, prepared once (canonical solves of every target at ¼, ½, ¾ and
    /// of every pair), within its `error_estimate` in --report (a fraction of the base's
    /// diagonal) of the full solve; one-hot weights are exact.
    #[arg(long, conflicts_with_all = ["linear", "anchor"])]
    pub interactive: bool,
    /// With --interactive: projected-Newton steps after each reduced solve (each costs about
    /// one Newton iteration of the full solve and brings the frame closer to it).
    #[arg(long, default_value_t = 0, requires = "interactive")]
    pub refine: usize,
    /// With --interactive: a file keeping the preparation; read when it holds one of this
    /// very rig (same shapes and options), otherwise written (replaced) after preparing; a
    /// file that is not such a cache (does not start with MKINTER) is refused, never replaced.
    #[arg(long, requires = "interactive")]
    pub interactive_cache: Option<PathBuf>,
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

/// `--threads`, by default the machine's cores.
fn threads(a: &BlendArgs) -> usize {
    a.threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, 64)
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
    let options = BlendOptions {
        springs: SpringOptions {
            k0: a.k0,
            bending: a.bending_springs,
            ..Default::default()
        },
        hinges: HingeOptions {
            weight: a.hinge_weight,
            ..Default::default()
        },
        fixed: welded_fixed(read_fixed(&a.fixed)?, &weld, Path::new(&a.fixed))?,
        gradient_tolerance: a.tolerance,
        kinematic_stretch: a.kinematic_stretch,
        tether: a.tether,
        thin_band_rings: a.thin_band_rings,
        refactor_every: a.refactor_every,
        keep_factor_cg: a.keep_factor_cg,
        sampled_start: !a.no_sampled_start,
        // References cost a probe solve and five factorizations per target, which only a
        // sequence pays back: a one-frame blend of a 40k-vertex sheet took 25 s with them and
        // 1.7 s without (docs/performance.md, "Film scale").
        reference_factor_bytes: if a.no_reference_factors || weights.len() < REFERENCE_MIN_FRAMES {
            0
        } else {
            BlendOptions::default().reference_factor_bytes
        },
        preconditioner: a.preconditioner,
        factor_precision: if a.factor_precision == "double" {
            Precision::Double
        } else {
            Precision::Single
        },
        max_memory_bytes: (a.max_memory * (1u64 << 30) as f64) as u64,
        ..Default::default()
    };
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
