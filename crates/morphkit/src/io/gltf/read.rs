//! Reading glTF/GLB into [`GltfMorphs`].

use super::accessor::{self, Data};
use super::anim::{target_names, weight_keys};
use super::buffers::load_buffers;
use super::choose::{choose, shared_names, Named};
use super::{extensions, GltfMorphs};
use crate::io::Format;
use crate::io::{source::read_file, IoError};
use crate::mesh::{Point, Polygons, TriMesh};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use std::borrow::Cow;
use std::path::Path;

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Checks the GLB container (header and chunk lengths) so that truncation is reported with a
/// byte offset before the `gltf` crate sees the file.
fn check_glb(path: &Path, b: &[u8]) -> Result<(), IoError> {
    if b.len() < 12 {
        return Err(IoError::binary(
            path,
            b.len() as u64,
            "the file ends inside the 12-byte GLB header",
        ));
    }
    let version = u32_at(b, 4);
    if version != 2 {
        return Err(IoError::binary(
            path,
            4,
            format!("GLB version {version}, only 2 is supported"),
        ));
    }
    let length = u32_at(b, 8) as usize;
    if length < 12 {
        return Err(IoError::binary(
            path,
            8,
            format!(
                "the GLB header declares a length of {length} bytes, less than the header itself"
            ),
        ));
    }
    if length > b.len() {
        return Err(IoError::binary(
            path,
            b.len() as u64,
            format!(
                "the GLB header declares {length} bytes but the file has {} (truncated)",
                b.len()
            ),
        ));
    }
    let mut off = 12;
    let mut chunk = 0;
    while off < length {
        if off + 8 > length {
            return Err(IoError::binary(
                path,
                off as u64,
                format!("the file ends inside the header of chunk {chunk}"),
            ));
        }
        let len = u32_at(b, off) as usize;
        if off + 8 + len > length {
            return Err(IoError::binary(
                path,
                off as u64,
                format!(
                    "chunk {chunk} declares {len} bytes but only {} remain (truncated)",
                    length - off - 8
                ),
            ));
        }
        off += 8 + len;
        chunk += 1;
    }
    Ok(())
}

/// How [`parse_gltf_morphs_with`] reads a file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GltfReadOptions {
    /// The mesh to read, by name or by index: the mesh of that name when exactly one has it
    /// (an error naming their indices when several share it); else, when the key is a number,
    /// the mesh at that index in `meshes` (`"1"`), so a mesh whose name is shared, or that has
    /// none, can be chosen. `None` (default): the mesh with morph targets (an error listing
    /// them when several meshes have them), or the first mesh when none has.
    pub mesh: Option<String>,
}

/// Reads the mesh with morph targets of a glTF or GLB file, with its morph-weight animation
/// (see the [module documentation](super)); [`read_gltf_morphs_with`] with the default
/// [`GltfReadOptions`].
///
/// Errors: unreadable, empty or truncated files (GLB truncation names the byte offset), files
/// the `gltf` crate rejects, a required extension morphkit does not decode (named), no mesh,
/// several meshes with morph targets (listing their names), non-triangle primitives,
/// `POSITION` not VEC3, accessors reaching past their buffer view, an index out of range
/// (naming primitive and index), primitives with different numbers of morph targets, a morph
/// target whose `POSITION` accessor has another count than the base `POSITION`, and weight
/// outputs whose count does not match keys × targets. Errors name the mesh and primitive.
pub fn read_gltf_morphs(path: &Path) -> Result<GltfMorphs, IoError> {
    parse_gltf_morphs(path, read_file(path)?)
}

/// [`read_gltf_morphs`] with options (which mesh to read).
pub fn read_gltf_morphs_with(path: &Path, opts: &GltfReadOptions) -> Result<GltfMorphs, IoError> {
    parse_gltf_morphs_with(path, read_file(path)?, opts)
}

/// Like [`read_gltf_morphs`], on the file's bytes (GLB or glTF JSON). `path` names the file in
/// errors, says whether it should be GLB (by extension), and is the base of relative buffer
/// URIs.
pub fn parse_gltf_morphs(path: &Path, bytes: Vec<u8>) -> Result<GltfMorphs, IoError> {
    parse_gltf_morphs_with(path, bytes, &GltfReadOptions::default())
}

/// [`parse_gltf_morphs`] with options (which mesh to read).
///
/// Positions are those of the mesh, in its own space: the transforms of the nodes using it
/// are not applied (a quantized file, `KHR_mesh_quantization`, usually keeps its dequantizing
/// scale and offset on the node, so its positions are in integer units), except for a rig
/// that morphkit quantized ([`super::GltfOptions::quantize`]): its mesh's
/// `extras.morphkitDequantization` (the node's translation and uniform scale) is applied.
pub fn parse_gltf_morphs_with(
    path: &Path,
    bytes: Vec<u8>,
    opts: &GltfReadOptions,
) -> Result<GltfMorphs, IoError> {
    load_with(path, bytes, opts, true, |_| Ok(())).map(|(l, ())| l.morphs)
}

