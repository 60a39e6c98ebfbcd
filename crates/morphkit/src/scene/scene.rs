//! Scene files: a blend rig, its weights over time, obstacles and pulls, in TOML.
//!
//! ```toml
//! base = "rest.obj"                      # paths are relative to the scene file
//! targets = ["bend.obj"]
//!
//! [weights]
//! frames = 24                            # alpha from 0 to 1 over 24 frames (one target)
//! # alpha = [0.2, 0.8]                   # … or another range
//! # constant = [0.5]                     # … or one weight vector held for `frames` frames
//! # file = "keys.csv"                    # … or one vector per frame (JSON or CSV)
//! # convex = true                        # weights over all shapes, base first, summing to 1
//!
//! [blend]                                # all optional; defaults as in `morphkit blend`
//! fixed = "auto"                         # "auto", "none" or [vertex ids]
//! # interior = "lattice"                 # internal springs: "none", "lattice" or "tetgen",
//! #                                      #   optionally ",density" (as `blend --interior`)
//! # anchor = "auto"                      # the rigid anchor: "auto" or "x,y,z[,size]"
//! # k0, bending, hinge_weight, tether, kinematic_stretch, thin_band_rings, tolerance,
//! # max_newton_iterations
//!
//! [collision]
//! tolerance = 1e-4                       # × the base's bounding-box diagonal
//! max_rounds = 10
//!
//! [output]
//! fps = 24
//!
//! [[obstacle]]
//! name = "post"
//! shape = "cylinder"                     # sphere (radius), box (size = [x, y, z]),
//! radius = 0.3                           # cylinder (radius, height, along local y),
//! height = 2.0                           # capsule (radius, length), plane (normal);
//! # mesh = "post.obj"                    # … or a closed OBJ / PLY / GLB mesh instead
//! translation = [1.5, 0.0, 1.0]          # a static pose, or keys:
//! rotation = { axis = [1, 0, 0], degrees = 90 }
//! # [[obstacle.key]]
//! # frame = 0                            # frame numbers, strictly increasing
//! # translation = [1.5, 0.0, 1.2]
//! # rotation = { axis = [1, 0, 0], degrees = 90 }
//!
//! [[pull]]
//! vertex = 417                           # 0-based
//! # stiffness = 10                       # soft (× mean spring stiffness); absent: hard
//! [[pull.key]]
//! frame = 0
//! position = [2.0, 0.0, 0.5]
//! ```
//!
//! Frame `k` of the output has weights `weights[k]`; obstacles and pulls are placed at frame
//! number `k`. Every error names the file, the line and the key.

use super::error::{line_column, SceneError};
use super::file::{FixedSpec, ObstacleSpec, PullSpec, RotationSpec, SceneFile, WeightsSpec};
use super::obstacle::{Obstacle, Primitive, RigidKey};
use super::pulls::{Pull, PullKey, PullKind};
use super::{CollisionOptions, SceneBlend};
use crate::io;
use crate::mesh::{bbox_diagonal, ShapeSet};
use crate::springs::{AnchorOptions, BlendOptions, FixedVertices, InteriorOptions, Weights};
use parry3d_f64::math::{Rotation, Vector};
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Most frames a scene may ask for.
const MAX_FRAMES: usize = 100_000;

/// A loaded scene: the shapes are read, every value is checked.
#[derive(Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Base and targets.
    pub shapes: ShapeSet,
    /// The mesh files read (base first), resolved against the scene's directory.
    pub inputs: Vec<PathBuf>,
    /// One weight vector per output frame.
    pub weights: Vec<Weights>,
    /// Options of the physical blend.
    pub blend: BlendOptions,
    /// Internal springs (`blend.interior`; default none).
    pub interior: InteriorOptions,
    /// The anchor (`blend.anchor`; default none).
    pub anchor: AnchorOptions,
    /// Options of collision handling.
    pub collision: CollisionOptions,
    /// The obstacles, in file order.
    pub obstacles: Vec<Obstacle>,
    /// The pulls, in file order.
    pub pulls: Vec<Pull>,
    /// Frame rate of animation outputs.
    pub fps: f64,
    /// The line of each pull's `vertex`, for errors found when the solver is built.
    pull_lines: Vec<usize>,
}

