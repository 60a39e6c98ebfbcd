//! Scenes with internal springs and the anchor (issue 12 with the options of issue 11): the
//! volumetric blend under obstacles and pulls, on a generated closed bar bent by 90°.

mod common;

use morphkit::mesh::{bbox_diagonal, Point};
use morphkit::scene::{
    CollisionOptions, Obstacle, Primitive, Pull, PullKey, PullKind, RigidKey, SceneBlend,
};
use morphkit::springs::{
    AnchorOptions, AnchorPlacement, BlendOptions, InteriorMode, InteriorOptions, VolumetricBlend,
    Weights,
};
use parry3d_f64::math::Rotation;

fn ball(at: Point, radius: f64) -> Obstacle {
    Obstacle::primitive("ball", &Primitive::Sphere { radius }, 1.0)
        .unwrap()
        .with_keys(vec![RigidKey {
            frame: 0.0,
            translation: at,
            rotation: Rotation::IDENTITY,
        }])
        .unwrap()
}

fn lattice() -> InteriorOptions {
    InteriorOptions {
        mode: InteriorMode::Lattice,
        ..Default::default()
    }
}

fn anchored() -> AnchorOptions {
    AnchorOptions {
        placement: AnchorPlacement::Auto,
        ..Default::default()
    }
}

/// Without obstacles and pulls a scene is the volumetric blend, surface and interior, bit for
/// bit; with a ball in the path nothing penetrates, contacts are surface vertices on the ball,
/// and the interior follows (it is not left where the surface was pushed away from).
#[test]
fn scenes_carry_the_interior_and_the_anchor() {
    let shapes = common::bent_bar();
    let n = shapes.num_vertices();
    let opts = BlendOptions::default();
    let tol = 1e-4 * bbox_diagonal(shapes.positions(0));
    for (what, interior, anchor) in [
        ("lattice", lattice(), AnchorOptions::default()),
        ("lattice + anchor", lattice(), anchored()),
    ] {
        let mut volume = VolumetricBlend::new(&shapes, &opts, &interior, &anchor).unwrap();
        let w = Weights::Alpha(0.6);
        let expected = volume.solve(&w).unwrap();
        assert!(!expected.extra.is_empty(), "{what}: an interior is built");
        let mut scene = SceneBlend::with_interior(
            &shapes,
            &opts,
            &interior,
            &anchor,
            vec![],
            vec![],
            &CollisionOptions::default(),
        )
        .unwrap();
        let f = scene.solve(0.0, &w).unwrap();
        common::assert_same_frame(&f.positions, &expected.positions, what);
        common::assert_same_frame(&f.extra, &expected.extra, what);
        assert!(scene.interior_report().is_some());

        // A ball centred on the free end's last vertex at this α.
        let tip = expected.positions[n - 1];
        let obstacle = ball(tip, 0.3);
        let placed = obstacle.placed(0.0);
        let mut scene = SceneBlend::with_interior(
            &shapes,
            &opts,
            &interior,
            &anchor,
            vec![obstacle.clone()],
            vec![],
            &CollisionOptions::default(),
        )
        .unwrap();
        let f = scene.solve(0.0, &w).unwrap();
        assert!(f.solver.converged, "{what}: {:?}", f.solver);
        assert!(f.collision.resolved, "{what}: {:?}", f.collision);
        assert!(
            f.collision.contacts > 0,
            "{what}: the ball is hit: {:?}",
            f.collision
        );
        assert_eq!(f.positions.len(), n);
        assert_eq!(f.extra.len(), expected.extra.len());
        for (v, p) in f.positions.iter().enumerate() {
            let d = placed.penetration(*p).map_or(0.0, |(_, d)| d);
            assert!(d <= tol, "{what}: vertex {v} is {d} inside");
        }
        for c in &f.contacts {
            assert!(
                (c.vertex as usize) < n,
                "{what}: interior vertex {} held",
                c.vertex
            );
            let d = placed.surface_distance(f.positions[c.vertex as usize]);
            assert!(d <= tol, "{what}: contact {} is {d} off the ball", c.vertex);
        }
        // The interior is pushed along: no interior point is left outside the bent surface's
        // bounding box grown by a tenth of the diagonal.
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for p in &f.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let grow = 0.1 * bbox_diagonal(&f.positions);
        for p in &f.extra {
            assert!(
                (0..3).all(|a| p[a] >= lo[a] - grow && p[a] <= hi[a] + grow),
                "{what}: interior point {p:?} outside the surface's box"
            );
        }
    }
}

