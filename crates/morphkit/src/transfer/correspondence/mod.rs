//! Triangle correspondence from marker pairs (Wang & Lee 2008, Sec. 3.1.2–3.1.3).
//!
//! 1. Both meshes are warped by least-squares meshes ([`super::lsmesh`], Eq. 2 and 4,
//!    ω = 10 000) with **their markers placed at the target markers' positions**, so the two
//!    warped meshes have similar shapes.
//! 2. Triangles are *compatible* when their warped centroids are close and their warped
//!    normals are less than 90° apart ($n_s \cdot n_t > 0$; a stricter cosine with
//!    [`CorrespondenceOptions::min_normal_cos`]).
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

mod file;
mod matching;
pub mod refine;

pub use file::{
    normal_agreement, polar, rotation_between, Correspondence, CONFIDENCE_FLOOR, FORMAT, VERSION,
};
pub use refine::{RefineOptions, RefineStep};

use super::error::{CorrespondenceError, Side};
use super::gradients::{degeneracy_tolerance, reference_frame_inverse};
use super::lsmesh::{LeastSquaresMesh, LsMeshOptions};
use super::markers::Markers;
use crate::mesh::{norm, sub, triangle_normal, validate, Point, Topology, TriMesh};
use serde::{Deserialize, Serialize};

/// Options of [`correspond`].
#[derive(Clone, Debug)]
pub struct CorrespondenceOptions {
    /// Least-squares mesh options (ω, Laplacian).
    pub lsmesh: LsMeshOptions,
    /// Centroid radius in units of the warped source mesh's mean edge length. Default 1.0.
    pub radius_factor: f64,
    /// Most source triangles kept per target triangle (the nearest). Default 8.
    pub max_matches: usize,
    /// Closest-point refinement of the source warp ([`refine`], Sumner & Popović 2004,
    /// Sec. 5) before matching; `None` matches the two least-squares warps directly (Wang &
    /// Lee's one-stage correspondence). Default on (`RefineOptions::default()`, issue 40):
    /// with the local-stretch frame and area-weighted solves (the [`TransferOptions`]
    /// defaults) it came closest in a leave-one-out study over horse → camel, cat → dog and
    /// the horse gallop and collapse onto the camel (docs/fidelity.md, "Transfer defaults";
    /// `examples/transfer_defaults_study.rs`), for about 1.7× the correspondence time.
    ///
    /// [`TransferOptions`]: crate::transfer::TransferOptions
    pub refine: Option<RefineOptions>,
    /// Also add every usable source triangle to its nearest compatible target triangle's
    /// matches ([`matching`]). Default true.
    pub two_way: bool,
    /// Compatible triangles' placed normals must have a cosine above this. Default 0 (less
    /// than 90° apart, Sumner & Popović and Wang & Lee).
    pub min_normal_cos: f64,
}

impl Default for CorrespondenceOptions {
    fn default() -> Self {
        Self {
            lsmesh: LsMeshOptions::default(),
            radius_factor: 1.0,
            max_matches: 8,
            refine: Some(RefineOptions::default()),
            two_way: true,
            min_normal_cos: 0.0,
        }
    }
}

impl CorrespondenceOptions {
    /// Turns the closest-point refinement on (keeping options already set, else
    /// [`RefineOptions::default`]) or off: what `--refine` / `--no-refine` and the Python
    /// module's `refine=True` / `refine=False` do to the defaults.
    pub fn set_refine(&mut self, on: bool) {
        if !on {
            self.refine = None;
        } else if self.refine.is_none() {
            self.refine = Some(RefineOptions::default());
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

/// How the gradients of several source triangles matched to one target triangle combine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GradientCombine {
    /// The arithmetic mean. Equivalent to Sumner & Popović's sum of one least-squares term
    /// per matched pair, up to a per-triangle weight, and smooths the tessellation difference
    /// between the meshes; but it blurs a self-transfer (a triangle averaged with its
    /// neighbours).
    Mean,
    /// The nearest source triangle's gradient only.
    Nearest,
    /// Inverse-distance weights $w_k = 1/d_k$ over the centroid distances $d_k$ recorded in
    /// the correspondence (default): matches at distance 0 alone when there are any (so a
    /// mesh onto itself is exact), the mean when the file records no distances.
    #[default]
    InverseDistance,
}

impl GradientCombine {
    /// Every combination by the name the CLI (`--combine`) and the Python module (`combine=`)
    /// give it, in the order of [`GradientCombine::NAMES`].
    pub const ALL: [GradientCombine; 3] = [Self::InverseDistance, Self::Mean, Self::Nearest];
    /// The names of [`GradientCombine::ALL`]: `inverse-distance`, `mean`, `nearest`.
    pub const NAMES: [&'static str; 3] = ["inverse-distance", "mean", "nearest"];

    /// The name of this combination (one of [`GradientCombine::NAMES`]).
    pub fn name(self) -> &'static str {
        match self {
            Self::InverseDistance => Self::NAMES[0],
            Self::Mean => Self::NAMES[1],
            Self::Nearest => Self::NAMES[2],
        }
    }

    /// The combination named `name` (one of [`GradientCombine::NAMES`]), or `None`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// A correspondence and the two warped meshes it was found on.
#[derive(Clone, Debug)]
pub struct CorrespondenceResult {
    /// The correspondence.
    pub correspondence: Correspondence,
    /// Source positions the matching used (#V_s): the least-squares warp, or the refined
    /// warp when [`CorrespondenceOptions::refine`] is set.
    pub warped_source: Vec<Point>,
    /// Target positions the matching used (#V_t): the least-squares warp, or the target
    /// itself when refined (the source was deformed onto it).
    pub warped_target: Vec<Point>,
    /// Matches added by the source → target pass of the two-way matching.
    pub added_by_source: usize,
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

    let (placed_source, placed_target, refinement) = match &opts.refine {
        Some(r) => {
            let (x, steps) = refine::refine(source, &topo_s, target, &ws, &src_v, &goal, r)?;
            (x, target.positions.clone(), steps)
        }
        None => (ws, wt, Vec::new()),
    };
    let (cs, ns) = centroids_and_normals(&placed_source, &source.triangles);
    let (ct, nt) = centroids_and_normals(&placed_target, &target.triangles);
    let usable = usable_source_triangles(source, &ns);
    let radius = opts.radius_factor * mean_edge_length(&placed_source, &topo_s);
    let m = matching::match_triangles(
        &matching::Placed {
            source_centroids: &cs,
            source_normals: &ns,
            usable: &usable,
            target_centroids: &ct,
            target_normals: &nt,
        },
        radius,
        opts.max_matches,
        opts.two_way,
        opts.min_normal_cos,
    );
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
        offsets: m.offsets,
        matches: m.matches,
        normal_violations: m.normal_violations,
        marker_residuals,
        distances: m.distances,
        refinement,
    };
    Ok(CorrespondenceResult {
        correspondence,
        warped_source: placed_source,
        warped_target: placed_target,
        added_by_source: m.added_by_source,
    })
}

#[cfg(test)]
mod tests;
