//! The reverse solve (Ma et al. 2012, Sec. 3.4 step 3; math notes §1): the positions of the
//! extra (interior and anchor) vertices in a target whose surface is known.
//!
//! With the target's surface vertices fixed and the extra springs at their *base* rest
//! lengths, the extra vertices are solved to equilibrium,
//!
//! $$y^s = \arg\min_y \sum_{q \in \text{extra}} \tfrac12 k_q \big(\lVert p_i - p_j \rVert - r_q^0\big)^2,
//! \qquad p = (x^s_{\text{surface}}, y),$$
//!
//! by the same Newton solver as the blend ([`PhysicalBlend::with_terms`] on a one-shape set whose
//! surface is all fixed). It starts from a guess that carries each extra vertex rigidly with
//! its surface neighbourhood: the weighted (1/d²) Kabsch motion of its nearest surface vertices
//! from the base to the target. For a target that is a rigid motion of the base the guess is
//! already the equilibrium (zero iterations).

use super::InteriorError;
use crate::geom::kabsch;
use crate::mesh::{norm, sub, Point, ShapeSet, TriMesh};
use crate::springs::terms::{EnergyTerm, SpringTerm};
use crate::springs::{
    BlendOptions, FixedVertices, HingeOptions, PhysicalBlend, Spring, SpringOptions, SpringSet,
    Weights,
};
use crate::transfer::kdtree::KdTree;

/// Surface neighbourhoods of the extra vertices, found once in the base.
pub struct Neighbourhoods {
    /// Per extra vertex: surface ids and weights.
    lists: Vec<Vec<(u32, f64)>>,
}

/// Most surface vertices that carry one extra vertex in the guess.
const NEIGHBOURS: usize = 32;

impl Neighbourhoods {
    /// For each extra point, its nearest surface vertices of `surface` (base positions).
    pub fn new(surface: &[Point], extra: &[Point]) -> Self {
        let tree = KdTree::new(surface);
        let mut found = Vec::new();
        let lists = extra
            .iter()
            .map(|&p| {
                let Some((_, d0)) = tree.nearest_filtered(p, |_| true) else {
                    return Vec::new();
                };
                let mut r = 2.0 * d0.max(f64::MIN_POSITIVE);
                loop {
                    found.clear();
                    tree.within(p, r, &mut found);
                    if found.len() >= NEIGHBOURS.min(surface.len()) || r > 1e3 * d0 {
                        break;
                    }
                    r *= 1.5;
                }
                let mut c: Vec<(f64, u32)> = found
                    .iter()
                    .map(|&v| (norm(sub(surface[v as usize], p)), v))
                    .collect();
                c.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                c.truncate(NEIGHBOURS);
                c.into_iter()
                    .map(|(d, v)| (v, 1.0 / (d * d).max(1e-30)))
                    .collect()
            })
            .collect();
        Self { lists }
    }

    /// The guess: each extra point moved by its neighbourhood's Kabsch motion.
    pub fn guess(&self, base: &[Point], target: &[Point], extra: &[Point]) -> Vec<Point> {
        self.lists
            .iter()
            .zip(extra)
            .map(|(l, &p)| {
                if l.is_empty() {
                    return p;
                }
                let from: Vec<Point> = l.iter().map(|&(v, _)| base[v as usize]).collect();
                let to: Vec<Point> = l.iter().map(|&(v, _)| target[v as usize]).collect();
                let w: Vec<f64> = l.iter().map(|&(_, w)| w).collect();
                kabsch(&from, &to, &w).apply(p)
            })
            .collect()
    }
}

/// Solves the extra vertices of target `s` of `shapes` (surface only). `base_extended` is the
/// base surface followed by the extra vertices' base positions; `springs` are the extra
/// springs with their stiffness multipliers; `start` the extra vertices' starting positions.
/// Returns the extra vertices' positions in target `s` and the Newton iterations taken.
pub fn solve(
    shapes: &ShapeSet,
    s: usize,
    base_extended: &[Point],
    springs: &[(Spring, f64)],
    start: &[Point],
    options: &BlendOptions,
) -> Result<(Vec<Point>, usize), InteriorError> {
    let n = shapes.num_vertices();
    let mesh = TriMesh::new(base_extended.to_vec(), shapes.triangles().to_vec());
    let measured = ShapeSet::new(mesh.clone(), vec![("base".into(), base_extended.to_vec())])?;
    let set = SpringSet::from_pairs(&measured, springs, &options.springs);
    let mut p = shapes.positions(s).to_vec();
    p.extend_from_slice(start);
    let helper = ShapeSet::new(mesh, vec![(shapes.name(s).to_string(), p)])?;
    let o = BlendOptions {
        springs: SpringOptions {
            bending: false,
            ..options.springs.clone()
        },
        hinges: HingeOptions {
            weight: 0.0,
            ..options.hinges.clone()
        },
        fixed: FixedVertices::Ids((0..n as u32).collect()),
        kinematic_stretch: f64::INFINITY,
        // The equilibrium of the extra springs alone: no pull towards the starting guess.
        tether: 0.0,
        // Set-up, not a frame: it converges slowly from far, and must not stop early.
        stall_iterations: 0,
        max_factorizations: 0,
        ..options.clone()
    };
    let term: Box<dyn EnergyTerm> = Box::new(SpringTerm::new(set, o.min_rest_fraction));
    let mut solver = PhysicalBlend::with_terms(&helper, &o, vec![term])?;
    let r = solver.solve(&Weights::Convex(vec![1.0]))?;
    if !r.stats.converged {
        return Err(InteriorError::ReverseSolve {
            target: shapes.name(s).to_string(),
            gradient: r.stats.gradient_norm,
            tolerance: r.stats.gradient_tolerance,
            iterations: r.stats.newton_iterations,
        });
    }
    Ok((r.positions[n..].to_vec(), r.stats.newton_iterations))
}
