//! Issue 9, diagnosis of the cycle-consistency error (horse → camel → horse, cat → dog →
//! cat). **A diagnostic, not a check**: it prints where the round trip's error comes from
//! (the checks are in `tests/transfer_quality_real_data.rs`). Run it with
//! `MORPHKIT_DATA=… cargo run --release -p morphkit --example cycle_diagnosis -- [diagnosis|variants|folds|explore|heldout|foldwhere]`
//! (default `diagnosis`; `DIAG_DUMP=dir` also writes per-vertex error maps as CSV there;
//! `explore` measures the correspondence and transfer variants given in `EXPLORE`;
//! `heldout` and `foldwhere` the held-out animations and the stretch-turning variants, see
//! `heldout.rs`). Written before issue 40 changed the transfer defaults: its correspondences
//! and baselines name their options; other transfer settings it leaves unnamed follow the new
//! defaults (local stretch, area weights). The defaults' own study is
//! `examples/transfer_defaults_study.rs`.

#[path = "../../tests/common/mod.rs"]
mod common;
mod heldout;
mod studies;
mod turns;

use studies::{combine_variants, cycle_error_diagnosis, explore, fold_locations};

use morphkit::mesh::{Point, TriMesh};
use morphkit::transfer::{
    correspond, AnimationTransfer, Correspondence, CorrespondenceOptions, GradientFrame,
    GradientOperator, TransferOptions, TranslationMode,
};
use nalgebra::{Matrix3, Vector3};

use common::{cat_dog as cat, horse_camel as horse, Pair};

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

use morphkit::geom::polar_decomposition as polar;

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
/// triangle's plane into the target triangle's when `normals` are given (the combine of the
/// library's `GradientFrame::LocalStretch`, re-implemented here to vary it; `nw=1` weights
/// matches by max(0, n_s · n_t), as the library did before it took cos⁴(θ/2); the solves are
/// not confidence-weighted here).
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

fn main() {
    if common::data_dir().is_none() {
        eprintln!("set MORPHKIT_DATA to the shared data directory");
        std::process::exit(2);
    }
    match std::env::args().nth(1).as_deref().unwrap_or("diagnosis") {
        "diagnosis" => cycle_error_diagnosis(),
        "variants" => combine_variants(),
        "folds" => fold_locations(),
        "explore" => explore(),
        "heldout" => heldout::heldout(),
        "foldwhere" => heldout::fold_where(),
        other => {
            eprintln!("unknown diagnostic '{other}': use diagnosis, variants, folds, explore, heldout or foldwhere");
            std::process::exit(2);
        }
    }
}
