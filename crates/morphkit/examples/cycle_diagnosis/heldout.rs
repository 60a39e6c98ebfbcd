//! Held-out animations (the horse gallop and the horse collapse onto the camel, with the
//! horse ↔ camel markers) and variants of how the local-stretch frame turns each stretch.
//!
//! `heldout` measures baseline, default and the old best setting (refined, local stretch,
//! area) and the turning variants of `TURN` (refined, area-weighted, confidence-weighted
//! solve) on the pairs of `PAIRS` (`horse,cat,gallop,collapse`, the default). `TURN` is a
//! comma-separated list of `none`, `smallest` (the library), `warp`, `warpal`, `smoothK`,
//! `smoothalK`, `cutC`, `partialP`, `coherentG`, `conformalG` (`turns::Turn`). Further
//! knobs: `LIBS=0` skips default and old best; `COMBINE=mean`; `SOFT=δ` (inverse distances
//! 1/(d + δ r) in the combine; the solve's confidence keeps 1/d); `SHRINK=e` (stretches
//! blended towards the identity by ((1 + c)/2)^e); `TWO_WAY=0`; `PER_FRAME=1` prints each
//! frame's sharp folds; `GALLOP_FIRST=k` takes gallop frames k, k + 4, … (default 1).
//! `foldwhere` says where the old best setting's extra folds (against turning nothing) are
//! on the gallop (`PAIRS=collapse` or `horse` for those).

use super::*;
use morphkit::mesh::Topology;
use morphkit::transfer::correspondence::rotation_between;
use morphkit::transfer::{RefineOptions, TriangleWeighting};
use std::path::PathBuf;
use turns::{corr_pair, cycle_turn, parse_turn, Dir, Measure, Turn};

/// The gallop's coordinates are this times the horse-camel reference's (its SOURCE.md).
const GALLOP_SCALE: f64 = 1.6768815;

fn horse_ref_and_markers() -> Option<(TriMesh, TriMesh, morphkit::transfer::Markers)> {
    use morphkit::io::read_mesh;
    let h = common::data_file("sumner-horse-camel/horse-reference.obj.gz")?;
    let c = common::data_file("sumner-horse-camel/camel-reference.obj.gz")?;
    let mk = common::data_file("sumner-horse-camel/markers-horse-camel.json")?;
    Some((
        read_mesh(&h).unwrap(),
        read_mesh(&c).unwrap(),
        morphkit::transfer::Markers::read(&mk).unwrap(),
    ))
}

/// Horse gallop → camel: every fourth of the 48 frames (`GALLOP_FIRST`, default 1, is the
/// first), brought to the horse-camel scale.
pub fn gallop() -> Option<Pair> {
    let (horse, camel, markers) = horse_ref_and_markers()?;
    let dir = common::data_dir()?.join("sumner-horse-gallop");
    let first: usize = std::env::var("GALLOP_FIRST").map_or(1, |s| s.parse().unwrap());
    let frames = (first..=48)
        .step_by(4)
        .map(|i| {
            let m =
                morphkit::io::read_mesh(&dir.join(format!("horse-gallop-{i:02}.obj.gz"))).unwrap();
            assert_eq!(m.triangles, horse.triangles);
            m.positions
                .iter()
                .map(|p| p.map(|x| x / GALLOP_SCALE))
                .collect()
        })
        .collect();
    Some(Pair {
        name: "gallop→camel",
        a_corr: horse.clone(),
        a_ref: horse,
        frames,
        b: camel,
        markers,
    })
}

/// Horse collapse → camel: its 27 frames, vertices put into the standard horse order by
/// `collapse_to_standard_vertex_map.json`, brought to the horse-camel scale.
pub fn collapse() -> Option<Pair> {
    let (horse, camel, markers) = horse_ref_and_markers()?;
    let dir = common::data_dir()?.join("sumner-horse-collapse");
    let map: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("collapse_to_standard_vertex_map.json")).unwrap(),
    )
    .unwrap();
    let map: Vec<usize> = map["collapse_to_standard"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect();
    let paths: Vec<PathBuf> = (1..=53)
        .step_by(2)
        .map(|i| dir.join(format!("horse-collapse-{i:02}.obj.gz")))
        .collect();
    let frames = paths
        .iter()
        .map(|path| {
            let m = morphkit::io::read_mesh(path).unwrap();
            let mut out = vec![[0.0; 3]; m.num_vertices()];
            for (i, p) in m.positions.iter().enumerate() {
                out[map[i]] = p.map(|x| x / GALLOP_SCALE);
            }
            out
        })
        .collect();
    Some(Pair {
        name: "collapse→camel",
        a_corr: horse.clone(),
        a_ref: horse,
        frames,
        b: camel,
        markers,
    })
}

