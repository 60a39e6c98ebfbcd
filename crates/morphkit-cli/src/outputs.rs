//! Output planning shared by every subcommand: check every output location before any work,
//! then write all outputs or none.
//!
//! A command lists its inputs and its outputs (each with the flag that named it and what it
//! must hold) in a [`Plan`]. [`Plan::check`] fails, before anything is read or solved, when
//! - an output is an input, or a directory holding one (compared after canonicalization);
//! - two outputs are the same file, or one is a `frame_*.obj` file inside another's frame
//!   directory;
//! - an output's extension names no format it can hold (`transfer --out t.ply`);
//! - an output's directory does not exist or cannot be written (`--report /proc/x.json`);
//! - a frame directory already holds `frame_*.obj` files, which the write would replace or
//!   delete, and `--force` was not given.
//!
//! The [`Outputs`] it returns stage every write to a temporary file next to its destination
//! ([`morphkit::io::Staging`]); [`Outputs::commit`] moves them all into place once every one
//! has been written. A failed write (or an error before the commit) leaves every destination
//! as it was.

use morphkit::io::{self, Format, FramesOptions, GltfMorphs, GltfOptions, Staging};
use morphkit::{ShapeSet, TriMesh};
use serde_json::json;
use std::path::{Path, PathBuf};

pub use crate::outputs_flags::{
    asset_max_targets, check_asset_flags, check_clip_flags, check_compact_asset_flags, clip_flags,
    meshopt_flag, quantize_flag, set_context, OutputFlags,
};
use crate::outputs_flags::{context, refuse_asset_flags};

/// The stem of a path without mesh extensions (`horse-07.obj.gz` → `horse-07`).
fn stem(p: &Path) -> String {
    let name = p
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    io::shape_name(&name).to_string()
}

/// The name of what the inputs hold: the longest prefix shared by at least two input stems
/// (without trailing digits and separators: `horse-gallop-01` … `horse-gallop-48` give
/// `horse-gallop`), else the first input's stem, else `morphkit`.
pub fn sequence_name(inputs: &[PathBuf]) -> String {
    let stems: Vec<String> = inputs
        .iter()
        .map(|p| stem(p))
        .filter(|s| !s.is_empty())
        .collect();
    let trim = |s: &str| {
        s.trim_end_matches(|c: char| c.is_ascii_digit() || matches!(c, '-' | '_' | '.' | ' '))
            .to_string()
    };
    let mut best = String::new();
    for (i, a) in stems.iter().enumerate() {
        for b in &stems[i + 1..] {
            let n = a
                .char_indices()
                .zip(b.chars())
                .take_while(|((_, x), y)| x == y)
                .last()
                .map_or(0, |((k, x), _)| k + x.len_utf8());
            let p = trim(&a[..n]);
            if p.len() > best.len() {
                best = p;
            }
        }
    }
    if best.is_empty() {
        best = stems.first().map_or_else(String::new, |s| trim(s));
    }
    if best.is_empty() {
        "morphkit".into()
    } else {
        best
    }
}

/// `opts` with what the run knows filled in where it still has the default: glTF and USD
/// names (the inputs' [`sequence_name`]; the clip is `NAME-SUBCOMMAND`, or `NAME` for
/// `convert`), the output flags, and extras / custom layer data with the command line, the
/// subcommand, the source files, the frame rate and the frame count (merged into extras the
/// command set, such as blend weights per frame).
pub fn frames_options(opts: &FramesOptions, frames: usize) -> FramesOptions {
    let ctx = context();
    let mut o = opts.clone();
    let name = sequence_name(&o.inputs);
    let defaults = GltfOptions::default();
    if o.gltf.name == defaults.name {
        o.gltf.name = name.clone();
        if o.gltf.clip_name.is_none() && !ctx.subcommand.is_empty() && ctx.subcommand != "convert" {
            o.gltf.clip_name = Some(format!("{name}-{}", ctx.subcommand));
        }
    }
    if o.usd.name == io::UsdOptions::default().name {
        o.usd.name = name;
    }
    ctx.flags.apply(&mut o.gltf);
    let mut extras = match o.gltf.extras.take() {
        Some(serde_json::Value::Object(m)) => m,
        Some(other) => {
            let mut m = serde_json::Map::new();
            m.insert("data".into(), other);
            m
        }
        None => serde_json::Map::new(),
    };
    if !ctx.command.is_empty() {
        extras.insert("command".into(), json!(ctx.command));
        extras.insert("subcommand".into(), json!(ctx.subcommand));
    }
    extras.insert(
        "sources".into(),
        json!(o
            .inputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()),
    );
    extras.insert("fps".into(), json!(o.fps));
    extras.insert("frames".into(), json!(frames));
    let extras = json!({ "morphkit": extras });
    o.gltf.extras = Some(extras.clone());
    if o.usd.custom_data.is_none() {
        o.usd.custom_data = Some(extras);
    }
    o
}

