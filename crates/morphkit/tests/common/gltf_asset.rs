//! A hand-built glTF asset as users bring them (issue 37): two meshes, a textured material
//! (a PNG image), UVs, normals, an optional skin, node transforms, names, extras, an extension,
//! and weights animations. Self-contained (`std` and `serde_json` only) so that the library's
//! unit tests, its integration tests and the CLI tests include the same file with `#[path]`.
#![allow(dead_code)]

use serde_json::{json, Value};
use std::path::Path;

/// A 1 × 1 RGBA PNG.
pub const PNG: &[u8] = &[
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x06, 0x00, 0x00, 0x00, 0x1f, 0x15, 0xc4,
    0x89, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x38, 0xd0, 0x90, 0xf0,
    0x1f, 0x00, 0x06, 0x44, 0x02, 0xa0, 0x62, 0xa6, 0xd8, 0x8e, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45,
    0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
];

/// One primitive of the morph-target mesh: positions, triangles (local indices) and the
/// absolute positions of each target.
#[derive(Clone, Debug)]
pub struct Prim {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub targets: Vec<Vec<[f64; 3]>>,
}

/// What the asset holds.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The primitives of mesh 1, "Body".
    pub prims: Vec<Prim>,
    pub target_names: Vec<String>,
    /// The keys of animation 0, "Wave" (LINEAR); it also moves the node "Prop".
    pub keys: Vec<(f32, Vec<f32>)>,
    /// Add animation 1, "Pulse": CUBICSPLINE weights of "Body" over two keys.
    pub cubic: bool,
    /// Skin "Body" (two joints); the node "Body" then has no transform of its own.
    pub skin: bool,
    /// Uniform scale of the node "Body" when not skinned.
    pub body_scale: f64,
    /// A `.gltf` with its buffer and image as external files (`asset.bin`, `skin.png`) beside
    /// it instead of data URIs.
    pub external: bool,
}

/// An open tube of `nu` × `nv` vertices along z (height 4), bent by `bend` radians about y and
/// scaled by `scale`: the CLI tests' `write_tube`, in memory (vertex `j · nu + i`).
pub fn tube(nu: usize, nv: usize, scale: f64, bend: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let h = 4.0;
    let mut p = Vec::new();
    for j in 0..nv {
        let z = h * j as f64 / (nv - 1) as f64;
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            let (x, y) = (a.cos(), a.sin());
            let (px, pz) = if bend == 0.0 {
                (x, z)
            } else {
                let r = h / bend;
                let th = bend * z / h;
                (r - (r - x) * th.cos(), (r - x) * th.sin())
            };
            p.push([scale * px, scale * y, scale * pz]);
        }
    }
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    let mut t = Vec::new();
    for j in 0..nv - 1 {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (p, t)
}