/// Baseline, default, the old best and the `TURN` variants (refined, area-weighted,
/// confidence-weighted solve) on every pair of `PAIRS` (default all four).
pub fn heldout() {
    let turns: Vec<Turn> = std::env::var("TURN")
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.is_empty())
        .map(parse_turn)
        .collect();
    let which = std::env::var("PAIRS").unwrap_or_else(|_| "horse,cat,gallop,collapse".into());
    let libs = std::env::var("LIBS").map_or(true, |s| s != "0");
    let pairs: Vec<Pair> = which
        .split(',')
        .filter_map(|w| match w {
            "horse" => horse(),
            "cat" => cat(),
            "gallop" => gallop(),
            "collapse" => collapse(),
            _ => None,
        })
        .collect();
    let base_c = CorrespondenceOptions {
        two_way: false,
        refine: None,
        ..Default::default()
    };
    let base_t = TransferOptions {
        combine: morphkit::transfer::GradientCombine::Mean,
        frame: GradientFrame::World,
        solver: morphkit::transfer::SolverOptions::default(),
        ..Default::default()
    };
    let refined = CorrespondenceOptions {
        refine: Some(RefineOptions::default()),
        two_way: std::env::var("TWO_WAY").as_deref() != Ok("0"),
        ..Default::default()
    };
    let mut best_t = local();
    best_t.solver.weighting = TriangleWeighting::Area;
    let mut var_t = best_t.clone();
    if std::env::var("COMBINE").as_deref() == Ok("mean") {
        var_t.combine = morphkit::transfer::GradientCombine::Mean;
    }
    for p in &pairs {
        let show = |name: &str, m: &Measure, base: f64| {
            eprintln!(
                "{:<15} {name:<40} cycle mean {:.4} % ({:+.1} %) max {:.3} %  sharp folds {:>4}  flipped {:>5}",
                p.name,
                100.0 * m.mean,
                100.0 * (m.mean / base - 1.0),
                100.0 * m.max,
                m.folds,
                m.flipped
            );
        };
        let topo_a = Topology::new(p.a_ref.num_vertices(), &p.a_ref.triangles);
        let own: usize = p
            .frames
            .iter()
            .map(|f| morphkit::transfer::sharp_folds(&p.a_ref, &topo_a, f))
            .sum();
        eprintln!("{:<15} the source frames' own sharp folds: {own}", p.name);
        let (bf, bb) = corr_pair(p, &base_c);
        let base = cycle_turn(p, &bf, &bb, &base_t, None).0;
        show("baseline", &base, base.mean);
        if libs {
            let (df, db) = corr_pair(p, &CorrespondenceOptions::default());
            show(
                "default",
                &cycle_turn(p, &df, &db, &TransferOptions::default(), None).0,
                base.mean,
            );
        }
        let (rf, rb) = corr_pair(p, &refined);
        if libs {
            show(
                "old best (refine, local, area)",
                &cycle_turn(p, &rf, &rb, &best_t, None).0,
                base.mean,
            );
        }
        for &t in &turns {
            show(
                &format!("refine, area, turn {t:?}"),
                &cycle_turn(p, &rf, &rb, &var_t, Some(t)).0,
                base.mean,
            );
        }
    }
}

