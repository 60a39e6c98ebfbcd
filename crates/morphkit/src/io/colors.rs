//! Colours for visualising per-vertex or per-face values (errors, rotation angles, weights).
//!
//! [`scalar_colors`] picks the map from the data:
//! - values of both signs get a **diverging** blue → white → red map, symmetric about 0
//!   (−max|v| is blue `(59, 76, 192)`, 0 white, +max|v| red `(180, 4, 38)`), so that zero always
//!   reads as white;
//! - values of one sign get a **sequential** viridis-like map from their minimum (dark purple)
//!   to their maximum (yellow), interpolated linearly between nine samples of viridis;
//! - NaN (and ±∞) get grey `(128, 128, 128)` and are ignored when finding the range.

/// Colours for a PLY file: one per vertex or one per face.
#[derive(Clone, Debug, PartialEq)]
pub enum Colors {
    /// One RGB colour per vertex.
    PerVertex(Vec<[u8; 3]>),
    /// One RGB colour per triangle (or per polygon, for a mesh with polygons).
    PerFace(Vec<[u8; 3]>),
}

/// Grey for values that are not finite.
pub const NAN_GREY: [u8; 3] = [128, 128, 128];

const VIRIDIS: [[f64; 3]; 9] = [
    [68.0, 1.0, 84.0],
    [71.0, 44.0, 122.0],
    [59.0, 81.0, 139.0],
    [44.0, 113.0, 142.0],
    [33.0, 144.0, 141.0],
    [39.0, 173.0, 129.0],
    [92.0, 200.0, 99.0],
    [170.0, 220.0, 50.0],
    [253.0, 231.0, 37.0],
];
const BLUE: [f64; 3] = [59.0, 76.0, 192.0];
const WHITE: [f64; 3] = [255.0, 255.0, 255.0];
const RED: [f64; 3] = [180.0, 4.0, 38.0];

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [u8; 3] {
    let c = |k: usize| (a[k] + (b[k] - a[k]) * t).round().clamp(0.0, 255.0) as u8;
    [c(0), c(1), c(2)]
}

/// Viridis-like colour of `t ∈ [0, 1]` (clamped); NaN gives [`NAN_GREY`].
pub fn viridis(t: f64) -> [u8; 3] {
    if !t.is_finite() {
        return NAN_GREY;
    }
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    lerp(VIRIDIS[i], VIRIDIS[i + 1], x - i as f64)
}

/// Diverging colour of `t ∈ [−1, 1]` (clamped): −1 blue, 0 white, +1 red; NaN gives grey.
pub fn diverging(t: f64) -> [u8; 3] {
    if !t.is_finite() {
        return NAN_GREY;
    }
    let t = t.clamp(-1.0, 1.0);
    if t < 0.0 {
        lerp(WHITE, BLUE, -t)
    } else {
        lerp(WHITE, RED, t)
    }
}

/// Colours for `values`, diverging when they have both signs and sequential otherwise (see the
/// module documentation). A constant input maps to the middle of the sequential map.
pub fn scalar_colors(values: &[f64]) -> Vec<[u8; 3]> {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if lo > hi {
        return vec![NAN_GREY; values.len()];
    }
    if lo < 0.0 && hi > 0.0 {
        let m = lo.abs().max(hi);
        values.iter().map(|&v| diverging(v / m)).collect()
    } else if hi > lo {
        values
            .iter()
            .map(|&v| viridis((v - lo) / (hi - lo)))
            .collect()
    } else {
        values
            .iter()
            .map(|&v| {
                if v.is_finite() {
                    viridis(0.5)
                } else {
                    NAN_GREY
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diverging_for_signed_values() {
        let c = scalar_colors(&[-2.0, 0.0, 1.0, f64::NAN]);
        assert_eq!(c[0], [59, 76, 192]);
        assert_eq!(c[1], [255, 255, 255]);
        assert_eq!(c[2], lerp(WHITE, RED, 0.5));
        assert_eq!(c[3], NAN_GREY);
    }

    #[test]
    fn sequential_for_one_sign() {
        let c = scalar_colors(&[1.0, 3.0, 2.0]);
        assert_eq!(c[0], [68, 1, 84]);
        assert_eq!(c[1], [253, 231, 37]);
        assert_eq!(c[2], [33, 144, 141]);
        assert_eq!(scalar_colors(&[f64::NAN]), vec![NAN_GREY]);
        assert_eq!(scalar_colors(&[5.0, 5.0]), vec![viridis(0.5); 2]);
    }
}
