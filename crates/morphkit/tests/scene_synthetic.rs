//! Scenes on generated meshes (issue 12; Ma et al. 2012, Sec. 4): no obstacle and a
//! never-touching obstacle change nothing, a pull with part of the boundary fixed (Fig. 5),
//! a keyframed obstacle denting a static pose, and scene-file errors that name the key.

mod common;

use morphkit::mesh::{bbox_diagonal, generate, Point, ShapeSet, TriMesh};
use morphkit::scene::{
    blend_scene, CollisionOptions, Obstacle, Primitive, Pull, PullKey, PullKind, RigidKey, Scene,
    SceneBlend, SceneError,
};
use morphkit::springs::{BlendOptions, FixedVertices, PhysicalBlend, Weights};
use parry3d_f64::math::Rotation;
use std::path::PathBuf;

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn sphere_at(name: &str, radius: f64, keys: Vec<(f64, Point)>) -> Obstacle {
    Obstacle::primitive(name, &Primitive::Sphere { radius }, 1.0)
        .unwrap()
        .with_keys(
            keys.into_iter()
                .map(|(frame, translation)| RigidKey {
                    frame,
                    translation,
                    rotation: Rotation::IDENTITY,
                })
                .collect(),
        )
        .unwrap()
}

fn alphas(n: usize) -> Vec<Weights> {
    (0..n)
        .map(|k| Weights::Alpha(k as f64 / (n - 1) as f64))
        .collect()
}

#[test]
fn no_obstacle_and_a_never_touching_obstacle_give_the_plain_blend() {
    let shapes = common::bent_bar();
    let opts = BlendOptions::default();
    let w = alphas(5);
    let mut plain = PhysicalBlend::new(&shapes, &opts).unwrap();
    let expected: Vec<_> = w
        .iter()
        .map(|w| plain.solve(w).unwrap().positions)
        .collect();

    let none = blend_scene(&shapes, &opts, vec![], vec![], &Default::default(), &w).unwrap();
    let far = sphere_at(
        "far",
        0.5,
        vec![(0.0, [0.0, 10.0, 0.0]), (4.0, [5.0, 10.0, 0.0])],
    );
    let never = blend_scene(&shapes, &opts, vec![far], vec![], &Default::default(), &w).unwrap();
    for k in 0..w.len() {
        common::assert_same_frame(
            &none[k].positions,
            &expected[k],
            &format!("frame {k}, no obstacle"),
        );
        common::assert_same_frame(
            &never[k].positions,
            &expected[k],
            &format!("frame {k}, far obstacle"),
        );
        assert_eq!(never[k].collision.contacts, 0);
        assert_eq!(never[k].collision.rounds, 0);
        assert_eq!(never[k].collision.max_penetration, 0.0);
    }
}

#[test]
fn an_obstacle_in_the_path_is_wrapped_without_penetration() {
    let shapes = common::bent_bar();
    let opts = BlendOptions::default();
    let w = alphas(6);
    let mut plain = PhysicalBlend::new(&shapes, &opts).unwrap();
    // A ball centred where the free end passes at α = 0.6 (frame 3).
    let free: Vec<Point> = plain.solve(&Weights::Alpha(0.6)).unwrap().positions;
    let tip = free[free.len() - 1];
    let ball = sphere_at("ball", 0.35, vec![(0.0, tip)]);
    let placed = ball.placed(0.0);
    let frames = blend_scene(
        &shapes,
        &opts,
        vec![ball.clone()],
        vec![],
        &Default::default(),
        &w,
    )
    .unwrap();
    let tol = 1e-4 * bbox_diagonal(shapes.positions(0));
    let mut touched = 0;
    for (k, f) in frames.iter().enumerate() {
        assert!(f.collision.resolved, "frame {k}: {:?}", f.collision);
        for (v, p) in f.positions.iter().enumerate() {
            let d = placed.penetration(*p).map_or(0.0, |(_, d)| d);
            assert!(d <= tol, "frame {k}: vertex {v} is {d} inside");
        }
        for c in &f.contacts {
            let d = placed.surface_distance(f.positions[c.vertex as usize]);
            assert!(
                d <= tol,
                "frame {k}: contact {} is {d} off the surface",
                c.vertex
            );
        }
        touched += usize::from(f.collision.contacts > 0);
    }
    assert!(touched >= 2, "the ball must be hit in several frames");
    assert_eq!(frames[0].collision.contacts, 0);
}