/// Everything a read found: the JSON as in the file, the buffers, the chosen mesh and its
/// merged morphs (what [`super::GltfAsset`] keeps).
pub(super) struct Loaded {
    /// The document's JSON text, as in the file (before supported required extensions were
    /// removed for the `gltf` crate).
    pub json: Vec<u8>,
    /// The bytes of every buffer (empty for meshopt fallback buffers).
    pub buffers: Vec<Vec<u8>>,
    /// Per buffer: a meshopt fallback buffer, without data.
    pub fallback: Vec<bool>,
    /// The index of the chosen mesh.
    pub mesh: usize,
    /// Per primitive of the chosen mesh: its vertex and triangle counts, in primitive order.
    pub primitives: Vec<(usize, usize)>,
    /// True when the mesh is the first part of a rig morphkit split into several meshes.
    pub split: bool,
    /// The merged mesh, its targets and the first weights animation.
    pub morphs: GltfMorphs,
}

/// What `scan` of [`load_with`] sees: the parsed document, its decoded data and the mesh.
pub(super) struct Scan<'a> {
    pub doc: &'a ::gltf::Document,
    pub data: &'a Data<'a>,
    pub mesh: ::gltf::Mesh<'a>,
}

/// Reads the file's bytes as [`parse_gltf_morphs_with`] does, also calling `scan` on the parsed
/// document (for what [`super::GltfAsset`] needs beyond the morphs). With `dequantize` false,
/// a morphkit-quantized rig stays in its mesh's own (integer) units, where edits are written.
pub(super) fn load_with<T>(
    path: &Path,
    bytes: Vec<u8>,
    opts: &GltfReadOptions,
    dequantize: bool,
    scan: impl FnOnce(Scan) -> Result<T, IoError>,
) -> Result<(Loaded, T), IoError> {
    let is_glb = bytes.starts_with(b"glTF");
    if is_glb {
        check_glb(path, &bytes)?;
    } else if Format::from_path(path) == Some(Format::Glb) {
        let looks_json = super::super::strip_bom(&bytes)
            .trim_ascii_start()
            .starts_with(b"{");
        return Err(IoError::binary(
            path,
            0,
            format!(
                "not a GLB file: it does not start with the magic 'glTF'{}",
                if looks_json {
                    " (it looks like glTF JSON; name it .gltf)"
                } else {
                    ""
                }
            ),
        ));
    }
    let gerr = |source| IoError::Gltf {
        path: path.to_path_buf(),
        cause: source,
    };
    super::precheck::check_positions(path, super::super::strip_bom(&bytes))?;
    let (json, blob): (Vec<u8>, Option<Vec<u8>>) = if is_glb {
        let glb = ::gltf::Glb::from_slice(&bytes).map_err(gerr)?;
        // The file's bytes are no longer needed once the JSON and the BIN chunk are copied.
        (glb.json.into_owned(), glb.bin.map(Cow::into_owned))
    } else {
        // The text is the JSON: no copy, only the byte-order mark removed.
        let mut bytes = bytes;
        let bom = bytes.len() - super::super::strip_bom(&bytes).len();
        bytes.drain(..bom);
        (bytes, None)
    };
    let stripped = extensions::strip_required(path, &json)?;
    let gltf = ::gltf::Gltf::from_slice_without_validation(stripped.as_deref().unwrap_or(&json))
        .map_err(gerr)?;
    validate(&gltf.document).map_err(gerr)?;
    drop(stripped);
    let doc = &gltf.document;
    // glTF requires count ≥ 1 (the gltf crate computed `count - 1` unchecked; cargo fuzz).
    if let Some(a) = doc.accessors().find(|a| a.count() == 0) {
        return Err(IoError::content(
            path,
            format!(
                "accessor {} has count 0; glTF requires at least 1",
                a.index()
            ),
        ));
    }
    super::buffers::check_views(path, doc)?;
    // What will be read, and what it costs, before anything is decoded.
    let mesh = choose_mesh(path, doc, opts)?;
    super::budget::check(path, doc, &mesh)?;
    let fallback = extensions::fallback_buffers(doc);
    let buffers = load_buffers(path, doc, blob, &fallback)?;
    let views = extensions::decode_views(path, doc, &buffers)?;
    let data = Data {
        buffers: &buffers,
        views: &views,
    };
    let (mut base, displacements, primitives) = read_mesh(path, &mesh, &data)?;
    // A quantized morphkit rig: positions back in their units (the node's transform), unless
    // the caller edits the file in the mesh's own space (GltfAsset).
    let dequant = super::read_chunks::dequantization(doc, &mesh).filter(|_| dequantize);
    if let Some(d) = dequant {
        super::read_chunks::dequantize(d, &mut base.positions);
    }
    let unscale = |mut d: Vec<Vec<Point>>| {
        if let Some((_, s)) = dequant {
            d.iter_mut().flatten().flatten().for_each(|x| *x *= s);
        }
        d
    };
    // Displacements become absolute positions in place (no second copy of every target).
    let mut targets = unscale(displacements);
    for d in &mut targets {
        for (q, b) in d.iter_mut().zip(&base.positions) {
            *q = [b[0] + q[0], b[1] + q[1], b[2] + q[2]];
        }
    }
    let split_rig = if mesh.index() == 0 {
        super::read_chunks::read_split(path, doc, &data, &base.positions, dequant)?
    } else {
        None
    };
    let split = split_rig.is_some();
    let morphs = match split_rig {
        Some((target_names, targets, weight_keys)) => GltfMorphs {
            base,
            target_names,
            targets,
            weight_keys,
        },
        None => GltfMorphs {
            target_names: target_names(mesh.extras(), targets.len()),
            weight_keys: weight_keys(path, doc, mesh.index(), targets.len(), &data)?,
            base,
            targets,
        },
    };
    let index = mesh.index();
    let extra = scan(Scan {
        doc,
        data: &data,
        mesh,
    })?;
    drop(views);
    Ok((
        Loaded {
            json,
            buffers,
            fallback,
            mesh: index,
            primitives,
            split,
            morphs,
        },
        extra,
    ))
}

