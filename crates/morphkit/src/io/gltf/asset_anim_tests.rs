//! Tests of the compact physical animation ([`GltfAsset::add_compact_animation`]): written,
//! read back and played from the stored numbers, it gives the frames within the basis's error.

use super::{CompactEncoding, GltfAsset, GltfAssetOptions, GltfReadOptions};
use crate::clip::{residual_basis, residual_basis_on, Grid};
use crate::geom::max_distance;
use crate::mesh::Point;
use std::path::PathBuf;

use super::asset_tests::fixture;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-anim-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// 30 frames for `a`'s mesh: the linear blend of its targets at smooth weights, plus a bend
/// that the targets cannot make (the "physical" residual), of rank 2 over the clip. Returns
/// the weights, the frames and their residuals against the linear blend.
#[allow(clippy::type_complexity)]
fn physical(a: &GltfAsset) -> (Vec<Vec<f64>>, Vec<Vec<Point>>, Vec<Vec<Point>>) {
    let m = a.morphs();
    let n0 = m.targets.len();
    let weights: Vec<Vec<f64>> = (0..30)
        .map(|k| {
            let t = k as f64 / 29.0;
            (0..n0).map(|i| (t * (i + 1) as f64).sin().abs()).collect()
        })
        .collect();
    let frames: Vec<Vec<Point>> = weights
        .iter()
        .enumerate()
        .map(|(k, w)| {
            let t = k as f64 / 29.0;
            m.evaluate(w)
                .iter()
                .zip(&m.base.positions)
                .map(|(q, b)| {
                    let bend = 0.05 * t * b[2] * b[2] + 0.02 * (3.0 * t).sin() * b[1];
                    [q[0] + bend, q[1], q[2]]
                })
                .collect()
        })
        .collect();
    let residuals: Vec<Vec<Point>> = frames
        .iter()
        .zip(&weights)
        .map(|(f, w)| {
            f.iter()
                .zip(m.evaluate(w))
                .map(|(p, l)| [p[0] - l[0], p[1] - l[1], p[2] - l[2]])
                .collect()
        })
        .collect();
    (weights, frames, residuals)
}

