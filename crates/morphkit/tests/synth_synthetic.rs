//! Animation synthesis on generated meshes: the invariants of issue 10.

use morphkit::mesh::{bbox_diagonal, generate, Point, TriMesh};
use morphkit::synth::{
    blend_gradients, BlendMode, BlendRegion, LayerSpec, PoseSpec, SynthError, SynthOptions,
    Synthesizer, Timing,
};
use morphkit::transfer::{
    transfer_animation, Correspondence, GradientOperator, SolverOptions, TransferOptions,
    TransferSolver,
};
use morphkit::ShapeSet;

fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: Point) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn bar() -> TriMesh {
    generate::bar(4.0, 0.5, 2, 32)
}

/// The far half (x > 1.9) bent up by (k + 1) · 30° over a joint at 1.9 … 2.15.
fn bend_animation(m: &TriMesh, n: usize, sign: f64) -> Vec<Vec<Point>> {
    (0..n)
        .map(|k| {
            let a = sign * (k as f64 + 1.0) * 30f64.to_radians();
            generate::bend(&m.positions, 1.9, 0.25, a)
        })
        .collect()
}

fn centroid_x(m: &TriMesh, t: usize) -> f64 {
    (0..3)
        .map(|k| m.positions[m.triangles[t][k] as usize][0])
        .sum::<f64>()
        / 3.0
}

fn layer(m: &TriMesh, frames: Vec<Vec<Point>>, scribble: Vec<bool>, mode: BlendMode) -> LayerSpec {
    LayerSpec {
        source_reference: m.clone(),
        frames,
        correspondence: Correspondence::identity(m),
        scribble,
        mode,
        timing: Timing::default(),
        region: BlendRegion::Partitions,
    }
}

fn max_dist(a: &[Point], b: &[Point]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| norm(sub(*p, *q)))
        .fold(0.0, f64::max)
}

fn plain_transfer(m: &TriMesh, frames: &[Vec<Point>]) -> Vec<Vec<Point>> {
    let set = ShapeSet::new(
        m.clone(),
        frames
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("f{i}"), f.clone()))
            .collect(),
    )
    .unwrap();
    transfer_animation(
        m,
        &set,
        m,
        &Correspondence::identity(m),
        &TransferOptions::default(),
    )
    .unwrap()
}

#[test]
fn one_layer_over_the_whole_target_is_plain_transfer() {
    let m = bar();
    let frames = bend_animation(&m, 5, 1.0);
    let all = vec![true; m.num_triangles()];
    let opts = SynthOptions {
        frames: 5,
        ..Default::default()
    };
    let s = Synthesizer::new(
        &m,
        vec![layer(&m, frames.clone(), all, BlendMode::Blend)],
        &[],
        &opts,
    )
    .unwrap();
    let info = s.layer_info(0);
    assert!(
        info.partitions.num_stiff() >= 2,
        "{}",
        info.partitions.num_stiff()
    );
    let plain = plain_transfer(&m, &frames);
    let diag = m.bbox_diagonal();
    for f in 0..5 {
        let x = s.frame(f).unwrap().positions;
        let d = max_dist(&x, &plain[f]);
        assert!(d < 1e-9 * diag, "frame {f}: {d}");
    }
}

