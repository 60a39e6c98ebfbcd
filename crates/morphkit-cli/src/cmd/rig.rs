//! `morphkit rig`: move a blendshape rig (a neutral and named expressions) onto another
//! character as named glTF morph targets, one deformation transfer per expression
//! ([`morphkit::transfer::rig`]).

use super::corr_args::CorrespondenceArgs;
use super::weld_util;
use crate::outputs::{Kind, Plan};
use anyhow::{bail, Context};
use morphkit::io::{self, Format, GltfAsset, GltfMorphs, GltfReadOptions};
use morphkit::transfer::{RigOptions, RigTransfer};
use morphkit::{ShapeSet, TriMesh};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  morphkit rig --source-neutral neutral.obj --source-shapes 'expr/*.obj' --target head.obj \\
      --markers markers.json --out head-rig.glb
  morphkit rig --source-shapes face-rig.glb --target head.obj --correspondence corr.json \\
      --out head-rig.glb --shapes-dir head-shapes --report rig.json
  morphkit rig --source-shapes face-rig.glb --target character.glb --mesh Head \\
      --markers markers.json --out character-rig.glb

One morph target per source shape, in the order given (a glob expands sorted by name, numbers as numbers: `pose2` before `pose10`), named by
the file stem (jawOpen.obj.gz → jawOpen) or the source GLB's target names. Deltas are relative to
the target mesh as given (its neutral). The neutral stays where it is (no root motion); a
target posed differently from the source (rotated, scaled) gets the expressions rotated and
scaled alike. A .glb/.gltf target comes back whole (materials, textures, skins, other meshes,
node transforms kept) with the shapes added as morph targets of its mesh (--mesh NAME when
several meshes have morph targets); a shape named as an existing target replaces it.";

/// Arguments of `morphkit rig`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct RigArgs {
    /// Source neutral mesh (optional when --source-shapes is a GLB: its base mesh).
    #[arg(long, value_name = "MESH")]
    pub source_neutral: Option<PathBuf>,
    /// Source expressions: mesh files, quoted globs, or one .glb/.gltf with morph targets.
    #[arg(long, required = true, num_args = 1.., value_name = "SHAPES")]
    pub source_shapes: Vec<String>,
    /// Target neutral mesh (the new character); a .glb/.gltf target's chosen mesh, and the
    /// output is that asset with the shapes added.
    #[arg(long, value_name = "MESH")]
    pub target: PathBuf,
    /// The mesh of a .glb/.gltf --target, by name or index (needed when several have morph
    /// targets; an index where they share a name).
    #[arg(long, value_name = "NAME|INDEX")]
    pub mesh: Option<String>,
    /// The mesh of a .glb/.gltf --source-shapes, by name or index.
    #[arg(long, value_name = "NAME|INDEX")]
    pub source_mesh: Option<String>,
    #[command(flatten)]
    pub corr: CorrespondenceArgs,
    /// Output rig: .glb or .gltf, the target with one named morph target per shape, or .usda
    /// (UsdSkel blend shapes with the same names).
    #[arg(long, value_name = "GLB")]
    pub out: PathBuf,
    /// Also write every transferred shape as DIR/NAME.obj (the directory is created).
    #[arg(long, value_name = "DIR")]
    pub shapes_dir: Option<PathBuf>,
    /// Write a JSON report (per-shape timings and fold counts).
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
}

/// The file stem without mesh extensions: `dir/jawOpen.obj.gz` → `jawOpen`.
fn stem(p: &Path) -> String {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    for ext in [".obj.gz", ".obj", ".ply", ".off", ".glb", ".gltf"] {
        if lower.ends_with(ext) {
            return name[..name.len() - ext.len()].to_string();
        }
    }
    name
}

/// Names must be usable as file names in --shapes-dir and be distinct.
fn check_names(names: &[String]) -> anyhow::Result<()> {
    for (i, n) in names.iter().enumerate() {
        if !io::is_valid_target_name(n) {
            bail!("shape {i}: the name '{n}' cannot be a morph-target or file name");
        }
        if let Some(j) = names[..i].iter().position(|m| m == n) {
            bail!("shapes {j} and {i} are both named '{n}'");
        }
    }
    Ok(())
}

