//! Triangle correspondence from marker pairs (Wang & Lee 2008, Sec. 3.1.2–3.1.3).
//!
//! 1. Both meshes are warped by least-squares meshes ([`super::lsmesh`], Eq. 2 and 4,
//!    ω = 10 000) with **their markers placed at the target markers' positions**, so the two
//!    warped meshes have similar shapes.
//! 2. Triangles are *compatible* when their warped centroids are close and their warped
//!    normals are less than 90° apart ($n_s \cdot n_t > 0$).
//!    "Close" means within $r = \rho\,\bar\ell_s$, $\bar\ell_s$ the mean edge length of the
//!    **warped** source mesh and $\rho$ = [`CorrespondenceOptions::radius_factor`]
//!    (default 1.0): the spacing of source centroids, so that a target triangle collects the
//!    source triangles that overlap it, whatever the units and however much the warp shrinks
//!    the meshes. At most [`CorrespondenceOptions::max_matches`] nearest are kept.
//! 3. Every target triangle gets at least one source triangle: when none is compatible within
//!    $r$, the nearest compatible one at any distance (exact branch-and-bound over a k-d tree
//!    of source centroids, [`super::kdtree`]); when no source triangle at all has a
//!    compatible normal, the nearest one, and the target triangle is listed in
//!    [`Correspondence::normal_violations`] as a place that needs more markers.
//!
//! Source triangles that are degenerate in the source reference or collapse in the warp have
//! no normal and are never matched. The work is `O((#F_s + #F_t) log #F_s)` besides the two
//! sparse factorizations.

use super::error::{CorrespondenceError, Side, TransferError};
use super::gradients::{degeneracy_tolerance, reference_frame_inverse};
use super::kdtree::KdTree;
use super::lsmesh::{LeastSquaresMesh, LsMeshOptions};
use super::markers::Markers;
use crate::mesh::{dot, norm, sub, triangle_normal, validate, Point, Topology, TriMesh};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// The `format` tag of correspondence files.
pub const FORMAT: &str = "morphkit-correspondence";
/// The current correspondence file version.
pub const VERSION: u32 = 1;

/// Options of [`correspond`].
#[derive(Clone, Debug)]
pub struct CorrespondenceOptions {
    /// Least-squares mesh options (ω, Laplacian).
    pub lsmesh: LsMeshOptions,
    /// Centroid radius in units of the warped source mesh's mean edge length. Default 1.0.
    pub radius_factor: f64,
    /// Most source triangles kept per target triangle (the nearest). Default 8.
    pub max_matches: usize,
}

impl Default for CorrespondenceOptions {
    fn default() -> Self {
        Self {
            lsmesh: LsMeshOptions::default(),
            radius_factor: 1.0,
            max_matches: 8,
        }
    }
}

/// How far one marker is from its target position after warping.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MarkerResidual {
    /// Source vertex.
    pub source: u32,
    /// Target vertex.
    pub target: u32,
    /// Distance of the warped source vertex from the target marker position.
    pub source_residual: f64,
    /// Distance of the warped target vertex from its own reference position.
    pub target_residual: f64,
    /// The larger of the two, over the target's bounding-box diagonal.
    pub relative: f64,
}

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
}

/// How the gradients of several source triangles matched to one target triangle combine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GradientCombine {
    /// The arithmetic mean (default). Equivalent to Sumner & Popović's sum of one
    /// least-squares term per matched pair, up to a per-triangle weight, and smooths the
    /// tessellation difference between the meshes.
    #[default]
    Mean,
    /// The nearest source triangle's gradient only.
    Nearest,
}

/// A correspondence and the two warped meshes it was found on.
#[derive(Clone, Debug)]
pub struct CorrespondenceResult {
    /// The correspondence.
    pub correspondence: Correspondence,
    /// Source positions after the least-squares warp (#V_s).
    pub warped_source: Vec<Point>,
    /// Target positions after the least-squares warp (#V_t).
    pub warped_target: Vec<Point>,
}

impl Correspondence {
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