/// Issue 55: one whole-target layer is plain transfer with the library's defaults (the
/// local-stretch frame, confidence and area weights, the fold guard) also where they matter:
/// a target shaped otherwise than the source (bent and flattened), so that matched triangles
/// face differently and the old configuration (world frame, uniform weights) is far off.
#[test]
fn one_layer_over_an_other_shaped_target_is_plain_transfer_with_its_defaults() {
    let m = bar();
    let target = m.with_positions(
        generate::bend(&m.positions, 1.0, 1.5, 0.9)
            .iter()
            .map(|p| [p[0], 1.4 * p[1], 0.7 * p[2]])
            .collect(),
    );
    let frames = bend_animation(&m, 4, 1.0);
    let c = Correspondence::identity(&m);
    let spec = LayerSpec {
        source_reference: m.clone(),
        frames: frames.clone(),
        correspondence: c.clone(),
        scribble: vec![true; m.num_triangles()],
        mode: BlendMode::Blend,
        timing: Timing::default(),
        region: BlendRegion::Partitions,
    };
    let opts = SynthOptions {
        frames: 4,
        ..Default::default()
    };
    let s = Synthesizer::new(&target, vec![spec], &[], &opts).unwrap();
    assert!(s.layer_info(0).weights.values.iter().all(|&w| w == 1.0));
    let set = ShapeSet::new(
        m.clone(),
        frames
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("f{i}"), f.clone()))
            .collect(),
    )
    .unwrap();
    let plain = transfer_animation(&m, &set, &target, &c, &TransferOptions::default()).unwrap();
    let old = TransferOptions {
        solver: SolverOptions::default(),
        frame: morphkit::transfer::GradientFrame::World,
        ..Default::default()
    };
    let old = transfer_animation(&m, &set, &target, &c, &old).unwrap();
    let diag = target.bbox_diagonal();
    let mut off = 0.0f64;
    for f in 0..4 {
        let x = s.frame(f).unwrap().positions;
        let d = max_dist(&x, &plain[f]);
        assert!(d < 1e-9 * diag, "frame {f}: {d}");
        off = off.max(max_dist(&old[f], &plain[f]));
    }
    assert!(off > 1e-3 * diag, "the defaults do not matter here: {off}");
}

#[test]
fn blending_an_animation_with_itself_returns_it() {
    let m = bar();
    let frames = bend_animation(&m, 4, 1.0);
    let far: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) > 2.2)
        .collect();
    let s = Synthesizer::new(
        &m,
        vec![layer(&m, frames.clone(), far, BlendMode::Blend)],
        &[],
        &SynthOptions::default(),
    )
    .unwrap();
    let w = &s.layer_info(0).weights.values;
    assert!(w.iter().any(|&v| v > 0.0 && v < 1.0));
    let op = GradientOperator::new(&m);
    let solver = TransferSolver::new(&m, &SolverOptions::default()).unwrap();
    let c = solver.constraint_vertices()[0] as usize;
    for f in &frames {
        let g = op.gradients(f).unwrap();
        for mode in [BlendMode::Blend] {
            let b = blend_gradients(&g, &g, w, mode);
            let x = solver.solve(&b).unwrap();
            // Equal up to the translation fixed by the constraint vertex.
            for (p, q) in x.iter().zip(f) {
                let d = norm(sub(sub(*p, x[c]), sub(*q, f[c])));
                assert!(d < 1e-9 * m.bbox_diagonal(), "{d}");
            }
        }
    }
}

#[test]
fn compounding_the_identity_returns_the_target_animation() {
    let m = bar();
    let frames = bend_animation(&m, 4, 1.0);
    let all = vec![true; m.num_triangles()];
    let far: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) > 2.2)
        .collect();
    // A second animation that bends the other way, to have partitions; but at rest: identity.
    let mut still = layer(&m, bend_animation(&m, 3, -1.0), far, BlendMode::Compound);
    still.frames = vec![m.positions.clone(); 3];
    // Partitions come from the frames: give the still layer the bend's flexibility by using the
    // bending frames for its partitions is not possible, so select with a geodesic band.
    still.region = BlendRegion::Geodesic { width: 0.5 };
    let opts = SynthOptions {
        frames: 4,
        follow_layer: Some(0),
        ..Default::default()
    };
    let s = Synthesizer::new(
        &m,
        vec![layer(&m, frames.clone(), all, BlendMode::Blend), still],
        &[],
        &opts,
    )
    .unwrap();
    let plain = plain_transfer(&m, &frames);
    for f in 0..4 {
        let d = max_dist(&s.frame(f).unwrap().positions, &plain[f]);
        assert!(d < 1e-9 * m.bbox_diagonal(), "frame {f}: {d}");
    }
}

