//! Issue 9, diagnosis of the cycle-consistency error (horse → camel → horse, cat → dog →
//! cat). **A diagnostic, not a check**: it prints where the round trip's error comes from
//! (the checks are in `tests/transfer_quality_real_data.rs`). Run it with
//! `MORPHKIT_DATA=… cargo run --release -p morphkit --example cycle_diagnosis -- [diagnosis|variants|folds]`
//! (default `diagnosis`; `DIAG_DUMP=dir` also writes per-vertex error maps as CSV there).

#[path = "../tests/common/mod.rs"]
mod common;

use morphkit::io::{read_mesh, read_shape_set};
use morphkit::mesh::{Point, TriMesh};
use morphkit::transfer::{
    correspond, AnimationTransfer, Correspondence, CorrespondenceOptions, GradientFrame,
    GradientOperator, Markers, TransferOptions, TranslationMode,
};
use nalgebra::{Matrix3, Vector3};
use std::path::PathBuf;

struct Pair {
    name: &'static str,
    a_corr: TriMesh,
    a_ref: TriMesh,
    frames: Vec<Vec<Point>>,
    b: TriMesh,
    markers: Markers,
}

fn horse() -> Option<Pair> {
    let h = common::data_file("sumner-horse-camel/horse-reference.obj.gz")?;
    let c = common::data_file("sumner-horse-camel/camel-reference.obj.gz")?;
    let mk = common::data_file("sumner-horse-camel/markers-horse-camel.json")?;
    let horse = read_mesh(&h).unwrap();
    let dir = common::data_dir().unwrap().join("sumner-horse-camel");
    let paths: Vec<PathBuf> = (1..=10)
        .map(|i| dir.join(format!("horse-{i:02}.obj.gz")))
        .collect();
    let poses = read_shape_set(&paths).unwrap();
    Some(Pair {
        name: "horse",
        a_corr: horse.clone(),
        a_ref: horse,
        frames: poses.all_positions().to_vec(),
        b: read_mesh(&c).unwrap(),
        markers: Markers::read(&mk).unwrap(),
    })
}

fn cat() -> Option<Pair> {
    let cat = common::data_file("lowpoly-cat-dog/cat-reference.obj")?;
    let dog = common::data_file("lowpoly-cat-dog/dog-reference.obj")?;
    let mk = common::data_file("lowpoly-cat-dog/markers-cat-dog.json")?;
    let dir = common::data_dir().unwrap().join("lowpoly-cat-dog/cat-run");
    let paths: Vec<PathBuf> = (1..=36)
        .map(|i| dir.join(format!("cat-run-{i:02}.obj.gz")))
        .collect();
    let run = read_shape_set(&paths).unwrap();
    Some(Pair {
        name: "cat",
        a_corr: read_mesh(&cat).unwrap(),
        a_ref: run.mesh(0),
        frames: run.all_positions().to_vec(),
        b: read_mesh(&dog).unwrap(),
        markers: Markers::read(&mk).unwrap(),
    })
}

