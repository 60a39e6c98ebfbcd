//! A whole glTF asset, edited in place: [`GltfAsset`].
//!
//! [`read_gltf_morphs`](super::read_gltf_morphs) keeps one mesh's positions, triangles and
//! morph targets; writing them gives a fresh file without the user's materials, textures,
//! skins, other meshes, nodes and transforms. A `GltfAsset` keeps **the whole document** (its
//! JSON as a [`serde_json::Value`]) and the bytes of every buffer and external image, plus the
//! chosen mesh (the rule of [`GltfReadOptions::mesh`]) merged into a [`GltfMorphs`]
//! ([`GltfAsset::morphs`]: `#V` positions in the mesh's own space, the primitives' vertices one
//! after the other, [`GltfAsset::primitive_vertices`] says which range is which primitive).
//!
//! Edits add accessors and repoint the chosen mesh at them; nothing that exists is rewritten
//! (see `asset_edit.rs` for each edit): [`GltfAsset::set_base`], [`GltfAsset::add_targets`],
//! [`GltfAsset::add_frame_animation`]. [`GltfAsset::write`] (`asset_write.rs`) merges every
//! buffer into one, embeds external images, and writes one self-contained `.glb` or `.gltf`.
//! What is carried and what is replaced: `docs/gltf-assets.md`.

use super::accessor;
use super::anim::{channel_data, keys_of, weight_channels, WeightChannel};
use super::choose::{choose, shared_names, Named};
use super::read::{load_with, Loaded, Scan};
use super::{GltfMorphs, GltfReadOptions, SAFE_MORPH_TARGETS};
use crate::io::source::{read_file, read_raw};
use crate::io::IoError;
use crate::mesh::Point;
use ::gltf::Semantic;
use serde_json::Value;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// One primitive of the chosen mesh.
#[derive(Clone, Debug)]
pub(super) struct Primitive {
    /// Its vertices in the merged mesh.
    pub vertices: Range<usize>,
    /// Its triangles in the merged mesh.
    pub triangles: Range<usize>,
    /// Its base `NORMAL`s as stored (`#vertices`), when it has that attribute.
    pub normals: Option<Vec<Point>>,
}

/// A sampler that drives the morph weights of the chosen mesh (through nodes using it).
#[derive(Clone, Debug)]
pub(super) struct WeightSampler {
    /// Animation index.
    pub anim: usize,
    /// Sampler index in the animation.
    pub sampler: usize,
    /// The channels of the animation that use it and drive the chosen mesh.
    pub channels: Vec<usize>,
    /// Also used by a channel that drives something else (then it is copied before padding).
    pub shared: bool,
    /// Its output values: a run of `#targets`-vectors (three per key for `CUBICSPLINE`).
    pub values: Vec<f64>,
}

/// An animation that drives the morph weights of the chosen mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfWeightAnimation {
    /// Its index in the document's `animations`.
    pub index: usize,
    /// Its name, when it has one.
    pub name: Option<String>,
    /// The keys of its first channel driving the mesh: `(time in seconds, one weight per
    /// target)`, in time order (the values of `CUBICSPLINE` keys). Of a rig morphkit split
    /// into several meshes, the keys of every part, one weight per target of the whole rig
    /// (as [`GltfAsset::morphs`] holds them).
    pub keys: Vec<(f64, Vec<f64>)>,
}

/// How [`GltfAsset::write`] writes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfAssetOptions {
    /// A JSON object whose members are added to the document's `asset.extras` (an object;
    /// other `asset.extras` values are left as they are). Default `None`: `asset` untouched.
    pub extras: Option<Value>,
}

