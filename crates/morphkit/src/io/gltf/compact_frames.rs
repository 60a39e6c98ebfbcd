//! A frame sequence as a compact clip (issue 56): `K ≪ F` morph targets and an `F × K` weight
//! track, within a tolerance on every vertex of every frame, instead of one target per frame.
//!
//! A long sequence (a 2 100-frame blend, a minute of capture) written one target per frame
//! costs `F · #V · 24` bytes and passes what a WebGL2 viewer holds in one mesh (200 targets),
//! so it is split into meshes shown in turn. Its frames are smooth in time, so a few shapes
//! span their displacements from frame 0: the shapes are [`crate::clip::residual_basis`] of
//! those displacements (the truncated SVD, taken until the largest vertex error of any frame
//! is within the tolerance), stored as `f32` targets, and each frame's key holds its
//! coefficients. glTF interpolates key weights linearly, so between two keys a viewer shows
//! the linear interpolation of the two rebuilt frames, as it does between one-hot keys.
//!
//! **Normals.** A frame's vertex normals are not linear in its positions, so each target's
//! `NORMAL` deltas are fitted to the frames rather than taken from the target's own shape:
//! the least-squares `N` of `Σ_f ‖(n_f − n_0) − Σ_k c_fk N_k‖²` over the frames' unit vertex
//! normals `n_f` (the `K × K` normal equations `CᵀC N = Cᵀ ΔN`). A viewer normalises the
//! interpolated normal, so a frame shades as its own normals do, up to the fit's residual.

use super::normals::vertex_normals;
use super::write::{build_with_normals, finish, write_document};
use super::{GltfMorphs, GltfOptions, GltfSummary};
use crate::clip::{residual_basis, ClipError};
use crate::io::IoError;
use crate::mesh::{Point, ShapeSet};
use nalgebra::DMatrix;
use std::path::Path;

/// How a glTF animation of a frame sequence is laid out ([`GltfOptions::layout`],
/// [`choose_layout`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum FrameLayout {
    /// A compact clip within [`crate::clip::DEFAULT_TOLERANCE`] of the diagonal when the
    /// sequence has more frames than [`GltfOptions::max_targets`] (nonzero), which one target
    /// per frame would split into meshes shown in turn; otherwise one target per frame.
    #[default]
    Auto,
    /// One morph target per frame, each frame exact as `f32`.
    PerFrame,
    /// A compact clip within this fraction of the diagonal, whatever the length.
    Compact(f64),
}

/// The most floating-point operations a compact clip may take by default
/// ([`FrameLayout::Auto`]): about 4e10, some seconds. The shapes' SVD forms the smaller Gram
/// matrix of the `F × 3V` frames and decomposes it, about `min² · max + min³` operations for
/// `min`, `max` the smaller and larger of `F` and `3V`; a 2 100-frame sequence of 420 vertices
/// is 3.3e9, 1 800 frames of 26 719 vertices 2.6e11 (and the frames twice more in memory).
/// Past it a sequence keeps one target per frame unless a tolerance is given; a compact clip
/// asked for then takes its directions in blocks ([`crate::clip::EXACT_FLOPS`]), whose work
/// grows with the shapes it needs (335 frames of that head: 16.8 s instead of 35.6 s).
/// The default stays on the Gram matrix's estimate, so what it compacts is unchanged.
pub const AUTO_COMPACT_FLOPS: f64 = 4e10;

/// [`AUTO_COMPACT_FLOPS`]'s estimate for `frames` frames of `vertices` vertices.
fn basis_flops(frames: usize, vertices: usize) -> f64 {
    let (a, b) = (frames as f64, 3.0 * vertices as f64);
    let (small, large) = (a.min(b), a.max(b));
    small * small * large + small.powi(3)
}

/// What [`choose_layout`] chose.
#[derive(Clone, Debug)]
pub enum Layout {
    /// One morph target per frame, and why, where a compact clip was asked for or due and
    /// could not be made within the tolerance and the target budget.
    PerFrame(Option<String>),
    /// A compact clip, and its tolerance as a fraction of frame 0's bounding-box diagonal.
    Compact(Box<CompactFrames>, f64),
}

