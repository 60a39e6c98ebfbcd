//! A facecap-like rig on a 24 × 30 tube (720 vertices): 16 targets — 4 bends of the whole
//! tube (in four directions, which turn its upper part: the linear blend shrinks there) and 12
//! local bulges — and a 300-key clip at 30 fps in which each bend rises and falls in its own
//! window while the bulges vary smoothly throughout, several at once. Used by the compact-clip
//! tests (`cli_compact_clip`) and by `examples/continuity_sweep.rs` (`bulges`): where a bend
//! meets three bulges the tube kinks, and the canonical solve passes between equilibria.

/// The tube's grid: `nu` around, `nv` along, for `gltf_asset::tube(NU, NV, 1.0, bend)`.
pub const NU: usize = 24;
pub const NV: usize = 30;
/// The bend of the four bend targets (radians over the tube's height).
pub const BEND: f64 = 1.4;

/// The 16 targets and their names, from the straight tube `p` and the tube bent by [`BEND`]
/// about `y` (`bent`), both from `gltf_asset::tube(NU, NV, 1.0, ·)`.
pub fn targets(p: &[[f64; 3]], bent: &[[f64; 3]]) -> (Vec<Vec<[f64; 3]>>, Vec<String>) {
    let mut targets = Vec::new();
    let mut names = Vec::new();
    for dir in 0..4 {
        let a = std::f64::consts::FRAC_PI_2 * dir as f64;
        let (c, sn) = (a.cos(), a.sin());
        // The bend in the xz plane, turned about z by a.
        targets.push(
            bent.iter()
                .zip(p)
                .map(|(q, r)| {
                    let (dx, dy) = (q[0] - r[0], q[1] - r[1]);
                    [r[0] + c * dx - sn * dy, r[1] + sn * dx + c * dy, q[2]]
                })
                .collect(),
        );
        names.push(format!("bend{dir}"));
    }
    for b in 0..12 {
        // A bump of radius 0.35 around (angle, height), pushed out along the normal by 0.3.
        let (ang, h) = (
            std::f64::consts::TAU * b as f64 / 12.0,
            0.5 + 0.25 * b as f64,
        );
        targets.push(
            p.iter()
                .map(|q| {
                    let da = (q[1].atan2(q[0]) - ang + std::f64::consts::PI)
                        .rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                    let d2 = (da * da + (q[2] - h).powi(2)) / (0.35 * 0.35);
                    let s = 0.3 * (-d2).exp();
                    [q[0] * (1.0 + s), q[1] * (1.0 + s), q[2]]
                })
                .collect(),
        );
        names.push(format!("bulge{b}"));
    }
    (targets, names)
}

/// The clip's 300 keys: `(time in seconds, the 16 weights)`.
pub fn keys() -> Vec<(f64, Vec<f64>)> {
    (0..300)
        .map(|k| {
            let t = k as f64 / 30.0;
            let mut w = Vec::with_capacity(16);
            for dir in 0..4 {
                // Bend `dir` up and down over [2.5 dir, 2.5 dir + 2.5) seconds.
                let x = (t - 2.5 * dir as f64) / 2.5;
                let on = if (0.0..1.0).contains(&x) {
                    (std::f64::consts::PI * x).sin().powi(2)
                } else {
                    0.0
                };
                w.push(0.9 * on);
            }
            for b in 0..12 {
                let x = (0.9 + 0.17 * b as f64) * t + 1.3 * b as f64;
                w.push(0.8 * x.sin().max(0.0).powi(2));
            }
            (t, w)
        })
        .collect()
}
