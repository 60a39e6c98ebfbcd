//! Animation transfer on real meshes from `MORPHKIT_DATA`: low-poly cat run → dog (41 markers,
//! 36 frames) and horse poses → camel (107 markers, 10 poses).
//!
//! Checked for every transferred frame: no NaN; fewer than 1 % of the target's triangles
//! flipped against the orientation their transferred gradient gives them
//! ([`flipped_triangles`]); the mean gradient error small against the motion itself (see
//! [`check_frames`]); and the correspondence covers every target triangle.

mod common;

use morphkit::io::{read_mesh, read_shape_set};
use morphkit::mesh::{Point, TriMesh};
use morphkit::transfer::{
    correspond, deformation_gradients, flipped_triangles, AnimationTransfer, Correspondence,
    CorrespondenceOptions, Markers, TransferOptions,
};
use nalgebra::Matrix3;
use std::path::PathBuf;

/// Mean Frobenius norm of the difference of two gradient lists.
fn mean_diff(a: &[Matrix3<f64>], b: &[Matrix3<f64>]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).sum::<f64>() / a.len() as f64
}

/// Per-frame checks. The gradient error is measured on the tangential part, the only part the
/// solve can match (a triangle's normal column follows from its vertices):
/// $e = \text{mean}_j \|(D_j - M_j) P_j\|_F$, $D_j$ the result's gradient relative to the
/// target reference, $M_j$ the wanted (transferred) gradient, $P_j$ the projector onto the
/// reference triangle's plane. It is compared with the size of the motion,
/// $m = \text{mean}_j \|(M_j - I) P_j\|_F$, the error of not moving at all. Neighbouring wanted
/// gradients disagree (they come from different source triangles and a different
/// tessellation), so a least-squares fit cannot match them exactly; a fit that explains the
/// motion leaves $e$ well below $m$: we require $e < 0.5\,m$ on every frame that moves
/// ($m > 0.05$), and $e < 0.25$ everywhere (the tangential identity has norm $\sqrt 2$, so this
/// is under 18 % of a gradient's size). Measured (debug and release agree): cat → dog
/// $e/m \le 0.27$, $e \le 0.18$; horse → camel $e/m \le 0.11$, $e \le 0.11$. Returns the worst
/// `(e, m)`.
fn check_frames(
    name: &str,
    target: &TriMesh,
    tr: &AnimationTransfer,
    frames: &[Vec<Point>],
    max_ratio: f64,
) -> (f64, f64) {
    let proj: Vec<Matrix3<f64>> = (0..target.num_triangles())
        .map(|t| {
            let n = nalgebra::Vector3::from(target.triangle_normal(t)).normalize();
            Matrix3::identity() - n * n.transpose()
        })
        .collect();
    let (mut worst_e, mut worst_m) = (0.0f64, 0.0f64);
    let mut moving = 0usize;
    for (f, frame) in frames.iter().enumerate() {
        let g = tr.source_gradients(frame).unwrap();
        let want = tr.target_gradients(&g);
        let x = tr.transfer_frame(frame).unwrap();
        assert!(
            x.iter().all(|p| p.iter().all(|c| c.is_finite())),
            "{name} frame {f}: NaN"
        );
        let flips = flipped_triangles(target, &x, &want);
        assert!(
            (flips.len() as f64) < 0.01 * target.num_triangles() as f64,
            "{name} frame {f}: {} of {} triangles flipped",
            flips.len(),
            target.num_triangles()
        );
        let got = deformation_gradients(target, &x).unwrap();
        let pw: Vec<_> = want.iter().zip(&proj).map(|(m, p)| m * p).collect();
        let pg: Vec<_> = got.iter().zip(&proj).map(|(m, p)| m * p).collect();
        let e = mean_diff(&pg, &pw);
        let m = mean_diff(&proj, &pw);
        eprintln!(
            "{name} frame {f}: gradient error {e:.4}, motion {m:.4}, flips {}",
            flips.len()
        );
        if m > 0.05 {
            moving += 1;
            assert!(
                e < max_ratio * m,
                "{name} frame {f}: gradient error {e:.4} is not below {max_ratio} × motion {m:.4}"
            );
        }
        assert!(e < 0.25, "{name} frame {f}: gradient error {e:.4} ≥ 0.25");
        worst_e = worst_e.max(e);
        worst_m = worst_m.max(m);
    }
    assert!(
        moving > 0,
        "{name}: no frame moves, the test would be vacuous"
    );
    (worst_e, worst_m)
}