/// Where the old best setting folds on the gallop: the folded edges it makes that turning
/// nothing does not, their triangles' confidence, their matches' reference-normal angles and
/// how far the smallest rotation's twist is from the warp's.
pub fn fold_where() {
    let Some(p) = (match std::env::var("PAIRS").as_deref() {
        Ok("collapse") => collapse(),
        Ok("horse") => horse(),
        _ => gallop(),
    }) else {
        return;
    };
    let refined = CorrespondenceOptions {
        refine: Some(RefineOptions::default()),
        ..Default::default()
    };
    let mut best_t = local();
    best_t.solver.weighting = TriangleWeighting::Area;
    let (rf, rb) = corr_pair(&p, &refined);
    let (mb, yb) = cycle_turn(&p, &rf, &rb, &best_t, None);
    let (mn, yn) = cycle_turn(&p, &rf, &rb, &best_t, Some(Turn::None));
    eprintln!("old best {mb:?}\nno turn  {mn:?}");
    let topo = Topology::new(p.b.num_vertices(), &p.b.triangles);
    let df = Dir::new(&p.a_ref, &p.b, &rf);
    let conf = rf
        .correspondence
        .local_confidence(&df.ns, &df.nt, Default::default());
    let tris = &p.b.triangles;
    let sharp = |q: &[Point], e: usize| {
        let f = topo.edge_faces(e);
        if f.len() != 2 {
            return false;
        }
        let a = v(morphkit::mesh::triangle_normal(q, tris[f[0] as usize]));
        let b = v(morphkit::mesh::triangle_normal(q, tris[f[1] as usize]));
        a.norm() > 0.0 && b.norm() > 0.0 && a.dot(&b) < -0.5 * a.norm() * b.norm()
    };
    // Per target triangle: least match normal cosine, the largest angle between the
    // smallest rotation and the warp rotation over its matches (degrees).
    let stats = |t: usize| {
        let m = rf.correspondence.matches_of(t);
        let cmin = m
            .iter()
            .map(|&i| df.ns[i as usize].dot(&df.nt[t]))
            .fold(1.0, f64::min);
        let twist = m
            .iter()
            .map(|&i| {
                let q = rotation_between(df.ns[i as usize], df.nt[t]);
                let w = df.wt[t].transpose() * df.ws[i as usize];
                let c = (((q.transpose() * w).trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
                c.acos().to_degrees()
            })
            .fold(0.0, f64::max);
        (cmin, twist)
    };
    let (mut extra, mut count_frames) = (Vec::new(), Vec::new());
    let mut per_tri = std::collections::BTreeMap::<usize, usize>::new();
    for (yb, yn) in yb.iter().zip(&yn) {
        let mut n = 0;
        for e in 0..topo.edges().len() {
            if sharp(yb, e) && !sharp(yn, e) && !sharp(&p.b.positions, e) {
                n += 1;
                for &t in topo.edge_faces(e) {
                    extra.push(t as usize);
                    *per_tri.entry(t as usize).or_default() += 1;
                }
            }
        }
        count_frames.push(n);
    }
    eprintln!("edges folded by the old best but not without turning, per frame: {count_frames:?}");
    let summarize = |name: &str, ts: &[usize]| {
        let n = ts.len().max(1) as f64;
        let (mut c, mut cm, mut tw) = (0.0, 0.0, 0.0);
        let mut hist = [0usize; 4];
        for &t in ts {
            let (cmin, twist) = stats(t);
            c += conf[t];
            cm += cmin;
            tw += twist;
            hist[if cmin < 0.0 {
                0
            } else if cmin < 0.5 {
                1
            } else if cmin < 0.9 {
                2
            } else {
                3
            }] += 1;
        }
        eprintln!(
            "  {name:<28} n {:>6}  mean confidence {:.3}  mean least match cosine {:.3} (<0 / <0.5 / <0.9 / ≥0.9: {hist:?})  mean largest twist vs warp {:.1}°",
            ts.len(),
            c / n,
            cm / n,
            tw / n
        );
    };
    summarize("extra-fold triangles", &extra);
    let all: Vec<usize> = (0..p.b.num_triangles()).collect();
    summarize("all camel triangles", &all);
    let (lo, hi) = p.b.bounding_box();
    let rear = extra
        .iter()
        .filter(|&&t| {
            let tri = p.b.triangles[t];
            let z = tri
                .iter()
                .map(|&i| p.b.positions[i as usize][2])
                .sum::<f64>()
                / 3.0;
            (z - lo[2]) / (hi[2] - lo[2]) < 0.3
        })
        .count();
    eprintln!(
        "  {rear} of the {} extra-fold triangles lie in the rear 30 % of the length (z)",
        extra.len()
    );
    let mut top: Vec<(usize, usize)> = per_tri.into_iter().map(|(t, n)| (n, t)).collect();
    top.sort_by(|a, b| b.cmp(a));
    for &(n, t) in top.iter().take(15) {
        let tri = p.b.triangles[t];
        let c = [0, 1, 2].map(|k| {
            tri.iter()
                .map(|&i| p.b.positions[i as usize][k])
                .sum::<f64>()
                / 3.0
        });
        let rel = [0, 1, 2].map(|k| (c[k] - lo[k]) / (hi[k] - lo[k]));
        let (cmin, twist) = stats(t);
        eprintln!(
            "  camel triangle {t:>6}: {n} extra folds; at ({:.2}, {:.2}, {:.2}) of the box; confidence {:.3}; least match cosine {cmin:.3}; largest twist vs warp {twist:.1}°; {} matches",
            rel[0], rel[1], rel[2], conf[t], rf.correspondence.matches_of(t).len()
        );
        let (alo, ahi) = p.a_ref.bounding_box();
        for &i in rf.correspondence.matches_of(t) {
            let tri = p.a_ref.triangles[i as usize];
            let c = [0, 1, 2].map(|k| {
                tri.iter()
                    .map(|&j| p.a_ref.positions[j as usize][k])
                    .sum::<f64>()
                    / 3.0
            });
            let rel = [0, 1, 2].map(|k| (c[k] - alo[k]) / (ahi[k] - alo[k]));
            eprintln!(
                "    matched source triangle {i} at ({:.2}, {:.2}, {:.2}) of the source box",
                rel[0], rel[1], rel[2]
            );
        }
    }
}
