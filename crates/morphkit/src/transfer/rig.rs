//! Blendshape rig transfer: a neutral plus named expressions moved onto another character,
//! one deformation transfer per expression (Sumner & Popović 2004, Sec. 4; each expression is
//! one "frame" relative to the source neutral).
//!
//! **Alignment.** Deformation gradients are measured in world axes, so a target that is posed
//! differently (rotated, scaled) would receive the source's motion in the source's axes. The
//! source is therefore first mapped by the similarity $p \mapsto sR(p - \mu_s) + \mu_t$ that
//! best fits the source anchor vertices of the neutral onto the target's (Umeyama 1991;
//! anchors: the correspondence's markers, or every vertex for an identity correspondence;
//! $\det R = +1$; $s = \operatorname{tr}(\Sigma D) / \sum \|a - \mu_s\|^2$). Its gradients
//! become $R D R^\top$; for meshes that are already aligned, $R \approx I$ and nothing changes.
//!
//! **No root motion.** The neutral stays where it is: each expression is solved with the
//! constraint vertices fixed, then translated so that the target anchors' centroid moves from
//! its neutral position by the (aligned) source anchors' centroid displacement,
//! $\bar t(e) = \bar t(\text{neutral}) + sR\,(\bar s(e) - \bar s(\text{neutral}))$,
//! **per connected component** of the target (a head's eyes, teeth and tongue are separate
//! parts; each is placed by its own anchors, a component without anchors by all of them), so
//! that no part drifts with its constraint vertex. The source neutral itself maps to the
//! target neutral exactly (its gradients are the identity).
//! Morph-target deltas are then the transferred expression minus the target neutral.

use super::animation::{AnimationTransfer, TransferOptions, TranslationMode};
use super::correspondence::{Correspondence, CorrespondenceOptions};
use super::error::{Side, TransferError};
use super::quality::{sharp_folds, FoldCount};
use crate::mesh::{validate, Point, ShapeSet, Topology, TriMesh};
use nalgebra::{Matrix3, Vector3};

/// Options of [`RigTransfer`].
#[derive(Clone, Debug)]
pub struct RigOptions {
    /// Transfer options (triangle weights, constraint vertices, gradient combination). The
    /// translation mode is ignored: a rig uses the no-root-motion convention of the
    /// [module docs](self). Default: the world frame and uniform weights, the
    /// [`TransferOptions`] defaults before issue 40 (its study of the defaults measured
    /// animations between characters, not rigs).
    pub transfer: TransferOptions,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            transfer: TransferOptions {
                solver: super::solve::SolverOptions::default(),
                frame: super::animation::GradientFrame::World,
                ..Default::default()
            },
        }
    }
}

impl RigOptions {
    /// The options a rig's correspondence is computed with from markers (`morphkit rig
    /// --markers`; [`RigTransfer`] itself takes a finished correspondence): the
    /// [`CorrespondenceOptions`] defaults without the closest-point refinement. Issue 40 made
    /// the refinement the default of animation transfer, but on the ICT head onto a rotated,
    /// scaled copy of itself (a known answer) it raised the largest error of cheekPuff_L from
    /// under 0.2 % to 6.9 % of its motion (tests/transfer_rig_real_data.rs).
    pub fn correspondence() -> CorrespondenceOptions {
        CorrespondenceOptions {
            refine: None,
            ..CorrespondenceOptions::default()
        }
    }
}

/// One transferred expression.
#[derive(Clone, Debug)]
pub struct TransferredShape {
    /// Name of the source expression.
    pub name: String,
    /// Target positions (#V_t), absolute.
    pub positions: Vec<Point>,
    /// Fold counts ([`super::quality`]).
    pub folds: FoldCount,
}

/// The best similarity $(s, R, \mu_s, \mu_t)$ taking points `a` onto points `b`.
fn similarity(a: &[Point], b: &[Point]) -> (f64, Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let n = a.len().max(1) as f64;
    let ma = a.iter().map(|p| Vector3::from(*p)).sum::<Vector3<f64>>() / n;
    let mb = b.iter().map(|p| Vector3::from(*p)).sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    let mut var = 0.0;
    for (p, q) in a.iter().zip(b) {
        let (x, y) = (Vector3::from(*p) - ma, Vector3::from(*q) - mb);
        h += y * x.transpose();
        var += x.norm_squared();
    }
    if var.is_nan() || var <= 0.0 || !h.iter().all(|x| x.is_finite()) {
        return (1.0, Matrix3::identity(), ma, mb);
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return (1.0, Matrix3::identity(), ma, mb);
    };
    let d = if (u * vt).determinant() < 0.0 {
        -1.0
    } else {
        1.0
    };
    let dm = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d));
    let r = u * dm * vt;
    let sv = svd.singular_values;
    let s = (sv[0] + sv[1] + d * sv[2]) / var;
    if s.is_nan() || s <= 0.0 || !s.is_finite() {
        return (1.0, r, ma, mb);
    }
    (s, r, ma, mb)
}

