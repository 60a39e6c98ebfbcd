//! `morphkit demo`: the main job on a built-in example, with nothing to download.
//!
//! A closed rectangular bar, straight, and the same bar with its second half bent by 120°.
//! The linear blend at α = 0.5 cuts the corner of the bend and the bar shrinks (Ma et al.
//! 2012, Fig. 1c); the physical blend keeps edge lengths, areas and volume (Fig. 1d).

use anyhow::Context;
use morphkit::io::{self, FramesOptions};
use morphkit::mesh::{generate, ShapeSet, Topology};
use morphkit::springs::{
    blend_metrics, linear_blend, BlendMetrics, BlendOptions, PhysicalBlend, Weights,
};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `morphkit demo`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  morphkit demo\n  morphkit demo --out /tmp/demo --angle 150\n\nWrites base.obj, target.obj, linear-0.5.{obj,glb}, physical-0.5.{obj,glb} and 36-frame\nlinear-sequence.glb / physical-sequence.glb into the output directory."
)]
pub struct DemoArgs {
    /// Output directory (created if missing).
    #[arg(long, default_value = "morphkit-demo")]
    pub out: PathBuf,
    /// Bend angle of the target, in degrees.
    #[arg(long, default_value_t = 120.0)]
    pub angle: f64,
}

fn row(name: &str, l: f64, p: f64) {
    println!("  {name:<34} {l:>12.4} {p:>12.4}");
}

fn table(lin: &BlendMetrics, phys: &BlendMetrics) {
    println!("  {:<34} {:>12} {:>12}", "α = 0.5", "linear", "physical");
    row(
        "edge length RMS deviation",
        lin.edge_length_rms,
        phys.edge_length_rms,
    );
    row(
        "edge length max deviation",
        lin.edge_length_max,
        phys.edge_length_max,
    );
    row("triangle area RMS deviation", lin.area_rms, phys.area_rms);
    if let (Some(l), Some(p)) = (lin.volume_ratio, phys.volume_ratio) {
        row("volume / interpolated volume", l, p);
    }
}

/// Runs `morphkit demo`.
pub fn run(a: &DemoArgs) -> anyhow::Result<()> {
    if !(a.angle.is_finite() && a.angle.abs() <= 270.0) {
        anyhow::bail!(
            "--angle must be a finite number of degrees in [-270, 270], got {}",
            a.angle
        );
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create the output directory", a.out.display()))?;
    let bar = generate::bar(4.0, 0.6, 3, 32);
    let bent = generate::bend(&bar.positions, 2.0, 2.0, a.angle.to_radians());
    let shapes = ShapeSet::new(
        bar.clone(),
        vec![
            ("straight".into(), bar.positions.clone()),
            ("bent".into(), bent),
        ],
    )?;
    let topology = Topology::new(shapes.num_vertices(), shapes.triangles());
    println!(
        "morphkit demo: a closed bar of {} vertices, straight and with its second half bent by {}°",
        shapes.num_vertices(),
        a.angle
    );

    let t0 = Instant::now();
    let mut solver = PhysicalBlend::new(&shapes, &BlendOptions::default())?;
    let setup = t0.elapsed();
    let half = Weights::Alpha(0.5);
    let phys = solver.solve(&half)?;
    let lin = linear_blend(&shapes, &half)?;
    let (mp, ml) = (
        blend_metrics(&shapes, &topology, &half, &phys.positions)?,
        blend_metrics(&shapes, &topology, &half, &lin)?,
    );
    println!(
        "  {} springs, {} fixed vertices (the straight half does not move); set-up {:.1} ms, solve {:.1} ms, {} Newton iterations, converged: {}",
        solver.summary().springs,
        solver.constraints().fixed.len(),
        setup.as_secs_f64() * 1e3,
        phys.stats.seconds * 1e3,
        phys.stats.newton_iterations,
        phys.stats.converged
    );
    println!();
    table(&ml, &mp);
    println!();
    println!(
        "  The linear blend distorts edge lengths by {:.1}% (RMS) and keeps {:.1}% of the volume: it cuts the corner.",
        ml.edge_length_rms * 100.0,
        ml.volume_ratio.unwrap_or(f64::NAN) * 100.0
    );
    println!(
        "  The physical blend's edges are within {:.2}% (RMS) of their rest lengths: no shrinking.",
        mp.edge_length_rms * 100.0
    );

    let write = |name: &str, p: &[[f64; 3]]| -> anyhow::Result<()> {
        let m = shapes.base().with_positions(p.to_vec());
        for ext in ["obj", "glb"] {
            io::write_mesh(&a.out.join(format!("{name}.{ext}")), &m)?;
        }
        Ok(())
    };
    io::write_mesh(&a.out.join("base.obj"), &shapes.mesh(0))?;
    io::write_mesh(&a.out.join("target.obj"), &shapes.mesh(1))?;
    write("linear-0.5", &lin)?;
    write("physical-0.5", &phys.positions)?;

    let t1 = Instant::now();
    let n = 36;
    let (mut phys_frames, mut lin_frames) = (Vec::new(), Vec::new());
    for k in 0..n {
        let w = Weights::Alpha(k as f64 / (n - 1) as f64);
        phys_frames.push((format!("frame_{k:04}"), solver.solve(&w)?.positions));
        lin_frames.push((format!("frame_{k:04}"), linear_blend(&shapes, &w)?));
    }
    let seq = t1.elapsed();
    let opts = FramesOptions::default();
    io::write_frames(
        &a.out.join("physical-sequence.glb"),
        &ShapeSet::new(bar.clone(), phys_frames)?,
        &opts,
    )?;
    io::write_frames(
        &a.out.join("linear-sequence.glb"),
        &ShapeSet::new(bar, lin_frames)?,
        &opts,
    )?;
    println!();
    println!(
        "  36-frame sequence: {:.2} ms per frame. Wrote base.obj, target.obj, linear-0.5.{{obj,glb}}, physical-0.5.{{obj,glb}},",
        seq.as_secs_f64() * 1e3 / n as f64
    );
    println!(
        "  linear-sequence.glb and physical-sequence.glb to {}/",
        a.out.display()
    );
    Ok(())
}