/// Fig. 5: a vertex pulled by hand (keyframed) drags its neighbourhood; the fixed part stays.
#[test]
fn a_keyframed_hard_pull_with_part_of_the_boundary_fixed() {
    let m = generate::grid(20, 10, 2.0, 1.0);
    let shapes = ShapeSet::new(
        m.clone(),
        vec![
            ("a".into(), m.positions.clone()),
            ("b".into(), m.positions.clone()),
        ],
    )
    .unwrap();
    let fixed: Vec<u32> = (0..m.num_vertices() as u32)
        .filter(|&v| m.positions[v as usize][0] < 0.15)
        .collect();
    let opts = BlendOptions {
        fixed: FixedVertices::Ids(fixed.clone()),
        ..Default::default()
    };
    let end = 20u32 + 5 * 21; // x = 2, y = 0.5
    let keys = vec![
        PullKey {
            frame: 0.0,
            position: [2.0, 0.5, 0.0],
        },
        PullKey {
            frame: 4.0,
            position: [2.0, 0.5, 0.8],
        },
    ];
    let hard = Pull::new(end, keys.clone(), PullKind::Hard).unwrap();
    let w = vec![Weights::Alpha(0.5); 5];
    let frames = blend_scene(
        &shapes,
        &opts,
        vec![],
        vec![hard.clone()],
        &Default::default(),
        &w,
    )
    .unwrap();
    for (k, f) in frames.iter().enumerate() {
        assert!(f.solver.converged, "frame {k}");
        let goal = hard.position_at(k as f64);
        assert!(dist(f.positions[end as usize], goal) < 1e-6, "frame {k}");
        for &v in &fixed {
            assert_eq!(
                f.positions[v as usize], m.positions[v as usize],
                "frame {k}"
            );
        }
        let row: Vec<f64> = (0..=20)
            .map(|i| dist(f.positions[5 * 21 + i], m.positions[5 * 21 + i]))
            .collect();
        for i in 1..row.len() {
            assert!(
                row[i] >= row[i - 1] - 1e-9,
                "frame {k}: not smooth: {row:?}"
            );
        }
    }
    // A soft pull moves the vertex only part of the way.
    let soft = Pull::new(end, keys, PullKind::Soft { stiffness: 0.05 }).unwrap();
    let f = blend_scene(&shapes, &opts, vec![], vec![soft], &Default::default(), &w).unwrap();
    let z = f[4].positions[end as usize][2];
    assert!(z > 0.05 && z < 0.8 - 1e-3, "soft pull reached z = {z}");
}

/// A keyframed ball slides along a pinned sheet held in a static pose; its dent follows it.
#[test]
fn a_moving_obstacle_dents_a_static_pose_frame_by_frame() {
    let m = generate::grid(30, 10, 3.0, 1.0);
    let shapes = ShapeSet::new(
        m.clone(),
        vec![
            ("a".into(), m.positions.clone()),
            ("b".into(), m.positions.clone()),
        ],
    )
    .unwrap();
    let fixed: Vec<u32> = (0..m.num_vertices() as u32)
        .filter(|&v| {
            let [x, y, _] = m.positions[v as usize];
            !(1e-9..=3.0 - 1e-9).contains(&x) || !(1e-9..=1.0 - 1e-9).contains(&y)
        })
        .collect();
    let opts = BlendOptions {
        fixed: FixedVertices::Ids(fixed),
        ..Default::default()
    };
    let ball = sphere_at(
        "ball",
        0.3,
        vec![(0.0, [0.8, 0.5, 0.25]), (4.0, [2.2, 0.5, 0.25])],
    );
    let mut scene = SceneBlend::new(
        &shapes,
        &opts,
        vec![ball.clone()],
        vec![],
        &Default::default(),
    )
    .unwrap();
    let mut last_x = f64::NEG_INFINITY;
    for k in 0..5 {
        let f = scene.solve(k as f64, &Weights::Alpha(0.5)).unwrap();
        assert!(
            f.collision.resolved && f.collision.contacts > 0,
            "frame {k}: {:?}",
            f.collision
        );
        let (low, p) = f
            .positions
            .iter()
            .enumerate()
            .min_by(|a, b| a.1[2].total_cmp(&b.1[2]))
            .unwrap();
        let (centre, _) = ball.pose_at(k as f64);
        assert!(p[2] < -0.01, "frame {k}: no dent (lowest z {})", p[2]);
        assert!(
            (p[0] - centre[0]).abs() < 0.15,
            "frame {k}: dent at x = {} (vertex {low}), ball at {}",
            p[0],
            centre[0]
        );
        assert!(
            p[0] > last_x,
            "frame {k}: the dent did not move with the ball"
        );
        last_x = p[0];
    }
}