/// The source neutral and its expressions.
fn read_source(args: &RigArgs, files: &[PathBuf]) -> anyhow::Result<(TriMesh, ShapeSet)> {
    let glb = match files {
        [one] if matches!(Format::from_path(one), Some(Format::Glb | Format::Gltf)) => Some(one),
        _ => None,
    };
    if let Some(g) = glb {
        let opts = GltfReadOptions {
            mesh: args.source_mesh.clone(),
        };
        let m = io::read_gltf_morphs_with(g, &opts)?;
        if m.targets.is_empty() {
            bail!("{}: has no morph targets", g.display());
        }
        let neutral = match &args.source_neutral {
            Some(n) => io::read_mesh(n)?,
            None => m.base.clone(),
        };
        let shapes = ShapeSet::new(
            m.base.clone(),
            m.target_names.iter().cloned().zip(m.targets).collect(),
        )?;
        return Ok((neutral, shapes));
    }
    let Some(n) = &args.source_neutral else {
        bail!("give --source-neutral MESH (needed unless --source-shapes is one .glb/.gltf)");
    };
    let neutral = io::read_mesh(n)?;
    let set = io::read_shape_set(files)?;
    let named = (0..set.len())
        .map(|i| (stem(&files[i]), set.positions(i).to_vec()))
        .collect();
    Ok((neutral, ShapeSet::new(set.base().clone(), named)?))
}

/// The target neutral, and the --target asset when it is a .glb/.gltf written to a .glb/.gltf
/// (with room for the shapes under --max-targets).
fn read_target(args: &RigArgs, shapes: &ShapeSet) -> anyhow::Result<(TriMesh, Option<GltfAsset>)> {
    let gltf = |p: &Path| matches!(Format::from_path(p), Some(Format::Glb | Format::Gltf));
    if !gltf(&args.target) {
        if args.mesh.is_some() {
            bail!("--mesh chooses the mesh of a .glb/.gltf --target");
        }
        return Ok((io::read_mesh(&args.target)?, None));
    }
    let opts = GltfReadOptions {
        mesh: args.mesh.clone(),
    };
    if !gltf(&args.out) {
        return Ok((io::read_mesh_with(&args.target, &opts)?.0, None));
    }
    crate::outputs::check_asset_flags(&args.out)?;
    let mut asset = GltfAsset::read(&args.target, &opts)?;
    let mesh = asset.morphs().base.clone();
    morphkit::mesh::validate(&mesh)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.target.display()))?;
    asset.set_max_targets(crate::outputs::asset_max_targets());
    let existing = &asset.morphs().target_names;
    let fresh = shapes
        .names()
        .iter()
        .filter(|n| !existing.contains(n))
        .count();
    asset.check_room(fresh)?;
    Ok((mesh, Some(asset)))
}

/// The correspondence arguments with the rig's own defaults (unrefined unless --refine:
/// [`RigOptions::correspondence`]) and the rig options (the library's [`RigOptions::default`]
/// with --combine).
pub(crate) fn options(args: &RigArgs) -> (CorrespondenceArgs, RigOptions) {
    let mut corr_args = args.corr.clone();
    corr_args.defaults = RigOptions::correspondence();
    let mut opts = RigOptions::default();
    opts.transfer.combine = args.corr.combine();
    (corr_args, opts)
}