/// `p` mapped by $q \mapsto sR(q - \mu_s) + \mu_t$.
fn align(p: &[Point], s: f64, r: &Matrix3<f64>, ms: Vector3<f64>, mt: Vector3<f64>) -> Vec<Point> {
    p.iter()
        .map(|q| (s * (r * (Vector3::from(*q) - ms)) + mt).into())
        .collect()
}

/// Centroid of side `side` (0 source, 1 target) of the anchor pairs in `p`.
fn anchor_centroid(anchors: &[[u32; 2]], p: &[Point], side: usize) -> Vector3<f64> {
    let n = anchors.len().max(1) as f64;
    anchors
        .iter()
        .map(|a| Vector3::from(p[a[side] as usize]))
        .sum::<Vector3<f64>>()
        / n
}

/// A rig transfer set up once for a source neutral, a target and their correspondence.
#[derive(Debug)]
pub struct RigTransfer {
    transfer: AnimationTransfer,
    target: TriMesh,
    topology: Topology,
    scale: f64,
    rotation: Matrix3<f64>,
    source_center: Vector3<f64>,
    target_center: Vector3<f64>,
    /// Per target component: its anchor pairs (all anchors when it has none).
    component_anchors: Vec<Vec<[u32; 2]>>,
    /// Per target component: the aligned source and the target anchor centroids of the neutral.
    component_neutral: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Target component of every target vertex.
    component: Vec<u32>,
    source_vertices: usize,
}

impl RigTransfer {
    /// Validates the meshes against `correspondence`, aligns the source neutral onto the
    /// target ([module docs](self)) and factors the target's transfer matrix.
    pub fn new(
        source_neutral: &TriMesh,
        target: &TriMesh,
        correspondence: &Correspondence,
        opts: &RigOptions,
    ) -> Result<Self, TransferError> {
        validate(source_neutral).map_err(|source| TransferError::Mesh {
            side: Side::Source,
            source,
        })?;
        correspondence.check(source_neutral, target)?;
        let anchors = correspondence.anchor_pairs();
        let a: Vec<Point> = anchors
            .iter()
            .map(|p| source_neutral.positions[p[0] as usize])
            .collect();
        let b: Vec<Point> = anchors
            .iter()
            .map(|p| target.positions[p[1] as usize])
            .collect();
        let (scale, rotation, source_center, target_center) = similarity(&a, &b);
        let aligned = align(
            &source_neutral.positions,
            scale,
            &rotation,
            source_center,
            target_center,
        );
        // The transfer is built on the aligned neutral (the gradients' reference).
        let transfer = AnimationTransfer::new(
            &source_neutral.with_positions(aligned.clone()),
            target,
            correspondence,
            &TransferOptions {
                translation: TranslationMode::FixedVertex,
                ..opts.transfer.clone()
            },
        )?;
        let topology = Topology::new(target.num_vertices(), &target.triangles);
        let component = topology.components().to_vec();
        let mut component_anchors = vec![Vec::new(); topology.num_components()];
        for a in &anchors {
            component_anchors[component[a[1] as usize] as usize].push(*a);
        }
        for c in &mut component_anchors {
            if c.is_empty() {
                c.clone_from(&anchors);
            }
        }
        let component_neutral = component_anchors
            .iter()
            .map(|a| {
                (
                    anchor_centroid(a, &aligned, 0),
                    anchor_centroid(a, &target.positions, 1),
                )
            })
            .collect();
        Ok(Self {
            transfer,
            target: target.clone(),
            topology,
            scale,
            rotation,
            source_center,
            target_center,
            component_anchors,
            component_neutral,
            component,
            source_vertices: source_neutral.num_vertices(),
        })
    }

    /// Scale $s$ of the source → target alignment.
    pub fn alignment_scale(&self) -> f64 {
        self.scale
    }

    /// Rotation $R$ of the source → target alignment.
    pub fn alignment_rotation(&self) -> Matrix3<f64> {
        self.rotation
    }

    /// The prefactored transfer (on the aligned source neutral).
    pub fn transfer(&self) -> &AnimationTransfer {
        &self.transfer
    }