/// Context for error messages.
struct Ctx<'a> {
    file: &'a Path,
    text: &'a str,
    dir: PathBuf,
}

impl Ctx<'_> {
    fn line(&self, span: Range<usize>) -> usize {
        line_column(self.text, span.start).0
    }
    fn invalid(&self, span: Range<usize>, key: &str, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            line: self.line(span),
            key: key.to_string(),
            message: message.into(),
        }
    }
    fn resolve(&self, rel: &str) -> PathBuf {
        self.dir.join(rel)
    }
    fn file_error(&self, span: Range<usize>, key: &str, source: io::IoError) -> SceneError {
        SceneError::File {
            file: self.file.to_path_buf(),
            line: self.line(span),
            key: key.to_string(),
            source: Box::new(source),
        }
    }
}

impl Scene {
    /// Reads and checks a scene file and the meshes it names.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Read {
            file: path.to_path_buf(),
            cause: e.to_string(),
        })?;
        Self::parse(path, &text)
    }

    /// Checks a scene given as text; `path` names it in messages and its directory resolves
    /// the relative paths.
    pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let ctx = Ctx {
            file: path,
            text,
            dir,
        };
        let f: SceneFile = toml::from_str(text).map_err(|e| {
            let (line, column) = line_column(text, e.span().map_or(0, |s| s.start));
            SceneError::Syntax {
                file: path.to_path_buf(),
                line,
                column,
                message: e.message().trim().to_string(),
            }
        })?;
        if f.targets.get_ref().is_empty() {
            return Err(ctx.invalid(f.targets.span(), "targets", "give at least one target"));
        }
        let mut inputs = vec![ctx.resolve(f.base.get_ref())];
        let mut spans = vec![(f.base.span(), "base".to_string())];
        for (i, t) in f.targets.get_ref().iter().enumerate() {
            inputs.push(ctx.resolve(t.get_ref()));
            spans.push((t.span(), format!("targets[{i}]")));
        }
        let mut meshes = Vec::with_capacity(inputs.len());
        for (p, (span, key)) in inputs.iter().zip(&spans) {
            let m = io::read_mesh(p).map_err(|e| ctx.file_error(span.clone(), key, e))?;
            meshes.push((p.display().to_string(), m));
        }
        let shapes = ShapeSet::from_meshes(meshes)
            .map_err(|e| ctx.invalid(f.targets.span(), "targets", e.to_string()))?;
        let weights = weights(&ctx, &f.weights, shapes.len())?;
        let blend = blend_options(&ctx, &f)?;
        let interior = match &f.blend.interior {
            None => InteriorOptions::default(),
            Some(v) => InteriorOptions::parse(v.get_ref())
                .map_err(|e| ctx.invalid(v.span(), "blend.interior", e))?,
        };
        let anchor = match &f.blend.anchor {
            None => AnchorOptions::default(),
            Some(v) => AnchorOptions::parse(v.get_ref())
                .map_err(|e| ctx.invalid(v.span(), "blend.anchor", e))?,
        };
        let collision = CollisionOptions {
            tolerance: f.collision.tolerance.unwrap_or(1e-4),
            max_rounds: f.collision.max_rounds.unwrap_or(10),
        };
        let fps = f.output.fps.unwrap_or(24.0);
        if !(fps.is_finite() && fps > 0.0) {
            return Err(ctx.invalid(0..0, "output.fps", format!("must be positive, got {fps}")));
        }
        let diag = bbox_diagonal(shapes.positions(0));
        let obstacles = f
            .obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| obstacle(&ctx, i, o, 4.0 * diag))
            .collect::<Result<Vec<_>, _>>()?;
        let n = shapes.num_vertices();
        let mut pull_lines = Vec::new();
        let pulls = f
            .pulls
            .iter()
            .enumerate()
            .map(|(i, p)| {
                pull_lines.push(ctx.line(p.get_ref().vertex.span()));
                pull(&ctx, i, p, n)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Scene {
            path: path.to_path_buf(),
            shapes,
            inputs,
            weights,
            blend,
            interior,
            anchor,
            collision,
            obstacles,
            pulls,
            fps,
            pull_lines,
        })
    }

    /// Builds the solver; pull problems found there (a fixed vertex, a free component, a
    /// vertex pulled twice) name the pull's line and key.
    pub fn build(&self) -> Result<SceneBlend, SceneError> {
        SceneBlend::with_interior(
            &self.shapes,
            &self.blend,
            &self.interior,
            &self.anchor,
            self.obstacles.clone(),
            self.pulls.clone(),
            &self.collision,
        )
        .map_err(|e| match e {
            SceneError::PullVertex { index, vertex, why } => SceneError::Invalid {
                file: self.path.clone(),
                line: self.pull_lines.get(index).copied().unwrap_or(0),
                key: format!("pull[{index}].vertex"),
                message: format!("vertex {vertex} {why}"),
            },
            e => e,
        })
    }
}