/// The layout of `frames` as a glTF animation at `fps` written with `opts`
/// ([`GltfOptions::layout`]). A compact clip has at most `max_targets` shapes (when nonzero)
/// and fewer than the frames' own targets, else the frames keep one target each. Quantized
/// ([`GltfOptions::quantize`]), the writer rounds each shape again (at most 2.7e-5 of the
/// diagonal a coordinate), so the basis is taken within three quarters of the tolerance.
pub fn choose_layout(frames: &ShapeSet, fps: f64, opts: &GltfOptions) -> Layout {
    let max = opts.max_targets;
    let relative = match opts.layout {
        FrameLayout::PerFrame => return Layout::PerFrame(None),
        FrameLayout::Compact(t) => t,
        FrameLayout::Auto if max != 0 && frames.len().saturating_sub(1) > max => {
            let cost = basis_flops(frames.len(), frames.num_vertices());
            if cost > AUTO_COMPACT_FLOPS {
                return Layout::PerFrame(Some(format!(
                    "{} frames of {} vertices are too many to compact by default (about {:.0e} \
                     operations for the shapes); written with one target per frame (ask for a \
                     compact clip with a tolerance: --clip-tolerance)",
                    frames.len(),
                    frames.num_vertices(),
                    cost
                )));
            }
            crate::clip::DEFAULT_TOLERANCE
        }
        FrameLayout::Auto => return Layout::PerFrame(None),
    };
    let diagonal = frames.base().bbox_diagonal();
    if !(diagonal > 0.0 && diagonal.is_finite()) || frames.len() < 3 {
        return Layout::PerFrame(None);
    }
    let mut most = frames.len() - 2;
    if max != 0 {
        most = most.min(max);
    }
    let share = if opts.quantize { 0.75 } else { 1.0 };
    match compact_frames(frames, fps, relative * diagonal * share, most) {
        Ok(c) if c.morphs.targets.is_empty() => Layout::PerFrame(None),
        Ok(c) => Layout::Compact(Box::new(c), relative),
        Err(ClipError::TooManyShapes { error, .. }) => Layout::PerFrame(Some(format!(
            "a compact clip within {relative:.1e} of the diagonal would need more than {most} \
             morph targets (with {most}, a frame stays {:.2e} off); written with one target \
             per frame",
            error / diagonal
        ))),
        Err(e) => Layout::PerFrame(Some(format!(
            "no compact clip ({e}); written with one target per frame"
        ))),
    }
}

/// A frame sequence as `K` shapes and their per-frame coefficients ([`compact_frames`]).
#[derive(Clone, Debug)]
pub struct CompactFrames {
    /// The rig a viewer plays: the base is frame 0 (over shape 0's connectivity), target `k`
    /// is frame 0 plus shape `k` (named `clip_00`, …), and key `i` at `i / fps` seconds holds
    /// frame `i`'s `K` coefficients.
    pub morphs: GltfMorphs,
    /// Per target, the fitted `NORMAL` deltas (`K × #V`; see the module documentation).
    pub normal_deltas: Vec<Vec<Point>>,
    /// The largest distance, over every vertex of every frame, between a frame and what the
    /// stored (`f32`) shapes and coefficients rebuild, in the frames' units.
    pub max_error: f64,
    /// The frame where [`CompactFrames::max_error`] is reached.
    pub worst_frame: usize,
}

/// `frames` as a compact clip keyed at `i / fps` seconds: the fewest shapes (at most
/// `max_shapes`) that bring every vertex of every frame within `tolerance` (a distance in the
/// frames' units) of its displacement from frame 0. A sequence whose frames all equal frame 0
/// gives no target and no key.
///
/// Errors: those of [`crate::clip::residual_basis`] (a non-finite coordinate, a tolerance that
/// is not a finite positive number, more than `max_shapes` shapes needed).
pub fn compact_frames(
    frames: &ShapeSet,
    fps: f64,
    tolerance: f64,
    max_shapes: usize,
) -> Result<CompactFrames, ClipError> {
    let first = frames.positions(0);
    let displacements: Vec<Vec<Point>> = (0..frames.len())
        .map(|i| {
            frames
                .positions(i)
                .iter()
                .zip(first)
                .map(|(p, q)| [p[0] - q[0], p[1] - q[1], p[2] - q[2]])
                .collect()
        })
        .collect();
    let basis = residual_basis(&displacements, tolerance, max_shapes)?;
    let base = frames.base().with_positions(first.to_vec());
    let k = basis.shapes.len();
    let targets: Vec<Vec<Point>> = basis
        .shapes
        .iter()
        .map(|s| {
            first
                .iter()
                .zip(s)
                .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                .collect()
        })
        .collect();
    let weight_keys = if k == 0 {
        Vec::new()
    } else {
        basis
            .coefficients
            .iter()
            .enumerate()
            .map(|(i, c)| (i as f64 / fps, c.clone()))
            .collect()
    };
    let normal_deltas = fitted_normal_deltas(frames, &basis.coefficients, k);
    Ok(CompactFrames {
        morphs: GltfMorphs {
            base,
            target_names: (0..k).map(|j| format!("clip_{j:02}")).collect(),
            targets,
            weight_keys,
        },
        normal_deltas,
        max_error: basis.max_error,
        worst_frame: basis.worst_frame,
    })
}