fn covers_every_target_triangle(c: &Correspondence, target: &TriMesh) {
    assert_eq!(c.target_triangles, target.num_triangles());
    for t in 0..target.num_triangles() {
        assert!(
            !c.matches_of(t).is_empty(),
            "target triangle {t} has no match"
        );
    }
}

#[test]
fn cat_run_to_dog() {
    let (Some(cat), Some(dog), Some(mk)) = (
        common::data_file("lowpoly-cat-dog/cat-reference.obj"),
        common::data_file("lowpoly-cat-dog/dog-reference.obj"),
        common::data_file("lowpoly-cat-dog/markers-cat-dog.json"),
    ) else {
        return common::skip("cat_run_to_dog");
    };
    let cat = read_mesh(&cat).unwrap();
    let dog = read_mesh(&dog).unwrap();
    let markers = Markers::read(&mk).unwrap();
    assert_eq!(markers.len(), 41);
    let r = correspond(&cat, &dog, &markers, &CorrespondenceOptions::default()).unwrap();
    let c = r.correspondence;
    covers_every_target_triangle(&c, &dog);
    eprintln!(
        "cat→dog: {:.2} matches per triangle, {} normal violations, max marker residual {:.2e}",
        c.mean_matches(),
        c.normal_violations.len(),
        c.marker_residuals
            .iter()
            .map(|m| m.relative)
            .fold(0.0, f64::max)
    );
    // The run frames are at 0.1× the reference scale: the first run frame is the source
    // reference for the gradients (the correspondence only depends on connectivity).
    let dir = common::data_dir().unwrap().join("lowpoly-cat-dog/cat-run");
    let paths: Vec<PathBuf> = (1..=36)
        .map(|i| dir.join(format!("cat-run-{i:02}.obj.gz")))
        .collect();
    let run = read_shape_set(&paths).unwrap();
    assert_eq!(run.len(), 36);
    let source_ref = run.mesh(0);
    let tr = AnimationTransfer::new(&source_ref, &dog, &c, &TransferOptions::default()).unwrap();
    let (e, m) = check_frames("cat→dog", &dog, &tr, run.all_positions(), 0.5);
    eprintln!("cat→dog: worst gradient error {e:.4}, worst motion {m:.4}");
}

#[test]
fn horse_poses_to_camel() {
    let (Some(horse), Some(camel), Some(mk)) = (
        common::data_file("sumner-horse-camel/horse-reference.obj.gz"),
        common::data_file("sumner-horse-camel/camel-reference.obj.gz"),
        common::data_file("sumner-horse-camel/markers-horse-camel.json"),
    ) else {
        return common::skip("horse_poses_to_camel");
    };
    let horse = read_mesh(&horse).unwrap();
    let camel = read_mesh(&camel).unwrap();
    let markers = Markers::read(&mk).unwrap();
    assert_eq!(markers.len(), 107);
    let r = correspond(&horse, &camel, &markers, &CorrespondenceOptions::default()).unwrap();
    let c = r.correspondence;
    covers_every_target_triangle(&c, &camel);
    eprintln!(
        "horse→camel: {:.2} matches per triangle, {} normal violations, max marker residual {:.2e}",
        c.mean_matches(),
        c.normal_violations.len(),
        c.marker_residuals
            .iter()
            .map(|m| m.relative)
            .fold(0.0, f64::max)
    );
    let dir = common::data_dir().unwrap().join("sumner-horse-camel");
    let paths: Vec<PathBuf> = (1..=10)
        .map(|i| dir.join(format!("horse-{i:02}.obj.gz")))
        .collect();
    let poses = read_shape_set(&paths).unwrap();
    let tr = AnimationTransfer::new(&horse, &camel, &c, &TransferOptions::default()).unwrap();
    let (e, m) = check_frames("horse→camel", &camel, &tr, poses.all_positions(), 0.5);
    eprintln!("horse→camel: worst gradient error {e:.4}, worst motion {m:.4}");
}