#[path = "outputs_clip.rs"]
pub(crate) mod clip;
#[path = "outputs_plan.rs"]
mod plan;
pub use plan::{is_frame_dir, Kind, Plan};

/// Writers for the outputs of a checked [`Plan`]: everything is staged, and
/// [`Outputs::commit`] moves it all into place.
#[derive(Debug)]
pub struct Outputs {
    staging: Staging,
    /// Warnings that name a staged output, printed by [`Outputs::commit`].
    notes: Vec<String>,
    /// The layout of each glTF frame animation staged ([`Outputs::clips`]).
    clips: Vec<serde_json::Value>,
}

impl Outputs {
    /// Stages one mesh (format by extension; a .glb/.gltf with the output flags).
    pub fn mesh(&mut self, path: &Path, mesh: &TriMesh) -> anyhow::Result<()> {
        let mut opts = GltfOptions::default();
        context().flags.apply(&mut opts);
        if opts != GltfOptions::default()
            && matches!(Format::from_path(path), Some(Format::Glb | Format::Gltf))
        {
            let rig = GltfMorphs {
                base: mesh.clone(),
                ..GltfMorphs::default()
            };
            return Ok(self.staging.write(path, false, |tmp| {
                io::write_gltf_with(tmp, &rig, &opts).map(|_| ())
            })?);
        }
        crate::outputs_flags::note_gltf_only_flags(path);
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_mesh(tmp, mesh))?)
    }

    /// Stages one mesh; an output of the `template`'s format (the input's own OBJ or PLY) is
    /// that file with the mesh's positions and recomputed normals, every other record kept.
    pub fn mesh_like(
        &mut self,
        path: &Path,
        mesh: &TriMesh,
        template: Option<&io::MeshTemplate>,
    ) -> anyhow::Result<()> {
        match template {
            // The staged file's name ends with the destination's, so it has the same format.
            Some(t) if t.fits(path) => Ok(self
                .staging
                .write(path, false, |tmp| t.write(tmp, &mesh.positions))?),
            _ => self.mesh(path, mesh),
        }
    }

    /// Stages a binary PLY with colours.
    pub fn colored_ply(
        &mut self,
        path: &Path,
        mesh: &TriMesh,
        colors: &io::Colors,
    ) -> anyhow::Result<()> {
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_ply_colored(tmp, mesh, colors))?)
    }

    /// Stages a glTF rig (target names kept) with the run's flags and extras, named `morphkit`;
    /// see [`Outputs::gltf_from`] to name it after the inputs.
    // Kept with its signature for the commands written against it (issue 9's `rig`).
    #[allow(dead_code)]
    pub fn gltf(&mut self, path: &Path, rig: &GltfMorphs) -> anyhow::Result<()> {
        self.gltf_from(path, rig, &[])
    }

    /// Stages a glTF rig (target names kept), with the run's names (after `inputs`), flags and
    /// extras ([`frames_options`]); warns on stderr about what viewers may not play.
    pub fn gltf_from(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        inputs: &[PathBuf],
    ) -> anyhow::Result<()> {
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            rig.weight_keys.len(),
        );
        self.gltf_with(path, rig, &opts.gltf)
    }

    fn gltf_with(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        opts: &GltfOptions,
    ) -> anyhow::Result<()> {
        let mut summary = io::GltfSummary::default();
        self.staging.write(path, false, |tmp| {
            summary = io::write_gltf_with(tmp, rig, opts)?;
            Ok(())
        })?;
        report_gltf(path, &summary, opts);
        Ok(())
    }

    /// Stages `frames` as the compact clip `c` ([`io::choose_layout`]), its layout in the asset's
    /// `extras.morphkit.clip`, and says how close to the frames it plays, measured on the
    /// written file ([`clip::played_error`]).
    fn compact_gltf(
        &mut self,
        path: &Path,
        frames: &ShapeSet,
        c: &io::CompactFrames,
        opts: &mut FramesOptions,
        tolerance: f64,
    ) -> anyhow::Result<()> {
        let diagonal = frames.base().bbox_diagonal();
        let layout = json!({
            "kind": "compact",
            "targets": c.morphs.targets.len(),
            "tolerance": tolerance,
            "max_error": c.max_error / diagonal,
        });
        if let Some(e) = opts.gltf.extras.as_mut() {
            e["morphkit"]["clip"] = layout.clone();
        }
        let mut summary = io::GltfSummary::default();
        let mut played = (0.0, 0);
        self.staging.write(path, false, |tmp| {
            summary = io::write_compact_frames_with(tmp, c, &opts.gltf)?;
            played = clip::played_error(tmp, frames)?;
            Ok(())
        })?;
        report_gltf(path, &summary, &opts.gltf);
        eprintln!(
            "note: {}: {} frames written as a compact clip: {} morph target{} at per-frame \
             weights, every frame within {:.2e} of the diagonal as played (--clip-tolerance \
             {tolerance:.1e}; --per-frame-targets keeps one target per frame)",
            path.display(),
            frames.len(),
            c.morphs.targets.len(),
            if c.morphs.targets.len() == 1 { "" } else { "s" },
            played.0
        );
        if played.0 > tolerance {
            eprintln!(
                "warning: {}: frame {} plays {:.2e} of the diagonal from its frame (the \
                 writer's rounding), more than --clip-tolerance {tolerance:.1e}",
                path.display(),
                played.1,
                played.0
            );
        }
        let mut layout = layout;
        layout["played_error"] = json!(played.0);
        layout["worst_frame"] = json!(played.1);
        self.clips.push(layout);
        Ok(())
    }

    /// The layout of each glTF frame animation staged so far (`kind`: `compact` or
    /// `per_frame_targets`, with the compact clip's targets and errors), for `--report`.
    pub fn clips(&self) -> &[serde_json::Value] {
        &self.clips
    }

    /// Stages a user's glTF asset ([`io::GltfAsset`]) as one file, with the run's command line,
    /// sources and frame count in `asset.extras.morphkit` ([`frames_options`]).
    pub fn gltf_asset(
        &mut self,
        path: &Path,
        asset: &io::GltfAsset,
        inputs: &[PathBuf],
        frames: usize,
    ) -> anyhow::Result<()> {
        self.gltf_asset_with(path, asset, inputs, frames, false)
    }

    /// [`Outputs::gltf_asset`]; `compact`: the edit adds a compact clip, which `--quantize`
    /// applies to ([`check_compact_asset_flags`]).
    pub fn gltf_asset_with(
        &mut self,
        path: &Path,
        asset: &io::GltfAsset,
        inputs: &[PathBuf],
        frames: usize,
        compact: bool,
    ) -> anyhow::Result<()> {
        refuse_asset_flags(path, compact)?;
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            frames,
        );
        let opts = io::GltfAssetOptions {
            extras: opts.gltf.extras,
        };
        Ok(self
            .staging
            .write(path, false, |tmp| asset.write(tmp, &opts))?)
    }

    /// Stages a rig as `UsdSkel` blend shapes named after its targets, with the run's names and
    /// custom layer data ([`frames_options`]).
    pub fn usd_blendshapes(
        &mut self,
        path: &Path,
        rig: &GltfMorphs,
        inputs: &[PathBuf],
    ) -> anyhow::Result<()> {
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            0,
        );
        Ok(self.staging.write(path, false, |tmp| {
            io::write_usd_blendshapes(tmp, &rig.base, &rig.targets, &rig.target_names, &opts.usd)
        })?)
    }

    /// Stages a bake ([`morphkit::bake::write_usd`]: slider and combination blend shapes with
    /// their in-betweens) with the run's names and custom layer data ([`frames_options`]).
    pub fn usd_bake(
        &mut self,
        path: &Path,
        base: &morphkit::TriMesh,
        baked: &morphkit::bake::BakedRig,
        sliders: &[String],
        inputs: &[PathBuf],
    ) -> anyhow::Result<()> {
        let opts = frames_options(
            &FramesOptions {
                inputs: inputs.to_vec(),
                ..FramesOptions::default()
            },
            0,
        );
        Ok(self.staging.write(path, false, |tmp| {
            morphkit::bake::write_usd(tmp, base, baked, sliders, &opts.usd)
        })?)
    }

    /// Stages an animation (a frame directory, `.glb`/`.gltf`, `.pc2` or `.usda`), calling
    /// `on_frame(i)` after each OBJ frame; names, flags and extras as [`frames_options`].
    pub fn frames(
        &mut self,
        path: &Path,
        frames: &ShapeSet,
        opts: &FramesOptions,
        on_frame: impl FnMut(usize),
    ) -> anyhow::Result<()> {
        let mut opts = frames_options(opts, frames.len());
        let dir = is_frame_dir(path);
        if !dir && matches!(Format::from_path(path), Some(Format::Glb | Format::Gltf)) {
            return match io::choose_layout(frames, opts.fps, &opts.gltf) {
                io::Layout::Compact(c, tolerance) => {
                    self.compact_gltf(path, frames, &c, &mut opts, tolerance)
                }
                io::Layout::PerFrame(note) => {
                    if let Some(n) = note {
                        eprintln!("note: {}: {n}", path.display());
                    }
                    let rig = io::frames_to_gltf(frames, opts.fps);
                    let targets = rig.targets.len();
                    self.clips
                        .push(json!({ "kind": "per_frame_targets", "targets": targets }));
                    self.gltf_with(path, &rig, &opts.gltf)
                }
            };
        }
        crate::outputs_flags::note_gltf_only_flags(path);
        Ok(self.staging.write(path, dir, |tmp| {
            io::write_frames_with(tmp, frames, &opts, on_frame)
        })?)
    }

    /// Stages an animation of a command's `target` mesh file: into the user's asset when both
    /// `target` and `path` are glTF (the frames added as the clip `clip`, at `k / fps` seconds:
    /// one morph target each, [`io::GltfAsset::add_frame_animation`], or compactly where the
    /// rule of sequences says so, [`clip::compacts_onto_asset`]), into the target's own OBJ records for
    /// a frame directory of an OBJ target, and as [`Outputs::frames`] otherwise.
    pub fn frames_of_target(
        &mut self,
        path: &Path,
        frames: &ShapeSet,
        opts: &FramesOptions,
        target: &Path,
        clip: &str,
    ) -> anyhow::Result<()> {
        if let Some(mut asset) = target_asset(path, target, frames.num_vertices())? {
            let positions: Vec<Vec<morphkit::mesh::Point>> = (0..frames.len())
                .map(|k| frames.positions(k).to_vec())
                .collect();
            let times = clip_times(frames.len(), opts.fps);
            if clip::compacts_onto_asset(&asset, frames.len()) {
                let summary = clip::add_frames_compactly(&mut asset, clip, &times, &positions)?;
                self.gltf_asset_with(path, &asset, &opts.inputs, frames.len(), true)?;
                eprintln!(
                    "added the animation '{clip}' ({} frames: {} targets of their displacements, \
                     within {:.2e} of the diagonal) to the asset of {}",
                    frames.len(),
                    summary["corrective_targets"],
                    summary["max_error"].as_f64().unwrap_or(f64::NAN),
                    target.display()
                );
                self.clips.push(summary);
                return Ok(());
            }
            asset.add_frame_animation(clip, &times, &positions)?;
            self.gltf_asset(path, &asset, &opts.inputs, frames.len())?;
            eprintln!(
                "added the animation '{clip}' ({} frames, one morph target each) to the asset of {}",
                frames.len(),
                target.display()
            );
            return Ok(());
        }
        let mut opts = opts.clone();
        if opts.obj_template.is_none() {
            opts.obj_template = crate::util::obj_template(target, frames.num_vertices())?;
        }
        self.frames(path, frames, &opts, |_| {})
    }

    /// Stages an animation written frame by frame ([`io::FrameStream`]: a frame directory
    /// when `dir`, else `.pc2`) of `frames` frames of `base`'s connectivity; a directory's
    /// frames are written into `template` where there is one.
    pub fn stream(
        &mut self,
        path: &Path,
        dir: bool,
        base: &TriMesh,
        frames: usize,
        template: Option<io::MeshTemplate>,
    ) -> anyhow::Result<io::FrameStream> {
        let tmp = self.staging.stage(path, dir)?;
        let template = template.and_then(io::MeshTemplate::into_obj);
        Ok(io::FrameStream::create(&tmp, path, dir, base, frames)?.with_obj_template(template))
    }

    /// Stages an output that `write` produces at the temporary path it is given (a file, or a
    /// directory when `dir`): for writers without a method of their own.
    pub fn custom(
        &mut self,
        path: &Path,
        dir: bool,
        write: impl FnOnce(&Path) -> Result<(), io::IoError>,
    ) -> anyhow::Result<()> {
        Ok(self.staging.write(path, dir, write)?)
    }

    /// Stages a JSON document (pretty-printed).
    pub fn json(&mut self, path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(value)?;
        self.text(path, &text)
    }

    /// Stages a text file.
    pub fn text(&mut self, path: &Path, text: &str) -> anyhow::Result<()> {
        Ok(self
            .staging
            .write(path, false, |tmp| io::write_atomic(tmp, text.as_bytes()))?)
    }

    /// Moves every staged output into place.
    pub fn commit(self) -> anyhow::Result<()> {
        self.staging.commit()?;
        for n in &self.notes {
            eprintln!("{n}");
        }
        Ok(())
    }

    /// Prints `text` on stderr once [`Outputs::commit`] has put every output in place: for a
    /// warning that names an output written beside the result (`OUT-jumps.ply`), so that a run
    /// failing later never points to a file it does not write.
    pub fn warn_after_commit(&mut self, text: String) {
        self.notes.push(text);
    }
}

