//! Spring structure (Ma et al. 2012, Sec. 3.1) and per-target rest lengths (Sec. 3.2).

use super::BlendError;
use crate::mesh::{norm, sub, Point, ShapeSet, Topology};

/// What a spring models.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum SpringKind {
    /// Along a mesh edge: in-surface elasticity.
    Structure,
    /// Between vertices at graph distance exactly 2: bending and curvature.
    Bending,
    /// Inside a closed surface, or from the surface to an interior vertex: volume (Sec. 3.1).
    Internal,
    /// The anchor's own edges and its ties to the body (Sec. 3.4, step 2).
    Anchor,
}

/// How spring stiffness depends on rest length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StiffnessRule {
    /// $k = k_0 / \bar r$ (Sec. 3.5): every spring exerts a similar force for the same relative
    /// strain, whatever its length. The default, and what the paper uses.
    #[default]
    InverseRestLength,
    /// $k = k_0$ for every spring.
    Uniform,
}

/// Which springs to build and how stiff they are.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringOptions {
    /// Structure springs on every edge. Default `true`.
    pub structure: bool,
    /// Ma et al.'s bending springs between vertices at graph distance 2. Default `false`:
    /// the blend's bending term is the signed hinge ([`HingeOptions`](crate::springs::HingeOptions)),
    /// which tells a fold up from a fold down, where a distance spring across an edge sees only
    /// the cosine of the fold. With the hinge on, the 2-ring springs cost two thirds of the
    /// springs and a third of the factor and bought no quality on the real rigs: without
    /// them, the horse and ICT sequences have fewer creases, no more folds, and ICT jawOpen's
    /// gums no longer snap (docs/choices.md).
    pub bending: bool,
    /// Base stiffness $k_0$. Default `1.0` (only ratios matter for the equilibrium).
    pub k0: f64,
    /// Multiplier of $k_0$ for bending springs. Default `1.0` (the paper uses one $k_0$).
    pub bending_scale: f64,
    /// Stiffness rule. Default [`StiffnessRule::InverseRestLength`].
    pub stiffness: StiffnessRule,
}

impl Default for SpringOptions {
    fn default() -> Self {
        Self {
            structure: true,
            bending: false,
            k0: 1.0,
            bending_scale: 1.0,
            stiffness: StiffnessRule::InverseRestLength,
        }
    }
}

/// One spring between vertices `i < j`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Spring {
    /// First vertex (the smaller index).
    pub i: u32,
    /// Second vertex.
    pub j: u32,
    /// What it models.
    pub kind: SpringKind,
}

/// The springs of a shape set and their rest lengths in every shape.
#[derive(Clone, Debug)]
pub struct SpringSet {
    springs: Vec<Spring>,
    /// `rest[s][q]`: length of spring `q` in shape `s`.
    rest: Vec<Vec<f64>>,
    /// Stiffness multiplier per spring (`k0`, times `bending_scale` for bending springs).
    scale: Vec<f64>,
    options: SpringOptions,
    dropped: usize,
}

/// The sizes (largest bounding-box extent) the solver accepts: lengths to the fourth power, as
/// in the energy's Hessian, stay normal double-precision numbers well inside this range.
pub const SCALE_RANGE: (f64, f64) = (1e-50, 1e50);

/// Refuses a shape whose size is outside [`SCALE_RANGE`] ([`BlendError::Scale`] names it):
/// a mesh of denormal coordinates would collapse to a point, one of 1e150 overflow.
pub fn check_scale(shapes: &ShapeSet) -> Result<(), BlendError> {
    for s in 0..shapes.len() {
        let p = shapes.positions(s);
        let mut extent = 0.0f64;
        for k in 0..3 {
            let lo = p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min);
            let hi = p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max);
            extent = extent.max(hi - lo);
        }
        // A shape collapsed to one point is [`BlendError::DegenerateShape`]'s to name.
        if extent != 0.0 && !(SCALE_RANGE.0..=SCALE_RANGE.1).contains(&extent) {
            return Err(BlendError::Scale {
                shape: shapes.name(s).to_string(),
                extent,
            });
        }
    }
    Ok(())
}

