//! The correspondence file: a target-triangle → source-triangles map in CSR form, its JSON
//! form and its structural validation.

use super::super::error::{CorrespondenceError, Side, TransferError};
use super::{GradientCombine, MarkerResidual, RefineStep};
use crate::mesh::TriMesh;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The `format` tag of correspondence files.
pub const FORMAT: &str = "morphkit-correspondence";
/// The current correspondence file version.
pub const VERSION: u32 = 1;

/// A reusable target-triangle → source-triangles map, saved as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Correspondence {
    /// Always [`FORMAT`].
    pub format: String,
    /// File version, [`VERSION`].
    pub version: u32,
    /// Source vertex count.
    pub source_vertices: usize,
    /// Source triangle count.
    pub source_triangles: usize,
    /// Target vertex count.
    pub target_vertices: usize,
    /// Target triangle count.
    pub target_triangles: usize,
    /// True for the identity correspondence (same mesh: target triangle `t` ↔ source `t`,
    /// vertex `v` ↔ vertex `v`).
    pub identity: bool,
    /// The marker pairs it was computed from (empty for the identity).
    pub markers: Vec<[u32; 2]>,
    /// Centroid radius used, in the warped meshes' units.
    pub radius: f64,
    /// ω used.
    pub omega: f64,
    /// CSR offsets, `#F_t + 1`: target triangle `t` matches
    /// `matches[offsets[t]..offsets[t + 1]]`, nearest first, never empty.
    pub offsets: Vec<u32>,
    /// Source triangle indices.
    pub matches: Vec<u32>,
    /// Target triangles whose only match fails the normal test (or whose warped normal is
    /// zero): places that need more markers.
    pub normal_violations: Vec<u32>,
    /// Per marker, its residual after warping.
    pub marker_residuals: Vec<MarkerResidual>,
    /// Centroid distance of every match (parallel to `matches`, in the matching space), for
    /// [`GradientCombine::InverseDistance`]; `f32` (weights need no more; horse → camel: 4.9 MB
    /// against 1.7 MB without distances, 7.2 MB with `f64`); empty in files written
    /// before it existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub distances: Vec<f32>,
    /// The closest-point refinement steps, empty when it was off.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub refinement: Vec<RefineStep>,
}

impl Correspondence {
    /// The same correspondence between other vertex numberings of its meshes (triangles keep
    /// their ids): `source`/`target` give `(map, count)`, vertex `v` becoming `map[v]` (kept
    /// where `map` has no entry, for a later check to refuse) among `count` vertices; `None`
    /// leaves that side as it is. Used to move a correspondence to and from welded meshes
    /// ([`crate::mesh::Weld`]: `to_welded` and `representative` are such maps).
    pub fn renumbered(
        mut self,
        source: Option<(&[u32], usize)>,
        target: Option<(&[u32], usize)>,
    ) -> Self {
        if self.identity {
            return self;
        }
        let remap = |map: &[u32], v: &mut u32| {
            if let Some(&x) = map.get(*v as usize) {
                *v = x;
            }
        };
        if let Some((m, n)) = source {
            self.source_vertices = n;
            self.markers.iter_mut().for_each(|p| remap(m, &mut p[0]));
            self.marker_residuals
                .iter_mut()
                .for_each(|r| remap(m, &mut r.source));
        }
        if let Some((m, n)) = target {
            self.target_vertices = n;
            self.markers.iter_mut().for_each(|p| remap(m, &mut p[1]));
            self.marker_residuals
                .iter_mut()
                .for_each(|r| remap(m, &mut r.target));
        }
        self
    }

    /// The identity correspondence of a mesh with itself.
    pub fn identity(mesh: &TriMesh) -> Self {
        let nf = mesh.num_triangles();
        Self {
            format: FORMAT.into(),
            version: VERSION,
            source_vertices: mesh.num_vertices(),
            source_triangles: nf,
            target_vertices: mesh.num_vertices(),
            target_triangles: nf,
            identity: true,
            markers: Vec::new(),
            radius: 0.0,
            omega: 0.0,
            offsets: (0..=nf as u32).collect(),
            matches: (0..nf as u32).collect(),
            normal_violations: Vec::new(),
            marker_residuals: Vec::new(),
            distances: Vec::new(),
            refinement: Vec::new(),
        }
    }