/// Rings `r0..=r1` of a tube of `nu` vertices around (its positions and local triangles), as
/// exporters write a mesh split at a seam: neighbouring parts repeat their shared ring.
pub fn rings(p: &[[f64; 3]], nu: usize, r0: usize, r1: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let pos = p[r0 * nu..(r1 + 1) * nu].to_vec();
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    let mut t = Vec::new();
    for j in 0..r1 - r0 {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (pos, t)
}

/// Unit area-weighted vertex normals.
fn normals(p: &[[f64; 3]], t: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut n = vec![[0.0f64; 3]; p.len()];
    for tri in t {
        let [a, b, c] = tri.map(|i| p[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let f = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in tri {
            for k in 0..3 {
                n[i as usize][k] += f[k];
            }
        }
    }
    n.iter()
        .map(|q| {
            let l = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            let f = if l > 0.0 {
                q.map(|x| (x / l) as f32)
            } else {
                [0.0, 0.0, 1.0]
            };
            let l = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            f.map(|x| x / l)
        })
        .collect()
}

#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, b: &[u8], target: Option<u32>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": b.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bytes.extend_from_slice(b);
        self.views.push(v);
        self.views.len() - 1
    }

    fn acc(&mut self, b: &[u8], target: Option<u32>, mut a: Value) -> usize {
        a["bufferView"] = json!(self.view(b, target));
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(&mut self, v: &[f32], ty: &str, count: usize, target: Option<u32>) -> usize {
        let b: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.acc(
            &b,
            target,
            json!({"componentType": 5126, "count": count, "type": ty}),
        )
    }

    fn vec3_bounded(&mut self, v: &[[f32; 3]]) -> usize {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for q in v {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let flat: Vec<f32> = v.iter().flatten().copied().collect();
        let a = self.floats(&flat, "VEC3", v.len(), Some(34962));
        self.accessors[a]["min"] = json!(lo);
        self.accessors[a]["max"] = json!(hi);
        a
    }

    fn indices(&mut self, t: &[[u32; 3]]) -> usize {
        let b: Vec<u8> = t
            .iter()
            .flatten()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect();
        self.acc(
            &b,
            Some(34963),
            json!({"componentType": 5123, "count": 3 * t.len(), "type": "SCALAR"}),
        )
    }

    fn times(&mut self, t: &[f32]) -> usize {
        let a = self.floats(t, "SCALAR", t.len(), None);
        self.accessors[a]["min"] = json!([t[0]]);
        self.accessors[a]["max"] = json!([t[t.len() - 1]]);
        a
    }
}

fn f32s(p: &[[f64; 3]]) -> Vec<[f32; 3]> {
    p.iter().map(|q| q.map(|x| x as f32)).collect()
}

/// The document and its one buffer.
pub fn build(spec: &Spec) -> (Value, Vec<u8>) {
    let mut b = Bin::default();
    let n = spec.target_names.len();
    let mut prims = Vec::new();
    for (pi, p) in spec.prims.iter().enumerate() {
        let pos = b.vec3_bounded(&f32s(&p.positions));
        let nor = {
            let f: Vec<f32> = normals(&p.positions, &p.triangles)
                .into_iter()
                .flatten()
                .collect();
            b.floats(&f, "VEC3", p.positions.len(), Some(34962))
        };
        let uv: Vec<f32> = (0..p.positions.len())
            .flat_map(|i| [(i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0])
            .collect();
        let uv = b.floats(&uv, "VEC2", p.positions.len(), Some(34962));
        let idx = b.indices(&p.triangles);
        let mut attrs = json!({"POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv});
        if spec.skin {
            let joints: Vec<u8> = (0..p.positions.len())
                .flat_map(|_| [0u8, 1, 0, 0])
                .collect();
            let j = b.acc(
                &joints,
                Some(34962),
                json!({"componentType": 5121, "count": p.positions.len(), "type": "VEC4"}),
            );
            let w: Vec<f32> = (0..p.positions.len())
                .flat_map(|_| [0.75f32, 0.25, 0.0, 0.0])
                .collect();
            let w = b.floats(&w, "VEC4", p.positions.len(), Some(34962));
            attrs["JOINTS_0"] = json!(j);
            attrs["WEIGHTS_0"] = json!(w);
        }
        let targets: Vec<Value> = p
            .targets
            .iter()
            .map(|t| {
                let d: Vec<[f32; 3]> = t
                    .iter()
                    .zip(&p.positions)
                    .map(|(a, o)| [0, 1, 2].map(|k| (a[k] - o[k]) as f32))
                    .collect();
                json!({"POSITION": b.vec3_bounded(&d)})
            })
            .collect();
        let mut prim =
            json!({"attributes": attrs, "indices": idx, "material": pi.min(1), "mode": 4});
        if n > 0 {
            prim["targets"] = json!(targets);
        }
        prims.push(prim);
    }
    // Mesh 0, "Prop": a tetrahedron.
    let tet = [
        [0.0, 0.0, 0.0],
        [0.2, 0.0, 0.0],
        [0.0, 0.2, 0.0],
        [0.0, 0.0, 0.2],
    ];
    let tet_pos = b.vec3_bounded(&f32s(&tet));
    let tet_idx = b.indices(&[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
    let image = b.view(PNG, None);
    let mut body = json!({
        "name": "Body",
        "primitives": prims,
        "extras": {"rigger": "fixture"},
    });
    if n > 0 {
        body["weights"] = json!(vec![0.0; n]);
        body["extras"]["targetNames"] = json!(spec.target_names);
    }
    let mut body_node = json!({"name": "Body", "mesh": 1, "extras": {"part": "body"}});
    if n > 0 {
        body_node["weights"] = json!(vec![0.0; n]);
    }
    let mut scene_nodes = vec![0, 2];
    let mut nodes = vec![
        json!({"name": "Root", "children": [1, 3], "scale": [100.0, 100.0, 100.0], "extras": {"note": "centimetres"}}),
        json!({"name": "Prop", "mesh": 0, "translation": [0.5, 0.25, 0.0], "rotation": [0.0, 0.0, 0.38268343, 0.9238795]}),
        body_node,
        json!({"name": "Bone", "translation": [0.0, 0.0, 1.0], "children": [4]}),
        json!({"name": "Bone.001", "translation": [0.0, 0.0, 2.0]}),
    ];
    if spec.skin {
        nodes[2]["skin"] = json!(0);
    } else {
        let s = spec.body_scale;
        nodes[2]["scale"] = json!([s, s, s]);
        scene_nodes.push(3);
        nodes[0]["children"] = json!([1]);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "morphkit test fixture", "copyright": "CC0", "extras": {"source": "fixture"}},
        "extensionsUsed": ["KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"name": "Scene", "nodes": scene_nodes, "extras": {"level": 1}}],
        "nodes": nodes,
        "meshes": [
            {"name": "Prop", "primitives": [{"attributes": {"POSITION": tet_pos}, "indices": tet_idx, "material": 1}]},
            body,
        ],
        "materials": [
            {"name": "Skin", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}}, "metallicFactor": 0.0}, "extras": {"shader": "skin"}},
            {"name": "Cloth", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.8, 1.0]}, "doubleSided": true},
        ],
        "textures": [{"name": "SkinTexture", "sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 33648}],
        "images": [{"name": "skin", "bufferView": image, "mimeType": "image/png"}],
    });
    if spec.skin {
        let mut ibm = Vec::new();
        for z in [1.0f32, 3.0] {
            ibm.extend_from_slice(&[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -z, 1.0,
            ]);
        }
        let ibm = b.floats(&ibm, "MAT4", 2, None);
        doc["skins"] = json!([{"name": "Armature", "joints": [3, 4], "inverseBindMatrices": ibm}]);
    }
    let mut animations = Vec::new();
    if !spec.keys.is_empty() && n > 0 {
        let t: Vec<f32> = spec.keys.iter().map(|k| k.0).collect();
        let w: Vec<f32> = spec.keys.iter().flat_map(|k| k.1.clone()).collect();
        let input = b.times(&t);
        let output = b.floats(&w, "SCALAR", w.len(), None);
        let tr: Vec<f32> = t.iter().flat_map(|&x| [0.5, 0.25, x]).collect();
        let tr = b.floats(&tr, "VEC3", t.len(), None);
        animations.push(json!({
            "name": "Wave",
            "samplers": [
                {"input": input, "output": tr, "interpolation": "LINEAR"},
                {"input": input, "output": output, "interpolation": "LINEAR"},
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 1, "path": "translation"}},
                {"sampler": 1, "target": {"node": 2, "path": "weights"}},
            ],
            "extras": {"take": 3},
        }));
    }
    if spec.cubic && n > 0 {
        let input = b.times(&[0.0, 1.0]);
        // Per key: in-tangents, values, out-tangents, each one weight per target.
        let mut w = Vec::new();
        for k in 0..2 {
            for part in 0..3 {
                for t in 0..n {
                    w.push(match part {
                        1 => 0.25 * (k + t) as f32,
                        _ => 0.125 * (part + t) as f32,
                    });
                }
            }
        }
        let output = b.floats(&w, "SCALAR", w.len(), None);
        animations.push(json!({
            "name": "Pulse",
            "samplers": [{"input": input, "output": output, "interpolation": "CUBICSPLINE"}],
            "channels": [{"sampler": 0, "target": {"node": 2, "path": "weights"}}],
        }));
    }
    if !animations.is_empty() {
        doc["animations"] = json!(animations);
    }
    while !b.bytes.len().is_multiple_of(4) {
        b.bytes.push(0);
    }
    doc["bufferViews"] = json!(b.views);
    doc["accessors"] = json!(b.accessors);
    doc["buffers"] = json!([{"byteLength": b.bytes.len(), "name": "data"}]);
    (doc, b.bytes)
}

fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() {
                A[(n >> (18 - 6 * k)) as usize & 63] as char
            } else {
                '='
            });
        }
    }
    s
}