/// A fresh directory with a 2-shape tube rig and an open (non-closed) mesh.
fn scene_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("morphkit-scene-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let tube = generate::tube(0.5, 4.0, 12, 8, false);
    morphkit::io::write_mesh(&dir.join("rest.obj"), &tube).unwrap();
    let bent = tube.with_positions(generate::bend(&tube.positions, 2.0, 2.0, 1.5));
    morphkit::io::write_mesh(&dir.join("bent.obj"), &bent).unwrap();
    let open: TriMesh = generate::grid(2, 2, 1.0, 1.0);
    morphkit::io::write_mesh(&dir.join("open.obj"), &open).unwrap();
    dir
}

const HEAD: &str = "base = \"rest.obj\"\ntargets = [\"bent.obj\"]\n[weights]\nframes = 3\n";

fn scene_error(tag: &str, body: &str) -> String {
    let dir = scene_dir(tag);
    let path = dir.join("scene.toml");
    std::fs::write(&path, format!("{HEAD}{body}")).unwrap();
    let e = Scene::load(&path)
        .and_then(|s| s.build().map(|_| ()))
        .unwrap_err();
    assert!(
        matches!(e, SceneError::Invalid { .. } | SceneError::Syntax { .. }),
        "{e:?}"
    );
    e.to_string()
}

#[test]
fn bad_scenes_name_the_key_and_the_line() {
    let e = scene_error("open", "[[obstacle]]\nmesh = \"open.obj\"\n");
    assert!(
        e.contains("scene.toml:6: obstacle[0].mesh") && e.contains("not closed"),
        "{e}"
    );

    let e = scene_error("prim", "[[obstacle]]\nshape = \"torus\"\nradius = 1\n");
    assert!(
        e.contains(":6: obstacle[0].shape") && e.contains("unknown primitive 'torus'"),
        "{e}"
    );

    let e = scene_error("range", "[[pull]]\nvertex = 5000\nposition = [0, 0, 0]\n");
    assert!(
        e.contains(":6: pull[0].vertex") && e.contains("out of range"),
        "{e}"
    );

    let body = "[[obstacle]]\nshape = \"sphere\"\nradius = 1\n[[obstacle.key]]\nframe = 2\n\
                translation = [0, 0, 5]\n[[obstacle.key]]\nframe = 1\ntranslation = [0, 0, 6]\n";
    let e = scene_error("order", body);
    assert!(
        e.contains(":12: obstacle[0].key[1].frame") && e.contains("out of order"),
        "{e}"
    );

    let body = "[[pull]]\nvertex = 100\n[[pull.key]]\nframe = 3\nposition = [0, 0, 0]\n\
                [[pull.key]]\nframe = 3\nposition = [0, 0, 1]\n";
    let e = scene_error("porder", body);
    assert!(
        e.contains(":11: pull[0].key[1].frame") && e.contains("out of order"),
        "{e}"
    );

    let e = scene_error("unknown", "[[obstacle]]\nshape = \"sphere\"\nradiuss = 1\n");
    assert!(e.contains(":7:") && e.contains("radiuss"), "{e}");

    let e = scene_error("interior", "[blend]\ninterior = \"voxels\"\n");
    assert!(
        e.contains(":6: blend.interior") && e.contains("unknown kind 'voxels'"),
        "{e}"
    );
    let e = scene_error("anchor", "[blend]\nanchor = \"1,2\"\n");
    assert!(e.contains(":6: blend.anchor") && e.contains("x,y,z"), "{e}");

    let e = scene_error("fixed", "[[pull]]\nvertex = 0\nposition = [0, 0, 0]\n");
    assert!(
        e.contains(":6: pull[0].vertex") && e.contains("fixed"),
        "{e}"
    );
}

#[test]
fn a_scene_file_runs_and_resolves_paths_next_to_it() {
    let dir = scene_dir("ok");
    let path = dir.join("scene.toml");
    let body = "[[obstacle]]\nname = \"ball\"\nshape = \"sphere\"\nradius = 0.3\ntranslation = [3.0, 0.0, 2.5]\n";
    std::fs::write(&path, format!("{HEAD}{body}")).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.weights.len(), 3);
    assert_eq!(scene.interior.mode, morphkit::springs::InteriorMode::None);
    let with = dir.join("with-interior.toml");
    std::fs::write(
        &with,
        format!("{HEAD}[blend]\ninterior = \"lattice,2\"\nanchor = \"auto\"\n"),
    )
    .unwrap();
    let v = Scene::load(&with).unwrap();
    assert_eq!(v.interior.mode, morphkit::springs::InteriorMode::Lattice);
    assert_eq!(v.interior.density, 2.0);
    assert_eq!(v.anchor.placement, morphkit::springs::AnchorPlacement::Auto);
    assert_eq!(scene.obstacles[0].name(), "ball");
    let mut s = scene.build().unwrap();
    let f = s.solve(2.0, &scene.weights[2]).unwrap();
    assert!(f.solver.converged);
    assert!(CollisionOptions::default().max_rounds > 0);
}
