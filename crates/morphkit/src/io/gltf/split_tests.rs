//! Issue 55: a long frame sequence that morphkit wrote split into meshes of at most
//! [`SAFE_MORPH_TARGETS`](super::SAFE_MORPH_TARGETS) targets reads back through
//! [`GltfAsset`] as what it is: every target, and an animation with one weight per target and
//! one key per frame, not the first window's 200 targets and 201 keys.

use super::{GltfAsset, GltfOptions, GltfReadOptions};
use crate::io::{frames_to_gltf, read_gltf_morphs};
use crate::mesh::generate;
use crate::ShapeSet;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-split-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `n` frames of a small open tube bending from straight to 120°, written as `blend` writes
/// a `.glb` (frame 0 the base, one target per further frame, windows of 200 targets).
fn long_sequence(n: usize, path: &std::path::Path) {
    let tube = generate::tube(0.5, 4.0, 6, 4, false);
    let shapes = (0..n)
        .map(|k| {
            let a = 2.0 * k as f64 / (n - 1) as f64;
            (
                format!("f{k:05}"),
                generate::bend(&tube.positions, 0.0, 2.0, a),
            )
        })
        .collect();
    let frames = ShapeSet::new(tube, shapes).unwrap();
    let summary = super::write_gltf_with(
        path,
        &frames_to_gltf(&frames, 24.0),
        &GltfOptions::default(),
    )
    .unwrap();
    assert_eq!(summary.meshes, 3, "450 frames are split into 3 meshes");
}

#[test]
fn a_split_frame_sequence_reads_as_one_rig_with_its_whole_animation() {
    let d = tmp("read");
    let p = d.join("long.glb");
    let n = 450;
    long_sequence(n, &p);
    let a = GltfAsset::read(&p, &GltfReadOptions::default()).unwrap();
    assert!(a.is_split_rig());
    let m = a.morphs();
    assert_eq!(m.targets.len(), n - 1);
    assert_eq!(m.weight_keys.len(), n);
    let anim = a
        .weight_animation(None)
        .unwrap()
        .expect("the sequence's clip");
    assert_eq!(a.weight_animations().len(), 1);
    // One key per frame, one weight per target: the same keys as the rig's.
    assert_eq!(anim.keys.len(), n, "one key per frame");
    assert!(anim.keys.iter().all(|(_, w)| w.len() == n - 1));
    assert_eq!(anim.keys, m.weight_keys);
    assert_eq!(m.weight_keys, read_gltf_morphs(&p).unwrap().weight_keys);
    anim.check_times(&p).unwrap();
    for (k, (t, w)) in anim.keys.iter().enumerate() {
        assert!((t - k as f64 / 24.0).abs() < 1e-5, "key {k} at {t}");
        let ones: Vec<usize> = (0..w.len()).filter(|&j| w[j] != 0.0).collect();
        let want: Vec<usize> = if k == 0 { vec![] } else { vec![k - 1] };
        assert_eq!(ones, want, "key {k}");
    }
    // Editing it (blend --rig or rig into the .glb) is refused by name, before any work.
    let e = a
        .check_frame_animation("c-physical", &[0.0], 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("long.glb") && e.contains("frame sequence morphkit split into 3 meshes"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
