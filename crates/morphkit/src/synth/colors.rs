//! Face colours for showing what synthesis sees and chose (the paper's Fig. 3 and Fig. 8).
//!
//! - [`flexibility_colors`]: blue (stiff, 0) → white (γ) → red (flexible, ≥ 2γ), through
//!   [`crate::io::diverging`], so the threshold that makes partitions reads as white.
//! - [`selection_colors`]: each triangle takes the colour of the layer with the largest weight
//!   there, faded towards white by that weight: full colour where a layer drives alone (its
//!   selected stiff partitions), white where no layer reaches (the rest pose).

use crate::io::diverging;

/// Distinct layer colours (repeating after eight layers).
pub const LAYER_PALETTE: [[u8; 3]; 8] = [
    [214, 39, 40],
    [31, 119, 180],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];

/// Blue → white (at `gamma`) → red per value.
pub fn flexibility_colors(values: &[f64], gamma: f64) -> Vec<[u8; 3]> {
    values
        .iter()
        .map(|&f| diverging((f / (2.0 * gamma)).clamp(0.0, 1.0) * 2.0 - 1.0))
        .collect()
}

/// The dominant layer's colour faded by its weight; `weights[k][t]` is layer `k`'s weight of
/// triangle `t`.
pub fn selection_colors(weights: &[&[f64]], num_triangles: usize) -> Vec<[u8; 3]> {
    (0..num_triangles)
        .map(|t| {
            let best = (0..weights.len()).fold(None, |b: Option<(usize, f64)>, k| {
                let w = weights[k][t];
                match b {
                    Some((_, bw)) if bw >= w => b,
                    _ => Some((k, w)),
                }
            });
            match best {
                Some((k, w)) if w > 0.0 => {
                    let c = LAYER_PALETTE[k % LAYER_PALETTE.len()];
                    c.map(|x| (255.0 + (x as f64 - 255.0) * w).round() as u8)
                }
                _ => [255, 255, 255],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_mark_stiff_threshold_and_layers() {
        let c = flexibility_colors(&[0.0, 0.1, 0.5], 0.1);
        assert_eq!(c[0], diverging(-1.0));
        assert_eq!(c[1], [255, 255, 255]);
        assert_eq!(c[2], diverging(1.0));
        let a = [1.0, 0.0, 0.5, 0.0];
        let b = [0.0, 1.0, 0.2, 0.0];
        let s = selection_colors(&[&a, &b], 4);
        assert_eq!(s[0], LAYER_PALETTE[0]);
        assert_eq!(s[1], LAYER_PALETTE[1]);
        assert_eq!(s[3], [255, 255, 255]);
        assert!(s[2][1] > LAYER_PALETTE[0][1]);
    }
}