fn weights(ctx: &Ctx, w: &Spanned<WeightsSpec>, shapes: usize) -> Result<Vec<Weights>, SceneError> {
    let spec = w.get_ref();
    let given = [
        spec.alpha.is_some(),
        spec.constant.is_some(),
        spec.file.is_some(),
    ];
    if given.iter().filter(|g| **g).count() > 1 {
        return Err(ctx.invalid(w.span(), "weights", "give one of alpha, constant or file"));
    }
    let wrap = |v: Vec<f64>| {
        if spec.convex {
            Weights::Convex(v)
        } else {
            Weights::Delta(v)
        }
    };
    let frames = |what: &str| -> Result<usize, SceneError> {
        let Some(n) = &spec.frames else {
            return Err(ctx.invalid(
                w.span(),
                "weights.frames",
                format!("{what} needs a frame count"),
            ));
        };
        let k = *n.get_ref();
        if !(1..=MAX_FRAMES).contains(&k) {
            return Err(ctx.invalid(
                n.span(),
                "weights.frames",
                format!("must be between 1 and {MAX_FRAMES}, got {k}"),
            ));
        }
        Ok(k)
    };
    let out: Vec<Weights> = if let Some(file) = &spec.file {
        if spec.frames.is_some() {
            return Err(ctx.invalid(
                w.span(),
                "weights.frames",
                "a weights file gives its own frames",
            ));
        }
        let rows = super::weights_file::read(&ctx.resolve(file.get_ref()))
            .map_err(|e| ctx.invalid(file.span(), "weights.file", e))?;
        rows.into_iter().map(wrap).collect()
    } else if let Some(c) = &spec.constant {
        let n = frames("constant weights")?;
        vec![wrap(c.get_ref().clone()); n]
    } else {
        let [a0, a1] = spec.alpha.as_ref().map_or([0.0, 1.0], |a| *a.get_ref());
        if shapes != 2 {
            return Err(ctx.invalid(
                w.span(),
                "weights",
                format!(
                    "alpha needs exactly one target ({} given); use constant or file",
                    shapes - 1
                ),
            ));
        }
        let n = frames("alpha")?;
        (0..n)
            .map(|k| {
                let t = if n == 1 {
                    0.0
                } else {
                    k as f64 / (n - 1) as f64
                };
                Weights::Alpha(a0 + t * (a1 - a0))
            })
            .collect()
    };
    for (k, wk) in out.iter().enumerate() {
        wk.coefficients(shapes)
            .map_err(|e| ctx.invalid(w.span(), "weights", format!("frame {k}: {e}")))?;
    }
    Ok(out)
}

