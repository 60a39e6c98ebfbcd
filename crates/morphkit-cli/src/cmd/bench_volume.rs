//! `morphkit bench --suite volume`: the physical blend with internal springs (Ma et al. 2012,
//! Sec. 3.1) at about 2.2k, 8.5k and 18.6k vertices *including* the interior, the counts of
//! the paper's Table I (Man, Horse, Hand), each with both fill-reducing orderings.
//!
//! The meshes are closed tubes bent by 90° whose surface resolution is chosen so that surface
//! plus BCC-lattice interior (density 1) reaches the target count. When `tetgen` is on the
//! PATH, each tube is also blended with a `tetgen` interior (density 1, METIS ordering); its
//! total differs from the lattice's. Every row also gives the relative volume deviation at
//! α = 0.5.

use super::bench::bent_tube;
use morphkit::mesh::{enclosed_volume, ShapeSet};
use morphkit::springs::interior::lattice;
use morphkit::springs::{
    AnchorOptions, BlendOptions, FillOrdering, InteriorMode, InteriorOptions, Preconditioner,
    VolumetricBlend, Weights,
};
use serde_json::json;
use std::time::Instant;

/// A bent tube whose surface plus interior has about `total` vertices.
fn tube_with_total(total: usize, o: &InteriorOptions) -> ShapeSet {
    let mut surface = total / 2;
    for _ in 0..4 {
        let s = bent_tube(surface);
        let inner = lattice::build(s.positions(0), s.triangles(), o)
            .points
            .len();
        let got = surface + inner;
        if (got as f64 - total as f64).abs() < 0.03 * total as f64 {
            return s;
        }
        surface = ((surface as f64) * total as f64 / got as f64).round() as usize;
    }
    bent_tube(surface)
}

/// One row: set-up, `steps` timed steps, and the relative volume deviation at α = 0.5 from
/// $(V_0 + V_1)/2$ (one more, untimed, solve).
fn row(
    name: &str,
    kind: &str,
    shapes: &ShapeSet,
    interior: &InteriorOptions,
    opts: &BlendOptions,
    steps: usize,
    threads: usize,
) -> anyhow::Result<serde_json::Value> {
    let t0 = Instant::now();
    let mut v = VolumetricBlend::new(shapes, opts, interior, &AnchorOptions::default())?;
    let setup = t0.elapsed().as_secs_f64();
    let w: Vec<Weights> = (0..steps)
        .map(|k| Weights::Alpha(k as f64 / (steps.max(2) - 1) as f64))
        .collect();
    let t1 = Instant::now();
    let (mut iters, mut factors, mut cgs, mut converged) = (0, 0, 0, true);
    for r in v.solve_many(&w, threads) {
        let r = r?;
        iters += r.stats.newton_iterations;
        factors += r.stats.factorizations;
        cgs += r.stats.cg_iterations;
        converged &= r.stats.converged;
    }
    let per_step = t1.elapsed().as_secs_f64() / steps as f64;
    let half = v.solve(&Weights::Alpha(0.5))?;
    let t = shapes.triangles();
    let mid =
        0.5 * (enclosed_volume(shapes.positions(0), t) + enclosed_volume(shapes.positions(1), t));
    let deviation = (enclosed_volume(&half.positions, t) - mid).abs() / mid.abs();
    let rep = v.report();
    let n_total = rep.surface_vertices + rep.interior_vertices;
    let springs = v.physical().summary().springs + rep.internal_springs;
    let summary = v.physical().summary();
    let aggregates = summary.aggregates;
    // The factor's multiply-adds, or the coarse factor's with the aggregation cycle.
    let gflop = if aggregates > 0 {
        summary.coarse_flops / 1e9
    } else {
        summary.factor_flops / 1e9
    };
    let order = match (aggregates > 0, summary.ordering) {
        (true, _) => "aggr",
        (false, FillOrdering::Amd) => "amd",
        _ => "metis",
    };
    println!(
        "{:<14} {:>8} {:>6} {:>6.2} {:>7} {:>7} {:>8} {:>9.0} {:>10.1} {:>7.2} {:>7.2} {:>6.1} {:>9} {:>9.2e}",
        name,
        kind,
        order,
        gflop,
        rep.surface_vertices,
        n_total,
        springs,
        setup * 1e3,
        per_step * 1e3,
        iters as f64 / steps as f64,
        factors as f64 / steps as f64,
        cgs as f64 / steps as f64,
        converged,
        deviation
    );
    Ok(json!({
        "mesh": name, "interior": kind, "ordering": order,
        "surface_vertices": rep.surface_vertices, "total_vertices": n_total,
        "springs": springs, "tetrahedra": rep.tetrahedra,
        "factor_nnz": v.physical().factor_nnz(), "factor_gflop": gflop,
        "aggregates": aggregates,
        "factorizations_per_step": factors as f64 / steps as f64,
        "cg_iterations_per_step": cgs as f64 / steps as f64,
        "setup_ms": setup * 1e3, "ms_per_step": per_step * 1e3,
        "newton_iterations_per_step": iters as f64 / steps as f64,
        "all_converged": converged, "threads": threads,
        "volume_deviation_half": deviation,
    }))
}