#[test]
fn two_layers_drive_two_halves_and_blend_at_the_joint() {
    // A tube bent at two joints: the left end by animation A, the right by animation B.
    let m = generate::bar(6.0, 0.5, 2, 48);
    let near: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) < 1.0)
        .collect();
    let farr: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) > 5.0)
        .collect();
    // A bends at x = 4.8 (moves the far end), B bends at x = 1.0 the other way.
    let a: Vec<Vec<Point>> = (1..4)
        .map(|k| generate::bend(&m.positions, 4.6, 0.4, k as f64 * 0.3))
        .collect();
    let b: Vec<Vec<Point>> = (1..4)
        .map(|k| {
            let mirrored: Vec<Point> = m
                .positions
                .iter()
                .map(|p| [6.0 - p[0], p[1], p[2]])
                .collect();
            generate::bend(&mirrored, 4.6, 0.4, -(k as f64) * 0.3)
                .into_iter()
                .map(|p| [6.0 - p[0], p[1], p[2]])
                .collect()
        })
        .collect();
    let opts = SynthOptions {
        frames: 3,
        ..Default::default()
    };
    let s = Synthesizer::new(
        &m,
        vec![
            layer(&m, a.clone(), farr, BlendMode::Blend),
            layer(&m, b.clone(), near, BlendMode::Blend),
        ],
        &[],
        &opts,
    )
    .unwrap();
    for f in 0..3 {
        let fr = s.frame(f).unwrap();
        assert!(fr.positions.iter().flatten().all(|c| c.is_finite()));
        assert!(s.flipped_triangles(&fr).is_empty());
        // Both ends bent: the far end follows A's shape, the near end B's (edge vectors).
        let edge = |x: &[Point], lo: f64, hi: f64| {
            let i = (0..m.num_vertices())
                .find(|&v| (m.positions[v][0] - lo).abs() < 1e-9)
                .unwrap();
            let j = (0..m.num_vertices())
                .find(|&v| {
                    (m.positions[v][0] - hi).abs() < 1e-9
                        && m.positions[v][1] == m.positions[i][1]
                        && m.positions[v][2] == m.positions[i][2]
                })
                .unwrap();
            sub(x[j], x[i])
        };
        // The joints blend I → R over the weight band instead of the source's own curve, so
        // the ends match up to the least-squares compromise of that band: within 2 %.
        let d = norm(sub(edge(&fr.positions, 5.5, 6.0), edge(&a[f], 5.5, 6.0)));
        assert!(d < 0.02 * 0.5, "far end {d}");
        let d = norm(sub(edge(&fr.positions, 0.0, 0.5), edge(&b[f], 0.0, 0.5)));
        assert!(d < 0.02 * 0.5, "near end {d}");
        // And they are really bent: the far end turned by A's angle, not left straight.
        let straight = norm(sub(edge(&fr.positions, 5.5, 6.0), [0.5, 0.0, 0.0]));
        assert!(straight > 0.1, "far end not bent: {straight}");
    }
}

#[test]
fn timing_offset_speed_and_loop() {
    let m = bar();
    let frames = bend_animation(&m, 4, 1.0);
    let all = vec![true; m.num_triangles()];
    let mut l = layer(&m, frames.clone(), all, BlendMode::Blend);
    l.timing = Timing {
        offset: 2,
        speed: 0.5,
        looped: false,
    };
    let opts = SynthOptions {
        frames: 10,
        transfer: TransferOptions {
            translation: morphkit::transfer::TranslationMode::FixedVertex,
            ..Default::default()
        },
        ..Default::default()
    };
    let s = Synthesizer::new(&m, vec![l.clone()], &[], &opts).unwrap();
    let plain = plain_transfer(&m, &frames);
    let x = |f: usize| s.frame(f).unwrap().positions;
    let shift = |a: &[Point]| -> Vec<Point> {
        let c = a[0];
        a.iter().map(|p| sub(*p, c)).collect()
    };
    // Before the offset: the rest pose; frame 2 + 2k: source frame k; past the end: rest.
    assert!(max_dist(&x(0), &m.positions) < 1e-9);
    assert!(max_dist(&shift(&x(4)), &shift(&plain[1])) < 1e-9);
    assert!(max_dist(&shift(&x(8)), &shift(&plain[3])) < 1e-9);
    assert!(max_dist(&x(9), &m.positions) < 1e-9);
    // In between (frame 3 = source 0.5): between source frames 0 and 1.
    let mid = shift(&x(3));
    assert!(max_dist(&mid, &shift(&plain[0])) > 1e-3 && max_dist(&mid, &shift(&plain[1])) > 1e-3);
    // Looping wraps: output frame 2 + 8 = source 4 ≡ 0.
    l.timing.looped = true;
    let s = Synthesizer::new(&m, vec![l], &[], &opts).unwrap();
    let y = shift(&s.frame(9).unwrap().positions);
    let z = shift(&s.frame(7).unwrap().positions);
    assert!(max_dist(&shift(&s.frame(2).unwrap().positions), &shift(&plain[0])) < 1e-9);
    assert!(max_dist(&y, &z) > 1e-6);
    // A single-frame layer is a pose held from its offset on.
    let mut pose = layer(
        &m,
        vec![frames[2].clone()],
        vec![true; m.num_triangles()],
        BlendMode::Blend,
    );
    pose.timing.offset = 3;
    let s = Synthesizer::new(&m, vec![pose], &[], &opts).unwrap();
    assert!(max_dist(&s.frame(2).unwrap().positions, &m.positions) < 1e-9);
    for f in [3, 9] {
        let x = shift(&s.frame(f).unwrap().positions);
        assert!(max_dist(&x, &shift(&plain[2])) < 1e-9, "frame {f}");
    }
}