/// The least-squares normal deltas of `k` shapes with per-frame `coefficients` (`F × k`): see
/// the module documentation. Zero deltas where the normal equations are singular (a shape no
/// frame uses, which the basis never gives).
fn fitted_normal_deltas(frames: &ShapeSet, coefficients: &[Vec<f64>], k: usize) -> Vec<Vec<Point>> {
    let nv = frames.num_vertices();
    if k == 0 {
        return Vec::new();
    }
    let triangles = frames.triangles();
    let n0 = vertex_normals(frames.positions(0), triangles);
    let mut gram = DMatrix::<f64>::zeros(k, k);
    let mut rhs = DMatrix::<f64>::zeros(k, 3 * nv);
    for (f, c) in coefficients.iter().enumerate() {
        for a in 0..k {
            for b in 0..k {
                gram[(a, b)] += c[a] * c[b];
            }
        }
        if c.iter().all(|&x| x == 0.0) {
            continue;
        }
        let n = vertex_normals(frames.positions(f), triangles);
        for (v, (p, q)) in n.iter().zip(&n0).enumerate() {
            for d in 0..3 {
                let dn = p[d] - q[d];
                if dn != 0.0 {
                    for a in 0..k {
                        rhs[(a, 3 * v + d)] += c[a] * dn;
                    }
                }
            }
        }
    }
    let Some(chol) = gram.cholesky() else {
        return vec![vec![[0.0; 3]; nv]; k];
    };
    let sol = chol.solve(&rhs);
    (0..k)
        .map(|a| {
            (0..nv)
                .map(|v| [sol[(a, 3 * v)], sol[(a, 3 * v + 1)], sol[(a, 3 * v + 2)]])
                .collect()
        })
        .collect()
}