/// Times the volumetric suite and prints one row per mesh and ordering, plus one row with a
/// `tetgen` interior (density 1, METIS) on the same tube when `tetgen` is on the PATH.
pub fn run_volume_bench(
    steps: usize,
    threads: usize,
    sampled_start: bool,
    preconditioner: Preconditioner,
    reference_factor_bytes: u64,
) -> anyhow::Result<serde_json::Value> {
    let with = |ordering| BlendOptions {
        ordering,
        sampled_start,
        preconditioner,
        reference_factor_bytes,
        ..Default::default()
    };
    let interior = InteriorOptions {
        mode: InteriorMode::Lattice,
        ..Default::default()
    };
    let tetgen = InteriorOptions {
        mode: InteriorMode::Tetgen,
        ..Default::default()
    };
    let have_tetgen = morphkit::springs::interior::tetgen::find_program(None).is_ok();
    println!("physical blend with internal springs (BCC lattice, density 1; tetgen rows: tetgen, density 1{}), {steps} steps, {threads} thread(s); vol dev: |V - (V0 + V1)/2| / ((V0 + V1)/2) at alpha = 0.5",
        if have_tetgen { "" } else { ", skipped: no tetgen on the PATH" });
    println!(
        "{:<14} {:>8} {:>6} {:>6} {:>7} {:>7} {:>8} {:>9} {:>10} {:>7} {:>7} {:>6} {:>9} {:>9}",
        "mesh",
        "interior",
        "order",
        "Gflop",
        "surface",
        "total",
        "springs",
        "setup ms",
        "ms/step",
        "newton",
        "factor",
        "cg",
        "conv",
        "vol dev"
    );
    let mut rows = Vec::new();
    for total in [2_200, 8_500, 18_600] {
        let shapes = tube_with_total(total, &interior);
        let name = format!("tube-{total}");
        for ordering in [FillOrdering::NestedDissection, FillOrdering::Amd] {
            // The aggregation cycle does not depend on the fine ordering: one row.
            if rows.last().is_some_and(|r: &serde_json::Value| {
                r["mesh"] == name.as_str() && r["aggregates"].as_u64() > Some(0)
            }) {
                continue;
            }
            rows.push(row(
                &name,
                "lattice",
                &shapes,
                &interior,
                &with(ordering),
                steps,
                threads,
            )?);
        }
        if have_tetgen {
            rows.push(row(
                &name,
                "tetgen",
                &shapes,
                &tetgen,
                &with(FillOrdering::NestedDissection),
                steps,
                threads,
            )?);
        }
    }
    Ok(json!(rows))
}
