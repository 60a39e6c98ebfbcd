//! The three studies of the cycle diagnosis: where the error comes from, variants of the
//! gradient combine, and where each gradient frame folds.

use super::*;

fn area_opts() -> TransferOptions {
    TransferOptions {
        frame: GradientFrame::LocalStretch,
        solver: morphkit::transfer::SolverOptions {
            weighting: morphkit::transfer::TriangleWeighting::Area,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn diagnose(p: &Pair) {
    eprintln!("== {}", p.name);
    // Unrefined: the issue-9 default this diagnosis was written for (issue 40 made the
    // refinement the default).
    let o = CorrespondenceOptions {
        refine: None,
        ..Default::default()
    };
    let fwd = correspond(&p.a_corr, &p.b, &p.markers, &o)
        .unwrap()
        .correspondence;
    let bwd = correspond(&p.b, &p.a_corr, &p.markers.reversed(), &o)
        .unwrap()
        .correspondence;
    // The old default: gradients carried over in the world frame.
    let t = TransferOptions {
        frame: GradientFrame::World,
        ..Default::default()
    };
    let base = cycle(p, &fwd, &bwd, &t, true, &p.frames);
    report("world frame (old default)", &base);
    report(
        "local stretch",
        &cycle(p, &fwd, &bwd, &local(), true, &p.frames),
    );
    // (b) The reference pose itself.
    let r = cycle(
        p,
        &fwd,
        &bwd,
        &t,
        true,
        std::slice::from_ref(&p.a_ref.positions),
    );
    report("reference pose only", &r);
    // (d) Placement: the paper's fixed vertex instead of following the markers.
    let fixed = TransferOptions {
        translation: TranslationMode::FixedVertex,
        ..t.clone()
    };
    report(
        "fixed-vertex placement",
        &cycle(p, &fwd, &bwd, &fixed, true, &p.frames),
    );
    // Mapping only (no solve on B): A gradients → B triangles → A triangles, solved on A.
    report(
        "gradients mapped there and back, no B solve",
        &cycle(p, &fwd, &bwd, &t, false, &p.frames),
    );
    for (name, idw) in [
        ("polar combine, mean", false),
        ("polar combine, inverse distance", true),
    ] {
        report(
            name,
            &cycle_with(p, &fwd, &bwd, &t, 1, &p.frames, Some(idw)),
        );
        report(
            &format!("{name}, no B solve"),
            &cycle_with(p, &fwd, &bwd, &t, 0, &p.frames, Some(idw)),
        );
    }
    report(
        "B: wanted tangential, solved normal part",
        &cycle_with(p, &fwd, &bwd, &t, 2, &p.frames, None),
    );
    report(
        "B: solved tangential, wanted normal part",
        &cycle_with(p, &fwd, &bwd, &t, 3, &p.frames, None),
    );
    for idw in [false, true] {
        report(
            &format!("polar, stretch turned into the target plane, idw {idw}"),
            &cycle_full(p, &fwd, &bwd, &t, 1, &p.frames, Some(idw), true),
        );
    }
    report(
        "polar aligned idw + area-weighted solves",
        &cycle_full(p, &fwd, &bwd, &area_opts(), 1, &p.frames, Some(true), true),
    );
    {
        let ro = CorrespondenceOptions {
            refine: Some(morphkit::transfer::RefineOptions::default()),
            ..Default::default()
        };
        let rf = correspond(&p.a_corr, &p.b, &p.markers, &ro)
            .unwrap()
            .correspondence;
        let rb = correspond(&p.b, &p.a_corr, &p.markers.reversed(), &ro)
            .unwrap()
            .correspondence;
        report("refined", &cycle(p, &rf, &rb, &t, true, &p.frames));
        report(
            "refined + local stretch",
            &cycle(p, &rf, &rb, &local(), true, &p.frames),
        );
        report(
            "refined + local stretch + area",
            &cycle(p, &rf, &rb, &area_opts(), true, &p.frames),
        );
        report(
            "refined + polar aligned idw",
            &cycle_full(p, &rf, &rb, &t, 1, &p.frames, Some(true), true),
        );
        report(
            "refined + polar aligned idw + area",
            &cycle_full(p, &rf, &rb, &area_opts(), 1, &p.frames, Some(true), true),
        );
    }
    // How much of the wanted B gradients the B solve cannot fit.
    {
        let tf = AnimationTransfer::new(&p.a_ref, &p.b, &fwd, &t).unwrap();
        let (mut res, mut mag) = (0.0, 0.0);
        for f in &p.frames {
            let g = tf.target_gradients(&tf.source_gradients(f).unwrap());
            let y = tf.solve_gradients(&g, Some(f)).unwrap();
            // T(y) relative to B's reference: B's own gradient operator.
            let ty = GradientOperator::new(&p.b).gradients(&y).unwrap();
            for (j, tri) in p.b.triangles.iter().enumerate() {
                let e1 = v(p.b.positions[tri[1] as usize]) - v(p.b.positions[tri[0] as usize]);
                let e2 = v(p.b.positions[tri[2] as usize]) - v(p.b.positions[tri[0] as usize]);
                // Tangential action only (what the solve fits).
                for e in [e1, e2] {
                    res += ((ty[j] - g[j]) * e).norm_squared() / e.norm_squared();
                    mag += ((g[j] - Matrix3::identity()) * e).norm_squared() / e.norm_squared();
                }
            }
        }
        eprintln!("  B solve: unfitted tangential part of the wanted gradients {:.1} % of their deviation from the identity (squared norms)", 100.0 * res / mag);
    }
    let area = TransferOptions {
        frame: GradientFrame::World,
        ..area_opts()
    };
    report(
        "area-weighted solves",
        &cycle(p, &fwd, &bwd, &area, true, &p.frames),
    );
    report(
        "local stretch + area-weighted solves",
        &cycle(p, &fwd, &bwd, &area_opts(), true, &p.frames),
    );
    // Backward correspondence = transpose of the forward one.
    let tr = transpose(&fwd, &bwd);
    report(
        "backward = transpose of forward",
        &cycle(p, &fwd, &tr, &t, true, &p.frames),
    );
    report(
        "transpose, no B solve",
        &cycle(p, &fwd, &tr, &t, false, &p.frames),
    );
    // The identity A → A → A with the forward map composed with its transpose: the blur of
    // the matching alone is `mapped, no B solve`; this is the A solve on its own.
    let id = Correspondence::identity(&p.a_ref);
    report(
        "A → A identity (floor of the A solve)",
        &cycle(
            &Pair {
                name: "",
                a_corr: p.a_corr.clone(),
                a_ref: p.a_ref.clone(),
                frames: Vec::new(),
                b: p.a_ref.clone(),
                markers: p.markers.clone(),
            },
            &id,
            &id,
            &t,
            true,
            &p.frames,
        ),
    );
    // (c) Where: the similarity-aligned per-vertex mean error against the distance to the
    // nearest marker (over A's diagonal) and the vertex's share.
    let d = p.a_ref.bbox_diagonal();
    let mv = p.markers.source_vertices();
    let dm: Vec<f64> = p
        .a_ref
        .positions
        .iter()
        .map(|&q| {
            mv.iter()
                .map(|&m| (v(q) - v(p.a_ref.positions[m as usize])).norm() / d)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let e = &base.per_vertex;
    let mut idx: Vec<usize> = (0..e.len()).collect();
    idx.sort_by(|&a, &b| dm[a].total_cmp(&dm[b]));
    let nb = 5;
    for k in 0..nb {
        let s = &idx[k * idx.len() / nb..(k + 1) * idx.len() / nb];
        eprintln!(
            "  marker-distance quintile {k}: distance {:.3}–{:.3} of the diagonal, mean error {:.4} %",
            dm[s[0]],
            dm[*s.last().unwrap()],
            100.0 * s.iter().map(|&i| e[i]).sum::<f64>() / s.len() as f64
        );
    }
    let mut sorted = e.clone();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let total: f64 = sorted.iter().sum();
    for frac in [0.01, 0.05, 0.1, 0.25] {
        let k = (frac * sorted.len() as f64) as usize;
        eprintln!(
            "  worst {:>3.0} % of the vertices carry {:.1} % of the error",
            100.0 * frac,
            100.0 * sorted[..k].iter().sum::<f64>() / total
        );
    }
    if let Ok(dir) = std::env::var("DIAG_DUMP") {
        let mut s = String::from("x,y,z,err,marker_dist\n");
        for (i, q) in p.a_ref.positions.iter().enumerate() {
            s += &format!("{},{},{},{},{}\n", q[0], q[1], q[2], e[i], dm[i]);
        }
        std::fs::write(format!("{dir}/{}-error.csv", p.name), s).unwrap();
    }
}

pub fn cycle_error_diagnosis() {
    for p in [horse(), cat()].into_iter().flatten() {
        diagnose(&p);
    }
}

/// Quick variants of the polar combine (`DIAG_VARIANT`: `noproj`, `cmin=…`), against the
/// world frame and the library default.
pub fn combine_variants() {
    for p in [horse(), cat()].into_iter().flatten() {
        eprintln!("== {}", p.name);
        let mut o = CorrespondenceOptions {
            refine: None,
            ..Default::default()
        };
        let var = std::env::var("DIAG_VARIANT").unwrap_or_default();
        if var.contains("refine") {
            o.refine = Some(morphkit::transfer::RefineOptions::default());
        }
        if let Some(c) = var.split(',').find_map(|x| x.strip_prefix("ncos=")) {
            o.min_normal_cos = c.parse().unwrap();
        }
        let rf = correspond(&p.a_corr, &p.b, &p.markers, &o).unwrap();
        let rb = correspond(&p.b, &p.a_corr, &p.markers.reversed(), &o).unwrap();
        if std::env::var("DIAG_VARIANT")
            .unwrap_or_default()
            .contains("warp")
        {
            *WARP.lock().unwrap() = Some((
                warp_rotations(&p.a_corr, &rf.warped_source),
                warp_rotations(&p.b, &rf.warped_target),
                warp_rotations(&p.b, &rb.warped_source),
                warp_rotations(&p.a_corr, &rb.warped_target),
            ));
        } else {
            *WARP.lock().unwrap() = None;
        }
        let (fwd, bwd) = (rf.correspondence, rb.correspondence);
        let mut world = TransferOptions {
            frame: GradientFrame::World,
            ..Default::default()
        };
        if std::env::var("DIAG_VARIANT")
            .unwrap_or_default()
            .contains("area")
        {
            world.solver.weighting = morphkit::transfer::TriangleWeighting::Area;
        }
        report("world", &cycle(&p, &fwd, &bwd, &world, true, &p.frames));
        report(
            "library local stretch",
            &cycle(&p, &fwd, &bwd, &local(), true, &p.frames),
        );
        for aligned in [false, true] {
            report(
                &format!("variant, aligned {aligned}"),
                &cycle_full(&p, &fwd, &bwd, &world, 1, &p.frames, Some(true), aligned),
            );
        }
    }
}

/// Where the forward sharp folds are, world frame against local stretch: per frame the
/// count, and the rest-normal agreement (cosine) of the folded triangles' matches.
pub fn fold_locations() {
    for p in [horse(), cat()].into_iter().flatten() {
        eprintln!("== {}", p.name);
        let mut o = CorrespondenceOptions {
            refine: None,
            ..Default::default()
        };
        if std::env::var("DIAG_VARIANT")
            .unwrap_or_default()
            .contains("refine")
        {
            o.refine = Some(morphkit::transfer::RefineOptions::default());
        }
        let fwd = correspond(&p.a_corr, &p.b, &p.markers, &o)
            .unwrap()
            .correspondence;
        let topo = morphkit::mesh::Topology::new(p.b.num_vertices(), &p.b.triangles);
        let (na, nb) = (unit_normals(&p.a_ref), unit_normals(&p.b));
        let (lo, hi) = p.b.bounding_box();
        for frame in [GradientFrame::World, GradientFrame::LocalStretch] {
            let tf = AnimationTransfer::new(
                &p.a_ref,
                &p.b,
                &fwd,
                &TransferOptions {
                    frame,
                    ..Default::default()
                },
            )
            .unwrap();
            let mut per_frame = Vec::new();
            let mut hist = [0usize; 4];
            let mut yb = [0usize; 5];
            for f in &p.frames {
                let g = tf.target_gradients(&tf.source_gradients(f).unwrap());
                let y = tf.solve_gradients(&g, Some(f)).unwrap();
                let mut n = 0;
                for e in 0..topo.edges().len() {
                    let fs = topo.edge_faces(e);
                    if fs.len() != 2 {
                        continue;
                    }
                    let sharp = |q: &[Point]| {
                        let a = v(morphkit::mesh::triangle_normal(
                            q,
                            p.b.triangles[fs[0] as usize],
                        ));
                        let b = v(morphkit::mesh::triangle_normal(
                            q,
                            p.b.triangles[fs[1] as usize],
                        ));
                        a.norm() > 0.0 && b.norm() > 0.0 && a.dot(&b) < -0.5 * a.norm() * b.norm()
                    };
                    if sharp(&y) && !sharp(&p.b.positions) {
                        n += 1;
                        for &t in fs {
                            let t = t as usize;
                            let c = fwd
                                .matches_of(t)
                                .iter()
                                .map(|&i| na[i as usize].dot(&nb[t]))
                                .fold(1.0, f64::min);
                            hist[if c < 0.0 {
                                0
                            } else if c < 0.5 {
                                1
                            } else if c < 0.9 {
                                2
                            } else {
                                3
                            }] += 1;
                            let ed = topo.edges()[e];
                            let yy = p.b.positions[ed[0] as usize][1];
                            let k =
                                (((yy - lo[1]) / (hi[1] - lo[1])) * 5.0).clamp(0.0, 4.99) as usize;
                            yb[k] += 1;
                        }
                    }
                }
                per_frame.push(n);
            }
            eprintln!(
                "  {frame:?}: sharp folds per frame {per_frame:?}; folded triangles by their matches' least rest-normal cosine <0 / <0.5 / <0.9 / ≥0.9: {hist:?}; by height (fifths, low to high): {yb:?}"
            );
        }
        // All target triangles, for comparison.
        let mut hist = [0usize; 4];
        for t in 0..p.b.num_triangles() {
            let c = fwd
                .matches_of(t)
                .iter()
                .map(|&i| na[i as usize].dot(&nb[t]))
                .fold(1.0, f64::min);
            hist[if c < 0.0 {
                0
            } else if c < 0.5 {
                1
            } else if c < 0.9 {
                2
            } else {
                3
            }] += 1;
        }
        eprintln!("  all target triangles by the same measure: {hist:?}");
    }
}

/// Measures any variants on both pairs, for tuning (prints, asserts nothing): `EXPLORE="r,w,c,radius,max[,wc/wc/…[,wi[,a[,l]]]];…"`
/// with r = 1 to refine, w = 1 for two-way, c = m(ean), n(earest) or i(nverse distance), the
/// radius factor, the most matches, the closest-point weights, the identity weight, `a`
/// for area-weighted solves and `l` for the local-stretch frame.
pub fn explore() {
    let spec = std::env::var("EXPLORE").unwrap_or_default();
    for item in spec.split(';').filter(|s| !s.is_empty()) {
        let f: Vec<&str> = item.split(',').collect();
        let mut refine = (f[0] == "1").then(morphkit::transfer::RefineOptions::default);
        if let Some(r) = refine.as_mut() {
            if let Some(w) = f.get(5) {
                r.closest_weights = w.split('/').map(|x| x.parse().unwrap()).collect();
            }
            if let Some(w) = f.get(6) {
                r.identity = w.parse().unwrap();
            }
        }
        let o = CorrespondenceOptions {
            refine,
            two_way: f[1] == "1",
            radius_factor: f[3].parse().unwrap(),
            max_matches: f[4].parse().unwrap(),
            ..Default::default()
        };
        let combine = match f[2] {
            "m" => morphkit::transfer::GradientCombine::Mean,
            "n" => morphkit::transfer::GradientCombine::Nearest,
            _ => morphkit::transfer::GradientCombine::InverseDistance,
        };
        let mut t = TransferOptions {
            combine,
            ..Default::default()
        };
        if f.get(7) == Some(&"a") {
            t.solver.weighting = morphkit::transfer::TriangleWeighting::Area;
        }
        if f.get(8) == Some(&"l") {
            t.frame = GradientFrame::LocalStretch;
        }
        eprintln!("== {item}");
        for p in [horse(), cat()].into_iter().flatten() {
            common::measure_with(&p, &o, t.clone());
        }
    }
}
