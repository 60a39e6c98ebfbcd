//! Issue 40, "Transfer defaults": the candidate configurations of the leave-one-out study
//! (`examples/transfer_defaults_study.rs`) and their measurement on a [`Pair`], shared with
//! `tests/transfer_defaults_real_data.rs`.

use super::Pair;
use morphkit::transfer::{
    correspond, cycle_consistency, Correspondence, CorrespondenceOptions, GradientFrame,
    RefineOptions, TransferOptions, TriangleWeighting,
};
use std::time::Instant;

/// One configuration: its name, its `morphkit transfer` flags (against the new defaults) and
/// its switches.
pub struct Config {
    pub name: &'static str,
    pub flags: &'static str,
    pub refine: bool,
    pub local: bool,
    pub area: bool,
    pub guard: bool,
}

const fn config(
    (name, flags): (&'static str, &'static str),
    refine: bool,
    local: bool,
    area: bool,
    guard: bool,
) -> Config {
    Config {
        name,
        flags,
        refine,
        local,
        area,
        guard,
    }
}

/// The candidates; the first is the old default (before issue 40), the fifth the new one.
/// The fold guard acts only in the local-stretch frame, so the world-frame configurations are
/// listed once.
pub const CONFIGS: [Config; 6] = [
    config(
        ("old default", "--no-refine --world-frame --uniform-weights"),
        false,
        false,
        false,
        false,
    ),
    config(
        ("refine", "--world-frame --uniform-weights"),
        true,
        false,
        false,
        false,
    ),
    config(("local+area", "--no-refine"), false, true, true, true),
    config(
        ("local+area, no guard", "--no-refine --no-fold-guard"),
        false,
        true,
        true,
        false,
    ),
    config(
        ("all three (new default)", "(none)"),
        true,
        true,
        true,
        true,
    ),
    config(
        ("all three, no guard", "--no-fold-guard"),
        true,
        true,
        true,
        false,
    ),
];

/// Index of the old default in [`CONFIGS`].
pub const OLD_DEFAULT: usize = 0;
/// Index of the new default in [`CONFIGS`].
pub const NEW_DEFAULT: usize = 4;

impl Config {
    /// The correspondence options, every switch set (independent of the library's defaults).
    pub fn correspondence_options(&self) -> CorrespondenceOptions {
        CorrespondenceOptions {
            refine: self.refine.then(RefineOptions::default),
            ..Default::default()
        }
    }

    /// The transfer options, every switch set (independent of the library's defaults).
    pub fn transfer_options(&self) -> TransferOptions {
        TransferOptions {
            frame: if self.local {
                GradientFrame::LocalStretch
            } else {
                GradientFrame::World
            },
            solver: morphkit::transfer::SolverOptions {
                weighting: if self.area {
                    TriangleWeighting::Area
                } else {
                    TriangleWeighting::Uniform
                },
                ..Default::default()
            },
            fold_guard: self.guard.then(Default::default),
            ..Default::default()
        }
    }
}

/// One pair × configuration.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cell {
    /// Mean and largest cycle-consistency error over A's diagonal.
    pub mean: f64,
    pub max: f64,
    /// Sharp folds and flipped triangles of the A → B frames, summed.
    pub folds: usize,
    pub flipped: usize,
    /// Seconds of the cycle (set-up and every frame there and back).
    pub cycle_s: f64,
}

/// Correspondences both ways and the seconds of the forward one.
fn corr_pair(p: &Pair, o: &CorrespondenceOptions) -> (Correspondence, Correspondence, f64) {
    let t = Instant::now();
    let f = correspond(&p.a_corr, &p.b, &p.markers, o)
        .unwrap()
        .correspondence;
    let s = t.elapsed().as_secs_f64();
    let b = correspond(&p.b, &p.a_corr, &p.markers.reversed(), o)
        .unwrap()
        .correspondence;
    (f, b, s)
}

/// Every configuration of [`CONFIGS`] on `p` (printed), and the forward correspondence
/// seconds `[unrefined, refined]`.
pub fn measure_all(p: &Pair) -> (Vec<Cell>, [f64; 2]) {
    let plain = corr_pair(p, &CONFIGS[OLD_DEFAULT].correspondence_options());
    let refined = corr_pair(p, &CONFIGS[NEW_DEFAULT].correspondence_options());
    let mut row = Vec::new();
    for c in &CONFIGS {
        let (f, b) = if c.refine {
            (&refined.0, &refined.1)
        } else {
            (&plain.0, &plain.1)
        };
        let t = Instant::now();
        let q = cycle_consistency(&p.a_ref, &p.frames, &p.b, f, b, &c.transfer_options()).unwrap();
        let cell = Cell {
            mean: q.mean,
            max: q.max,
            folds: q.forward_sharp_folds.iter().sum(),
            flipped: q.forward_flipped.iter().sum(),
            cycle_s: t.elapsed().as_secs_f64(),
        };
        eprintln!(
            "{:<15} {:<24} mean {:.4} % max {:.3} % sharp folds {:>4} flipped {:>5} ({:.1} s)",
            p.name,
            c.name,
            100.0 * cell.mean,
            100.0 * cell.max,
            cell.folds,
            cell.flipped,
            cell.cycle_s
        );
        row.push(cell);
    }
    (row, [plain.2, refined.2])
}
