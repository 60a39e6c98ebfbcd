//! Issue 40, "thin parts that turn far": a tail that curls 150–190° over its attachment,
//! with and without a roll about its own axis, must not twist on the way.

mod common;

use common::tail::Tail;
use morphkit::mesh::Topology;
use morphkit::springs::{fold_metrics, BlendOptions, FixedVertices, PhysicalBlend, Weights};

#[test]
fn measure_table() {
    let geo = std::env::var("TAIL_GEO").unwrap_or_default();
    let frames: usize = std::env::var("TAIL_FRAMES").ok().and_then(|s| s.parse().ok()).unwrap_or(12);
    let none = std::env::var("TAIL_NONE").is_ok();
    let list = |k: &str, d: &str| -> Vec<f64> { std::env::var(k).unwrap_or(d.into()).split(',').map(|x| x.parse().unwrap()).collect() };
    let only_bad = std::env::var("TAIL_BAD").is_ok();
    for bend in list("TAIL_BENDS", "150,170,180,190") {
        for roll in list("TAIL_ROLLS", "0,45,90") {
            let mut t = Tail::new(bend, roll);
            match geo.as_str() {
                "thin" => { t.radius = 0.1; t.around = 8; t.along = 40; }
                "coarse" => { t.radius = 0.15; t.around = 6; t.along = 24; }
                "coarse4" => { t.radius = 0.12; t.around = 4; t.along = 16; }
                "long" => { t.radius = 0.1; t.around = 8; t.along = 80; t.length = 8.0; t.attach = 1.0; t.curl = 6.0; }
                "short" => { t.radius = 0.2; t.around = 8; t.along = 24; t.length = 4.0; t.attach = 1.0; t.curl = 1.5; }
                _ => {}
            }
            let s = t.shapes();
            let topo = Topology::new(s.num_vertices(), s.triangles());
            let opts = BlendOptions { fixed: if none { FixedVertices::None } else { FixedVertices::Auto }, sampled_start: std::env::var("TAIL_NOSAMPLE").is_err(), ..Default::default() };
            let mut b = PhysicalBlend::new(&s, &opts).unwrap();
            let (mut fs, mut fp, mut fl, mut conv, mut lmin, mut lmax, mut tw, mut seg, mut tip) = (0, 0, 0, true, 9.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
            let mut worst = String::new();
            for k in 1..frames {
                let a = k as f64 / frames as f64;
                let w = Weights::Alpha(a);
                let p = b.predict(&w).unwrap();
                let r = b.solve(&w).unwrap();
                let f = fold_metrics(&s, &topo, &w, &r.positions).unwrap();
                let g = fold_metrics(&s, &topo, &w, &p).unwrap();
                let ts = t.shape(&s, &r.positions);
                if f.folds > fs { worst = format!("a={a:.3}"); }
                fs = fs.max(f.folds); fp = fp.max(g.folds); fl = fl.max(f.folds_linear);
                conv &= r.stats.converged;
                lmin = lmin.min(ts.length_ratio); lmax = lmax.max(ts.length_ratio);
                tw = tw.max((ts.twist_deg - a * roll).abs()); seg = seg.max(ts.max_segment_twist_deg);
                tip = tip.max(ts.tip_offset);
            }
            if only_bad && fs <= fl && conv && tw < 20.0 && lmin > 0.99 { continue; }
            println!("{geo} bend {bend:4.0} roll {roll:3.0}: folds solve {fs:3} pred {fp:3} lin {fl:3} {worst} | conv {conv} | len {lmin:.4}..{lmax:.4} | twist err {tw:6.1} maxseg {seg:6.1} tip {tip:.3}");
        }
    }
}

#[test]
fn probe_cat() {
    let Some(dir) = common::data_dir() else { return };
    let dir = dir.join("lowpoly-cat-dog/cat-run");
    let paths: Vec<_> = (1..=36).map(|i| dir.join(format!("cat-run-{i:02}.obj.gz"))).collect();
    for i in [1usize, 10, 19, 28] {
        for j in 1..=36usize {
            if j == i { continue; }
            let s = morphkit::io::read_shape_set(&[paths[i - 1].clone(), paths[j - 1].clone()]).unwrap();
            let topo = Topology::new(s.num_vertices(), s.triangles());
            let mut b = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
            let w = Weights::Alpha(0.5);
            let p = b.predict(&w).unwrap();
            let r = b.solve(&w).unwrap();
            let f = fold_metrics(&s, &topo, &w, &r.positions).unwrap();
            let g = fold_metrics(&s, &topo, &w, &p).unwrap();
            if f.folds > 0 || g.folds > 0 || !r.stats.converged {
                println!("cat {i}->{j}: folds {} pred {} lin {} conv {}", f.folds, g.folds, f.folds_linear, r.stats.converged);
            }
        }
    }
}