/// A glTF document with its data, one mesh of which is edited (see the
/// [module documentation](self)).
#[derive(Clone, Debug)]
pub struct GltfAsset {
    pub(super) path: PathBuf,
    pub(super) doc: Value,
    /// Every buffer's bytes (empty for meshopt fallback buffers), then the edits' buffer.
    pub(super) buffers: Vec<Vec<u8>>,
    pub(super) fallback: Vec<bool>,
    pub(super) edit_buffer: Option<usize>,
    /// The meshopt `fallback` buffer of the edits' compressed views (see `asset_pack.rs`).
    pub(super) edit_fallback: Option<usize>,
    /// Per image: the bytes and media type of an external file, to embed on writing.
    pub(super) images: Vec<Option<ImageData>>,
    pub(super) mesh: usize,
    pub(super) primitives: Vec<Primitive>,
    pub(super) morphs: GltfMorphs,
    pub(super) samplers: Vec<WeightSampler>,
    pub(super) animations: Vec<GltfWeightAnimation>,
    pub(super) split: bool,
    pub(super) max_targets: usize,
    /// Store new targets' deltas sparsely where that is smaller ([`GltfAsset::set_sparse_targets`]).
    pub(super) sparse_targets: bool,
}

/// What the read finds beyond [`Loaded`].
struct Found {
    normals: Vec<Option<Vec<Point>>>,
    samplers: Vec<WeightSampler>,
    animations: Vec<GltfWeightAnimation>,
}

fn scan(path: &Path, s: Scan) -> Result<Found, IoError> {
    let label = super::read::mesh_label(&s.mesh);
    let mut normals = Vec::new();
    for (pi, prim) in s.mesh.primitives().enumerate() {
        normals.push(match prim.get(&Semantic::Normals) {
            Some(acc) => Some(accessor::read_vec3(&acc, s.data).map_err(|m| {
                IoError::content(path, format!("{label}, primitive {pi}: NORMAL {m}"))
            })?),
            None => None,
        });
    }
    let n = s
        .mesh
        .primitives()
        .next()
        .map_or(0, |p| p.morph_targets().count());
    let channels = if n == 0 {
        Vec::new()
    } else {
        weight_channels(s.doc, s.mesh.index())
    };
    let mut samplers: Vec<WeightSampler> = Vec::new();
    let mut animations: Vec<GltfWeightAnimation> = Vec::new();
    for ch in &channels {
        if let Some(w) = samplers
            .iter_mut()
            .find(|w| w.anim == ch.anim && w.sampler == ch.sampler)
        {
            w.channels.push(ch.channel);
            continue;
        }
        let (times, values, cubic) = channel_data(path, s.doc, *ch, n, s.data)?;
        if !animations.iter().any(|a| a.index == ch.anim) {
            animations.push(GltfWeightAnimation {
                index: ch.anim,
                name: s
                    .doc
                    .animations()
                    .nth(ch.anim)
                    .and_then(|a| a.name().map(String::from)),
                keys: keys_of(&times, &values, cubic, n),
            });
        }
        samplers.push(WeightSampler {
            anim: ch.anim,
            sampler: ch.sampler,
            channels: vec![ch.channel],
            shared: false,
            values,
        });
    }
    // A rig morphkit split into meshes (a long animation) is read as the one rig it is: its
    // animations' keys span every target, as `morphs` does, not the first window's.
    for a in &mut animations {
        if let Some(keys) =
            super::read_chunks::split_animation_keys(path, s.doc, s.data, s.mesh.index(), a.index)?
        {
            a.keys = keys;
        }
    }
    // A sampler also used by a channel that is not ours (another mesh's weights).
    for w in &mut samplers {
        let aj = &s.doc.as_json().animations[w.anim];
        w.shared = aj.channels.iter().enumerate().any(|(c, cj)| {
            cj.sampler.value() == w.sampler
                && !channels.contains(&WeightChannel {
                    anim: w.anim,
                    channel: c,
                    sampler: w.sampler,
                    node: cj.target.node.value(),
                })
        });
    }
    Ok(Found {
        normals,
        samplers,
        animations,
    })
}

/// The media type of image bytes, by their signature, else by the file's extension.
fn media_type(bytes: &[u8], file: &Path) -> Option<String> {
    let by_magic = if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("image/jpeg")
    } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some("image/webp")
    } else if bytes.starts_with(b"\xabKTX 20\xbb") {
        Some("image/ktx2")
    } else {
        None
    };
    if let Some(m) = by_magic {
        return Some(m.into());
    }
    let ext = file.extension()?.to_string_lossy().to_ascii_lowercase();
    Some(
        match ext.as_str() {
            "png" => "image/png",
            "jpg" | "jpeg" => "image/jpeg",
            "webp" => "image/webp",
            "ktx2" => "image/ktx2",
            "avif" => "image/avif",
            "dds" => "image/vnd-ms.dds",
            _ => return None,
        }
        .into(),
    )
}