/// Runs `morphkit rig`.
pub fn run(args: &RigArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    args.corr.require()?;
    if !matches!(
        Format::from_path(&args.out),
        Some(Format::Glb | Format::Gltf | Format::Usda)
    ) {
        bail!(
            "--out {}: a rig is written as .glb, .gltf or .usda (UsdSkel blend shapes)",
            args.out.display()
        );
    }
    let expanded = super::convert::expand(&args.source_shapes)?;
    let files = expanded.files;
    let mut inputs = expanded.protected;
    inputs.extend([args.target.clone()]);
    inputs.extend(args.source_neutral.iter().cloned());
    inputs.extend(args.corr.inputs());
    crate::util::announce_reading(&inputs);
    let (neutral, shapes) = read_source(args, &files)?;
    check_names(shapes.names())?;
    if let Some(d) = &args.shapes_dir {
        if !d.exists() {
            std::fs::create_dir_all(d)
                .with_context(|| format!("--shapes-dir {}: cannot create it", d.display()))?;
        }
    }
    let shape_paths: Vec<PathBuf> = match &args.shapes_dir {
        Some(d) => shapes
            .names()
            .iter()
            .map(|n| d.join(format!("{n}.obj")))
            .collect(),
        None => Vec::new(),
    };
    let mut plan = Plan::new(&inputs)
        .output("--out", &args.out, Kind::Mesh)
        .output_opt("--report", args.report.as_ref(), Kind::Json);
    for p in &shape_paths {
        plan = plan.output("--shapes-dir", p, Kind::Mesh);
    }
    let mut outputs = plan.check()?;
    let (target, asset) = read_target(args, &shapes)?;

    let mut report = json!({
        "source_neutral": args.source_neutral,
        "source_shapes": files,
        "target": args.target,
        "out": args.out,
        "shapes": shapes.len(),
    });
    // Split seams and hard edges are one vertex for the solves (mesh::weld): the source's
    // where they coincide in the neutral and every shape, the target's where they coincide in
    // the target; the shapes go back in the target's own layout.
    let input_target = target;
    let (source_weld, target_weld) =
        weld_util::source_and_target(&neutral, &shapes, &input_target, &mut report);
    let neutral = source_weld.mesh(&neutral);
    let target = target_weld.mesh(&input_target);
    let shapes = if source_weld.is_identity() {
        shapes
    } else {
        source_weld.shapes(&shapes)?
    };
    let (corr_args, opts) = options(args);
    let corr = weld_util::obtain_welded(
        &corr_args,
        (&neutral, &source_weld),
        (&target, &target_weld),
        &mut report,
        false,
    )?
    .correspondence;
    crate::util::announce_work("factorizing the transfer system", target.num_vertices());
    let t0 = Instant::now();
    let rt = RigTransfer::new(&neutral, &target, &corr, &opts)?;
    rt.transfer()
        .check_frames(&shapes)
        .context("source shapes vs. the source neutral")?;
    let factor_s = t0.elapsed().as_secs_f64();
    let mut per_shape = Vec::with_capacity(shapes.len());
    let mut targets = Vec::with_capacity(shapes.len());
    for i in 0..shapes.len() {
        let t1 = Instant::now();
        let (x, folds) = rt
            .transfer_shape(i, shapes.positions(i))
            .with_context(|| format!("shape {i} ({})", shapes.name(i)))?;
        let secs = t1.elapsed().as_secs_f64();
        let x = target_weld.scatter(&x);
        let max_delta = x
            .iter()
            .zip(&input_target.positions)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        per_shape.push(json!({
            "name": shapes.name(i),
            "seconds": secs,
            "flipped_triangles": folds.flipped,
            "sharp_folds": folds.sharp_folds,
            "max_delta": max_delta,
        }));
        targets.push(x);
    }
    // An OBJ or PLY target's shapes come back as the artist's own file (io::MeshTemplate).
    let template = crate::util::template(&args.target, input_target.num_vertices())?;
    for (p, x) in shape_paths.iter().zip(&targets) {
        outputs.mesh_like(
            p,
            &input_target.with_positions(x.clone()),
            template.as_ref(),
        )?;
    }
    let rig = GltfMorphs {
        base: input_target.clone(),
        target_names: shapes.names().to_vec(),
        targets,
        weight_keys: Vec::new(),
    };
    // Named after the new head.
    if let Some(mut asset) = asset {
        asset.add_targets(&rig.target_names, &rig.targets)?;
        outputs.gltf_asset(&args.out, &asset, std::slice::from_ref(&args.target), 0)?;
    } else if Format::from_path(&args.out) == Some(Format::Usda) {
        outputs.usd_blendshapes(&args.out, &rig, std::slice::from_ref(&args.target))?;
    } else {
        outputs.gltf_from(&args.out, &rig, std::slice::from_ref(&args.target))?;
    }
    let total = t_all.elapsed().as_secs_f64();
    eprintln!(
        "transferred {} shapes onto {} vertices: factorization {:.3} s, {:.1} ms per shape, {:.2} s in all",
        shapes.len(),
        input_target.num_vertices(),
        factor_s,
        1e3 * per_shape
            .iter()
            .map(|s| s["seconds"].as_f64().unwrap_or(0.0))
            .sum::<f64>()
            / shapes.len().max(1) as f64,
        total
    );
    if let Some(r) = &args.report {
        report["alignment_scale"] = json!(rt.alignment_scale());
        report["factorization_s"] = json!(factor_s);
        report["per_shape"] = json!(per_shape);
        report["total_s"] = json!(total);
        report["target_vertices"] = json!(input_target.num_vertices());
        outputs.json(r, &report)?;
    }
    outputs.commit()?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_and_names() {
        assert_eq!(stem(Path::new("a/jawOpen.obj.gz")), "jawOpen");
        assert_eq!(stem(Path::new("mouthSmile_L.OBJ")), "mouthSmile_L");
        assert_eq!(stem(Path::new("x.y.ply")), "x.y");
        assert!(check_names(&["a".into(), "b".into()]).is_ok());
        assert!(check_names(&["a".into(), "a".into()]).is_err());
        assert!(check_names(&["../x".into()]).is_err());
        assert!(check_names(&["".into()]).is_err());
    }
}
