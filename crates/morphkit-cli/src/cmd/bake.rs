//! `morphkit bake`: a glTF rig's physical blend baked into ordinary blendshapes (issue 56), so
//! that a DCC or an engine plays the physical look live at the cost of a linear blend. The
//! asset comes back whole with the in-between and combination shapes added as morph targets
//! and the mapping from its sliders to them in `mesh.extras.morphkitBake`
//! ([`morphkit::bake::add_to_gltf`]; the client's evaluation is in docs/bake.md). The
//! shapes are [`morphkit::bake::bake`]'s, on the welded rig, written in the asset's layout.

use crate::outputs::{Kind, Plan};
use crate::weights::{self, Origin};
use anyhow::{bail, Context};
use morphkit::bake::{bake, BakeOptions};
use morphkit::geom::max_distance;
use morphkit::io::{Format, GltfAsset, GltfReadOptions};
use morphkit::mesh::{ShapeSet, Weld, WELD_TOLERANCE};
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  morphkit bake --rig face.glb --out face-baked.glb
  morphkit bake --rig face.glb --mesh Head --inbetweens 3 --report bake.json --out baked.glb
  morphkit bake --rig face.glb --out face-baked.usda
  morphkit bake --rig face.glb --out baked.glb --check poses.csv --check-frames played/ --report bake.json

The output plays in any glTF viewer as the linear blend of the sliders' targets; the physical
look needs the sliders mapped to the baked targets' weights (mesh.extras.morphkitBake; about
twenty lines of JavaScript for three.js in docs/bake.md).";

/// Arguments of `morphkit bake`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct BakeArgs {
    /// The rig: a .glb/.gltf whose mesh has named morph targets (the sliders).
    #[arg(long)]
    pub rig: PathBuf,
    /// The mesh, by name or index, when several have morph targets.
    #[arg(long)]
    pub mesh: Option<String>,
    /// The baked asset (.glb or .gltf: the asset with the shapes added and the slider mapping
    /// in its extras) or a .usda (UsdSkel blend shapes with in-betweens).
    #[arg(long)]
    pub out: PathBuf,
    /// In-between shapes per target, at k / (N + 1) (default 7: the eighths).
    #[arg(long)]
    pub inbetweens: Option<usize>,
    /// Most combination shapes' pairs, those that move a vertex farthest first (default 120).
    #[arg(long)]
    pub max_pairs: Option<usize>,
    /// More in-betweens where a target's interpolation between its in-betweens is farther than
    /// this fraction of the diagonal from its equilibrium (default 1e-3; 0 keeps the regular
    /// in-betweens), halving segments down to 1/64, as many as the room --max-targets leaves
    /// (at most 64).
    #[arg(long, value_name = "FRACTION")]
    pub inbetween_tolerance: Option<f64>,
    /// A JSON report: counts, sizes and timings.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Slider weights to check the bake at: a CSV whose header names the targets, one state
    /// per row (as `blend --weights-file`). Each row is solved in full and compared with the
    /// bake's evaluation (what a client plays) and with the linear blend; `--report` lists the
    /// distances (`check`), and a line says the worst.
    #[arg(long)]
    pub check: Option<PathBuf>,
    /// The bake's evaluation at each `--check` row, as an animation (a frame directory,
    /// .pc2, .glb or .usda): the positions a client playing the baked rig shows.
    #[arg(long, requires = "check")]
    pub check_frames: Option<PathBuf>,
    /// Threads for the solves (default: the machine's cores); the result does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Overwrite outputs that exist.
    #[arg(long)]
    pub force: bool,
}

