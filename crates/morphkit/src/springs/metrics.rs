//! Quality measures of a blend and the classic linear blend to compare with.
//!
//! All measures compare a blended shape with the *interpolated* intrinsic quantities: an edge's
//! target length is $\bar r_e = \sum_s c_s \ell_e^s$, a triangle's target area
//! $\bar A_t = \sum_s c_s A_t^s$, the target volume $\bar V = \sum_s c_s V^s$. A linear blend of
//! two shapes related by a large rotation shortens edges and loses area and volume (the paper's
//! Fig. 1c); a good physical blend keeps all three close to their targets.

use super::{BlendError, Weights};
use crate::mesh::{norm, sub, triangle_normal, Point, ShapeSet, Topology};

/// Quality of one blended shape.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BlendMetrics {
    /// RMS over edges of $(\ell_e - \bar r_e) / \bar r_e$.
    pub edge_length_rms: f64,
    /// Max over edges of $|\ell_e - \bar r_e| / \bar r_e$.
    pub edge_length_max: f64,
    /// RMS over triangles of $A_t / \bar A_t - 1$.
    pub area_rms: f64,
    /// Enclosed (signed) volume, for closed meshes.
    pub volume: Option<f64>,
    /// $V / \bar V$, for closed meshes.
    pub volume_ratio: Option<f64>,
}

/// The linear blendshape $\sum_s c_s x^s$ for the same weights.
pub fn linear_blend(shapes: &ShapeSet, weights: &Weights) -> Result<Vec<Point>, BlendError> {
    let c = weights.coefficients(shapes.len())?;
    let mut out = vec![[0.0; 3]; shapes.num_vertices()];
    for (s, &w) in c.iter().enumerate() {
        if w != 0.0 {
            for (o, p) in out.iter_mut().zip(shapes.positions(s)) {
                for a in 0..3 {
                    o[a] += w * p[a];
                }
            }
        }
    }
    Ok(out)
}

/// Measures `positions` against the targets interpolated with `weights`.
pub fn blend_metrics(
    shapes: &ShapeSet,
    topology: &Topology,
    weights: &Weights,
    positions: &[Point],
) -> Result<BlendMetrics, BlendError> {
    let c = weights.coefficients(shapes.len())?;
    let tiny = f64::MIN_POSITIVE * 1e10;
    let (mut sum2, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for &[i, j] in topology.edges() {
        let len = |p: &[Point]| norm(sub(p[i as usize], p[j as usize]));
        let r: f64 = c
            .iter()
            .enumerate()
            .map(|(s, w)| w * len(shapes.positions(s)))
            .sum();
        if r > tiny {
            let d = (len(positions) - r) / r;
            sum2 += d * d;
            max = max.max(d.abs());
            n += 1;
        }
    }
    let edge_length_rms = (sum2 / n.max(1) as f64).sqrt();
    let (mut a2, mut na) = (0.0, 0usize);
    for &t in shapes.triangles() {
        let area = |p: &[Point]| 0.5 * norm(triangle_normal(p, t));
        let target: f64 = c
            .iter()
            .enumerate()
            .map(|(s, w)| w * area(shapes.positions(s)))
            .sum();
        if target > tiny {
            let d = area(positions) / target - 1.0;
            a2 += d * d;
            na += 1;
        }
    }
    let (volume, volume_ratio) = if topology.is_closed() {
        let v = crate::mesh::enclosed_volume(positions, shapes.triangles());
        let target: f64 = c
            .iter()
            .enumerate()
            .map(|(s, w)| w * crate::mesh::enclosed_volume(shapes.positions(s), shapes.triangles()))
            .sum();
        (Some(v), (target.abs() > tiny).then(|| v / target))
    } else {
        (None, None)
    };
    Ok(BlendMetrics {
        edge_length_rms,
        edge_length_max: max,
        area_rms: (a2 / na.max(1) as f64).sqrt(),
        volume,
        volume_ratio,
    })
}

/// Fold, crease and distance measures of a blended shape (blend-design §2), each also
/// computed for the linear blend so that the two can be compared.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FoldMetrics {
    /// Triangles whose normal turns more than 120° away from their normal in *every* shape
    /// with a non-zero coefficient (a triangle that legitimately turns 170° between two shapes
    /// lags behind one of them, not both).
    pub folds: usize,
    /// The same count for the linear blend.
    pub folds_linear: usize,
    /// Interior edges whose signed dihedral angle is more than 30° off the blended angle
    /// (among those whose angle is well defined in every shape with a nonzero coefficient).
    pub creases: usize,
    /// The same count for the linear blend.
    pub creases_linear: usize,
    /// Largest distance of a vertex from its linear blend.
    pub max_from_linear: f64,
    /// Largest distance any vertex moves between two of the shapes in the blend (the base
    /// and every shape with a non-zero coefficient; all shapes at an endpoint).
    pub largest_move: f64,
}

/// Counts folds and creases of `positions` and of the linear blend for `weights`.
pub fn fold_metrics(
    shapes: &ShapeSet,
    topology: &Topology,
    weights: &Weights,
    positions: &[Point],
) -> Result<FoldMetrics, BlendError> {
    let c = weights.coefficients(shapes.len())?;
    let lin = linear_blend(shapes, weights)?;
    let active: Vec<usize> = (0..shapes.len()).filter(|&s| c[s] != 0.0).collect();
    let folds = |p: &[Point]| {
        shapes
            .triangles()
            .iter()
            .filter(|&&t| {
                let n = triangle_normal(p, t);
                let ln = norm(n);
                ln > 0.0
                    && active.iter().all(|&s| {
                        let m = triangle_normal(shapes.positions(s), t);
                        let lm = norm(m);
                        lm > 0.0 && crate::mesh::dot(n, m) < -0.5 * ln * lm
                    })
            })
            .count()
    };
    let hinges = super::terms::HingeTerm::new(
        shapes,
        topology,
        &super::terms::HingeOptions {
            weight: 1.0,
            ..Default::default()
        },
        1.0,
        1.0,
    );
    let target = hinges.blended_angles(&c);
    let creases = |p: &[Point]| {
        let x: Vec<f64> = p.iter().flatten().copied().collect();
        (0..hinges.len())
            .filter(|&k| {
                if !hinges.defined_at(k, &c) {
                    return false;
                }
                let mut d = hinges.angle_at(&x, k) - target[k];
                d -= std::f64::consts::TAU * (d / std::f64::consts::TAU).round();
                d.abs() > 30f64.to_radians()
            })
            .count()
    };
    let dist = |a: Point, b: Point| norm(sub(a, b));
    let max_from_linear = positions
        .iter()
        .zip(&lin)
        .fold(0.0f64, |m, (p, q)| m.max(dist(*p, *q)));
    let mut largest_move = 0.0f64;
    let mut involved = active.clone();
    if !involved.contains(&0) {
        involved.insert(0, 0);
    }
    if involved.len() < 2 {
        // One shape alone (an endpoint): measure against every shape of the set.
        involved = (0..shapes.len()).collect();
    }
    for (k, &s) in involved.iter().enumerate() {
        for &t in &involved[k + 1..] {
            for (p, q) in shapes.positions(s).iter().zip(shapes.positions(t)) {
                largest_move = largest_move.max(dist(*p, *q));
            }
        }
    }
    Ok(FoldMetrics {
        folds: folds(positions),
        folds_linear: folds(&lin),
        creases: creases(positions),
        creases_linear: creases(&lin),
        max_from_linear,
        largest_move,
    })
}