    /// Source triangles matched to target triangle `t`, nearest first.
    pub fn matches_of(&self, t: usize) -> &[u32] {
        &self.matches[self.offsets[t] as usize..self.offsets[t + 1] as usize]
    }

    /// Mean number of source triangles per target triangle.
    pub fn mean_matches(&self) -> f64 {
        self.matches.len() as f64 / self.target_triangles.max(1) as f64
    }

    /// Vertex pairs `(source, target)` whose centroids define the translation convention:
    /// the markers, or every vertex for the identity.
    pub fn anchor_pairs(&self) -> Vec<[u32; 2]> {
        if self.identity {
            (0..self.target_vertices as u32).map(|v| [v, v]).collect()
        } else {
            self.markers.clone()
        }
    }

    /// Calls `f(source_triangle, weight)` for the matches of target triangle `t` that
    /// `combine` uses, with their (unnormalised, positive) weights.
    fn for_each_weight(&self, t: usize, combine: GradientCombine, mut f: impl FnMut(usize, f64)) {
        let m = self.matches_of(t);
        match combine {
            GradientCombine::Nearest => f(m[0] as usize, 1.0),
            GradientCombine::InverseDistance if !self.distances.is_empty() => {
                let d = &self.distances[self.offsets[t] as usize..self.offsets[t + 1] as usize];
                if d[0] == 0.0 {
                    // Nearest first: the exact matches are a prefix.
                    for (&i, _) in m.iter().zip(d).take_while(|x| *x.1 == 0.0) {
                        f(i as usize, 1.0);
                    }
                } else {
                    for (&i, &di) in m.iter().zip(d) {
                        f(i as usize, 1.0 / f64::from(di));
                    }
                }
            }
            GradientCombine::InverseDistance | GradientCombine::Mean => {
                for &i in m {
                    f(i as usize, 1.0);
                }
            }
        }
    }

    /// Per-target-triangle gradients from per-source-triangle gradients, combined in the
    /// world frame ([`GradientFrame::World`](crate::transfer::GradientFrame::World)): the
    /// weighted mean of the matched source gradients.
    pub fn map_gradients(
        &self,
        source: &[Matrix3<f64>],
        combine: GradientCombine,
    ) -> Vec<Matrix3<f64>> {
        (0..self.target_triangles)
            .map(|t| {
                let (mut s, mut wsum) = (Matrix3::zeros(), 0.0);
                self.for_each_weight(t, combine, |i, w| {
                    s += source[i] * w;
                    wsum += w;
                });
                s / wsum
            })
            .collect()
    }

    /// Per-target-triangle gradients with each match's stretch turned into the target
    /// triangle's plane ([`GradientFrame::LocalStretch`](crate::transfer::GradientFrame::LocalStretch)):
    /// `source_polar` holds the polar factors $(R_i, S_i)$ of every source gradient
    /// ($G_i = R_i S_i$), `source_normals` / `target_normals` the unit normals of the two
    /// reference meshes (zero for a degenerate triangle). With $w_k$ the weights of `combine`
    /// times the agreement $a_k$ of the reference normals ([`normal_agreement`]; the weights
    /// of `combine` alone when every $a_k$ is 0), the result is
    /// $M_j = \operatorname{proj}_{SO(3)}\big(\sum_k w_k R_k\big)\,
    /// \frac{\sum_k w_k Q_{kj} S_k Q_{kj}^\top}{\sum_k w_k}$, $Q_{kj}$ the smallest rotation
    /// taking source normal $k$ onto target normal $j$.
    pub fn map_gradients_local(
        &self,
        source_polar: &[(Matrix3<f64>, Matrix3<f64>)],
        source_normals: &[Vector3<f64>],
        target_normals: &[Vector3<f64>],
        combine: GradientCombine,
    ) -> Vec<Matrix3<f64>> {
        self.map_local(source_polar, source_normals, target_normals, combine, true)
    }