impl SpringSet {
    /// Mean stiffness scale and mean squared rest length of the base's structure springs of
    /// positive length, under `rule` (the stiffness without $k_0$): the units of the hinges'
    /// $\mu$ and of point-target stiffness.
    pub fn base_means(&self, rule: StiffnessRule) -> (f64, f64) {
        let (mut ksum, mut lsum, mut count) = (0.0, 0.0, 0usize);
        for (q, s) in self.springs().iter().enumerate() {
            if s.kind == SpringKind::Structure {
                let r = self.rest_lengths(0)[q];
                if r > 0.0 {
                    ksum += match rule {
                        StiffnessRule::InverseRestLength => self.stiffness_scale(q) / r,
                        StiffnessRule::Uniform => self.stiffness_scale(q),
                    };
                    lsum += r * r;
                    count += 1;
                }
            }
        }
        let count = count.max(1) as f64;
        (ksum / count, lsum / count)
    }

    /// Refuses shapes in which no structure spring has positive length (all its vertices
    /// coincide): [`BlendError::DegenerateShape`] names the first.
    pub fn check_degenerate(&self, shapes: &ShapeSet) -> Result<(), BlendError> {
        for s in 0..shapes.len() {
            let any = self
                .springs()
                .iter()
                .zip(self.rest_lengths(s))
                .any(|(q, &r)| q.kind == SpringKind::Structure && r > 0.0);
            if !any {
                return Err(BlendError::DegenerateShape {
                    shape: shapes.name(s).to_string(),
                });
            }
        }
        Ok(())
    }

    /// Builds the springs from the shared connectivity and measures them in every shape.
    pub fn new(shapes: &ShapeSet, topology: &Topology, options: &SpringOptions) -> Self {
        let mut springs = Vec::new();
        if options.structure {
            springs.extend(topology.edges().iter().map(|&[i, j]| Spring {
                i,
                j,
                kind: SpringKind::Structure,
            }));
        }
        if options.bending {
            for v in 0..topology.num_vertices() {
                for &w in topology.two_ring(v) {
                    if (v as u32) < w {
                        springs.push(Spring {
                            i: v as u32,
                            j: w,
                            kind: SpringKind::Bending,
                        });
                    }
                }
            }
        }
        let mut rest: Vec<Vec<f64>> = shapes
            .all_positions()
            .iter()
            .map(|p| lengths(&springs, p))
            .collect();
        // A spring between coincident vertices in every shape (UV seams that meet at a pole,
        // say) would get stiffness k0 / 0: it is left out, and counted.
        let eps = 1e-12 * crate::mesh::bbox_diagonal(shapes.positions(0)).max(f64::MIN_POSITIVE);
        let keep: Vec<bool> = (0..springs.len())
            .map(|q| rest.iter().any(|r| r[q] > eps))
            .collect();
        let dropped = keep.iter().filter(|k| !**k).count();
        if dropped > 0 {
            let mut it = keep.iter();
            springs.retain(|_| *it.next().unwrap_or(&true));
            for r in &mut rest {
                let mut it = keep.iter();
                r.retain(|_| *it.next().unwrap_or(&true));
            }
        }
        let scale = springs
            .iter()
            .map(|s| match s.kind {
                SpringKind::Bending => options.k0 * options.bending_scale,
                _ => options.k0,
            })
            .collect();
        Self {
            springs,
            rest,
            scale,
            options: options.clone(),
            dropped,
        }
    }

    /// Springs between explicit vertex pairs (internal and anchor springs, Sec. 3.1 and 3.4),
    /// measured in every shape of `shapes`; `scale[q]` is spring `q`'s stiffness multiplier
    /// ($k_q = $ `scale[q]` $/ \bar r_q$ under the paper's rule, Sec. 3.5). Pairs are stored
    /// with `i < j`; pairs whose vertices coincide in every shape are left out and counted,
    /// as in [`new`](Self::new). `options` gives the stiffness rule.
    pub fn from_pairs(shapes: &ShapeSet, pairs: &[(Spring, f64)], options: &SpringOptions) -> Self {
        let eps = 1e-12 * crate::mesh::bbox_diagonal(shapes.positions(0)).max(f64::MIN_POSITIVE);
        let mut springs = Vec::with_capacity(pairs.len());
        let mut scale = Vec::with_capacity(pairs.len());
        let mut dropped = 0;
        for &(s, k) in pairs {
            let (i, j) = (s.i.min(s.j), s.i.max(s.j));
            let long = shapes
                .all_positions()
                .iter()
                .any(|p| norm(sub(p[i as usize], p[j as usize])) > eps);
            if i == j || !long {
                dropped += 1;
                continue;
            }
            springs.push(Spring { i, j, kind: s.kind });
            scale.push(k);
        }
        let rest = shapes
            .all_positions()
            .iter()
            .map(|p| lengths(&springs, p))
            .collect();
        Self {
            springs,
            rest,
            scale,
            options: options.clone(),
            dropped,
        }
    }