fn blend_options(ctx: &Ctx, f: &SceneFile) -> Result<BlendOptions, SceneError> {
    let b = &f.blend;
    let mut o = BlendOptions::default();
    if let Some(fixed) = &b.fixed {
        o.fixed = match fixed.get_ref() {
            FixedSpec::Ids(ids) => FixedVertices::Ids(ids.clone()),
            FixedSpec::Mode(m) => match m.as_str() {
                "auto" => FixedVertices::Auto,
                "none" => FixedVertices::None,
                other => {
                    return Err(ctx.invalid(
                        fixed.span(),
                        "blend.fixed",
                        format!("'{other}' is not \"auto\", \"none\" or an array of vertex ids"),
                    ));
                }
            },
        };
    }
    if let Some(k0) = b.k0 {
        o.springs.k0 = k0;
    }
    if let Some(bending) = b.bending {
        o.springs.bending = bending;
    }
    if let Some(h) = b.hinge_weight {
        o.hinges.weight = h;
    }
    if let Some(t) = b.tether {
        o.tether = t;
    }
    if let Some(k) = b.kinematic_stretch {
        o.kinematic_stretch = k;
    }
    if let Some(r) = b.thin_band_rings {
        o.thin_band_rings = r;
    }
    if let Some(t) = b.tolerance {
        o.gradient_tolerance = t;
    }
    if let Some(m) = b.max_newton_iterations {
        o.max_newton_iterations = m;
    }
    Ok(o)
}

fn rotation(
    ctx: &Ctx,
    r: Option<RotationSpec>,
    span: Range<usize>,
    key: &str,
) -> Result<Rotation, SceneError> {
    let Some(r) = r else {
        return Ok(Rotation::IDENTITY);
    };
    let axis = Vector::new(r.axis[0], r.axis[1], r.axis[2]);
    let len = axis.length();
    if !(len.is_finite() && len > 0.0 && r.degrees.is_finite()) {
        return Err(ctx.invalid(span, key, "needs a non-zero finite axis and finite degrees"));
    }
    Ok(Rotation::from_axis_angle(
        axis / len,
        r.degrees.to_radians(),
    ))
}

fn obstacle(
    ctx: &Ctx,
    i: usize,
    o: &Spanned<ObstacleSpec>,
    display: f64,
) -> Result<Obstacle, SceneError> {
    let (span, spec) = (o.span(), o.get_ref());
    let key = format!("obstacle[{i}]");
    let name = spec.name.clone().unwrap_or_else(|| format!("obstacle_{i}"));
    let base = match (&spec.mesh, &spec.shape) {
        (Some(_), Some(s)) => {
            return Err(ctx.invalid(
                s.span(),
                &format!("{key}.shape"),
                "give either mesh or shape, not both",
            ));
        }
        (None, None) => {
            return Err(ctx.invalid(
                span,
                &key,
                "needs a mesh file or a shape (sphere, box, capsule, cylinder, plane)",
            ));
        }
        (Some(m), None) => {
            let mkey = format!("{key}.mesh");
            let mesh = io::read_mesh(&ctx.resolve(m.get_ref()))
                .map_err(|e| ctx.file_error(m.span(), &mkey, e))?;
            Obstacle::from_mesh(&name, &mesh)
                .map_err(|e| ctx.invalid(m.span(), &mkey, e.to_string()))?
        }
        (None, Some(s)) => {
            let skey = format!("{key}.shape");
            let need = |v: Option<f64>, what: &str| {
                v.ok_or_else(|| {
                    ctx.invalid(s.span(), &skey, format!("a {} needs `{what}`", s.get_ref()))
                })
            };
            let used: &[&str] = match s.get_ref().as_str() {
                "sphere" => &["radius"],
                "box" => &["size"],
                "cylinder" => &["radius", "height"],
                "capsule" => &["radius", "length"],
                "plane" => &["normal"],
                other => {
                    return Err(ctx.invalid(s.span(), &skey, format!("unknown primitive '{other}'; expected sphere, box, capsule, cylinder or plane")));
                }
            };
            let present = [
                ("radius", spec.radius.is_some()),
                ("size", spec.size.is_some()),
                ("height", spec.height.is_some()),
                ("length", spec.length.is_some()),
                ("normal", spec.normal.is_some()),
            ];
            if let Some((extra, _)) = present.iter().find(|(k, p)| *p && !used.contains(k)) {
                return Err(ctx.invalid(
                    s.span(),
                    &format!("{key}.{extra}"),
                    format!(
                        "a {} has no `{extra}` (it takes {})",
                        s.get_ref(),
                        used.join(", ")
                    ),
                ));
            }
            let prim = match s.get_ref().as_str() {
                "sphere" => Primitive::Sphere {
                    radius: need(spec.radius, "radius")?,
                },
                "box" => Primitive::Box {
                    size: spec
                        .size
                        .ok_or_else(|| ctx.invalid(s.span(), &skey, "a box needs `size`"))?,
                },
                "cylinder" => Primitive::Cylinder {
                    radius: need(spec.radius, "radius")?,
                    height: need(spec.height, "height")?,
                },
                "capsule" => Primitive::Capsule {
                    radius: need(spec.radius, "radius")?,
                    length: need(spec.length, "length")?,
                },
                _ => Primitive::Plane {
                    normal: spec
                        .normal
                        .ok_or_else(|| ctx.invalid(s.span(), &skey, "a plane needs `normal`"))?,
                },
            };
            Obstacle::primitive(&name, &prim, display)
                .map_err(|e| ctx.invalid(s.span(), &key, e.to_string()))?
        }
    };
    let mut keys = Vec::new();
    if spec.key.is_empty() {
        keys.push(RigidKey {
            frame: 0.0,
            translation: spec.translation.unwrap_or([0.0; 3]),
            rotation: rotation(ctx, spec.rotation, span.clone(), &format!("{key}.rotation"))?,
        });
    } else if spec.translation.is_some() || spec.rotation.is_some() {
        return Err(ctx.invalid(
            span,
            &key,
            "give either translation/rotation or [[obstacle.key]] entries, not both",
        ));
    }
    for (j, k) in spec.key.iter().enumerate() {
        let fkey = format!("{key}.key[{j}].frame");
        if j > 0 && *k.frame.get_ref() <= *spec.key[j - 1].frame.get_ref() {
            return Err(ctx.invalid(k.frame.span(), &fkey, format!("keyframe out of order: frame {} after frame {}; keys must be in increasing frame order", k.frame.get_ref(), spec.key[j - 1].frame.get_ref())));
        }
        keys.push(RigidKey {
            frame: *k.frame.get_ref(),
            translation: k.translation,
            rotation: rotation(
                ctx,
                k.rotation,
                k.frame.span(),
                &format!("{key}.key[{j}].rotation"),
            )?,
        });
    }
    base.with_keys(keys)
        .map_err(|e| ctx.invalid(span, &key, e.to_string()))
}