/// With an anchor the blend solves in the anchor's frame: a hard pull given in world
/// coordinates still lands exactly on its world position.
#[test]
fn a_hard_pull_on_an_anchored_scene_is_met_in_world_coordinates() {
    let shapes = common::bent_bar();
    let n = shapes.num_vertices();
    let opts = BlendOptions::default();
    let w = Weights::Alpha(0.5);
    let mut volume = VolumetricBlend::new(&shapes, &opts, &lattice(), &anchored()).unwrap();
    let free = volume.solve(&w).unwrap();
    let v = (n - 1) as u32;
    let goal = [
        free.positions[n - 1][0],
        free.positions[n - 1][1] + 0.3,
        free.positions[n - 1][2],
    ];
    let pull = Pull::new(
        v,
        vec![PullKey {
            frame: 0.0,
            position: goal,
        }],
        PullKind::Hard,
    )
    .unwrap();
    let mut scene = SceneBlend::with_interior(
        &shapes,
        &opts,
        &lattice(),
        &anchored(),
        vec![],
        vec![pull],
        &CollisionOptions::default(),
    )
    .unwrap();
    let f = scene.solve(0.0, &w).unwrap();
    assert!(f.solver.converged, "{:?}", f.solver);
    let p = f.positions[n - 1];
    let err =
        ((p[0] - goal[0]).powi(2) + (p[1] - goal[1]).powi(2) + (p[2] - goal[2]).powi(2)).sqrt();
    assert!(
        err < 1e-9 * bbox_diagonal(shapes.positions(0)),
        "pulled vertex {err} from its goal"
    );
    // The pull moved the shape: the end is no longer where the free blend put it.
    assert!((p[1] - free.positions[n - 1][1]).abs() > 0.25);
}

/// Scene frames solved on two threads, and in reverse order, are those solved one by one.
#[test]
fn scene_frames_on_threads_equal_frames_one_by_one() {
    let shapes = common::bent_bar();
    let opts = BlendOptions::default();
    let tip = VolumetricBlend::new(&shapes, &opts, &lattice(), &AnchorOptions::default())
        .unwrap()
        .solve(&Weights::Alpha(0.6))
        .unwrap()
        .positions[shapes.num_vertices() - 1];
    // A ball moving across the free end's path over the frames.
    let moving = Obstacle::primitive("ball", &Primitive::Sphere { radius: 0.3 }, 1.0)
        .unwrap()
        .with_keys(vec![
            RigidKey {
                frame: 0.0,
                translation: [tip[0], tip[1] - 0.6, tip[2]],
                rotation: Rotation::IDENTITY,
            },
            RigidKey {
                frame: 5.0,
                translation: [tip[0], tip[1] + 0.6, tip[2]],
                rotation: Rotation::IDENTITY,
            },
        ])
        .unwrap();
    let frames: Vec<(f64, Weights)> = (0..6)
        .map(|k| (k as f64, Weights::Alpha(0.4 + 0.05 * k as f64)))
        .collect();
    for interior in [InteriorOptions::default(), lattice()] {
        let build = || {
            SceneBlend::with_interior(
                &shapes,
                &opts,
                &interior,
                &AnchorOptions::default(),
                vec![moving.clone()],
                vec![],
                &CollisionOptions::default(),
            )
            .unwrap()
        };
        let mut one = build();
        let expected: Vec<_> = frames
            .iter()
            .map(|(f, w)| one.solve(*f, w).unwrap())
            .collect();
        assert!(expected.iter().any(|f| f.collision.contacts > 0));
        let mut many = build();
        let threaded = many.solve_many(&frames, 2);
        let reversed: Vec<(f64, Weights)> = frames.iter().rev().cloned().collect();
        let backwards = many.solve_many(&reversed, 2);
        for k in 0..frames.len() {
            let t = threaded[k].as_ref().unwrap();
            let b = backwards[frames.len() - 1 - k].as_ref().unwrap();
            for got in [t, b] {
                common::assert_same_frame(&got.positions, &expected[k].positions, "threads");
                common::assert_same_frame(&got.extra, &expected[k].extra, "threads");
                assert_eq!(got.contacts, expected[k].contacts);
            }
        }
    }
}
