//! Issue 40, "Transfer defaults": a leave-one-out study of the transfer configurations on the
//! real pairs of `MORPHKIT_DATA` (horse → camel, cat → dog, horse gallop → camel, horse
//! collapse → camel). Run it with
//! `MORPHKIT_DATA=… cargo run --release -p morphkit --example transfer_defaults_study`
//! (`PAIRS=horse,cat,gallop,collapse` selects pairs; `GALLOP_STEP=k` takes every k-th gallop
//! frame, default 1: all 48). Writes a Markdown report to stdout, progress to stderr.
//!
//! **Measure** (no pair here has a reference answer: docs/fidelity.md, "Transfer defaults"):
//! the cycle-consistency error (A → B → A, per-vertex distance over A's diagonal, mean over
//! vertices and frames; `transfer::cycle_consistency`) and the sharp folds of the A → B
//! frames. **Score** of a configuration on a set of pairs: the mean over the pairs of its
//! relative change of the mean cycle error against the old default (`refine` off, world
//! frame, uniform weights); a configuration is **eligible** only if it makes no more sharp
//! folds than the old default on every pair of the set. **Leave one out**: for each pair, the
//! eligible configuration with the lowest score on the other pairs, and its change on the
//! held-out pair.

#[path = "../tests/common/mod.rs"]
mod common;

use common::defaults::{measure_all, Cell, CONFIGS, OLD_DEFAULT};
use common::Pair;
use std::time::Instant;

/// Relative change of `c`'s mean cycle error against the old default's.
fn change(row: &[Cell], c: usize) -> f64 {
    row[c].mean / row[OLD_DEFAULT].mean - 1.0
}

/// The eligible configuration with the lowest mean change over `pairs` (indices into `rows`).
fn choose(rows: &[Vec<Cell>], pairs: &[usize]) -> usize {
    (0..CONFIGS.len())
        .filter(|&c| {
            pairs
                .iter()
                .all(|&p| rows[p][c].folds <= rows[p][OLD_DEFAULT].folds)
        })
        .min_by(|&a, &b| {
            let s = |c| pairs.iter().map(|&p| change(&rows[p], c)).sum::<f64>();
            s(a).total_cmp(&s(b))
        })
        .expect("the old default is always eligible")
}

fn main() {
    let which = std::env::var("PAIRS").unwrap_or_else(|_| "horse,cat,gallop,collapse".into());
    let step: usize = std::env::var("GALLOP_STEP").map_or(1, |s| s.parse().unwrap());
    let pairs: Vec<Pair> = which
        .split(',')
        .map(|w| {
            let p = match w {
                "horse" => common::horse_camel(),
                "cat" => common::cat_dog(),
                "gallop" => common::gallop_camel().map(|mut p| {
                    p.frames = p.frames.into_iter().step_by(step).collect();
                    p
                }),
                "collapse" => common::collapse_camel(),
                _ => panic!("unknown pair {w}"),
            };
            p.expect("set MORPHKIT_DATA to the data directory")
        })
        .collect();
    let total = Instant::now();
    let mut rows: Vec<Vec<Cell>> = Vec::new();
    // Forward correspondence seconds per pair: [plain, refined].
    let mut corr_s: Vec<[f64; 2]> = Vec::new();
    for p in &pairs {
        let (row, secs) = measure_all(p);
        corr_s.push(secs);
        rows.push(row);
    }
    report(&pairs, &rows, &corr_s);
    eprintln!("total {:.0} s", total.elapsed().as_secs_f64());
}

fn report(pairs: &[Pair], rows: &[Vec<Cell>], corr_s: &[[f64; 2]]) {
    println!("Configurations (`morphkit transfer` flags against the new defaults)\n");
    for c in &CONFIGS {
        println!("- {}: `{}`", c.name, c.flags);
    }
    println!();
    let frames: Vec<usize> = pairs.iter().map(|p| p.frames.len()).collect();
    println!(
        "Mean cycle error, % of the diagonal (change against the old default) · sharp folds\n"
    );
    print!("| configuration |");
    for (p, n) in pairs.iter().zip(&frames) {
        print!(" {} ({n} fr) |", p.name);
    }
    println!(" mean change |");
    println!("|---|{}---|", "---|".repeat(pairs.len()));
    let all: Vec<usize> = (0..pairs.len()).collect();
    for (c, cfg) in CONFIGS.iter().enumerate() {
        print!("| {} |", cfg.name);
        for row in rows {
            print!(
                " {:.3} ({:+.1} %) · {} |",
                100.0 * row[c].mean,
                100.0 * change(row, c),
                row[c].folds
            );
        }
        let m = all.iter().map(|&p| change(&rows[p], c)).sum::<f64>() / all.len() as f64;
        println!(" {:+.1} % |", 100.0 * m);
    }
    println!("\nLeave one out (chosen on the other pairs; eligible: no more sharp folds than the old default on each)\n");
    println!("| held out | chosen on the others | its change on the held-out pair · folds (old default's) | best there |");
    println!("|---|---|---|---|");
    for h in 0..pairs.len() {
        let others: Vec<usize> = all.iter().copied().filter(|&p| p != h).collect();
        let c = choose(rows, &others);
        let best = choose(rows, &[h]);
        println!(
            "| {} | {} | {:+.1} % · {} ({}) | {} ({:+.1} %) |",
            pairs[h].name,
            CONFIGS[c].name,
            100.0 * change(&rows[h], c),
            rows[h][c].folds,
            rows[h][0].folds,
            CONFIGS[best].name,
            100.0 * change(&rows[h], best)
        );
    }
    println!(
        "\nChosen on all pairs: `{}`\n",
        CONFIGS[choose(rows, &all)].name
    );
    println!("Cost: forward correspondence (s) and cycle seconds per frame (there and back, with set-up)\n");
    print!("| configuration |");
    for p in pairs {
        print!(" {} |", p.name);
    }
    println!();
    println!("|---|{}", "---|".repeat(pairs.len()));
    for (c, cfg) in CONFIGS.iter().enumerate() {
        print!("| {} |", cfg.name);
        for (i, row) in rows.iter().enumerate() {
            print!(
                " {:.2} s + {:.2} s/fr |",
                corr_s[i][usize::from(cfg.refine)],
                row[c].cycle_s / frames[i] as f64
            );
        }
        println!();
    }
    println!("\nLargest cycle error, % · flipped triangles\n");
    for (c, cfg) in CONFIGS.iter().enumerate() {
        print!("| {} |", cfg.name);
        for row in rows {
            print!(" {:.2} · {} |", 100.0 * row[c].max, row[c].flipped);
        }
        println!();
    }
}