/// An external image's bytes and media type.
pub(super) type ImageData = (Vec<u8>, String);

/// The bytes and media type of every image with an external (not `data:`) URI.
fn load_images(path: &Path, doc: &Value) -> Result<Vec<Option<ImageData>>, IoError> {
    let Some(images) = doc.get("images").and_then(Value::as_array) else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(images.len());
    for (i, img) in images.iter().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str) else {
            out.push(None);
            continue;
        };
        if uri.starts_with("data:") {
            out.push(None);
            continue;
        }
        let at = |m: String| IoError::content(path, format!("image {i}: {m}"));
        let file = super::buffers::resolve_uri(path, uri).map_err(at)?;
        if !std::fs::metadata(&file).is_ok_and(|m| m.is_file()) {
            return Err(at(format!(
                "{} (uri '{uri}') is not a readable file next to the glTF; the texture would be lost",
                file.display()
            )));
        }
        // Embedded exactly as they are: an image is never decompressed (read_file would
        // gunzip a file that starts with 1f 8b).
        let bytes = read_raw(&file)?;
        let mime = img
            .get("mimeType")
            .and_then(Value::as_str)
            .map(String::from)
            .or_else(|| media_type(&bytes, &file))
            .ok_or_else(|| {
                at(format!(
                    "{} (uri '{uri}'): not a PNG, JPEG, WebP or KTX2 image, and it has no mimeType",
                    file.display()
                ))
            })?;
        out.push(Some((bytes, mime)));
    }
    Ok(out)
}

