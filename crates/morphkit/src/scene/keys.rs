//! Keyframe interpolation over frame numbers, shared by pulls and obstacle motion.
//!
//! Keys are given at (possibly fractional) frame numbers, strictly increasing. Before the first
//! key the first value holds, after the last key the last value holds, and between two keys
//! the value is interpolated with the parameter $t = (f - f_i) / (f_{i+1} - f_i) \in [0, 1]$:
//! linearly for positions and translations, by quaternion slerp for rotations.

use crate::mesh::Point;
use parry3d_f64::math::Rotation;

/// The two keys around `frame` and the interpolation parameter between them: `(i, j, t)` with
/// `j = i + 1` inside the key range, `i = j` (and `t = 0`) outside it or for one key.
/// `frames` must be non-empty and strictly increasing (checked on load).
pub(crate) fn bracket(frames: &[f64], frame: f64) -> (usize, usize, f64) {
    debug_assert!(!frames.is_empty());
    let last = frames.len() - 1;
    if frame <= frames[0] {
        return (0, 0, 0.0);
    }
    if frame >= frames[last] {
        return (last, last, 0.0);
    }
    // First key strictly after `frame`; it exists and is ≥ 1 by the checks above.
    let j = frames.partition_point(|&f| f <= frame);
    let i = j - 1;
    (i, j, (frame - frames[i]) / (frames[j] - frames[i]))
}

/// Linear interpolation of two points.
pub(crate) fn lerp(a: Point, b: Point, t: f64) -> Point {
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

/// Shortest-arc spherical interpolation of two unit quaternions.
pub(crate) fn slerp(a: Rotation, b: Rotation, t: f64) -> Rotation {
    a.slerp(b, t).normalize()
}

/// Index of the first frame that is not strictly after its predecessor, if any.
pub(crate) fn first_out_of_order(frames: &[f64]) -> Option<usize> {
    frames.windows(2).position(|w| w[1] <= w[0]).map(|i| i + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bracket_holds_outside_and_interpolates_inside() {
        let f = [0.0, 2.0, 6.0];
        assert_eq!(bracket(&f, -1.0), (0, 0, 0.0));
        assert_eq!(bracket(&f, 0.0), (0, 0, 0.0));
        assert_eq!(bracket(&f, 1.0), (0, 1, 0.5));
        assert_eq!(bracket(&f, 2.0), (1, 2, 0.0));
        assert_eq!(bracket(&f, 5.0), (1, 2, 0.75));
        assert_eq!(bracket(&f, 6.0), (2, 2, 0.0));
        assert_eq!(bracket(&f, 9.0), (2, 2, 0.0));
        assert_eq!(bracket(&[3.0], 1.0), (0, 0, 0.0));
    }

    #[test]
    fn order_check_finds_the_first_bad_key() {
        assert_eq!(first_out_of_order(&[0.0, 1.0, 2.0]), None);
        assert_eq!(first_out_of_order(&[0.0, 3.0, 2.0]), Some(2));
        assert_eq!(first_out_of_order(&[0.0, 0.0]), Some(1));
    }

    #[test]
    fn slerp_halves_a_rotation() {
        let a = Rotation::IDENTITY;
        let b = Rotation::from_axis_angle(parry3d_f64::math::Vector::Z, 1.0);
        let h = slerp(a, b, 0.5);
        let (axis, angle) = h.to_axis_angle();
        assert!((angle - 0.5).abs() < 1e-12 && (axis.z - 1.0).abs() < 1e-12);
    }
}