    /// [`Correspondence::map_gradients_local`] with every $Q_{kj} = I$ (the same weights, the
    /// stretches not turned): the fallback of the fold guard
    /// ([`FoldGuard`](crate::transfer::FoldGuard)).
    pub fn map_gradients_local_unturned(
        &self,
        source_polar: &[(Matrix3<f64>, Matrix3<f64>)],
        source_normals: &[Vector3<f64>],
        target_normals: &[Vector3<f64>],
        combine: GradientCombine,
    ) -> Vec<Matrix3<f64>> {
        self.map_local(source_polar, source_normals, target_normals, combine, false)
    }

    fn map_local(
        &self,
        source_polar: &[(Matrix3<f64>, Matrix3<f64>)],
        source_normals: &[Vector3<f64>],
        target_normals: &[Vector3<f64>],
        combine: GradientCombine,
        turn: bool,
    ) -> Vec<Matrix3<f64>> {
        (0..self.target_triangles)
            .map(|t| {
                let nt = target_normals[t];
                let mut any = false;
                self.for_each_weight(t, combine, |i, _| {
                    any |= normal_agreement(source_normals[i].dot(&nt)) > 0.0;
                });
                let (mut r, mut s, mut wsum) = (Matrix3::zeros(), Matrix3::zeros(), 0.0);
                self.for_each_weight(t, combine, |i, w| {
                    let c = source_normals[i].dot(&nt);
                    let w = if any { w * normal_agreement(c) } else { w };
                    if w == 0.0 {
                        return;
                    }
                    let (ri, si) = &source_polar[i];
                    r += ri * w;
                    if turn {
                        let q = rotation_between(source_normals[i], nt);
                        s += q * si * q.transpose() * w;
                    } else {
                        s += si * w;
                    }
                    wsum += w;
                });
                polar(&r).0 * (s / wsum)
            })
            .collect()
    }

    /// The confidence $c_j = \sum_k \hat w_k a_k$ of every target triangle's
    /// [`Correspondence::map_gradients_local`] gradient: $\hat w_k$ the weights of `combine`
    /// normalised to sum 1, $a_k$ the [`normal_agreement`] of the reference normals; at
    /// least [`CONFIDENCE_FLOOR`]. Sumner & Popović (2004, Sec. 4) minimise one term
    /// $\|T_j - M_k\|_F^2$ per matched pair; weighting each pair by $\hat w_k a_k$, the
    /// terms of triangle $j$ sum to $c_j \|T_j - M_j\|_F^2$ plus a constant, $M_j$ the
    /// weighted mean. So $c_j$ is triangle $j$'s weight in the solve
    /// ([`GradientFrame::LocalStretch`](crate::transfer::GradientFrame::LocalStretch)): a
    /// triangle whose matches face away in the references (its wanted gradient carried over
    /// through a large turn, or from the wrong side) counts for little, and its neighbours
    /// shape it. 1 for every triangle of a mesh onto itself.
    pub fn local_confidence(
        &self,
        source_normals: &[Vector3<f64>],
        target_normals: &[Vector3<f64>],
        combine: GradientCombine,
    ) -> Vec<f64> {
        (0..self.target_triangles)
            .map(|t| {
                let (mut a, mut wsum) = (0.0, 0.0);
                self.for_each_weight(t, combine, |i, w| {
                    a += w * normal_agreement(source_normals[i].dot(&target_normals[t]));
                    wsum += w;
                });
                (a / wsum).max(CONFIDENCE_FLOOR)
            })
            .collect()
    }

