//! The arguments of `morphkit blend` and what follows from them alone: the clap struct
//! [`BlendArgs`], the limits every mode shares ([`MAX_FRAMES`], [`FRAME_CHUNK`]), the thread
//! count, and the solver's [`BlendOptions`] built from the flags.
//!
//! This is the bottom of `blend`'s one-way stack (see [`super::blend`]): every mode and every
//! shared step reads `BlendArgs`, so it sits in a module that imports none of them. Nothing
//! here reads a file or writes one; the fixed vertices arrive already read and welded.

use morphkit::springs::{BlendOptions, FixedVertices, HingeOptions, Precision, SpringOptions};
use std::path::PathBuf;

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
animation, NAME-physical, keyed at the keys' times: the asset's own targets at the clip's weights
plus a few corrective targets, the basis of the physical-minus-linear residual within
--clip-tolerance (1e-3 of the diagonal) in every frame; --per-frame-targets keys one new morph
target per frame instead (more frames than --max-targets, default 200, what WebGL2 viewers play,
is then refused before any solve).";

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
    /// Solve each frame by continuation along its weights' ray from the rest shape in K steps
    /// (each from the last equilibrium), so that a part that could settle either way keeps
    /// the branch the motion starts on. About K times the work per frame; 0 (the default) or
    /// 1: one solve from the canonical start. Frames stay functions of their weights.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=64))]
    pub continuation: u64,
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

/// `--threads`, by default the machine's cores, clamped to 1..=64.
pub(super) fn threads(a: &BlendArgs) -> usize {
    a.threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, 64)
}

/// The solver's options from the flags, for a blend of `frames` frames with `fixed` the
/// boundary conditions in the welded numbering (`blend_inputs::welded_fixed`). Reference
/// factors are only asked for from [`REFERENCE_MIN_FRAMES`] frames on; the memory limit is
/// `--max-memory` GiB in bytes.
pub(super) fn blend_options(a: &BlendArgs, fixed: FixedVertices, frames: usize) -> BlendOptions {
    BlendOptions {
        springs: SpringOptions {
            k0: a.k0,
            bending: a.bending_springs,
            ..Default::default()
        },
        hinges: HingeOptions {
            weight: a.hinge_weight,
            ..Default::default()
        },
        fixed,
        gradient_tolerance: a.tolerance,
        kinematic_stretch: a.kinematic_stretch,
        tether: a.tether,
        thin_band_rings: a.thin_band_rings,
        refactor_every: a.refactor_every,
        keep_factor_cg: a.keep_factor_cg,
        sampled_start: !a.no_sampled_start,
        continuation_steps: a.continuation as usize,
        // References cost a probe solve and five factorizations per target, which only a
        // sequence pays back: a one-frame blend of a 40k-vertex sheet took 25 s with them and
        // 1.7 s without (docs/performance.md, "Film scale").
        reference_factor_bytes: if a.no_reference_factors || frames < REFERENCE_MIN_FRAMES {
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
    }
}