/// Runs `morphkit bake`.
pub fn run(a: &BakeArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let usd = match Format::from_path(&a.out) {
        Some(Format::Glb | Format::Gltf) => false,
        Some(Format::Usda) => true,
        _ => bail!(
            "{}: the baked rig is written as .glb, .gltf (the asset with the shapes and the \
             slider mapping) or .usda (UsdSkel blend shapes with in-betweens)",
            a.out.display()
        ),
    };
    let defaults = BakeOptions::default();
    let mut options = BakeOptions {
        inbetweens: a.inbetweens.unwrap_or(defaults.inbetweens),
        max_pairs: a.max_pairs.unwrap_or(defaults.max_pairs),
        inbetween_tolerance: a
            .inbetween_tolerance
            .unwrap_or(defaults.inbetween_tolerance),
        ..defaults
    };
    if options.inbetweens == 0 {
        bail!("--inbetweens must be at least 1");
    }
    let t = options.inbetween_tolerance;
    if !(t.is_finite() && t >= 0.0) {
        bail!(
            "--inbetween-tolerance must be a finite fraction of the diagonal, 0 or more, not {t}"
        );
    }
    let mut inputs = vec![a.rig.clone()];
    inputs.extend(a.check.iter().cloned());
    let mut outputs = Plan::new(&inputs)
        .force(a.force)
        .output("--out", &a.out, Kind::Mesh)
        .output_opt("--report", a.report.as_ref(), Kind::Json)
        .output_opt("--check-frames", a.check_frames.as_ref(), Kind::Animation)
        .check()?;
    crate::outputs::check_asset_flags(&a.out)?;
    crate::util::announce_reading(&inputs);
    let mut asset = GltfAsset::read(
        &a.rig,
        &GltfReadOptions {
            mesh: a.mesh.clone(),
        },
    )?;
    asset.set_max_targets(crate::outputs::asset_max_targets());
    morphkit::bake::check_gltf(&asset)?;
    let m = asset.morphs().clone();
    if m.targets.is_empty() {
        bail!("{}: the mesh has no morph targets to bake", a.rig.display());
    }
    // Before the solves: the room for every shape the bake may add.
    let n = m.targets.len();
    let most = n * options.inbetweens
        + options.max_pairs.min(n * (n - 1) / 2) * options.pair_samples.len();
    asset.check_room(most).context(
        "the bake adds in-betweens and combination shapes; lower --inbetweens or --max-pairs",
    )?;
    // The in-betweens a tolerance adds fit in the room left.
    if asset.max_targets() != 0 {
        let left = (asset
            .max_targets()
            .saturating_sub(asset.morphs().targets.len()))
        .saturating_sub(most);
        options.max_refined = options.max_refined.min(left);
    }
    let check_rows = match &a.check {
        Some(f) => check_rows(f, &m.target_names)?,
        None => Vec::new(),
    };
    let named = std::iter::once(("base".to_string(), m.base.positions.clone()))
        .chain(m.target_names.iter().cloned().zip(m.targets.clone()))
        .collect();
    let shapes = ShapeSet::new(m.base.clone(), named)
        .with_context(|| format!("{}: the morph targets", a.rig.display()))?;
    let weld = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let welded = weld.shapes(&shapes)?;
    let threads = a
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, 64);
    crate::util::announce_work("baking the physical blend", shapes.num_vertices());
    let mut solver = PhysicalBlend::new(&welded, &BlendOptions::default())?;
    let t_bake = Instant::now();
    let baked = bake(&mut solver, &options, threads)?.unweld(&weld, &welded);
    let bake_seconds = t_bake.elapsed().as_secs_f64();
    let checked = check(&mut solver, &weld, &shapes, &baked, &check_rows, threads)?;
    if let (Some(path), false) = (&a.check_frames, checked.is_empty()) {
        let frames = ShapeSet::new(
            shapes.base().clone(),
            checked
                .iter()
                .enumerate()
                .map(|(k, c)| (format!("frame_{k:04}"), c.played.clone()))
                .collect(),
        )?;
        let opts = morphkit::io::FramesOptions {
            inputs: inputs.clone(),
            ..Default::default()
        };
        outputs.frames(path, &frames, &opts, |_| {})?;
    }
    let added = if usd {
        outputs.usd_bake(&a.out, shapes.base(), &baked, &m.target_names, &inputs)?;
        baked.num_shapes() - n
    } else {
        morphkit::bake::add_to_gltf(&mut asset, &baked)?;
        outputs.gltf_asset(&a.out, &asset, &inputs, 0)?;
        asset.morphs().targets.len() - n
    };
    if let Some(r) = &a.report {
        let report = json!({
            "command": "bake",
            "rig": a.rig.display().to_string(),
            "output": a.out.display().to_string(),
            "vertices": shapes.num_vertices(),
            "welded_vertices": weld.merged(),
            "sliders": n,
            "inbetweens_per_target": options.inbetweens,
            // Per target, its in-betweens (its own shape at 1 included), after the tolerance.
            "inbetweens": baked.targets.iter().map(|t| t.weights.clone()).collect::<Vec<_>>(),
            "inbetween_tolerance": options.inbetween_tolerance,
            "combinations": baked.combinations.iter().map(|c| [c.targets.0, c.targets.1]).collect::<Vec<_>>(),
            "targets_added": added,
            "shapes_total": n + added,
            "solves": baked.solves,
            "threads": threads,
            "check": checked.iter().map(|c| json!({
                "weights": c.weights,
                "bake_error": c.bake_error,
                "linear_error": c.linear_error,
                "converged": c.converged,
            })).collect::<Vec<_>>(),
            "timings": { "bake_seconds": bake_seconds, "total_seconds": start.elapsed().as_secs_f64() },
        });
        outputs.json(r, &report)?;
    }
    outputs.commit()?;
    if let Some(worst) = checked
        .iter()
        .max_by(|x, y| x.bake_error.total_cmp(&y.bake_error))
    {
        let closer = checked
            .iter()
            .filter(|c| c.bake_error < c.linear_error)
            .count();
        eprintln!(
            "checked {} states: the bake is within {:.2e} of the diagonal of the full solve (the linear blend {:.2e} there); closer than the linear blend in {closer}",
            checked.len(),
            worst.bake_error,
            worst.linear_error
        );
    }
    // In-betweens proper: each target's shapes but its own at 1.
    let inbetweens: usize = baked.targets.iter().map(|t| t.weights.len() - 1).sum();
    eprintln!(
        "baked {n} target{} into {inbetweens} in-betweens ({} where the tolerance needed them) \
         and {} combination shapes ({added} shapes added) in {}",
        if n == 1 { "" } else { "s" },
        inbetweens - n * options.inbetweens,
        baked.combinations.len(),
        a.out.display()
    );
    Ok(())
}