    /// Checks the structure ([`Correspondence::validate`]) and that the meshes have the
    /// recorded sizes.
    pub fn check(&self, source: &TriMesh, target: &TriMesh) -> Result<(), TransferError> {
        self.validate()?;
        for (side, m, nv, nf) in [
            (
                Side::Source,
                source,
                self.source_vertices,
                self.source_triangles,
            ),
            (
                Side::Target,
                target,
                self.target_vertices,
                self.target_triangles,
            ),
        ] {
            if m.num_vertices() != nv || m.num_triangles() != nf {
                return Err(TransferError::CorrespondenceMismatch {
                    side,
                    expected_vertices: nv,
                    expected_triangles: nf,
                    found_vertices: m.num_vertices(),
                    found_triangles: m.num_triangles(),
                });
            }
        }
        Ok(())
    }

    /// Serialises to JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("correspondence serialises")
    }

    /// Parses and structurally validates JSON written by [`Correspondence::to_json`].
    pub fn from_json(text: &str) -> Result<Self, CorrespondenceError> {
        let c: Self = serde_json::from_str(crate::io::strip_bom_str(text))
            .map_err(|e| CorrespondenceError::Invalid(format!("not a correspondence file: {e}")))?;
        c.validate()?;
        Ok(c)
    }

    /// Structural checks: format, offsets, every index read from the file in range, no empty
    /// match list, and for the identity equal mesh sizes and matches `t ↔ [t]`. After it
    /// passes, no method of the correspondence indexes out of range.
    pub fn validate(&self) -> Result<(), CorrespondenceError> {
        let bad = |m: String| Err(CorrespondenceError::Invalid(m));
        if self.format != FORMAT || self.version != VERSION {
            return bad(format!(
                "format '{}' version {} (expected '{FORMAT}' version {VERSION})",
                self.format, self.version
            ));
        }
        // Counts must fit the u32 indices the file stores.
        for (what, n) in [
            ("source vertex", self.source_vertices),
            ("source triangle", self.source_triangles),
            ("target vertex", self.target_vertices),
            ("target triangle", self.target_triangles),
        ] {
            if n > u32::MAX as usize {
                return bad(format!("{what} count {n} exceeds the 32-bit index range"));
            }
        }
        if self.identity
            && (self.source_vertices != self.target_vertices
                || self.source_triangles != self.target_triangles)
        {
            return Err(CorrespondenceError::IdentityMismatch {
                source_vertices: self.source_vertices,
                source_triangles: self.source_triangles,
                target_vertices: self.target_vertices,
                target_triangles: self.target_triangles,
            });
        }
        if self.offsets.len() != self.target_triangles + 1
            || self.offsets.first() != Some(&0)
            || *self.offsets.last().unwrap_or(&0) as usize != self.matches.len()
        {
            return bad(format!(
                "{} offsets ending at {} for {} target triangles and {} matches (expected {} \
                 offsets from 0 to the match count)",
                self.offsets.len(),
                self.offsets.last().copied().unwrap_or(0),
                self.target_triangles,
                self.matches.len(),
                self.target_triangles + 1
            ));
        }
        // Strictly increasing from 0 to matches.len(): every range is non-empty and in bounds.
        for t in 0..self.target_triangles {
            if self.offsets[t + 1] <= self.offsets[t] {
                return bad(format!(
                    "target triangle {t} has no source triangle (offsets {} then {})",
                    self.offsets[t],
                    self.offsets[t + 1]
                ));
            }
        }
        if let Some((k, &s)) = self
            .matches
            .iter()
            .enumerate()
            .find(|(_, &s)| s as usize >= self.source_triangles)
        {
            return bad(format!(
                "match {k}: source triangle {s} is out of range ({} source triangles)",
                self.source_triangles
            ));
        }
        if self.identity {
            if let Some(t) = (0..self.target_triangles).find(|&t| self.matches_of(t) != [t as u32])
            {
                return Err(CorrespondenceError::IdentityMatches {
                    target_triangle: t,
                    matches: self.matches_of(t).to_vec(),
                });
            }
        }
        if let Some((k, p)) = self.markers.iter().enumerate().find(|(_, p)| {
            p[0] as usize >= self.source_vertices || p[1] as usize >= self.target_vertices
        }) {
            return bad(format!(
                "marker {k} {p:?} is out of range ({} source / {} target vertices)",
                self.source_vertices, self.target_vertices
            ));
        }
        if let Some(&t) = self
            .normal_violations
            .iter()
            .find(|&&t| t as usize >= self.target_triangles)
        {
            return bad(format!(
                "normal violation: target triangle {t} is out of range ({} target triangles)",
                self.target_triangles
            ));
        }
        if !self.distances.is_empty() {
            if self.distances.len() != self.matches.len() {
                return bad(format!(
                    "{} distances for {} matches",
                    self.distances.len(),
                    self.matches.len()
                ));
            }
            if let Some(k) = self
                .distances
                .iter()
                .position(|d| !(d.is_finite() && *d >= 0.0))
            {
                return bad(format!(
                    "match {k}: distance {} is not a finite non-negative number",
                    self.distances[k]
                ));
            }
            for t in 0..self.target_triangles {
                let d = &self.distances[self.offsets[t] as usize..self.offsets[t + 1] as usize];
                if d.windows(2).any(|w| w[1] < w[0]) {
                    return bad(format!(
                        "target triangle {t}: match distances are not sorted nearest first"
                    ));
                }
            }
        }
        if let Some((k, r)) = self.marker_residuals.iter().enumerate().find(|(_, r)| {
            r.source as usize >= self.source_vertices || r.target as usize >= self.target_vertices
        }) {
            return bad(format!(
                "marker residual {k}: vertices [{}, {}] are out of range ({} source / {} target \
                 vertices)",
                r.source, r.target, self.source_vertices, self.target_vertices
            ));
        }
        Ok(())
    }
}