fn pull(ctx: &Ctx, i: usize, p: &Spanned<PullSpec>, n: usize) -> Result<Pull, SceneError> {
    let (span, spec) = (p.span(), p.get_ref());
    let key = format!("pull[{i}]");
    let v = *spec.vertex.get_ref();
    if v as usize >= n {
        return Err(ctx.invalid(
            spec.vertex.span(),
            &format!("{key}.vertex"),
            format!("vertex {v} is out of range: the mesh has {n} vertices (ids are 0-based)"),
        ));
    }
    let mut keys = Vec::new();
    match (&spec.position, spec.key.is_empty()) {
        (Some(position), true) => keys.push(PullKey {
            frame: 0.0,
            position: *position,
        }),
        (None, false) => {}
        _ => {
            return Err(ctx.invalid(
                span,
                &key,
                "give either position or [[pull.key]] entries (one of them)",
            ))
        }
    }
    for (j, k) in spec.key.iter().enumerate() {
        if j > 0 && *k.frame.get_ref() <= *spec.key[j - 1].frame.get_ref() {
            return Err(ctx.invalid(k.frame.span(), &format!("{key}.key[{j}].frame"), format!("keyframe out of order: frame {} after frame {}; keys must be in increasing frame order", k.frame.get_ref(), spec.key[j - 1].frame.get_ref())));
        }
        keys.push(PullKey {
            frame: *k.frame.get_ref(),
            position: k.position,
        });
    }
    let kind = match &spec.stiffness {
        Some(s) => PullKind::Soft {
            stiffness: *s.get_ref(),
        },
        None => PullKind::Hard,
    };
    Pull::new(v, keys, kind).map_err(|e| ctx.invalid(span, &key, e.to_string()))
}
