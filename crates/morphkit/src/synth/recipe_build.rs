//! Turning a [`RecipeFile`] into a [`Synthesizer`]: reading the meshes, frames, markers or
//! correspondences and scribbles it names, and mapping every failure back to the recipe line
//! and key that caused it.
//!
//! Choices: a layer without `source_reference` animates the target itself (identity
//! correspondence; any same-connectivity sequence, such as a `morphkit blend` result);
//! `source_scale` multiplies the source frames only (as `morphkit transfer --source-scale`);
//! two layers with the same source reference and markers share one correspondence.

use super::recipe::{PathList, RecipeError, RecipeFile, RegionKind, TranslationKind};
use super::recipe_weld::{welded_correspondence, welded_markers};
use super::{
    BlendMode, BlendRegion, LayerSpec, PoseSpec, Scribble, SynthError, SynthFrame, SynthOptions,
    Synthesizer, Timing,
};
use crate::io::{self, Format};
use crate::mesh::{Point, ShapeSet, TriMesh, Weld};
use crate::transfer::{
    correspond, Correspondence, CorrespondenceOptions, Markers, TransferOptions, TranslationMode,
};
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A built recipe: the synthesizer and what the caller needs around it.
#[derive(Debug)]
pub struct BuiltRecipe {
    /// Ready to yield frames, on the welded target: its frames are in the welded numbering
    /// ([`BuiltRecipe::weld`]); [`BuiltRecipe::frame`] gives them in the target's own.
    pub synthesizer: Synthesizer,
    /// The target reference, as read.
    pub target: TriMesh,
    /// The target reference's file (outputs of the target carry it: its OBJ records or glTF
    /// asset).
    pub target_path: PathBuf,
    /// The weld of the target's split vertices the synthesizer solves on (the identity when
    /// nothing coincides); see [`super::recipe_weld`].
    pub weld: Weld,
    /// Per layer, how many split vertices of its source reference were welded (the target's
    /// count for a layer that animates the target).
    pub source_welded_vertices: Vec<usize>,
    /// Every file the recipe read (outputs must not overwrite them).
    pub inputs: Vec<PathBuf>,
    /// Layer names (`layer N` when unnamed).
    pub layer_names: Vec<String>,
    /// Frame rate for glTF output.
    pub fps: f64,
    /// Seconds computing correspondences.
    pub correspondence_seconds: f64,
    /// Seconds reading files.
    pub read_seconds: f64,
}

impl BuiltRecipe {
    /// Output frame `f` in the target's own vertex layout and order.
    pub fn frame(&self, f: usize) -> Result<SynthFrame, SynthError> {
        let mut fr = self.synthesizer.frame(f)?;
        if !self.weld.is_identity() {
            fr.positions = self.weld.scatter(&fr.positions);
        }
        Ok(fr)
    }

    /// Every output frame in order, as [`BuiltRecipe::frame`].
    pub fn frames(&self) -> impl Iterator<Item = Result<SynthFrame, SynthError>> + '_ {
        (0..self.synthesizer.num_frames()).map(|f| self.frame(f))
    }

    /// Triangles of a frame from [`BuiltRecipe::frame`] that face against their wanted
    /// orientation ([`Synthesizer::flipped_triangles`]; triangle ids are the target's).
    pub fn flipped_triangles(&self, frame: &SynthFrame) -> Vec<usize> {
        if self.weld.is_identity() {
            return self.synthesizer.flipped_triangles(frame);
        }
        let welded = SynthFrame {
            positions: self.weld.gather(&frame.positions),
            ..frame.clone()
        };
        self.synthesizer.flipped_triangles(&welded)
    }
}

/// Frames of one layer: a glob, a directory, an animation file, one mesh, or a list.
fn read_frames(
    rf: &RecipeFile,
    spec: &PathList,
    reference: &Path,
    inputs: &mut Vec<PathBuf>,
) -> Result<ShapeSet, String> {
    let items: Vec<&String> = match spec {
        PathList::One(s) => vec![s],
        PathList::Many(v) => v.iter().collect(),
    };
    let mut files = Vec::new();
    for s in items {
        let p = rf.resolve(s);
        if !p.exists() && s.contains(['*', '?', '[']) {
            let pattern = p.to_string_lossy().into_owned();
            let mut m: Vec<PathBuf> = glob::glob(&pattern)
                .map_err(|e| format!("invalid glob '{s}': {e}"))?
                .filter_map(Result::ok)
                .filter(|p| p.is_file())
                .collect();
            if m.is_empty() {
                return Err(format!("no files match '{s}'"));
            }
            crate::io::sort_frame_paths(&mut m);
            files.extend(m);
        } else if p.is_dir()
            || matches!(
                Format::from_path(&p),
                Some(Format::Glb | Format::Gltf | Format::Pc2)
            )
        {
            if matches!(spec, PathList::Many(_)) {
                return Err(format!(
                    "'{s}': a directory or animation file must be the only source_frames entry"
                ));
            }
            inputs.push(p.clone());
            return io::read_animation(&p, Some(reference)).map_err(|e| e.to_string());
        } else {
            files.push(p);
        }
    }
    inputs.extend(files.iter().cloned());
    io::read_shape_set(&files).map_err(|e| e.to_string())
}

