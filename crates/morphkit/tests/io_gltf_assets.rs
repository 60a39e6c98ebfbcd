//! The glTF reader on files made the way users make them: a rig written by morphkit, then
//! passed through the exporters' tools in `tools/gltf-assets` (gltfpack: quantized,
//! meshopt-compressed with and without quantization; gltf-transform: sparse accessors,
//! meshopt). Each variant must read back to the original base, targets, names and keys.
//!
//! The tools are Node packages: `npm ci` in `tools/gltf-assets`. Without `node` or the
//! installed packages the test skips with a message, unless `MORPHKIT_REQUIRE_GLTF_TOOLS` is
//! set, when it fails.

use morphkit::io::{self, GltfMorphs};
use morphkit::mesh::generate::{bend, grid};
use morphkit::mesh::Point;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "morphkit-gltf-assets-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `tools/gltf-assets` when node and its packages are installed; else `None` (skip), or a
/// panic when `MORPHKIT_REQUIRE_GLTF_TOOLS` is set.
fn tools() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf-assets");
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let bins = ["gltfpack", "gltf-transform"]
        .iter()
        .all(|b| dir.join("node_modules/.bin").join(b).exists());
    if node && bins {
        return Some(dir);
    }
    let why = if node {
        "tools/gltf-assets/node_modules is not installed (run `npm ci` there)"
    } else {
        "`node` is not on PATH"
    };
    if std::env::var_os("MORPHKIT_REQUIRE_GLTF_TOOLS").is_some() {
        panic!("MORPHKIT_REQUIRE_GLTF_TOOLS is set but {why}");
    }
    eprintln!("skipping the glTF exporter-tool tests: {why}");
    None
}

/// A bent grid with two targets (one moves only part of the vertices, so sparse storage pays)
/// and a weight animation.
fn rig() -> GltfMorphs {
    let base = grid(16, 6, 2.0, 0.75);
    let bent = bend(&base.positions, 0.8, 1.2, 1.0);
    let lifted: Vec<Point> = base
        .positions
        .iter()
        .map(|&[x, y, z]| [x, y, z + 0.3 * (x - 1.4).max(0.0) * (1.0 + y)])
        .collect();
    GltfMorphs {
        base,
        target_names: vec!["bend".into(), "lift".into()],
        targets: vec![bent, lifted],
        weight_keys: vec![
            (0.0, vec![0.0, 0.0]),
            (0.5, vec![1.0, 0.0]),
            (1.0, vec![0.5, 0.5]),
            (1.5, vec![0.0, 1.0]),
            (2.0, vec![0.0, 0.0]),
        ],
    }
}

type Mat = [[f64; 4]; 4];

fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// A node's local matrix (row-major, column vectors) from `matrix` or TRS.
fn local(node: &serde_json::Value) -> Mat {
    let f = |k: &str, d: &[f64]| -> Vec<f64> {
        node.get(k)
            .and_then(|v| v.as_array())
            .map_or(d.to_vec(), |a| {
                a.iter().map(|x| x.as_f64().unwrap()).collect()
            })
    };
    if let Some(m) = node.get("matrix") {
        let m: Vec<f64> = m
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let mut r = [[0.0; 4]; 4];
        for c in 0..4 {
            for row in 0..4 {
                r[row][c] = m[c * 4 + row];
            }
        }
        return r;
    }
    let t = f("translation", &[0.0; 3]);
    let q = f("rotation", &[0.0, 0.0, 0.0, 1.0]);
    let s = f("scale", &[1.0; 3]);
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let mut m = [
        [0.0, 0.0, 0.0, 0.0],
        [0.0; 4],
        [0.0; 4],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = r[i][j] * s[j];
        }
        m[i][3] = t[i];
    }
    m
}

/// The world matrix of the (first) node that uses the file's first mesh with morph targets:
/// exporters that quantize put the dequantization there.
fn mesh_node_matrix(glb: &Path) -> Mat {
    let bytes = std::fs::read(glb).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let meshes = doc["meshes"].as_array().unwrap();
    let mesh = meshes
        .iter()
        .position(|m| m["primitives"][0].get("targets").is_some())
        .unwrap();
    let nodes = doc["nodes"].as_array().unwrap();
    let mut n = nodes
        .iter()
        .position(|x| x["mesh"].as_u64() == Some(mesh as u64))
        .unwrap();
    let mut m = local(&nodes[n]);
    // Walk up the parents.
    while let Some(p) = nodes.iter().position(|x| {
        x["children"]
            .as_array()
            .is_some_and(|c| c.iter().any(|c| c.as_u64() == Some(n as u64)))
    }) {
        m = mul(&local(&nodes[p]), &m);
        n = p;
    }
    m
}