    /// Springs left out because their two vertices coincide in every shape.
    pub fn dropped_zero_length(&self) -> usize {
        self.dropped
    }

    /// The springs.
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.springs.len()
    }
    /// True when there are no springs.
    pub fn is_empty(&self) -> bool {
        self.springs.is_empty()
    }
    /// Number of springs of one kind.
    pub fn count(&self, kind: SpringKind) -> usize {
        self.springs.iter().filter(|s| s.kind == kind).count()
    }
    /// Rest lengths of every spring in shape `s`.
    pub fn rest_lengths(&self, s: usize) -> &[f64] {
        &self.rest[s]
    }
    /// Number of shapes measured.
    pub fn num_shapes(&self) -> usize {
        self.rest.len()
    }
    /// The options the set was built with.
    pub fn options(&self) -> &SpringOptions {
        &self.options
    }
    /// Stiffness of spring `q` at interpolated rest length `r`.
    #[inline]
    pub fn stiffness(&self, q: usize, r: f64) -> f64 {
        match self.options.stiffness {
            StiffnessRule::InverseRestLength => self.scale[q] / r,
            StiffnessRule::Uniform => self.scale[q],
        }
    }
    /// Stiffness multiplier of spring `q`: `k0`, times `bending_scale` for bending springs.
    #[inline]
    pub fn stiffness_scale(&self, q: usize) -> f64 {
        self.scale[q]
    }
    /// Current lengths of every spring for positions `p`.
    pub fn lengths(&self, p: &[Point]) -> Vec<f64> {
        lengths(&self.springs, p)
    }
}

fn lengths(springs: &[Spring], p: &[Point]) -> Vec<f64> {
    springs
        .iter()
        .map(|s| norm(sub(p[s.i as usize], p[s.j as usize])))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;

    #[test]
    fn base_means_and_degenerate_shapes() {
        // A right triangle with legs 3 and 4: edges 3, 4, 5.
        let p = vec![[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 4.0, 0.0]];
        let m = TriMesh::new(p.clone(), vec![[0, 1, 2]]);
        let flat = vec![[0.0, 0.0, 0.0]; 3];
        let set = ShapeSet::new(m.clone(), vec![("a".into(), p), ("b".into(), flat)]).unwrap();
        let s = SpringSet::new(&set, &Topology::new(3, &m.triangles), &Default::default());
        let k0 = SpringOptions::default().k0;
        let (k, l2) = s.base_means(StiffnessRule::Uniform);
        assert!(
            (k - k0).abs() < 1e-15 * k0 && (l2 - 50.0 / 3.0).abs() < 1e-12,
            "{k} {l2}"
        );
        let (k, _) = s.base_means(StiffnessRule::InverseRestLength);
        let want = k0 * (1.0 / 3.0 + 1.0 / 4.0 + 1.0 / 5.0) / 3.0;
        assert!((k - want).abs() < 1e-15 * want, "{k} vs {want}");
        // Shape "b" has every vertex at one point.
        match s.check_degenerate(&set) {
            Err(BlendError::DegenerateShape { shape }) => assert_eq!(shape, "b"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn springs_between_coincident_vertices_are_left_out() {
        // Two triangles meeting at vertex 2; vertex 4 sits exactly on vertex 0 (a UV seam).
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 0.0, 0.0],
        ];
        let m = TriMesh::new(p.clone(), vec![[0, 1, 2], [2, 3, 4]]);
        let set = ShapeSet::new(m.clone(), vec![("a".into(), p.clone()), ("b".into(), p)]).unwrap();
        let topo = Topology::new(5, &m.triangles);
        // Vertices 0 and 4 are two edges apart: only a bending spring joins them.
        let options = SpringOptions {
            bending: true,
            ..Default::default()
        };
        let s = SpringSet::new(&set, &topo, &options);
        assert_eq!(s.dropped_zero_length(), 1);
        assert!(s.springs().iter().all(|q| !(q.i == 0 && q.j == 4)));
        assert!(s.rest_lengths(0).iter().all(|&r| r > 0.0));
        assert_eq!(s.rest_lengths(1).len(), s.len());
    }
}
