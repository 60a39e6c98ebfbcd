//! Fig. 2 analogue of Ma et al. 2012 (issue 12) on real data: the cragl bending cylinder goes
//! from rest to `cylinder-bend-4` and wraps around a solid bar placed in the path of its
//! bending half. Also runs the shipped example scene.

mod common;

use morphkit::io;
use morphkit::mesh::{bbox_diagonal, Point};
use morphkit::scene::{CollisionOptions, Obstacle, Primitive, RigidKey, Scene, SceneBlend};
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};
use parry3d_f64::math::Rotation;
use std::path::Path;

/// The bar of the example: a cylinder of radius 0.2 along y through (1.35, ·, 0.95).
const AXIS_X: f64 = 1.35;
const AXIS_Z: f64 = 0.95;
const RADIUS: f64 = 0.2;

/// Signed distance to the bar's side (negative inside), computed here without parry.
fn bar_distance(p: Point) -> f64 {
    ((p[0] - AXIS_X).powi(2) + (p[2] - AXIS_Z).powi(2)).sqrt() - RADIUS
}

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn fig2_the_bending_cylinder_wraps_around_a_solid_bar() {
    let (Some(rest), Some(bend)) = (
        common::data_file("cragl-bending-cylinder/cylinder-rest.obj"),
        common::data_file("cragl-bending-cylinder/cylinder-bend-4.obj"),
    ) else {
        return common::skip("fig2_the_bending_cylinder_wraps_around_a_solid_bar");
    };
    let shapes = io::read_shape_set(&[rest, bend]).unwrap();
    let opts = BlendOptions::default();
    let bar = Obstacle::primitive(
        "bar",
        &Primitive::Cylinder {
            radius: RADIUS,
            height: 2.0,
        },
        1.0,
    )
    .unwrap()
    .with_keys(vec![RigidKey {
        frame: 0.0,
        translation: [AXIS_X, 0.0, AXIS_Z],
        rotation: Rotation::IDENTITY,
    }])
    .unwrap();
    let mut scene = SceneBlend::new(
        &shapes,
        &opts,
        vec![bar],
        vec![],
        &CollisionOptions::default(),
    )
    .unwrap();
    let mut plain = PhysicalBlend::new(&shapes, &opts).unwrap();
    let diag = bbox_diagonal(shapes.positions(0));
    let tol = 1e-4 * diag;
    let rest = shapes.positions(0);
    let n = 12;
    let mut touched = 0;
    for k in 0..n {
        let w = Weights::Alpha(k as f64 / (n - 1) as f64);
        let f = scene.solve(k as f64, &w).unwrap();
        let free = plain.solve(&w).unwrap().positions;
        assert!(f.solver.converged, "frame {k}: {:?}", f.solver);
        assert!(f.collision.resolved, "frame {k}: {:?}", f.collision);
        // No surface vertex inside the bar by more than the tolerance.
        for (v, p) in f.positions.iter().enumerate() {
            let inside = -bar_distance(*p);
            assert!(
                inside <= tol,
                "frame {k}: vertex {v} is {inside} inside the bar"
            );
        }
        // Contact vertices lie on the bar's surface.
        for c in &f.contacts {
            let d = bar_distance(f.positions[c.vertex as usize]).abs();
            assert!(
                d <= tol,
                "frame {k}: contact vertex {} is {d} off the surface",
                c.vertex
            );
        }
        // Vertices far from the contact (the unbent half and the start of the bend) match the
        // collision-free blend closely.
        for (v, p) in f.positions.iter().enumerate() {
            if rest[v][0] <= 0.4 {
                let d = dist(*p, free[v]);
                assert!(
                    d <= 0.01 * diag,
                    "frame {k}: far vertex {v} moved {d} from the free blend"
                );
            }
        }
        if f.collision.contacts > 0 {
            touched += 1;
            // The contact really changed the shape: the free blend penetrates the bar.
            let deepest = free.iter().map(|p| -bar_distance(*p)).fold(0.0, f64::max);
            assert!(
                deepest > tol,
                "frame {k}: contacts but the free blend does not penetrate"
            );
        }
    }
    assert!(
        touched >= 3,
        "the bar must be hit in several frames (hit in {touched})"
    );
}

/// The README's example (its meshes are generated and committed beside it, issue 55: it needs
/// no data).
#[test]
fn the_example_scene_loads_its_meshes_and_hits_the_bar() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/bend-around-cylinder/scene.toml");
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.shapes.num_vertices(), 420);
    assert_eq!(scene.obstacles.len(), 1);
    let mut s = scene.build().unwrap();
    let last = scene.weights.len() - 1;
    let f = s.solve(last as f64, &scene.weights[last]).unwrap();
    assert!(
        f.collision.resolved && f.collision.contacts > 0,
        "{:?}",
        f.collision
    );
}