#[test]
fn a_compact_clip_plays_the_frames_within_its_error() {
    let d = tmp("compact");
    let p = d.join("a.glb");
    fixture::write(&p, &fixture::standard(true, 1.0));
    let mut a = GltfAsset::read(&p, &GltfReadOptions::default()).unwrap();
    let (weights, frames, residuals) = physical(&a);
    let m = a.morphs().clone();
    let n0 = m.targets.len();
    let diag = m.base.bbox_diagonal();
    let basis = residual_basis(&residuals, 1e-4 * diag, 10).unwrap();
    assert_eq!(basis.shapes.len(), 2, "{} {}", basis.max_error, diag);
    let times: Vec<f64> = (0..30).map(|k| k as f64 / 30.0).collect();
    // Rows that do not match are refused before anything changes.
    let e = a
        .clone()
        .add_compact_animation(
            "physical",
            &times[..29],
            &weights[..29],
            &basis,
            &CompactEncoding::default(),
        )
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("30 rows of corrective weights for 29 keys"),
        "{e}"
    );
    a.add_compact_animation(
        "physical",
        &times,
        &weights,
        &basis,
        &CompactEncoding::default(),
    )
    .unwrap();
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    let b = GltfAsset::read(&out, &GltfReadOptions::default()).unwrap();
    assert_eq!(b.morphs().targets.len(), n0 + 2);
    assert_eq!(
        b.morphs().target_names[n0..],
        ["physical_corrective_00", "physical_corrective_01"]
    );
    let anim = b.weight_animation(Some("physical")).unwrap().unwrap();
    assert_eq!(anim.keys.len(), 30);
    for (k, (t, w)) in anim.keys.iter().enumerate() {
        assert_eq!(*t, times[k] as f32 as f64);
        let played = b.morphs().evaluate(w);
        let e = max_distance(&played, &frames[k]);
        // The basis's error, and f32 storage of targets and weights.
        assert!(e <= basis.max_error + 1e-5 * diag, "frame {k}: {e}");
    }
    // The other animations leave the correctives at 0.
    for other in ["Wave", "Pulse"] {
        let anim = b.weight_animation(Some(other)).unwrap().unwrap();
        assert!(anim.keys.iter().all(|(_, w)| w[n0..] == [0.0, 0.0]));
    }
    // A second run on the output replaces the correctives and the clip by name...
    let padded: Vec<Vec<f64>> = weights
        .iter()
        .map(|w| w.iter().copied().chain([0.0, 0.0]).collect())
        .collect();
    let mut c = b.clone();
    let e = c
        .clone()
        .add_compact_animation(
            "physical",
            &times,
            &weights,
            &basis,
            &CompactEncoding::default(),
        )
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!(
            "key 0: {n0} weights for the mesh's {} targets",
            n0 + 2
        )),
        "{e}"
    );
    c.add_compact_animation(
        "physical",
        &times,
        &padded,
        &basis,
        &CompactEncoding::default(),
    )
    .unwrap();
    assert_eq!(c.morphs().targets.len(), n0 + 2);
    assert_eq!(c.weight_animations().len(), b.weight_animations().len());
    // ...but refuses to replace a corrective the clip itself weighs.
    let mut own = padded.clone();
    own[3][n0 + 1] = 0.5;
    let e = c
        .add_compact_animation(
            "physical",
            &times,
            &own,
            &basis,
            &CompactEncoding::default(),
        )
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weighs the target 'physical_corrective_01'"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Quantized (`KHR_mesh_quantization`) and meshopt-compressed correctives: each is rounded to
/// its 16-bit grid before its coefficients are projected, so what a reader decodes from the
/// file plays the frames within the basis's error, and the file is smaller than with `f32`.
#[test]
fn quantized_compressed_correctives_play_the_stored_numbers() {
    let d = tmp("compact-packed");
    let p = d.join("a.glb");
    fixture::write(&p, &fixture::standard(true, 1.0));
    let a = GltfAsset::read(&p, &GltfReadOptions::default()).unwrap();
    let (weights, frames, residuals) = physical(&a);
    let n0 = a.morphs().targets.len();
    let diag = a.morphs().base.bbox_diagonal();
    let times: Vec<f64> = (0..30).map(|k| k as f64 / 30.0).collect();
    let tol = 1e-4 * diag;
    let mut sizes = Vec::new();
    for (name, quantize, meshopt) in [
        ("f32", false, None),
        ("quantized", true, None),
        ("packed", true, Some("EXT_meshopt_compression".to_string())),
    ] {
        let enc = CompactEncoding { quantize, meshopt };
        let mut a = a.clone();
        let basis = residual_basis_on(&residuals, tol, 10, a.corrective_grid(&enc, tol)).unwrap();
        assert!(basis.max_error <= tol, "{name}: {}", basis.max_error);
        let want = if quantize {
            Grid::I16Normalized
        } else {
            Grid::F32
        };
        assert!(
            basis.grids.iter().all(|g| *g == want),
            "{name}: {:?}",
            basis.grids
        );
        // Coefficients within Blender's shape-key range.
        assert!(basis.coefficients.iter().flatten().all(|c| c.abs() <= 10.0));
        a.add_compact_animation("physical", &times, &weights, &basis, &enc)
            .unwrap();
        let out = d.join(format!("{name}.glb"));
        a.write(&out, &GltfAssetOptions::default()).unwrap();
        fixture::assert_valid(&[&out]);
        let b = GltfAsset::read(&out, &GltfReadOptions::default()).unwrap();
        assert_eq!(b.morphs().targets, a.morphs().targets, "{name}");
        let anim = b.weight_animation(Some("physical")).unwrap().unwrap();
        for (k, (_, w)) in anim.keys.iter().enumerate() {
            let e = max_distance(&b.morphs().evaluate(w), &frames[k]);
            // The basis's error, and the f32 storage of the weights.
            assert!(e <= basis.max_error + 1e-6 * diag, "{name}, frame {k}: {e}");
        }
        let doc = b.document();
        let required = doc["extensionsRequired"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        let has = |e: &str| required.iter().any(|x| x == e);
        assert_eq!(has("KHR_mesh_quantization"), quantize, "{name}");
        assert_eq!(has("EXT_meshopt_compression"), name == "packed", "{name}");
        let target = &doc["meshes"][b.mesh_index()]["primitives"][0]["targets"][n0];
        let acc = &doc["accessors"][target["POSITION"].as_u64().unwrap() as usize];
        assert_eq!(acc["componentType"], if quantize { 5122 } else { 5126 });
        sizes.push(std::fs::metadata(&out).unwrap().len());
    }
    assert!(sizes[1] < sizes[0] && sizes[2] < sizes[1], "{sizes:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn sparse_targets_store_only_the_moved_vertices_and_read_back_the_same() {
    let d = tmp("sparse");
    let p = d.join("a.glb");
    fixture::write(&p, &fixture::standard(false, 1.0));
    let mut a = GltfAsset::read(&p, &GltfReadOptions::default()).unwrap();
    let base = a.morphs().base.positions.clone();
    // Ten of the 120 vertices move.
    let local: Vec<Point> = base
        .iter()
        .enumerate()
        .map(|(i, q)| if i < 10 { [q[0] + 0.1, q[1], q[2]] } else { *q })
        .collect();
    a.set_sparse_targets(true);
    a.add_targets(&["local".to_string()], std::slice::from_ref(&local))
        .unwrap();
    a.set_sparse_targets(false);
    let out = d.join("b.glb");
    a.write(&out, &GltfAssetOptions::default()).unwrap();
    fixture::assert_valid(&[&out]);
    let b = GltfAsset::read(&out, &GltfReadOptions::default()).unwrap();
    let k = b
        .morphs()
        .target_names
        .iter()
        .position(|n| n == "local")
        .unwrap();
    assert!(max_distance(&b.morphs().targets[k], &local) < 1e-6);
    let doc = fixture::json_of(&out);
    let mesh = doc["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "Body")
        .unwrap();
    let acc = mesh["primitives"][0]["targets"][k]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let sparse = &doc["accessors"][acc]["sparse"];
    assert_eq!(sparse["count"], 10, "{}", doc["accessors"][acc]);
    assert_eq!(
        doc["accessors"][acc]["min"],
        serde_json::json!([0.0, 0.0, 0.0])
    );
    let _ = std::fs::remove_dir_all(&d);
}