fn v(p: Point) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// Best similarity (`scale`, `rigid`: scale fixed at 1, `translation_only`) of `z` onto `f`;
/// returns the aligned copy of `z`.
fn align(z: &[Point], f: &[Point], mode: u8) -> Vec<Point> {
    let n = z.len() as f64;
    let cz = z.iter().map(|&p| v(p)).sum::<Vector3<f64>>() / n;
    let cf = f.iter().map(|&p| v(p)).sum::<Vector3<f64>>() / n;
    if mode == 0 {
        return z.iter().map(|&p| (v(p) - cz + cf).into()).collect();
    }
    let mut h = Matrix3::zeros();
    let mut var = 0.0;
    for (a, b) in z.iter().zip(f) {
        let (a, b) = (v(*a) - cz, v(*b) - cf);
        h += b * a.transpose();
        var += a.norm_squared();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut d = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * vt;
    let s = if mode == 2 {
        (svd.singular_values.component_mul(&d.diagonal())).sum() / var
    } else {
        1.0
    };
    z.iter()
        .map(|&p| (s * r * (v(p) - cz) + cf).into())
        .collect()
}

fn errs(z: &[Point], f: &[Point], d: f64) -> Vec<f64> {
    z.iter()
        .zip(f)
        .map(|(a, b)| (v(*a) - v(*b)).norm() / d)
        .collect()
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// The backward correspondence as the transpose of the forward one: each A triangle gets the
/// B triangles whose matches include it (same distances, nearest first); A triangles that no
/// B triangle matched keep `fallback`'s matches.
fn transpose(fwd: &Correspondence, fallback: &Correspondence) -> Correspondence {
    let mut lists: Vec<Vec<(f32, u32)>> = vec![Vec::new(); fwd.source_triangles];
    for t in 0..fwd.target_triangles {
        let (o0, o1) = (fwd.offsets[t] as usize, fwd.offsets[t + 1] as usize);
        for k in o0..o1 {
            lists[fwd.matches[k] as usize].push((fwd.distances[k], t as u32));
        }
    }
    let mut c = fallback.clone();
    c.offsets = vec![0];
    c.matches.clear();
    c.distances.clear();
    for (s, l) in lists.iter_mut().enumerate() {
        if l.is_empty() {
            let (o0, o1) = (
                fallback.offsets[s] as usize,
                fallback.offsets[s + 1] as usize,
            );
            l.extend((o0..o1).map(|k| (fallback.distances[k], fallback.matches[k])));
        }
        l.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        c.matches.extend(l.iter().map(|x| x.1));
        c.distances.extend(l.iter().map(|x| x.0));
        c.offsets.push(c.matches.len() as u32);
    }
    c
}

/// Rotation parts of the warps' gradients (forward source, forward target, backward source,
/// backward target), for the `warp` variant of [`map_polar_aligned`].
type Warps = (
    Vec<Matrix3<f64>>,
    Vec<Matrix3<f64>>,
    Vec<Matrix3<f64>>,
    Vec<Matrix3<f64>>,
);
static WARP: std::sync::Mutex<Option<Warps>> = std::sync::Mutex::new(None);

fn warp_rotations(reference: &TriMesh, warped: &[Point]) -> Vec<Matrix3<f64>> {
    GradientOperator::new(reference)
        .gradients(warped)
        .unwrap()
        .iter()
        .map(|m| polar(m).0)
        .collect()
}

struct Cycle {
    folds: usize,
    flipped: usize,
    raw: f64,
    trans: f64,
    rigid: f64,
    sim: f64,
    per_vertex: Vec<f64>,
}

/// The cycle of every frame with `fwd`/`bwd`; `solve_b = false` skips the solve on B (the
/// gradients are mapped A → B → A and solved on A only).
fn cycle(
    p: &Pair,
    fwd: &Correspondence,
    bwd: &Correspondence,
    topts: &TransferOptions,
    solve_b: bool,
    frames: &[Vec<Point>],
) -> Cycle {
    cycle_with(p, fwd, bwd, topts, u8::from(solve_b), frames, None)
}

/// Polar decomposition `M = R S` (R a rotation, S symmetric).
fn polar(m: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let svd = m.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut d = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * vt;
    (r, r.transpose() * m)
}

/// The nearest rotation to `m`.
fn project_rotation(m: &Matrix3<f64>) -> Matrix3<f64> {
    polar(m).0
}

/// The rotation taking unit `a` to unit `b` (identity when nearly opposite).
fn rotation_between(a: Vector3<f64>, b: Vector3<f64>) -> Matrix3<f64> {
    let k = a.cross(&b);
    let c = a.dot(&b);
    if c < -0.9 {
        return Matrix3::identity();
    }
    let kx = k.cross_matrix();
    Matrix3::identity() + kx + kx * kx / (1.0 + c)
}

/// Source and target reference unit normals, or rotations of the warps.
type Pairwise<'a, T> = (&'a [T], &'a [T]);
type Normals<'a> = Pairwise<'a, Vector3<f64>>;
type WarpRotations<'a> = Pairwise<'a, Matrix3<f64>>;

/// Combines matched gradients by their polar factors: the rotations' chordal mean
/// (projected sum) times the weighted mean of the stretches, each turned from its source
/// triangle's plane into the target triangle's when `normals` are given (the library's
/// `GradientFrame::LocalStretch`, re-implemented here to vary it).
fn map_polar_aligned(
    c: &Correspondence,
    g: &[Matrix3<f64>],
    idw: bool,
    normals: Option<Normals>,
    warp: Option<WarpRotations>,
) -> Vec<Matrix3<f64>> {
    let var = std::env::var("DIAG_VARIANT").unwrap_or_default();
    let noproj = var.contains("noproj");
    let cmin: f64 = var
        .split(',')
        .find_map(|x| x.strip_prefix("cmin="))
        .map_or(-0.9, |x| x.parse().unwrap());
    let noturn = var.contains("noturn");
    let nw: f64 = var
        .split(',')
        .find_map(|x| x.strip_prefix("nw="))
        .map_or(0.0, |x| x.parse().unwrap());
    let pol: Vec<(Matrix3<f64>, Matrix3<f64>)> = g.iter().map(polar).collect();
    (0..c.target_triangles)
        .map(|t| {
            let (o0, o1) = (c.offsets[t] as usize, c.offsets[t + 1] as usize);
            let m = &c.matches[o0..o1];
            let d = &c.distances[o0..o1];
            let exact = d.iter().take_while(|&&x| x == 0.0).count();
            let mut r = Matrix3::zeros();
            let mut s = Matrix3::zeros();
            let mut ws = 0.0;
            // Normal-agreement factors (all 1 when none agrees).
            let agree: Vec<f64> = m
                .iter()
                .map(|&i| match normals {
                    Some((ns, nt)) if nw > 0.0 => ns[i as usize].dot(&nt[t]).max(0.0).powf(nw),
                    _ => 1.0,
                })
                .collect();
            let any = agree.iter().any(|&a| a > 1e-6);
            for (k, (&i, &di)) in m.iter().zip(d).enumerate() {
                let w0 = if !idw {
                    1.0
                } else if exact > 0 {
                    if k < exact {
                        1.0
                    } else {
                        0.0
                    }
                } else {
                    1.0 / f64::from(di)
                };
                let w = if any { w0 * agree[k] } else { w0 };
                r += pol[i as usize].0 * w;
                let st = pol[i as usize].1;
                let st = match normals {
                    None => st,
                    Some((ns, nt)) => {
                        let (a, b) = (ns[i as usize], nt[t]);
                        if noturn || a.dot(&b) < cmin {
                            st
                        } else {
                            let q = match warp {
                                Some((fs, ft)) => ft[t].transpose() * fs[i as usize],
                                None => rotation_between(a, b),
                            };
                            q * st * q.transpose()
                        }
                    }
                };
                if noproj {
                    s += pol[i as usize].0 * st * w;
                } else {
                    s += st * w;
                }
                ws += w;
            }
            if noproj {
                s / ws
            } else {
                project_rotation(&r) * (s / ws)
            }
        })
        .collect()
}

fn cycle_with(
    p: &Pair,
    fwd: &Correspondence,
    bwd: &Correspondence,
    topts: &TransferOptions,
    solve_b: u8,
    frames: &[Vec<Point>],
    polar_idw: Option<bool>,
) -> Cycle {
    cycle_full(p, fwd, bwd, topts, solve_b, frames, polar_idw, false)
}

fn unit_normals(m: &TriMesh) -> Vec<Vector3<f64>> {
    (0..m.num_triangles())
        .map(|j| {
            let n = v(m.triangle_normal(j));
            if n.norm() > 0.0 {
                n.normalize()
            } else {
                n
            }
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn cycle_full(
    p: &Pair,
    fwd: &Correspondence,
    bwd: &Correspondence,
    topts: &TransferOptions,
    solve_b: u8,
    frames: &[Vec<Point>],
    polar_idw: Option<bool>,
    aligned: bool,
) -> Cycle {
    let (na, nbb) = (unit_normals(&p.a_ref), unit_normals(&p.b));
    // B's reference unit normals, for splitting a gradient into its tangential and normal
    // action (solve_b 2: tangential from the wanted gradients, normal from the solve; 3: the
    // other way round).
    let nb: Vec<Vector3<f64>> = (0..p.b.num_triangles())
        .map(|j| v(p.b.triangle_normal(j)).normalize())
        .collect();
    let tf = AnimationTransfer::new(&p.a_ref, &p.b, fwd, topts).unwrap();
    let tb = AnimationTransfer::new(&p.b, &p.a_ref, bwd, topts).unwrap();
    let d = p.a_ref.bbox_diagonal();
    let topo_b = morphkit::mesh::Topology::new(p.b.num_vertices(), &p.b.triangles);
    let mut c = Cycle {
        folds: 0,
        flipped: 0,
        raw: 0.0,
        trans: 0.0,
        rigid: 0.0,
        sim: 0.0,
        per_vertex: vec![0.0; p.a_ref.num_vertices()],
    };
    for f in frames {
        let map = |tr: &AnimationTransfer, c: &Correspondence, g: &[Matrix3<f64>], dir: bool| {
            match polar_idw {
                None => tr.target_gradients(g),
                Some(idw) => {
                    let nrm = if dir {
                        (&na[..], &nbb[..])
                    } else {
                        (&nbb[..], &na[..])
                    };
                    let w = WARP.lock().unwrap();
                    let warp = w.as_ref().map(|w| {
                        if dir {
                            (&w.0[..], &w.1[..])
                        } else {
                            (&w.2[..], &w.3[..])
                        }
                    });
                    map_polar_aligned(c, g, idw, aligned.then_some(nrm), warp)
                }
            }
        };
        let g = map(&tf, fwd, &tf.source_gradients(f).unwrap(), true);
        let y = tf.solve_gradients(&g, Some(f)).unwrap();
        c.folds += morphkit::transfer::sharp_folds(&p.b, &topo_b, &y);
        c.flipped += tf.flipped_triangles(&y, &g).len();
        let ty = tb.source_gradients(&y).unwrap();
        let gb: Vec<Matrix3<f64>> = match solve_b {
            0 => g.clone(),
            1 => ty,
            k => (0..g.len())
                .map(|j| {
                    let n = nb[j];
                    let pn = n * n.transpose();
                    let pt = Matrix3::identity() - pn;
                    if k == 2 {
                        g[j] * pt + ty[j] * pn
                    } else {
                        ty[j] * pt + g[j] * pn
                    }
                })
                .collect(),
        };
        let z = tb
            .solve_gradients(&map(&tb, bwd, &gb, false), Some(&y))
            .unwrap();
        c.raw += mean(&errs(&z, f, d));
        c.trans += mean(&errs(&align(&z, f, 0), f, d));
        c.rigid += mean(&errs(&align(&z, f, 1), f, d));
        let e = errs(&align(&z, f, 2), f, d);
        c.sim += mean(&e);
        for (a, b) in c.per_vertex.iter_mut().zip(&e) {
            *a += b / frames.len() as f64;
        }
    }
    let n = frames.len() as f64;
    c.raw /= n;
    c.trans /= n;
    c.rigid /= n;
    c.sim /= n;
    c
}

fn report(name: &str, c: &Cycle) {
    eprintln!(
        "  {name:<44} raw {:.4} %  translation-aligned {:.4} %  rigid-aligned {:.4} %  similarity-aligned {:.4} %  forward sharp folds {} flipped {}",
        100.0 * c.raw,
        100.0 * c.trans,
        100.0 * c.rigid,
        100.0 * c.sim,
        c.folds,
        c.flipped
    );
}

fn local() -> TransferOptions {
    TransferOptions {
        frame: GradientFrame::LocalStretch,
        ..Default::default()
    }
}

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
    let o = CorrespondenceOptions::default();
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

fn cycle_error_diagnosis() {
    for p in [horse(), cat()].into_iter().flatten() {
        diagnose(&p);
    }
}

/// Quick variants of the polar combine (`DIAG_VARIANT`: `noproj`, `cmin=…`), against the
/// world frame and the library default.
fn combine_variants() {
    for p in [horse(), cat()].into_iter().flatten() {
        eprintln!("== {}", p.name);
        let mut o = CorrespondenceOptions::default();
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
fn fold_locations() {
    for p in [horse(), cat()].into_iter().flatten() {
        eprintln!("== {}", p.name);
        let mut o = CorrespondenceOptions::default();
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

fn main() {
    if common::data_dir().is_none() {
        eprintln!("set MORPHKIT_DATA to the shared data directory");
        std::process::exit(2);
    }
    match std::env::args().nth(1).as_deref().unwrap_or("diagnosis") {
        "diagnosis" => cycle_error_diagnosis(),
        "variants" => combine_variants(),
        "folds" => fold_locations(),
        other => {
            eprintln!("unknown diagnostic '{other}': use diagnosis, variants or folds");
            std::process::exit(2);
        }
    }
}