#[test]
fn a_pose_edit_rotates_the_reference_and_needs_no_new_factorization() {
    let m = bar();
    let frames = bend_animation(&m, 3, 1.0);
    let far: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) > 2.2)
        .collect();
    let near: Vec<bool> = far.iter().map(|&f| !f).collect();
    let mut s = Synthesizer::new(
        &m,
        vec![layer(&m, frames, near.clone(), BlendMode::Blend)],
        &[],
        &SynthOptions::default(),
    )
    .unwrap();
    let pose = PoseSpec {
        scribble: far,
        layer: 0,
        axis: [0.0, 1.0, 0.0],
        angle: 0.4,
    };
    let x = s.edit_pose(&pose).unwrap();
    let d = m.bbox_diagonal();
    let far_end = (0..m.num_vertices())
        .max_by(|&a, &b| m.positions[a][0].total_cmp(&m.positions[b][0]))
        .unwrap();
    assert!(norm(sub(x[far_end], m.positions[far_end])) > 0.1 * d);
    assert!(bbox_diagonal(&x) > 0.5 * d);
    // Synthesis after the edit: the edited far half stays turned in every frame.
    let f = s.frame(0).unwrap().positions;
    assert!(norm(sub(f[far_end], m.positions[far_end])) > 0.1 * d);
}

#[test]
fn bad_layers_are_errors_naming_the_layer() {
    let m = bar();
    let frames = bend_animation(&m, 3, 1.0);
    let all = vec![true; m.num_triangles()];
    let far: Vec<bool> = (0..m.num_triangles())
        .map(|t| centroid_x(&m, t) > 2.2)
        .collect();
    let e = Synthesizer::new(
        &m,
        vec![
            layer(&m, frames.clone(), all.clone(), BlendMode::Compound),
            layer(&m, frames.clone(), far.clone(), BlendMode::Blend),
        ],
        &[],
        &SynthOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            SynthError::ContradictingLayers {
                first: 0,
                second: 1,
                ..
            }
        ),
        "{e}"
    );
    // The same two layers the other way round are fine: compound over blend.
    Synthesizer::new(
        &m,
        vec![
            layer(&m, frames.clone(), all, BlendMode::Blend),
            layer(&m, frames.clone(), far, BlendMode::Compound),
        ],
        &[],
        &SynthOptions::default(),
    )
    .unwrap();
    let e = Synthesizer::new(
        &m,
        vec![layer(
            &m,
            frames.clone(),
            vec![false; m.num_triangles()],
            BlendMode::Blend,
        )],
        &[],
        &SynthOptions::default(),
    )
    .unwrap_err();
    assert!(
        e.to_string().starts_with("layer 0: scribble: it is empty"),
        "{e}"
    );
    // A scribble on the flexible joint alone selects nothing.
    let joint: Vec<bool> = (0..m.num_triangles())
        .map(|t| (1.95..2.1).contains(&centroid_x(&m, t)))
        .collect();
    let e = Synthesizer::new(
        &m,
        vec![layer(&m, frames, joint, BlendMode::Blend)],
        &[],
        &SynthOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("none of the"), "{e}");
}