fn scribble_mask(
    rf: &RecipeFile,
    path: &str,
    span: Range<usize>,
    (target, weld): (&TriMesh, &Weld),
    inputs: &mut Vec<PathBuf>,
) -> Result<Vec<bool>, RecipeError> {
    let p = rf.resolve(path);
    inputs.push(p.clone());
    Scribble::read(&p)
        .and_then(|s| super::recipe_weld::scribble_mask(&s, target, weld))
        .map_err(|e| rf.error(span, "scribble", format!("{}: {e}", p.display())))
}

/// A layer's meshes as read (input numbering), before the welds are known.
struct ReadLayer {
    /// The source reference and its path; `None` for a layer animating the target.
    source: Option<(TriMesh, PathBuf)>,
    /// The source frames, scaled.
    frames: ShapeSet,
}

impl RecipeFile {
    /// Reads the source reference and frames of layer `k`.
    fn read_layer(
        &self,
        k: usize,
        target: (&TriMesh, &Path),
        inputs: &mut Vec<PathBuf>,
    ) -> Result<ReadLayer, RecipeError> {
        let l = self.recipe.layers[k].get_ref();
        let source = match &l.source_reference {
            Some(s) => {
                let p = self.resolve(s.get_ref());
                inputs.push(p.clone());
                let m =
                    io::read_mesh(&p).map_err(|e| self.error(s.span(), "source_reference", e))?;
                Some((m, p))
            }
            None => {
                if let Some(m) = l.markers.as_ref().or(l.correspondence.as_ref()) {
                    return Err(self.error(
                        m.span(),
                        "markers",
                        "a layer without source_reference animates the target itself and takes no markers or correspondence",
                    ));
                }
                None
            }
        };
        let (reference, ref_path) = source.as_ref().map_or(target, |(m, p)| (m, p.as_path()));
        let mut frames = read_frames(self, l.source_frames.get_ref(), ref_path, inputs)
            .map_err(|e| self.error(l.source_frames.span(), "source_frames", e))?;
        frames
            .check_connectivity("source reference", reference)
            .map_err(|e| {
                self.error(
                    l.source_frames.span(),
                    "source_frames",
                    format!("{e} (the frames must share the source reference's connectivity)"),
                )
            })?;
        if let Some(s) = &l.source_scale {
            let f = *s.get_ref();
            if !(f.is_finite() && f > 0.0) {
                return Err(self.error(s.span(), "source_scale", "must be positive"));
            }
            let scaled = (0..frames.len())
                .map(|i| {
                    let p = frames
                        .positions(i)
                        .iter()
                        .map(|q| q.map(|x| f * x))
                        .collect();
                    (frames.name(i).to_string(), p)
                })
                .collect();
            frames = ShapeSet::new(frames.base().clone(), scaled)
                .map_err(|e| self.error(s.span(), "source_scale", e))?;
        }
        Ok(ReadLayer { source, frames })
    }