/// The user's asset that [`Outputs::frames_of_target`] edits for frames of `vertices`
/// vertices of `target` written to `path`: `Some` when both are glTF files and the asset's mesh
/// has that many vertices, with --max-targets set.
fn target_asset(
    path: &Path,
    target: &Path,
    vertices: usize,
) -> anyhow::Result<Option<io::GltfAsset>> {
    let gltf = |p: &Path| matches!(Format::from_path(p), Some(Format::Glb | Format::Gltf));
    if !(gltf(target) && gltf(path) && !is_frame_dir(path)) {
        return Ok(None);
    }
    let mut asset = io::GltfAsset::read(target, &io::GltfReadOptions::default())?;
    if asset.morphs().base.num_vertices() != vertices {
        return Ok(None);
    }
    asset.set_max_targets(asset_max_targets());
    Ok(Some(asset))
}

/// The times of `frames` frames at `fps`: `k / fps` seconds.
fn clip_times(frames: usize, fps: f64) -> Vec<f64> {
    (0..frames).map(|k| k as f64 / fps).collect()
}

/// Refuses, before any frame is made, what [`Outputs::frames_of_target`] would refuse at the
/// write of `frames` frames of `vertices` vertices as the clip `clip`: where the output is an
/// edit of the user's asset `target`, the output flags the edit does not apply
/// ([`check_asset_flags`]) and what the asset refuses
/// ([`io::GltfAsset::check_frame_animation`]: more morph targets than --max-targets, no node
/// to play the clip).
pub fn check_frames_of_target(
    path: &Path,
    target: &Path,
    vertices: usize,
    frames: usize,
    clip: &str,
    fps: f64,
) -> anyhow::Result<()> {
    if let Some(asset) = target_asset(path, target, vertices)? {
        let times = clip_times(frames, fps);
        if clip::compacts_onto_asset(&asset, frames) {
            check_compact_asset_flags(path)?;
            asset.check_clip_keys(clip, &times, frames)?;
        } else {
            check_asset_flags(path)?;
            asset.check_frame_animation(clip, &times, frames)?;
        }
    }
    Ok(())
}

/// Tells on stderr when a glTF animation was split or will not play everywhere.
pub fn report_gltf(path: &Path, summary: &io::GltfSummary, opts: &GltfOptions) {
    for w in &summary.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    if summary.float_position_targets + summary.float_normal_targets > 0 {
        eprintln!(
            "note: {}: of {} quantized morph targets, {} keep f32 position deltas (they move \
             farther than the mesh's size) and {} keep f32 normal deltas (normals turn too far for \
             8 bits); --no-normals leaves normals out",
            path.display(),
            summary.targets,
            summary.float_position_targets,
            summary.float_normal_targets
        );
    }
    if summary.meshes > 1 {
        eprintln!(
            "warning: {}: {} morph targets are more than the {} one mesh may hold in WebGL2 \
             viewers (--max-targets); written as {} meshes of at most {} targets, shown in turn by \
             node scale",
            path.display(),
            summary.targets,
            opts.max_targets,
            summary.meshes,
            opts.max_targets
        );
    }
}

#[cfg(test)]
#[path = "outputs_tests.rs"]
mod tests;