impl GltfAsset {
    /// Reads a `.gltf` or `.glb` file whole: its JSON, every buffer (the GLB `BIN` chunk, data
    /// URIs, external files beside it), external images, and the mesh chosen as by
    /// [`read_gltf_morphs_with`](super::read_gltf_morphs_with) merged into
    /// [`GltfAsset::morphs`].
    ///
    /// Errors: those of [`read_gltf_morphs_with`](super::read_gltf_morphs_with); an external
    /// image that cannot be read or whose type is unknown (naming the image); a weights
    /// animation of the chosen mesh whose data disagrees with its target count.
    pub fn read(path: &Path, opts: &GltfReadOptions) -> Result<Self, IoError> {
        let bytes = read_file(path)?;
        let (loaded, found) = load_with(path, bytes, opts, false, |s| scan(path, s))?;
        let Loaded {
            json,
            buffers,
            fallback,
            mesh,
            primitives,
            split,
            morphs,
        } = loaded;
        let mut doc: Value = serde_json::from_slice(&json)
            .map_err(|e| IoError::content(path, format!("the JSON does not parse: {e}")))?;
        drop(json);
        // Buffers in data URIs are held decoded; the text is not needed twice.
        if let Some(bs) = doc.get_mut("buffers").and_then(Value::as_array_mut) {
            for b in bs {
                if b.get("uri")
                    .and_then(Value::as_str)
                    .is_some_and(|u| u.starts_with("data:"))
                {
                    b.as_object_mut().map(|o| o.remove("uri"));
                }
            }
        }
        let images = load_images(path, &doc)?;
        let (mut v, mut t) = (0, 0);
        let primitives = primitives
            .into_iter()
            .zip(found.normals)
            .map(|((nv, nt), normals)| {
                let p = Primitive {
                    vertices: v..v + nv,
                    triangles: t..t + nt,
                    normals,
                };
                v += nv;
                t += nt;
                p
            })
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            doc,
            buffers,
            fallback,
            edit_buffer: None,
            edit_fallback: None,
            images,
            mesh,
            primitives,
            morphs,
            samplers: found.samplers,
            animations: found.animations,
            split,
            max_targets: SAFE_MORPH_TARGETS,
            sparse_targets: false,
        })
    }

    /// The chosen mesh after the edits so far: base (`#V` positions in the mesh's own space,
    /// primitives one after the other), absolute target positions (`#targets × #V`), target
    /// names, and the keys of the first weights animation. Positions are what reading the
    /// written file gives (edits are rounded to `f32` as they are stored).
    pub fn morphs(&self) -> &GltfMorphs {
        &self.morphs
    }

    /// What the asset holds besides the chosen mesh's positions, triangles, morph targets and
    /// weights animations, in words (`"2 materials"`, `"UV set TEXCOORD_0"`, …): what an
    /// output of positions and triangles only (OBJ, PLY, PC2, …) leaves out, so a command can
    /// say so. Empty when nothing would be lost.
    pub fn not_geometry(&self) -> Vec<String> {
        let doc = &self.doc;
        let count = |key: &str| doc[key].as_array().map_or(0, |a| a.len());
        let mut out = Vec::new();
        let mut counted = |n: usize, one: &str, many: &str| {
            if n == 1 {
                out.push(format!("1 {one}"));
            } else if n > 1 {
                out.push(format!("{n} {many}"));
            }
        };
        // The default grey material of a file morphkit wrote itself is nothing of the user's
        // (an asset morphkit carried keeps its own generator).
        let own = doc["asset"]["generator"]
            .as_str()
            .is_some_and(|g| g.starts_with("morphkit "));
        let materials = if own { 0 } else { count("materials") };
        counted(materials, "material", "materials");
        counted(count("textures"), "texture", "textures");
        counted(count("skins"), "skin", "skins");
        counted(count("cameras"), "camera", "cameras");
        counted(
            count("meshes").saturating_sub(1),
            "other mesh",
            "other meshes",
        );
        let transformed = doc["nodes"].as_array().map_or(0, |nodes| {
            nodes
                .iter()
                .filter(|n| {
                    ["translation", "rotation", "scale", "matrix"]
                        .iter()
                        .any(|k| n.get(k).is_some())
                })
                .count()
        });
        counted(transformed, "node transform", "node transforms");
        let moving = doc["animations"].as_array().map_or(0, |anims| {
            anims
                .iter()
                .flat_map(|a| a["channels"].as_array().into_iter().flatten())
                .filter(|c| c["target"]["path"].as_str() != Some("weights"))
                .count()
        });
        counted(moving, "node animation channel", "node animation channels");
        let mut attributes: Vec<String> = doc["meshes"][self.mesh]["primitives"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|p| p["attributes"].as_object())
            .flat_map(|a| a.keys().cloned())
            .filter(|k| k != "POSITION" && k != "NORMAL")
            .collect();
        attributes.sort();
        attributes.dedup();
        out.extend(attributes.into_iter().map(|a| {
            let what = if a.starts_with("TEXCOORD") {
                "UV set"
            } else if a.starts_with("COLOR") {
                "vertex colours"
            } else if a.starts_with("JOINTS") || a.starts_with("WEIGHTS") {
                "skin attribute"
            } else {
                "attribute"
            };
            format!("{what} {a}")
        }));
        out
    }

    /// The file the asset was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The document's JSON as it will be written, before buffers are merged and images
    /// embedded (buffers read from data URIs are listed without their `uri`).
    pub fn document(&self) -> &Value {
        &self.doc
    }

    /// The index of the chosen mesh in `meshes`.
    pub fn mesh_index(&self) -> usize {
        self.mesh
    }

    /// The name of the chosen mesh, when it has one.
    pub fn mesh_name(&self) -> Option<&str> {
        self.doc["meshes"][self.mesh]["name"].as_str()
    }

    /// Per primitive of the chosen mesh, in order: its vertices in [`GltfAsset::morphs`].
    pub fn primitive_vertices(&self) -> Vec<Range<usize>> {
        self.primitives.iter().map(|p| p.vertices.clone()).collect()
    }

    /// True when the chosen mesh is part of a rig morphkit split into several meshes (a long
    /// animation, `extras.morphkitTargets`): it is carried as it is, and edits are refused.
    pub fn is_split_rig(&self) -> bool {
        self.split
    }

    /// Every animation that drives the chosen mesh's morph weights, in document order.
    pub fn weight_animations(&self) -> &[GltfWeightAnimation] {
        &self.animations
    }

    /// The weights animation `name` chooses, by name or index (the rule of
    /// [`GltfReadOptions::mesh`]: an index is the animation's in `animations`); with `None`,
    /// the only one (`None` when there is none). Errors: no animation of that name or index,
    /// several of that name (naming their indices), or several and no name (all list them).
    pub fn weight_animation(
        &self,
        name: Option<&str>,
    ) -> Result<Option<&GltfWeightAnimation>, IoError> {
        let items: Vec<Named> = self
            .animations
            .iter()
            .map(|a| Named {
                index: a.index,
                name: a.name.as_deref(),
            })
            .collect();
        // Listed by name, and by index too where names are shared.
        let shared = shared_names(&items);
        let list = || {
            self.animations
                .iter()
                .map(|a| match &a.name {
                    Some(n) if shared => format!("animation {} '{n}'", a.index),
                    Some(n) => format!("'{n}'"),
                    None => format!("animation {} (unnamed)", a.index),
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let what = match self.mesh_name() {
            Some(n) => format!("mesh '{n}'"),
            None => format!("mesh {}", self.mesh),
        };
        match name {
            Some(n) => {
                let scope = format!(" driving the morph weights of {what}");
                let i = choose(&self.path, "animation", &scope, &items, n, || {
                    format!(
                        "no animation named '{n}'{} drives the morph weights of {what}; {}",
                        if n.parse::<usize>().is_ok() {
                            " or of that index"
                        } else {
                            ""
                        },
                        if self.animations.is_empty() {
                            "none does".to_string()
                        } else {
                            format!("these do: {}", list())
                        }
                    )
                })?;
                Ok(Some(&self.animations[i]))
            }
            None if self.animations.len() > 1 => Err(IoError::content(
                &self.path,
                format!(
                    "{} animations drive the morph weights of {what} ({}); choose one {}",
                    self.animations.len(),
                    list(),
                    if shared {
                        "by index (names are shared)"
                    } else {
                        "by name or index"
                    }
                ),
            )),
            None => Ok(self.animations.first()),
        }
    }

    /// The most morph targets edits may give the chosen mesh: default [`SAFE_MORPH_TARGETS`]
    /// (what WebGL2 viewers such as three.js play; a mesh with more stays at its base there);
    /// `0` allows any number.
    pub fn max_targets(&self) -> usize {
        self.max_targets
    }

    /// Sets [`GltfAsset::max_targets`].
    pub fn set_max_targets(&mut self, max: usize) {
        self.max_targets = max;
    }

    /// Targets added from now on store their position and normal deltas as sparse accessors
    /// (glTF 2.0 §3.6.2.3: the moved vertices' indices and values, zeros elsewhere) where that
    /// is smaller than dense (fewer than three quarters of the vertices move): for edits that add many local shapes (a bake). Off by default.
    pub fn set_sparse_targets(&mut self, on: bool) {
        self.sparse_targets = on;
    }

    /// Fails, before any work, when `new` more morph targets would take the chosen mesh over
    /// [`GltfAsset::max_targets`], or when the mesh cannot be edited (a split rig). The error
    /// says what to do.
    pub fn check_room(&self, new: usize) -> Result<(), IoError> {
        if self.split {
            let meshes = self.doc["meshes"].as_array().map_or(0, |m| {
                m.iter()
                    .filter(|m| m["extras"]["morphkitTargets"].is_array())
                    .count()
            });
            return Err(IoError::content(
                &self.path,
                format!(
                    "a frame sequence morphkit split into {meshes} meshes (a long animation, \
                     extras.morphkitTargets), whose {} morph targets it reads as one rig: it can \
                     be read and carried (convert) but not edited (new targets or animations); \
                     write it unsplit (--max-targets 0) or write the frames to .pc2, OBJ or USD",
                    self.morphs.targets.len()
                ),
            ));
        }
        let have = self.morphs.targets.len();
        let total = have.saturating_add(new);
        if self.max_targets != 0 && total > self.max_targets {
            return Err(IoError::content(
                &self.path,
                format!(
                    "the mesh would have {total} morph targets ({have} + {new}), more than {}: \
                     WebGL2 viewers such as three.js leave a mesh with more at its base. Write \
                     fewer frames (a shorter animation or fewer weight rows), or allow it \
                     (max_targets 0; on the command line --max-targets 0)",
                    self.max_targets
                ),
            ));
        }
        Ok(())
    }
}