/// The agreement of two unit reference normals with cosine `c` (angle $\theta$):
/// $a = \big(\tfrac{1 + c}{2}\big)^2 = \cos^4(\theta / 2)$: 1 when they are the same, 1/4 at
/// 90°, 0 when opposite (where the smallest rotation between them is undefined). Each match of
/// [`Correspondence::map_gradients_local`] is weighted by it, and
/// [`Correspondence::local_confidence`] sums it. Measured on horse ↔ camel and cat ↔ dog
/// (refined, area-weighted; `tests/transfer_quality_real_data.rs`): $\cos^2(\theta/2)$ lowers
/// the cycle error less (−29.2 % / −23.5 % against −32.6 % / −26.0 %), $\cos^8(\theta/2)$
/// folds more (123 / 101 sharp folds against 27 / 98; the baseline has 77 / 99).
pub fn normal_agreement(c: f64) -> f64 {
    let h = 0.5 * (1.0 + c.clamp(-1.0, 1.0));
    h * h
}

/// The least confidence of a target triangle ([`Correspondence::local_confidence`]), so that
/// no triangle drops out of the solve (a vertex with only such triangles would be free).
pub const CONFIDENCE_FLOOR: f64 = 1e-3;

/// Polar decomposition $M = R S$: $R$ the rotation nearest to $M$ (det +1, from the SVD),
/// $S = R^\top M$ (symmetric).
pub fn polar(m: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let svd = m.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return (Matrix3::identity(), *m);
    };
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        let mut d = Matrix3::identity();
        d[(2, 2)] = -1.0;
        r = u * d * vt;
    }
    (r, r.transpose() * m)
}

/// The smallest rotation taking unit `a` onto unit `b`; the identity when either is zero or
/// they are nearly opposite (no well-defined smallest rotation).
pub fn rotation_between(a: Vector3<f64>, b: Vector3<f64>) -> Matrix3<f64> {
    let c = a.dot(&b);
    if c < -0.9 || a == Vector3::zeros() || b == Vector3::zeros() {
        return Matrix3::identity();
    }
    let k = a.cross(&b).cross_matrix();
    Matrix3::identity() + k + k * k / (1.0 + c)
}
