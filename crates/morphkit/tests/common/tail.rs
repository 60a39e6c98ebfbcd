//! A generated tail that curls far (issue 40, "thin parts that turn far"): a closed tube whose
//! first part (the attachment, standing in for the body) moves in no shape, and a target in
//! which the rest curls over the attachment (150–220° in `tests/springs_twist.rs`) and rolls
//! about its own axis.

use morphkit::mesh::{generate, Point, ShapeSet};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// The tube and its curl.
#[derive(Clone, Copy, Debug)]
pub struct Tail {
    /// Vertices per ring.
    pub around: usize,
    /// Segments along the tube (rings − 1).
    pub along: usize,
    pub length: f64,
    pub radius: f64,
    /// The tube for x ≤ `attach` stays in every shape (`FixedVertices::Auto` fixes it).
    pub attach: f64,
    /// The curl happens over `attach ≤ x ≤ attach + curl`; the rest follows straight.
    pub curl: f64,
    /// Total turn of the curl about z, degrees.
    pub bend_deg: f64,
    /// Roll about the tube's own axis, growing linearly along the curl, degrees.
    pub roll_deg: f64,
}

impl Tail {
    /// A tube of 12 × 49 vertices, 6 long, radius 0.25, still over its first 1.5, curled over
    /// the next 3 (the last 1.5 follows straight).
    pub fn new(bend_deg: f64, roll_deg: f64) -> Self {
        Self {
            around: 12,
            along: 48,
            length: 6.0,
            radius: 0.25,
            attach: 1.5,
            curl: 3.0,
            bend_deg,
            roll_deg,
        }
    }

    /// The straight tube and the tube curled by `bend_deg` about z, its curled part rolled
    /// about its own axis.
    pub fn shapes(&self) -> ShapeSet {
        let m = generate::tube(self.radius, self.length, self.around, self.along, true);
        let (attach, curl, roll_deg) = (self.attach, self.curl, self.roll_deg);
        let rolled: Vec<Point> = m
            .positions
            .iter()
            .map(|&p| {
                let f = ((p[0] - attach) / curl).clamp(0.0, 1.0);
                let (s, c) = (f * roll_deg.to_radians()).sin_cos();
                [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]]
            })
            .collect();
        let curled = generate::bend(&rolled, attach, curl, self.bend_deg.to_radians());
        super::two_shapes(&m, "rest", ("curled", curled))
    }

    /// Measures positions `p` of [`Tail::shapes`] against the rest shape.
    pub fn shape(&self, shapes: &ShapeSet, p: &[Point]) -> TailShape {
        let (around, along) = (self.around, self.along);
        let rest = shapes.positions(0);
        let (mut length, mut twist, mut max_seg) = (0.0, 0.0, 0.0f64);
        let mut prev: Option<(Vector3<f64>, UnitQuaternion<f64>)> = None;
        for j in 0..=along {
            let (c, now) = ring(p, around, j);
            let (_, then) = ring(rest, around, j);
            let q = ring_rotation(&then, &now);
            if let Some((c0, q0)) = prev {
                length += (c - c0).norm();
                // Rest rings face +x: the twist is the relative rotation's part about x.
                let rel = q0.inverse() * q;
                let mut a = 2.0 * rel.i.atan2(rel.w);
                a -= std::f64::consts::TAU * (a / std::f64::consts::TAU).round();
                twist += a;
                max_seg = max_seg.max(a.abs());
            }
            prev = Some((c, q));
        }
        TailShape {
            length_ratio: length / self.length,
            twist_deg: twist.to_degrees(),
            max_segment_twist_deg: max_seg.to_degrees(),
        }
    }
}

/// Shape of a tail: its centre line's length over the rest length, its twist (the roll of
/// each ring relative to the one before, about the ring's axis, summed along the tube), the
/// largest twist between two consecutive rings.
#[derive(Clone, Copy, Debug)]
pub struct TailShape {
    pub length_ratio: f64,
    pub twist_deg: f64,
    pub max_segment_twist_deg: f64,
}

fn ring(p: &[Point], around: usize, j: usize) -> (Vector3<f64>, Vec<Vector3<f64>>) {
    let pts: Vec<Vector3<f64>> = (0..around)
        .map(|i| Vector3::from(p[j * around + i]))
        .collect();
    let c = pts.iter().sum::<Vector3<f64>>() / around as f64;
    (c, pts.into_iter().map(|q| q - c).collect())
}

/// Each ring's rotation from its rest placement (Kabsch of the centred rings).
fn ring_rotation(rest: &[Vector3<f64>], now: &[Vector3<f64>]) -> UnitQuaternion<f64> {
    let h: Matrix3<f64> = rest.iter().zip(now).map(|(a, b)| b * a.transpose()).sum();
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt;
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r))
}