    /// Per-target-triangle gradients from per-source-triangle gradients.
    pub fn map_gradients(
        &self,
        source: &[Matrix3<f64>],
        combine: GradientCombine,
    ) -> Vec<Matrix3<f64>> {
        (0..self.target_triangles)
            .map(|t| {
                let m = self.matches_of(t);
                match combine {
                    GradientCombine::Nearest => source[m[0] as usize],
                    GradientCombine::Mean => {
                        let mut s = Matrix3::zeros();
                        for &i in m {
                            s += source[i as usize];
                        }
                        s / m.len() as f64
                    }
                }
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

/// Mean edge length of `p` over `topo`'s edges.
fn mean_edge_length(p: &[Point], topo: &Topology) -> f64 {
    let e = topo.edges();
    if e.is_empty() {
        return 0.0;
    }
    e.iter()
        .map(|&[a, b]| norm(sub(p[a as usize], p[b as usize])))
        .sum::<f64>()
        / e.len() as f64
}

/// Centroid and unit normal (zero when degenerate) of every triangle.
fn centroids_and_normals(p: &[Point], tris: &[[u32; 3]]) -> (Vec<Point>, Vec<Point>) {
    tris.iter()
        .map(|&t| {
            let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
            let cen = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
            let n = triangle_normal(p, t);
            let l = norm(n);
            let n = if l > 0.0 && l.is_finite() {
                n.map(|x| x / l)
            } else {
                [0.0; 3]
            };
            (cen, n)
        })
        .unzip()
}

/// Source triangles that may be matched: a non-zero warped normal (`warped_normals`) and not
/// degenerate in the source reference by the same test as
/// [`GradientOperator`](super::GradientOperator) (which gives
/// degenerate triangles the identity gradient, so matching one would feed the identity into
/// the mean).
fn usable_source_triangles(source: &TriMesh, warped_normals: &[Point]) -> Vec<bool> {
    let tol = degeneracy_tolerance(source);
    source
        .triangles
        .iter()
        .zip(warped_normals)
        .map(|(&tri, n)| {
            norm(*n) > 0.0 && reference_frame_inverse(&source.positions, tri, tol).is_some()
        })
        .collect()
}

/// Computes the correspondence of `source` and `target` from `markers`.
pub fn correspond(
    source: &TriMesh,
    target: &TriMesh,
    markers: &Markers,
    opts: &CorrespondenceOptions,
) -> Result<CorrespondenceResult, CorrespondenceError> {
    for (side, m) in [(Side::Source, source), (Side::Target, target)] {
        validate(m).map_err(|source| CorrespondenceError::Mesh { side, source })?;
    }
    markers.validate(source.num_vertices(), target.num_vertices())?;
    let diag_t = target.bbox_diagonal();
    markers.check_spread(&target.positions, diag_t)?;
    let topo_s = Topology::new(source.num_vertices(), &source.triangles);
    let topo_t = Topology::new(target.num_vertices(), &target.triangles);
    let src_v = markers.source_vertices();
    let tgt_v = markers.target_vertices();
    let goal: Vec<Point> = tgt_v
        .iter()
        .map(|&v| target.positions[v as usize])
        .collect();
    let ws =
        LeastSquaresMesh::new(source, &topo_s, &src_v, &opts.lsmesh, Side::Source)?.solve(&goal)?;
    let wt =
        LeastSquaresMesh::new(target, &topo_t, &tgt_v, &opts.lsmesh, Side::Target)?.solve(&goal)?;
    let marker_residuals = markers
        .pairs
        .iter()
        .zip(&goal)
        .map(|(&[s, t], g)| {
            let rs = norm(sub(ws[s as usize], *g));
            let rt = norm(sub(wt[t as usize], *g));
            MarkerResidual {
                source: s,
                target: t,
                source_residual: rs,
                target_residual: rt,
                relative: rs.max(rt) / diag_t.max(f64::MIN_POSITIVE),
            }
        })
        .collect();

    let (cs, ns) = centroids_and_normals(&ws, &source.triangles);
    let (ct, nt) = centroids_and_normals(&wt, &target.triangles);
    let usable = usable_source_triangles(source, &ns);
    let radius = opts.radius_factor * mean_edge_length(&ws, &topo_s);
    let tree = KdTree::new(&cs);

    let mut offsets = Vec::with_capacity(target.num_triangles() + 1);
    offsets.push(0u32);
    let mut matches = Vec::with_capacity(2 * target.num_triangles());
    let mut normal_violations = Vec::new();
    let mut cand = Vec::new();
    let mut scored: Vec<(f64, u32)> = Vec::new();
    for t in 0..target.num_triangles() {
        let (q, n) = (ct[t], nt[t]);
        let compatible = |s: u32| usable[s as usize] && dot(ns[s as usize], n) > 0.0;
        cand.clear();
        scored.clear();
        if norm(n) > 0.0 && radius > 0.0 {
            tree.within(q, radius, &mut cand);
            scored.extend(
                cand.iter()
                    .filter(|&&s| compatible(s))
                    .map(|&s| (norm(sub(cs[s as usize], q)), s)),
            );
            scored.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            scored.truncate(opts.max_matches.max(1));
        }
        if scored.is_empty() {
            let nearest = if norm(n) > 0.0 {
                tree.nearest_filtered(q, compatible)
            } else {
                None
            };
            match nearest {
                Some((s, d2)) => scored.push((d2.sqrt(), s)),
                None => {
                    normal_violations.push(t as u32);
                    let (s, d2) = tree
                        .nearest_filtered(q, |s| usable[s as usize])
                        .or_else(|| tree.nearest_filtered(q, |_| true))
                        .expect("the source mesh has triangles");
                    scored.push((d2.sqrt(), s));
                }
            }
        }
        matches.extend(scored.iter().map(|x| x.1));
        offsets.push(matches.len() as u32);
    }
    let correspondence = Correspondence {
        format: FORMAT.into(),
        version: VERSION,
        source_vertices: source.num_vertices(),
        source_triangles: source.num_triangles(),
        target_vertices: target.num_vertices(),
        target_triangles: target.num_triangles(),
        identity: false,
        markers: markers.pairs.clone(),
        radius,
        omega: opts.lsmesh.omega,
        offsets,
        matches,
        normal_violations,
        marker_residuals,
    };
    Ok(CorrespondenceResult {
        correspondence,
        warped_source: ws,
        warped_target: wt,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::gradients::GradientOperator;
    use crate::transfer::testmesh::sphere;

    fn markers_on(m: &TriMesh) -> Markers {
        // Six "poles" of the sphere as markers.
        let mut pairs = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let v = (0..m.num_vertices())
                    .max_by(|&a, &b| {
                        (sign * m.positions[a][axis]).total_cmp(&(sign * m.positions[b][axis]))
                    })
                    .unwrap() as u32;
                pairs.push(v);
            }
        }
        Markers::new(pairs.into_iter().map(|v| [v, v]).collect())
    }

    #[test]
    fn self_correspondence_matches_each_triangle_to_itself_first() {
        let m = sphere(16, 10, 1.0);
        let r = correspond(&m, &m, &markers_on(&m), &CorrespondenceOptions::default()).unwrap();
        let c = &r.correspondence;
        assert!(c.normal_violations.is_empty());
        for t in 0..m.num_triangles() {
            assert_eq!(c.matches_of(t)[0], t as u32, "triangle {t}");
        }
        assert!(c.mean_matches() > 1.0, "neighbours within one edge length");
        let back = Correspondence::from_json(&c.to_json()).unwrap();
        assert_eq!((&back.offsets, &back.matches), (&c.offsets, &c.matches));
        assert_eq!(back.markers, c.markers);
        for res in &c.marker_residuals {
            assert!(res.relative < 1e-3);
        }
    }

    #[test]
    fn different_tessellations_and_a_scaled_target_correspond() {
        let s = sphere(16, 10, 1.0);
        let t0 = sphere(23, 13, 1.0);
        let t = t0.with_positions(
            t0.positions
                .iter()
                .map(|p| p.map(|x| 5.0 * x + 2.0))
                .collect(),
        );
        // Markers: poles of both meshes, matched by direction.
        let ms = markers_on(&s);
        let mt = markers_on(&t);
        let pairs = ms
            .pairs
            .iter()
            .zip(&mt.pairs)
            .map(|(a, b)| [a[0], b[1]])
            .collect();
        let r = correspond(
            &s,
            &t,
            &Markers::new(pairs),
            &CorrespondenceOptions::default(),
        )
        .unwrap();
        let c = &r.correspondence;
        assert!(c.normal_violations.is_empty());
        // Matched triangles point the same way on the original spheres.
        let (_, ns) = centroids_and_normals(&s.positions, &s.triangles);
        let (_, nt) = centroids_and_normals(&t.positions, &t.triangles);
        for (tt, n) in nt.iter().enumerate() {
            for &ss in c.matches_of(tt) {
                assert!(dot(ns[ss as usize], *n) > 0.5, "{tt} ↔ {ss}");
            }
        }
        let bad = Correspondence {
            offsets: vec![0; c.offsets.len()],
            ..c.clone()
        };
        assert!(matches!(
            Correspondence::from_json(&bad.to_json()),
            Err(CorrespondenceError::Invalid(_))
        ));
    }

    #[test]
    fn identity_flag_with_unequal_counts_is_a_typed_error() {
        let s = sphere(8, 6, 1.0);
        let t = sphere(12, 8, 1.0);
        let ns = s.num_triangles() as u32;
        let bad = Correspondence {
            target_vertices: t.num_vertices(),
            target_triangles: t.num_triangles(),
            offsets: (0..=t.num_triangles() as u32).collect(),
            matches: (0..t.num_triangles() as u32).map(|k| k % ns).collect(),
            ..Correspondence::identity(&s)
        };
        let e = Correspondence::from_json(&bad.to_json()).unwrap_err();
        match e {
            CorrespondenceError::IdentityMismatch {
                source_vertices,
                target_vertices,
                source_triangles,
                target_triangles,
            } => {
                assert_eq!(source_vertices, s.num_vertices());
                assert_eq!(target_vertices, t.num_vertices());
                assert_eq!(source_triangles, s.num_triangles());
                assert_eq!(target_triangles, t.num_triangles());
            }
            e => panic!("{e}"),
        }
        // `check` validates too, so a hand-built correspondence cannot slip through.
        assert!(matches!(
            bad.check(&s, &t),
            Err(TransferError::Correspondence(
                CorrespondenceError::IdentityMismatch { .. }
            ))
        ));
        // Equal counts but matches other than t ↔ [t].
        let mut swapped = Correspondence::identity(&s);
        swapped.matches.swap(2, 3);
        assert!(matches!(
            Correspondence::from_json(&swapped.to_json()),
            Err(CorrespondenceError::IdentityMatches {
                target_triangle: 2,
                ..
            })
        ));
    }

    #[test]
    fn malformed_correspondence_files_are_errors_not_panics() {
        let m = sphere(16, 10, 1.0);
        let r = correspond(&m, &m, &markers_on(&m), &CorrespondenceOptions::default()).unwrap();
        let good = r.correspondence;
        let nf = good.target_triangles;
        type Corrupt = Box<dyn Fn(&mut Correspondence)>;
        let corruptions: Vec<(&str, Corrupt)> = vec![
            ("offsets not increasing", Box::new(|c| c.offsets.swap(1, 2))),
            (
                "offset beyond matches",
                Box::new(|c| c.offsets[1] = u32::MAX),
            ),
            (
                "offsets too short",
                Box::new(|c| {
                    c.offsets.pop();
                }),
            ),
            (
                "last offset",
                Box::new(|c| *c.offsets.last_mut().unwrap() -= 1),
            ),
            ("match range", Box::new(move |c| c.matches[0] = nf as u32)),
            ("marker source", Box::new(|c| c.markers[0][0] = u32::MAX)),
            (
                "marker target",
                Box::new(|c| c.markers[1][1] = c.target_vertices as u32),
            ),
            (
                "normal violation",
                Box::new(move |c| c.normal_violations.push(nf as u32)),
            ),
            (
                "residual source",
                Box::new(|c| c.marker_residuals[0].source = u32::MAX),
            ),
            (
                "residual target",
                Box::new(|c| c.marker_residuals[0].target = u32::MAX),
            ),
            ("huge count", Box::new(|c| c.target_triangles = usize::MAX)),
            (
                "identity sizes",
                Box::new(|c| {
                    c.identity = true;
                    c.source_vertices -= 1;
                }),
            ),
            ("format", Box::new(|c| c.format = "x".into())),
        ];
        for (what, f) in corruptions {
            let mut c = good.clone();
            f(&mut c);
            let res = std::panic::catch_unwind(|| Correspondence::from_json(&c.to_json()));
            assert!(matches!(res, Ok(Err(_))), "{what}: {res:?}");
        }
        assert!(Correspondence::from_json(&good.to_json()).is_ok());
    }

    #[test]
    fn tiny_source_triangles_are_unusable_exactly_when_gradients_call_them_degenerate() {
        // A tetrahedron and a sliver fan: areas 0, below and above the gradient
        // operator's tolerance (1e-14 · diag²; diag ≈ 4 here).
        let mut m = crate::mesh::TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.1, 0.0],
                [0.2, 1.0, 0.1],
                [0.3, 0.2, 1.0],
                [2.0, 0.0, 0.0],
                [2.0, 1e-14, 0.0],
                [3.0, 1e-11, 0.0],
                [4.0, 0.0, 0.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        );
        m.triangles.push([1, 4, 5]); // doubled area ≈ 1e-14: non-zero but degenerate
        m.triangles.push([1, 4, 6]); // doubled area ≈ 1e-11: usable
        m.triangles.push([0, 4, 7]); // exactly collinear
        let (_, n) = centroids_and_normals(&m.positions, &m.triangles);
        assert!(norm(n[4]) > 0.0, "the sliver has a (non-zero) normal");
        let usable = usable_source_triangles(&m, &n);
        assert_eq!(usable, vec![true, true, true, true, false, true, false]);
        let op = GradientOperator::new(&m);
        let degenerate: Vec<usize> = (0..usable.len()).filter(|&t| !usable[t]).collect();
        assert_eq!(op.degenerate(), degenerate.as_slice());
    }
}