    /// Reads everything the recipe names and builds the [`Synthesizer`] (one factorization) on
    /// the welded target (see [`super::recipe_weld`]).
    pub fn build(&self) -> Result<BuiltRecipe, RecipeError> {
        let r = &self.recipe;
        let t0 = Instant::now();
        let mut inputs = vec![self.path.clone()];
        let target_path = self.resolve(r.target.get_ref());
        inputs.push(target_path.clone());
        let target =
            io::read_mesh(&target_path).map_err(|e| self.error(r.target.span(), "target", e))?;
        let diag = target.bbox_diagonal();
        let mut read = Vec::with_capacity(r.layers.len());
        for k in 0..r.layers.len() {
            read.push(self.read_layer(k, (&target, &target_path), &mut inputs)?);
        }
        let rest = match &r.rest {
            Some(s) => {
                let p = self.resolve(s.get_ref());
                inputs.push(p.clone());
                let m = io::read_mesh(&p).map_err(|e| self.error(s.span(), "rest", e))?;
                if m.triangles != target.triangles {
                    return Err(self.error(
                        s.span(),
                        "rest",
                        "has other connectivity than the target",
                    ));
                }
                Some(m.positions)
            }
            None => None,
        };
        // The target's shapes: rest and the frames of the layers that animate it.
        let mut target_shapes: Vec<&[Point]> = rest.iter().map(|p| &p[..]).collect();
        for l in read.iter().filter(|l| l.source.is_none()) {
            target_shapes.extend(l.frames.all_positions().iter().map(|p| &p[..]));
        }
        let target_weld = Weld::keeping_triangles(&target, &target_shapes);
        let welded_target = target_weld.mesh(&target);
        let mut corr_seconds = 0.0;
        let mut cache: HashMap<(PathBuf, PathBuf), Correspondence> = HashMap::new();
        let mut layers = Vec::with_capacity(r.layers.len());
        let mut names = Vec::new();
        let mut source_welds = Vec::new();
        for (k, (sl, rl)) in r.layers.iter().zip(read).enumerate() {
            let l = sl.get_ref();
            let table = sl.span();
            names.push(l.name.clone().unwrap_or_else(|| format!("layer {k}")));
            let ReadLayer { source, frames } = rl;
            let source_weld = match &source {
                Some((m, _)) => {
                    let all: Vec<&[Point]> =
                        frames.all_positions().iter().map(|p| &p[..]).collect();
                    Weld::keeping_triangles(m, &all)
                }
                None => target_weld.clone(),
            };
            let source_reference = match &source {
                Some((m, _)) => source_weld.mesh(m),
                None => welded_target.clone(),
            };
            let correspondence = match (&source, &l.markers, &l.correspondence) {
                (None, _, _) => Correspondence::identity(&welded_target),
                (Some((_, ref_path)), Some(m), None) => {
                    let p = self.resolve(m.get_ref());
                    inputs.push(p.clone());
                    let key = (ref_path.clone(), p.clone());
                    match cache.get(&key) {
                        Some(c) => c.clone(),
                        None => {
                            let markers = Markers::read(&p).map_err(|e| {
                                self.error(m.span(), "markers", format!("{}: {e}", p.display()))
                            })?;
                            let markers = welded_markers(&markers, &source_weld, &target_weld);
                            let t = Instant::now();
                            let c = correspond(
                                &source_reference,
                                &welded_target,
                                &markers,
                                &CorrespondenceOptions::default(),
                            )
                            .map_err(|e| self.error(m.span(), "markers", e))?
                            .correspondence;
                            corr_seconds += t.elapsed().as_secs_f64();
                            cache.insert(key, c.clone());
                            c
                        }
                    }
                }
                (Some(_), None, Some(c)) => {
                    let p = self.resolve(c.get_ref());
                    inputs.push(p.clone());
                    let file = std::fs::read_to_string(&p)
                        .map_err(|e| e.to_string())
                        .and_then(|t| Correspondence::from_json(&t).map_err(|e| e.to_string()))
                        .map_err(|e| {
                            self.error(c.span(), "correspondence", format!("{}: {e}", p.display()))
                        })?;
                    welded_correspondence(file, &source_weld, &target_weld)
                }
                (Some(_), None, None) => {
                    let s = l.source_reference.as_ref().expect("a source");
                    return Err(self.error(
                        s.span(),
                        "source_reference",
                        "give markers or correspondence for a layer with another source mesh",
                    ));
                }
                (Some(_), Some(m), Some(_)) => {
                    return Err(self.error(
                        m.span(),
                        "markers",
                        "give markers or correspondence, not both",
                    ))
                }
            };
            let scribble = scribble_mask(
                self,
                l.scribble.get_ref(),
                l.scribble.span(),
                (&target, &target_weld),
                &mut inputs,
            )?;
            let speed = l.speed.as_ref().map_or(1.0, |s| *s.get_ref());
            let region = match l.blend_region.unwrap_or_default() {
                RegionKind::Partitions => {
                    if let Some(w) = &l.blend_width {
                        return Err(self.error(
                            w.span(),
                            "blend_width",
                            "only used with blend_region = \"geodesic\"",
                        ));
                    }
                    BlendRegion::Partitions
                }
                RegionKind::Geodesic => {
                    let w = l.blend_width.as_ref().map_or(0.05, |w| *w.get_ref());
                    if !(w.is_finite() && w > 0.0) {
                        let span = l.blend_width.as_ref().map_or(table.clone(), |w| w.span());
                        return Err(self.error(span, "blend_width", "must be positive"));
                    }
                    BlendRegion::Geodesic { width: w * diag }
                }
            };
            let frames = frames
                .all_positions()
                .iter()
                .map(|p| source_weld.gather(p))
                .collect();
            source_welds.push(source_weld.merged());
            layers.push(LayerSpec {
                source_reference,
                frames,
                correspondence,
                scribble,
                mode: l.mode.as_ref().map_or(BlendMode::Blend, |m| *m.get_ref()),
                timing: Timing {
                    offset: l.offset.unwrap_or(0),
                    speed,
                    looped: l.looped.unwrap_or(false),
                },
                region,
            });
        }
        if layers.is_empty() {
            return Err(self.error(0..0, "layer", "the recipe has no [[layer]]"));
        }
        let mut poses = Vec::new();
        for sp in &r.poses {
            let p = sp.get_ref();
            let scribble = scribble_mask(
                self,
                p.scribble.get_ref(),
                p.scribble.span(),
                (&target, &target_weld),
                &mut inputs,
            )?;
            poses.push(PoseSpec {
                scribble,
                layer: p.layer.as_ref().map_or(0, |l| *l.get_ref()),
                axis: *p.axis.get_ref(),
                angle: p.angle.to_radians(),
            });
        }
        let opts = SynthOptions {
            frames: *r.frames.get_ref(),
            gamma: r.gamma.as_ref().map_or(super::GAMMA, |g| *g.get_ref()),
            kappa: r.kappa.as_ref().map_or(super::KAPPA, |g| *g.get_ref()),
            transfer: TransferOptions {
                translation: match r.translation.unwrap_or_default() {
                    TranslationKind::Follow => TranslationMode::FollowMarkers,
                    TranslationKind::Fixed => TranslationMode::FixedVertex,
                },
                ..TransferOptions::default()
            },
            follow_layer: r.follow_layer.as_ref().map(|f| *f.get_ref()),
            rest: rest.map(|p| target_weld.gather(&p)),
        };
        let read_seconds = t0.elapsed().as_secs_f64() - corr_seconds;
        let synthesizer =
            Synthesizer::new(&welded_target, layers, &poses, &opts).map_err(|e| self.locate(e))?;
        let fps = r.fps.unwrap_or(24.0);
        if !(fps.is_finite() && fps > 0.0) {
            return Err(self.error(0..0, "fps", "must be positive"));
        }
        Ok(BuiltRecipe {
            synthesizer,
            target,
            target_path,
            weld: target_weld,
            source_welded_vertices: source_welds,
            inputs,
            layer_names: names,
            fps,
            correspondence_seconds: corr_seconds,
            read_seconds,
        })
    }