/// Writes a compact clip to `path` atomically with `opts`, as [`super::write_gltf_with`]
/// writes a rig, each target's normal deltas the fitted ones
/// ([`CompactFrames::normal_deltas`]).
///
/// Errors: those of [`super::write_gltf_with`].
pub fn write_compact_frames_with(
    path: &Path,
    clip: &CompactFrames,
    opts: &GltfOptions,
) -> Result<GltfSummary, IoError> {
    let normals =
        (opts.normals && !clip.normal_deltas.is_empty()).then_some(clip.normal_deltas.as_slice());
    let (doc, b, summary) = build_with_normals(path, &clip.morphs, opts, normals)?;
    let (doc, bin) = finish(doc, b, opts);
    write_document(path, doc, &bin)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{read_gltf_morphs, GltfOptions};
    use crate::mesh::generate;

    /// A tube bending back and forth and swelling at its own pace: `n` frames whose
    /// displacements need more than one shape.
    fn sequence(n: usize) -> ShapeSet {
        let tube = generate::tube(0.3, 4.0, 12, 24, false);
        let shapes = (0..n)
            .map(|i| {
                let t = i as f64 / (n - 1) as f64;
                let angle = 2.0 * (std::f64::consts::PI * 2.0 * t).sin();
                let mut p = generate::bend(&tube.positions, 1.0, 2.5, angle);
                let swell = 1.0 + 0.2 * (std::f64::consts::PI * 3.0 * t).sin().powi(2);
                for q in &mut p {
                    q[0] *= swell;
                }
                (format!("f{i:03}"), p)
            })
            .collect();
        ShapeSet::new(tube, shapes).unwrap()
    }

    fn angle(a: Point, b: Point) -> f64 {
        let la = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let lb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
        ((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb))
            .clamp(-1.0, 1.0)
            .acos()
    }

    #[test]
    fn a_long_sequence_plays_within_its_tolerance_from_a_few_targets() {
        let frames = sequence(120);
        let diag = frames.base().bbox_diagonal();
        let tol = 1e-3 * diag;
        let c = compact_frames(&frames, 30.0, tol, 50).unwrap();
        let k = c.morphs.targets.len();
        assert!((2..20).contains(&k), "{k} shapes for a bend and a swell");
        assert!(c.max_error <= tol);
        let dir = std::env::temp_dir().join(format!("mk-compact-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("clip.glb");
        write_compact_frames_with(&path, &c, &GltfOptions::default()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // What a reader plays, key by key, is the frame within the tolerance.
        let rig = read_gltf_morphs(&path).unwrap();
        assert_eq!(rig.weight_keys.len(), 120);
        assert_eq!(rig.targets.len(), k);
        for (i, (t, w)) in rig.weight_keys.iter().enumerate() {
            assert!((t - i as f64 / 30.0).abs() < 1e-6);
            let e = crate::geom::max_distance(&rig.evaluate(w), frames.positions(i));
            assert!(e <= tol * 1.0001, "frame {i}: {e} > {tol}");
        }
        // The fitted normal deltas shade each frame as its own normals do; the targets' own
        // normals, added at the same weights, do not.
        let tris = frames.triangles();
        let n0 = vertex_normals(frames.positions(0), tris);
        let own: Vec<Vec<Point>> = c
            .morphs
            .targets
            .iter()
            .map(|t| {
                let n = vertex_normals(t, tris);
                n.iter()
                    .zip(&n0)
                    .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                    .collect()
            })
            .collect();
        let worst = |deltas: &[Vec<Point>]| {
            let mut worst = 0.0f64;
            for (i, (_, w)) in c.morphs.weight_keys.iter().enumerate() {
                let truth = vertex_normals(frames.positions(i), tris);
                for v in 0..truth.len() {
                    let mut n = n0[v];
                    for (wk, d) in w.iter().zip(deltas) {
                        for a in 0..3 {
                            n[a] += wk * d[v][a];
                        }
                    }
                    worst = worst.max(angle(n, truth[v]));
                }
            }
            worst.to_degrees()
        };
        let (fitted, naive) = (worst(&c.normal_deltas), worst(&own));
        eprintln!("{k} shapes; normals off by {fitted:.2}° fitted, {naive:.2}° from the targets");
        assert!(
            fitted < 10.0 && fitted < naive,
            "fitted {fitted}°, own {naive}°"
        );
        // Same frames, same bytes.
        let again = compact_frames(&frames, 30.0, tol, 50).unwrap();
        write_compact_frames_with(&path, &again, &GltfOptions::default()).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn write_frames_lays_out_a_long_sequence_compactly_unless_told_otherwise() {
        let frames = sequence(60);
        let dir = std::env::temp_dir().join(format!("mk-layout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.glb");
        let write = |layout: FrameLayout, max_targets: usize| {
            let opts = crate::io::FramesOptions {
                gltf: GltfOptions {
                    layout,
                    max_targets,
                    ..GltfOptions::default()
                },
                ..Default::default()
            };
            crate::io::write_frames(&path, &frames, &opts).unwrap();
            read_gltf_morphs(&path).unwrap().targets.len()
        };
        // Longer than the budget: compact by default, one target a frame when asked.
        let compact = write(FrameLayout::Auto, 20);
        assert!((2..=20).contains(&compact), "{compact}");
        assert_eq!(
            write(FrameLayout::PerFrame, 20),
            58,
            "the last frame equals frame 0"
        );
        // Within the budget: exact by default, compact when a tolerance is given.
        assert_eq!(write(FrameLayout::Auto, 200), 58);
        assert_eq!(write(FrameLayout::Compact(1e-3), 200), compact);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_default_compacts_what_takes_seconds_not_minutes() {
        // The 2 100-frame tube of the README and a minute of a 2.7k-vertex face capture are
        // compacted by default; 4 000 frames of 4 096 vertices (a cli_interrupts test) or
        // 1 800 of the 26 719-vertex ICT head are not.
        assert!(basis_flops(2100, 420) < AUTO_COMPACT_FLOPS);
        assert!(basis_flops(1800, 2694) < AUTO_COMPACT_FLOPS);
        assert!(basis_flops(4000, 4096) > AUTO_COMPACT_FLOPS);
        assert!(basis_flops(1800, 26719) > AUTO_COMPACT_FLOPS);
    }

    #[test]
    fn a_still_sequence_has_no_target_and_a_short_budget_is_refused() {
        let tube = generate::tube(0.3, 4.0, 8, 8, false);
        let still = ShapeSet::new(
            tube.clone(),
            (0..5)
                .map(|i| (format!("f{i}"), tube.positions.clone()))
                .collect(),
        )
        .unwrap();
        let c = compact_frames(&still, 24.0, 1e-6, 4).unwrap();
        assert!(c.morphs.targets.is_empty() && c.morphs.weight_keys.is_empty());
        let frames = sequence(40);
        let e = compact_frames(&frames, 24.0, 1e-9, 1).unwrap_err();
        assert!(
            matches!(e, ClipError::TooManyShapes { max_shapes: 1, .. }),
            "{e}"
        );
    }
}
