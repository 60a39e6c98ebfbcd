//! Writing a morph-target animation together with rigid meshes that move beside it (the
//! obstacles of a scene), as glTF or GLB.
//!
//! The morph-target mesh is written exactly as by [`write_gltf_with`](super::write_gltf_with)
//! (meshes and nodes first); each rigid mesh adds one mesh and one node, with its first pose as the
//! node's `translation` / `rotation`, and, when it has more than one key, `LINEAR`
//! `translation` and `rotation` channels (glTF interpolates rotations by slerp) in the same
//! animation as the morph weights, so everything plays together.

use super::write::{build_with, finish, to_f32, write_document, Builder};
use super::{GltfMorphs, GltfOptions, GltfSummary};
use crate::io::IoError;
use crate::mesh::{Point, TriMesh};
use serde_json::{json, Value};
use std::path::Path;

const FLOAT: u32 = 5126;

/// A rigid mesh with keyed poses.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfRigidMesh {
    /// Node and mesh name.
    pub name: String,
    /// The mesh in its local frame.
    pub mesh: TriMesh,
    /// `(time in seconds, translation, rotation quaternion [x, y, z, w])`, times strictly
    /// increasing; at least one.
    pub keys: Vec<(f64, Point, [f64; 4])>,
}

fn floats(b: &mut Builder, values: &[f32], ty: &str, count: usize) -> usize {
    let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
    let view = b.view(&bytes, None);
    b.accessors
        .push(json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": ty}));
    b.accessors.len() - 1
}

fn add_rigid(
    path: &Path,
    doc: &mut Value,
    b: &mut Builder,
    r: &GltfRigidMesh,
) -> Result<(), IoError> {
    let bad = |msg: String| IoError::content(path, format!("rigid mesh '{}': {msg}", r.name));
    let nv = r.mesh.num_vertices();
    if r.keys.is_empty() {
        return Err(bad("has no pose".into()));
    }
    if r.mesh.triangles.iter().flatten().any(|&i| i as usize >= nv) {
        return Err(bad(format!("a triangle refers to a vertex beyond {nv}")));
    }
    let ok_times = r.keys.iter().all(|k| k.0.is_finite())
        && r.keys.windows(2).all(|w| (w[0].0 as f32) < (w[1].0 as f32));
    if !ok_times {
        return Err(bad(
            "key times must be finite and strictly increasing (as f32)".into(),
        ));
    }
    let pos = to_f32(path, &r.name, &r.mesh.positions, None)?;
    let pos = b.vec3(&pos);
    let indices = b.triangle_indices(&r.mesh);
    let meshes = doc["meshes"].as_array_mut().expect("build writes meshes");
    meshes.push(json!({"name": r.name, "primitives": [{"attributes": {"POSITION": pos}, "indices": indices, "mode": 4}]}));
    let mesh = meshes.len() - 1;
    let (_, t0, q0) = r.keys[0];
    let nodes = doc["nodes"].as_array_mut().expect("build writes nodes");
    nodes.push(json!({"mesh": mesh, "name": r.name, "translation": t0, "rotation": q0}));
    let node = nodes.len() - 1;
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .expect("build writes a scene")
        .push(json!(node));
    if r.keys.len() < 2 {
        return Ok(());
    }
    let times: Vec<f32> = r.keys.iter().map(|k| k.0 as f32).collect();
    let tb: Vec<u8> = times.iter().flat_map(|t| t.to_le_bytes()).collect();
    let input = b.scalars(
        tb,
        times.len(),
        FLOAT,
        None,
        Some((times[0], times[times.len() - 1])),
    );
    let tr: Vec<f32> = r.keys.iter().flat_map(|k| k.1.map(|x| x as f32)).collect();
    let rot: Vec<f32> = r.keys.iter().flat_map(|k| k.2.map(|x| x as f32)).collect();
    if tr.iter().chain(&rot).any(|x| !x.is_finite()) {
        return Err(bad("a pose is not representable as f32".into()));
    }
    let tr = floats(b, &tr, "VEC3", times.len());
    let rot = floats(b, &rot, "VEC4", times.len());
    if doc.get("animations").is_none() {
        doc["animations"] = json!([{"name": "morphkit", "samplers": [], "channels": []}]);
    }
    let anim = &mut doc["animations"][0];
    for (output, target) in [(tr, "translation"), (rot, "rotation")] {
        let samplers = anim["samplers"]
            .as_array_mut()
            .expect("animation has samplers");
        samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
        let s = samplers.len() - 1;
        anim["channels"]
            .as_array_mut()
            .expect("animation has channels")
            .push(json!({"sampler": s, "target": {"node": node, "path": target}}));
    }
    Ok(())
}

/// Writes `m` (see [`write_gltf_morphs`](super::write_gltf_morphs)) with `rigid` meshes
/// beside it, atomically; GLB for `.glb`, otherwise glTF JSON with a data URI.
pub fn write_gltf_scene(
    path: &Path,
    m: &GltfMorphs,
    rigid: &[GltfRigidMesh],
) -> Result<(), IoError> {
    write_gltf_scene_with(path, m, rigid, &GltfOptions::default()).map(|_| ())
}

/// Like [`write_gltf_scene`], writing the morph-target mesh with `opts`
/// (see [`write_gltf_with`](super::write_gltf_with)).
pub fn write_gltf_scene_with(
    path: &Path,
    m: &GltfMorphs,
    rigid: &[GltfRigidMesh],
    opts: &GltfOptions,
) -> Result<GltfSummary, IoError> {
    let (mut doc, mut b, summary) = build_with(path, m, opts)?;
    for r in rigid {
        add_rigid(path, &mut doc, &mut b, r)?;
    }
    let (doc, bin) = finish(doc, b, opts);
    write_document(path, doc, &bin)?;
    Ok(summary)
}