/// The `gltf` crate's validation, except that an accessor may have neither a buffer view nor
/// sparse values (glTF 2.0 §5.1.1: it is then all zeros; gltf-transform writes such accessors
/// for all-zero morph-target normals), and that textures, images and materials, which are not
/// read, are not checked.
fn validate(doc: &::gltf::Document) -> Result<(), ::gltf::Error> {
    use ::gltf::json::validation::{Error, Validate};
    let root = doc.as_json();
    let mut errors = Vec::new();
    root.validate(root, ::gltf::json::Path::new, &mut |path, error| {
        let p = path();
        let zeros = matches!(error, Error::Missing)
            && p.as_str().starts_with("accessors[")
            && p.as_str().ends_with("].bufferView");
        // Never read; a texture of KHR_texture_basisu or EXT_texture_webp has no `source`.
        let unread = ["textures[", "images[", "materials["]
            .iter()
            .any(|k| p.as_str().starts_with(k));
        if !zeros && !unread {
            errors.push((p, error));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        Err(::gltf::Error::Validation(errors))
    }
}

/// How errors and listings name a mesh: `mesh 2 'Face'`.
pub(super) fn mesh_label(m: &::gltf::Mesh) -> String {
    match m.name() {
        Some(n) => format!("mesh {} '{n}'", m.index()),
        None => format!("mesh {} (unnamed)", m.index()),
    }
}

/// The mesh to read: the one `opts` chooses by name or index ([`super::choose`]), else the one
/// with morph targets, else the first.
fn choose_mesh<'a>(
    path: &Path,
    doc: &'a ::gltf::Document,
    opts: &GltfReadOptions,
) -> Result<::gltf::Mesh<'a>, IoError> {
    let all = || {
        doc.meshes()
            .map(|m| mesh_label(&m))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(key) = &opts.mesh {
        let meshes: Vec<_> = doc.meshes().collect();
        let items: Vec<Named> = meshes
            .iter()
            .map(|m| Named {
                index: m.index(),
                name: m.name(),
            })
            .collect();
        let i = choose(path, "mesh", "", &items, key, || {
            let index = if key.parse::<usize>().is_ok() {
                " or index"
            } else {
                ""
            };
            format!(
                "the file has no mesh named '{key}'{index}; its meshes: {}",
                all()
            )
        })?;
        return Ok(meshes[i].clone());
    }
    let morph: Vec<_> = doc
        .meshes()
        .filter(|m| m.primitives().any(|p| p.morph_targets().next().is_some()))
        .collect();
    // A split rig (`extras.morphkitTargets`, see read_chunks) is one rig over several meshes.
    let split = morph.first().is_some_and(|m| m.index() == 0)
        && morph
            .iter()
            .all(|m| super::read_chunks::rig_indices(m.extras()).is_some());
    match morph.len() {
        0 => doc
            .meshes()
            .next()
            .ok_or_else(|| IoError::content(path, "the file has no mesh")),
        1 => Ok(morph[0].clone()),
        _ if split => Ok(morph[0].clone()),
        n => {
            let items: Vec<Named> = morph
                .iter()
                .map(|m| Named {
                    index: m.index(),
                    name: m.name(),
                })
                .collect();
            let how = if shared_names(&items) {
                "by index (names are shared)"
            } else {
                "by name or index"
            };
            Err(IoError::content(
                path,
                format!(
                    "{n} meshes have morph targets ({}); choose one {how} (GltfReadOptions::mesh, \
                     the command line's --mesh)",
                    morph.iter().map(mesh_label).collect::<Vec<_>>().join(", ")
                ),
            ))
        }
    }
}

/// The base mesh (all triangle primitives merged, indices offset by the vertices before), the
/// morph-target displacements of `mesh`, and each primitive's vertex and triangle counts.
#[allow(clippy::type_complexity)]
fn read_mesh(
    path: &Path,
    mesh: &::gltf::Mesh,
    data: &Data,
) -> Result<(TriMesh, Vec<Vec<Point>>, Vec<(usize, usize)>), IoError> {
    let label = mesh_label(mesh);
    let mut positions: Vec<Point> = Vec::new();
    let mut polys = Polygons {
        offsets: vec![0],
        indices: Vec::new(),
    };
    let mut displacements: Vec<Vec<Point>> = Vec::new();
    let mut counts = Vec::new();
    for (pi, prim) in mesh.primitives().enumerate() {
        let at = |m: String| IoError::content(path, format!("{label}, primitive {pi}: {m}"));
        if prim.mode() != Mode::Triangles {
            return Err(at(format!(
                "mode {:?}; only triangles are supported",
                prim.mode()
            )));
        }
        let pos_acc = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| at("no POSITION attribute".into()))?;
        let p = accessor::read_vec3(&pos_acc, data).map_err(|m| at(format!("POSITION {m}")))?;
        if let Some(v) = p.iter().position(|q| q.iter().any(|x| !x.is_finite())) {
            return Err(at(format!(
                "POSITION: vertex {v} has a non-finite coordinate"
            )));
        }
        let n = p.len();
        let offset = u32::try_from(positions.len())
            .ok()
            .filter(|o| o.checked_add(n as u32).is_some() && n <= u32::MAX as usize)
            .ok_or_else(|| at("too many vertices".into()))?;
        let idx: Vec<u32> = match prim.indices() {
            Some(acc) => {
                if acc.dimensions() != Dimensions::Scalar
                    || !matches!(
                        acc.data_type(),
                        DataType::U8 | DataType::U16 | DataType::U32
                    )
                {
                    return Err(at(format!(
                        "index accessor {} is {:?} {:?}, expected an unsigned integer type (SCALAR)",
                        acc.index(),
                        acc.data_type(),
                        acc.dimensions()
                    )));
                }
                accessor::read(&acc, data)
                    .map_err(|m| at(format!("indices: {m}")))?
                    .into_iter()
                    .map(|i| i as u32)
                    .collect()
            }
            // Non-indexed: consecutive vertex triples.
            None => (0..n as u32).collect(),
        };
        if !idx.len().is_multiple_of(3) {
            return Err(at(format!("{} indices is not a multiple of 3", idx.len())));
        }
        if let Some((k, &i)) = idx.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(at(format!(
                "index {k} is {i}, but the primitive has {n} vertices"
            )));
        }
        for t in idx.chunks_exact(3) {
            polys.indices.extend(t.iter().map(|&i| i + offset));
            polys.offsets.push(polys.indices.len() as u32);
        }
        let targets: Vec<_> = prim.morph_targets().collect();
        if pi > 0 && targets.len() != displacements.len() {
            return Err(at(format!(
                "has {} morph targets, primitive 0 has {}",
                targets.len(),
                displacements.len()
            )));
        }
        if pi == 0 {
            displacements = vec![Vec::new(); targets.len()];
        }
        for (t, target) in targets.iter().enumerate() {
            accessor::reserve(&mut displacements[t], n)
                .map_err(|m| at(format!("morph target {t}: {m}")))?;
            let Some(acc) = target.positions() else {
                displacements[t].extend(std::iter::repeat_n([0.0; 3], n));
                continue;
            };
            if acc.count() != n {
                return Err(at(format!(
                    "morph target {t}: POSITION accessor {} has {} elements, the base POSITION has {n}",
                    acc.index(),
                    acc.count()
                )));
            }
            let d = accessor::read_vec3(&acc, data)
                .map_err(|m| at(format!("morph target {t}: POSITION {m}")))?;
            if let Some(v) = d.iter().position(|q| q.iter().any(|x| !x.is_finite())) {
                return Err(at(format!(
                    "morph target {t}: vertex {v} has a non-finite displacement {:?}",
                    d[v]
                )));
            }
            displacements[t].extend(d);
        }
        accessor::reserve(&mut positions, n).map_err(at)?;
        positions.extend(p);
        counts.push((n, idx.len() / 3));
    }
    Ok((
        TriMesh::from_polygons(positions, polys),
        displacements,
        counts,
    ))
}