    /// Transfers expression number `index` (positions over the source neutral's connectivity,
    /// checked by vertex count; errors name `index`).
    pub fn transfer_shape(
        &self,
        index: usize,
        shape: &[Point],
    ) -> Result<(Vec<Point>, FoldCount), TransferError> {
        if shape.len() != self.source_vertices {
            return Err(TransferError::FrameVertexCount {
                frame: index,
                expected: self.source_vertices,
                found: shape.len(),
            });
        }
        if let Some(v) = shape.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(TransferError::NonFinite {
                what: "source shape vertex",
                index: v,
            });
        }
        let aligned = align(
            shape,
            self.scale,
            &self.rotation,
            self.source_center,
            self.target_center,
        );
        let (mut x, g, _) = self
            .transfer
            .transfer_gradients(&self.transfer.source_gradients_at(index, &aligned)?, None)?;
        let shifts: Vec<Vector3<f64>> = self
            .component_anchors
            .iter()
            .zip(&self.component_neutral)
            .map(|(a, (s0, t0))| {
                t0 + (anchor_centroid(a, &aligned, 0) - s0) - anchor_centroid(a, &x, 1)
            })
            .collect();
        for (p, &c) in x.iter_mut().zip(&self.component) {
            let d = shifts[c as usize];
            for k in 0..3 {
                p[k] += d[k];
            }
        }
        let folds = FoldCount {
            flipped: self.transfer.flipped_triangles(&x, &g).len(),
            sharp_folds: sharp_folds(&self.target, &self.topology, &x),
        };
        Ok((x, folds))
    }
}

/// One-shot rig transfer: every shape of `shapes` (expressions over `source_neutral`'s
/// connectivity, names kept, order kept) onto `target`.
pub fn transfer_rig(
    source_neutral: &TriMesh,
    shapes: &ShapeSet,
    target: &TriMesh,
    correspondence: &Correspondence,
    opts: &RigOptions,
) -> Result<Vec<TransferredShape>, TransferError> {
    let rt = RigTransfer::new(source_neutral, target, correspondence, opts)?;
    rt.transfer.check_frames(shapes)?;
    (0..shapes.len())
        .map(|i| {
            let (positions, folds) = rt.transfer_shape(i, shapes.positions(i))?;
            Ok(TransferredShape {
                name: shapes.name(i).to_string(),
                positions,
                folds,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::testmesh::sphere;
    use nalgebra::Rotation3;

    fn bump(m: &TriMesh, amount: f64) -> Vec<Point> {
        m.positions
            .iter()
            .map(|p| {
                let w = (p[2] - 0.5).max(0.0);
                [p[0] * (1.0 + amount * w), p[1], p[2] + amount * w * p[0]]
            })
            .collect()
    }

    #[test]
    fn the_neutral_stays_put_and_a_rotated_scaled_copy_gets_rotated_scaled_shapes() {
        let m = sphere(16, 10, 1.0);
        let shapes = ShapeSet::new(
            m.clone(),
            vec![
                ("neutral".into(), m.positions.clone()),
                ("bump".into(), bump(&m, 0.4)),
            ],
        )
        .unwrap();
        let r = *Rotation3::from_euler_angles(0.4, -1.1, 2.0).matrix();
        let (s, t) = (2.5, Vector3::new(1.0, -2.0, 0.5));
        let map = |p: &Point| -> Point { (s * (r * Vector3::from(*p)) + t).into() };
        let target = m.with_positions(m.positions.iter().map(map).collect());
        let c = Correspondence::identity(&m);
        let out = transfer_rig(&m, &shapes, &target, &c, &RigOptions::default()).unwrap();
        assert_eq!(out[0].name, "neutral");
        assert_eq!(out[1].name, "bump");
        let d = target.bbox_diagonal();
        for (a, b) in out[0].positions.iter().zip(&target.positions) {
            assert!(crate::mesh::norm(crate::mesh::sub(*a, *b)) < 1e-9 * d);
        }
        for (a, b) in out[1].positions.iter().zip(shapes.positions(1)) {
            let want = map(b);
            assert!(
                crate::mesh::norm(crate::mesh::sub(*a, want)) < 1e-9 * d,
                "{a:?} vs {want:?}"
            );
        }
        assert_eq!(out[1].folds.flipped, 0);
        let rt = RigTransfer::new(&m, &target, &c, &RigOptions::default()).unwrap();
        assert!((rt.alignment_scale() - s).abs() < 1e-12);
        assert!((rt.alignment_rotation() - r).norm() < 1e-12);
        assert!(matches!(
            rt.transfer_shape(3, &m.positions[1..]),
            Err(TransferError::FrameVertexCount { frame: 3, .. })
        ));
    }
}