fn apply(m: &Mat, p: Point) -> Point {
    let mut q = [0.0; 3];
    for i in 0..3 {
        q[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    }
    q
}

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Checks that `got` (read from `file`, placed by its node's transform) is `want` up to
/// vertex order and `tol` (a fraction of the bounding-box diagonal).
fn check_same(file: &Path, got: &GltfMorphs, want: &GltfMorphs, tol: f64, weight_tol: f64) {
    let name = file.file_name().unwrap().to_string_lossy();
    let m = mesh_node_matrix(file);
    let (lo, hi) = want.base.bounding_box();
    let eps = tol * dist(lo, hi);
    let place = |p: &[Point]| p.iter().map(|&q| apply(&m, q)).collect::<Vec<_>>();
    let base = place(&got.base.positions);
    let targets: Vec<Vec<Point>> = got.targets.iter().map(|t| place(t)).collect();
    assert_eq!(
        base.len(),
        want.base.positions.len(),
        "{name}: vertex count"
    );
    assert_eq!(
        got.base.triangles.len(),
        want.base.triangles.len(),
        "{name}: triangles"
    );
    assert_eq!(got.target_names, want.target_names, "{name}: target names");
    // Exporters reorder vertices: match each one to the nearest original.
    let mut map = vec![usize::MAX; base.len()];
    let mut worst = 0.0f64;
    for (i, &p) in base.iter().enumerate() {
        let (j, d) = want
            .base
            .positions
            .iter()
            .enumerate()
            .map(|(j, &q)| (j, dist(p, q)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        map[i] = j;
        worst = worst.max(d);
        for (t, tp) in targets.iter().enumerate() {
            worst = worst.max(dist(tp[i], want.targets[t][j]));
        }
    }
    assert!(worst <= eps, "{name}: off by {worst:e}, allowed {eps:e}");
    let mut seen = map.clone();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(
        seen.len(),
        map.len(),
        "{name}: two vertices match the same original"
    );
    let canon = |t: [u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let mut want_tris: Vec<_> = want.base.triangles.iter().map(|&t| canon(t)).collect();
    let mut got_tris: Vec<_> = got
        .base
        .triangles
        .iter()
        .map(|t| canon(t.map(|i| map[i as usize] as u32)))
        .collect();
    want_tris.sort_unstable();
    got_tris.sort_unstable();
    assert_eq!(got_tris, want_tris, "{name}: triangles");
    assert_eq!(
        got.weight_keys.len(),
        want.weight_keys.len(),
        "{name}: keys"
    );
    for ((t, w), (t0, w0)) in got.weight_keys.iter().zip(&want.weight_keys) {
        assert!((t - t0).abs() < 1e-4, "{name}: key time {t} vs {t0}");
        for (a, b) in w.iter().zip(w0) {
            assert!(
                (a - b).abs() <= weight_tol,
                "{name}: weight {a} vs {b} at {t0}"
            );
        }
    }
}

#[test]
fn exporter_variants_read_back() {
    let Some(tools) = tools() else {
        return;
    };
    let d = tmp_dir("variants");
    let input = d.join("rig.glb");
    io::write_gltf_morphs(&input, &rig()).unwrap();
    // The reference is the file as written (f32 positions).
    let want = io::read_gltf_morphs(&input).unwrap();
    let out = d.join("out");
    let st = Command::new("sh")
        .arg(tools.join("make-variants.sh"))
        .arg(&input)
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success(), "make-variants.sh failed");
    // (file, position tolerance as a fraction of the diagonal, weight tolerance,
    //  extension it must use)
    // gltfpack stores weights as 8-bit normalized integers (steps of 1/255), even with -noq.
    let w8 = 1.0 / 255.0;
    let cases = [
        ("quantized.glb", 1e-3, w8, Some("KHR_mesh_quantization")),
        ("meshopt.glb", 1e-3, w8, Some("meshopt_compression")),
        ("meshopt-noq.glb", 1e-6, w8, Some("meshopt_compression")),
        ("sparse.glb", 1e-7, 0.0, None),
        (
            "transform-meshopt.glb",
            1e-3,
            w8,
            Some("meshopt_compression"),
        ),
    ];
    for (file, tol, wtol, ext) in cases {
        let p = out.join(file);
        let got = io::read_gltf_morphs(&p).unwrap_or_else(|e| panic!("{file}: {e}"));
        if let Some(ext) = ext {
            let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).into_owned();
            assert!(text.contains(ext), "{file} does not use {ext}");
        }
        check_same(&p, &got, &want, tol, wtol);
    }
    let sparse =
        String::from_utf8_lossy(&std::fs::read(out.join("sparse.glb")).unwrap()).into_owned();
    assert!(
        sparse.contains("\"sparse\""),
        "sparse.glb has no sparse accessor"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The fuzz seeds (`fuzz/seeds/gltf`: exporter variants and a hand-built quantized,
/// non-indexed, sparse, CUBICSPLINE file) read without node, and evaluate as the fuzz target
/// does; those named `refused-*` (issue 55: a file amplifying memory, a view past its buffer)
/// are refused with an error naming the file.
#[test]
fn fuzz_seeds_read() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/gltf");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("refused-")
        {
            let e = io::read_gltf_morphs(&p).unwrap_err().to_string();
            assert!(e.starts_with(&p.display().to_string()), "{e}");
            continue;
        }
        let rig = io::read_gltf_morphs(&p).unwrap_or_else(|e| panic!("{e}"));
        morphkit::mesh::validate(&rig.base).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        io::gltf_to_frames(&p, &rig).unwrap_or_else(|e| panic!("{e}"));
        n += 1;
    }
    assert!(n >= 7, "{n} seeds");
    let hand = io::read_gltf_morphs(&dir.join("non-indexed-sparse-cubic.gltf")).unwrap();
    assert_eq!(hand.base.triangles, [[0, 1, 2], [3, 4, 5]]);
    assert_eq!(hand.base.positions[4], [1.0, 1.0, 0.0]);
    assert_eq!(hand.targets[0][2], [0.0, 1.0, 0.5]);
    assert_eq!(hand.target_names, ["fold"]);
    let w: Vec<f64> = hand.weight_keys.iter().map(|k| k.1[0]).collect();
    assert_eq!(w, [0.2f32 as f64, 0.9f32 as f64]);
}