/// One `--check` state: its slider weights, what the bake plays there, and the distances of
/// that and of the linear blend from the full solve (largest vertex distance over the base's
/// bounding-box diagonal).
struct Checked {
    weights: Vec<f64>,
    played: Vec<morphkit::mesh::Point>,
    bake_error: f64,
    linear_error: f64,
    converged: bool,
}

/// The rows of the `--check` file `f`, checked as `blend --weights-file` checks them.
fn check_rows(f: &std::path::Path, names: &[String]) -> anyhow::Result<Vec<Vec<f64>>> {
    let rows = morphkit::io::read_named_weights(f, names)?;
    let mut out = Vec::with_capacity(rows.len());
    for (frame, row) in rows.iter().enumerate() {
        let w = Weights::Delta(row.values.clone());
        weights::check(
            &w,
            names.len() + 1,
            Origin::File {
                path: f,
                row,
                frame,
            },
        )?;
        out.push(row.values.clone());
    }
    Ok(out)
}

/// Solves every row in full on up to `threads` threads (on the welded rig, each copy then
/// given its own position) and compares it with `baked`'s evaluation and the linear blend.
fn check(
    solver: &mut PhysicalBlend,
    weld: &Weld,
    shapes: &ShapeSet,
    baked: &morphkit::bake::BakedRig,
    rows: &[Vec<f64>],
    threads: usize,
) -> anyhow::Result<Vec<Checked>> {
    let diag = morphkit::mesh::bbox_diagonal(shapes.positions(0)).max(f64::MIN_POSITIVE);
    let weights: Vec<Weights> = rows.iter().map(|w| Weights::Delta(w.clone())).collect();
    let solved = solver.solve_many(&weights, threads);
    let mut out = Vec::with_capacity(rows.len());
    for ((w, x), r) in rows.iter().zip(&weights).zip(solved) {
        let r = r?;
        let solved = weld.scatter_frame(&r.positions, &x.coefficients(shapes.len())?);
        let played = baked.evaluate(w);
        let linear = morphkit::springs::linear_blend(shapes, x)?;
        out.push(Checked {
            weights: w.clone(),
            bake_error: max_distance(&played, &solved) / diag,
            linear_error: max_distance(&linear, &solved) / diag,
            converged: r.stats.converged,
            played,
        });
    }
    Ok(out)
}