/// A GLB of `doc` and `bin`.
pub fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

/// Writes the asset to `path`: GLB for `.glb`; otherwise glTF JSON with data URIs, or with
/// `asset.bin` and `skin.png` beside it when `spec.external`. Returns the document as written.
pub fn write(path: &Path, spec: &Spec) -> Value {
    let (mut doc, bin) = build(spec);
    if path.extension().is_some_and(|e| e == "glb") {
        std::fs::write(path, glb(&doc, &bin)).unwrap();
        return doc;
    }
    if spec.external {
        let dir = path.parent().unwrap();
        std::fs::write(dir.join("asset.bin"), &bin).unwrap();
        std::fs::write(dir.join("skin.png"), PNG).unwrap();
        doc["buffers"][0]["uri"] = json!("asset.bin");
        doc["images"][0] = json!({"name": "skin", "uri": "skin.png"});
    } else {
        doc["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64(&bin)
        ));
    }
    std::fs::write(path, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
    doc
}

/// The JSON chunk of a GLB.
pub fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The JSON of a `.glb` or `.gltf` file.
pub fn json_of(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    if bytes.starts_with(b"glTF") {
        glb_json(&bytes)
    } else {
        serde_json::from_slice(&bytes).unwrap()
    }
}

/// The standard spec: a 12 × 9 tube split at ring 4 into two primitives (16 vertices
/// repeated at the seam), two targets ("bend", "lift"), three keys, a CUBICSPLINE animation,
/// and a skin or a ×`scale` node.
pub fn standard(skin: bool, scale: f64) -> Spec {
    let (nu, nv) = (12, 9);
    let (p, _) = tube(nu, nv, 1.0, 0.0);
    let (bent, _) = tube(nu, nv, 1.0, 0.9);
    let lift: Vec<[f64; 3]> = p
        .iter()
        .map(|q| [q[0], q[1] + 0.05 * q[2] * q[2], q[2]])
        .collect();
    let prim = |r0, r1| {
        let (pos, tri) = rings(&p, nu, r0, r1);
        Prim {
            positions: pos,
            triangles: tri,
            targets: vec![rings(&bent, nu, r0, r1).0, rings(&lift, nu, r0, r1).0],
        }
    };
    Spec {
        prims: vec![prim(0, 4), prim(4, nv - 1)],
        target_names: vec!["bend".into(), "lift".into()],
        keys: vec![
            (0.0, vec![0.0, 0.0]),
            (0.5, vec![1.0, 0.0]),
            (1.0, vec![0.5, 0.5]),
        ],
        cubic: true,
        skin,
        body_scale: scale,
        external: false,
    }
}

/// Runs the Khronos validator (`MORPHKIT_GLTF_VALIDATOR`) on `files`; `None` when it is not
/// set. Returns each file's report line; panics when the validator fails to run.
pub fn validate(files: &[&Path]) -> Option<String> {
    let script = std::env::var_os("MORPHKIT_GLTF_VALIDATOR")?;
    let out = std::process::Command::new("node")
        .arg(script)
        .args(files)
        .output()
        .expect("run node");
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Asserts the validator reports 0 errors and 0 warnings for `files` (skips without it).
pub fn assert_valid(files: &[&Path]) {
    let Some(text) = validate(files) else {
        eprintln!("MORPHKIT_GLTF_VALIDATOR is unset; skipping the Khronos validator");
        return;
    };
    for f in files {
        let line = text
            .lines()
            .find(|l| l.starts_with(&f.display().to_string()))
            .unwrap_or_else(|| panic!("no report for {}:\n{text}", f.display()));
        assert!(line.contains(": 0 errors, 0 warnings"), "{line}\n{text}");
    }
}