    /// Maps a synthesizer error to the recipe line and key that caused it.
    fn locate(&self, e: SynthError) -> RecipeError {
        let r = &self.recipe;
        match e {
            SynthError::InLayer { layer, source } => {
                let l = &r.layers[layer];
                let (span, key) = match *source {
                    SynthError::EmptyScribble
                    | SynthError::NothingSelected { .. }
                    | SynthError::ScribbleOutOfRange { .. }
                    | SynthError::ScribbleCoversNoTriangle { .. } => {
                        (l.get_ref().scribble.span(), "scribble")
                    }
                    SynthError::Parameter { name: "speed", .. } => (
                        l.get_ref().speed.as_ref().map_or(l.span(), |s| s.span()),
                        "speed",
                    ),
                    SynthError::Parameter { name: "gamma", .. } => {
                        (r.gamma.as_ref().map_or(l.span(), |g| g.span()), "gamma")
                    }
                    _ => (l.span(), "layer"),
                };
                self.error(span, key, format!("layer {layer}: {source}"))
            }
            SynthError::InPose { pose, source } => {
                let p = &r.poses[pose];
                let (span, key) = match *source {
                    SynthError::Parameter { name: "axis", .. } => (p.get_ref().axis.span(), "axis"),
                    SynthError::Parameter {
                        name: "pose layer", ..
                    } => (
                        p.get_ref().layer.as_ref().map_or(p.span(), |l| l.span()),
                        "layer",
                    ),
                    _ => (p.get_ref().scribble.span(), "scribble"),
                };
                self.error(span, key, format!("pose {pose}: {source}"))
            }
            SynthError::ContradictingLayers { second, .. } => {
                let l = &r.layers[second];
                let span = l.get_ref().mode.as_ref().map_or(l.span(), |m| m.span());
                self.error(span, "mode", e)
            }
            SynthError::Parameter {
                name: "follow_layer",
                ..
            } => self.error(
                r.follow_layer.as_ref().map_or(0..0, |f| f.span()),
                "follow_layer",
                e,
            ),
            SynthError::Parameter { name: "frames", .. } => {
                self.error(r.frames.span(), "frames", e)
            }
            e => self.error(r.target.span(), "target", e),
        }
    }
}
