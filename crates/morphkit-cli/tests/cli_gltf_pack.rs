//! Issue 37: `--quantize` and `--sparse-targets` make smaller .glb/.gltf output wherever glTF is
//! written (animations, rigs, single meshes); it reads back within 1e-4 of the diagonal and
//! passes the Khronos validator (`MORPHKIT_GLTF_VALIDATOR`).

mod common;
use common::*;
use std::path::Path;

fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let jl = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + jl]).unwrap()
}

fn obj_positions(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

fn size(p: &Path) -> u64 {
    std::fs::metadata(p).unwrap().len()
}

#[test]
fn the_flags_are_documented() {
    let h = ok(&["convert", "--help"]);
    assert!(
        h.contains("--quantize") && h.contains("KHR_mesh_quantization"),
        "{h}"
    );
    assert!(h.contains("--sparse-targets"), "{h}");
    let h = ok(&["blend", "--help"]);
    assert!(
        h.contains("--quantize") && h.contains("--sparse-targets"),
        "{h}"
    );
}

#[test]
fn quantized_sparse_animations_read_back_within_the_bound() {
    let d = tmp_dir("gltf-pack");
    let (base, bent) = (d.join("base.obj"), d.join("bent.obj"));
    write_tube(&base, 16, 12, 1.0, 0.0);
    write_tube(&bent, 16, 12, 1.0, 1.0);
    ok(&blend_args(
        &base,
        &bent,
        &["--frames", "12", "--linear", "--out", s(&d.join("frames"))],
    ));
    let frames = d.join("frames");
    let files = [
        ("plain.glb", vec![]),
        ("sparse.glb", vec!["--sparse-targets"]),
        ("quantized.glb", vec!["--quantize"]),
        ("packed.glb", vec!["--quantize", "--sparse-targets"]),
    ];
    for (name, flags) in &files {
        let mut args = vec!["convert", s(&frames)];
        args.extend(flags.iter().copied());
        let out = d.join(name);
        args.push(s(&out));
        ok(&args);
        let doc = glb_json(&out);
        let quantized = flags.contains(&"--quantize");
        assert_eq!(
            doc.get("extensionsRequired").is_some(),
            quantized,
            "{name}: {}",
            doc["extensionsRequired"]
        );
        // Back to OBJ frames: equal to the blend within the bound.
        let back = d.join(format!("back-{}", name.trim_end_matches(".glb")));
        ok(&["convert", s(&out), s(&back)]);
        let mut worst: f64 = 0.0;
        let mut diag: f64 = 0.0;
        for k in 0..12 {
            let f = format!("frame_{k:04}.obj");
            let (a, b) = (
                obj_positions(&frames.join(&f)),
                obj_positions(&back.join(&f)),
            );
            assert_eq!(a.len(), b.len());
            let (lo, hi) = a
                .iter()
                .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
                    (
                        [0, 1, 2].map(|i| lo[i].min(p[i])),
                        [0, 1, 2].map(|i| hi[i].max(p[i])),
                    )
                });
            diag = diag.max((0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt());
            for (p, q) in a.iter().zip(&b) {
                worst = worst.max((0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt());
            }
        }
        let bound = if quantized { 1e-4 } else { 1e-6 };
        assert!(worst <= bound * diag, "{name}: {worst} of {diag}");
    }
    let (plain, sparse, quantized, packed) = (
        size(&d.join("plain.glb")),
        size(&d.join("sparse.glb")),
        size(&d.join("quantized.glb")),
        size(&d.join("packed.glb")),
    );
    assert!(quantized * 10 < plain * 6, "{quantized} vs {plain}");
    // The tube's first ring stays put: sparse drops it (a small saving here).
    assert!(sparse < plain && packed < quantized, "{sparse} {packed}");
    // A single mesh and a rig quantize too.
    ok(&["convert", s(&base), "--quantize", s(&d.join("mesh.glb"))]);
    let doc = glb_json(&d.join("mesh.glb"));
    assert_eq!(doc["extensionsUsed"][0], "KHR_mesh_quantization");
    assert_eq!(doc["accessors"][0]["componentType"], 5122);
    if let Some(script) = std::env::var_os("MORPHKIT_GLTF_VALIDATOR") {
        let mut cmd = std::process::Command::new("node");
        cmd.arg(script).arg(d.join("mesh.glb"));
        for (name, _) in &files {
            cmd.arg(d.join(name));
        }
        let out = cmd.output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{text}");
        assert_eq!(text.matches(": 0 errors, 0 warnings").count(), 5, "{text}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
