//! Per-triangle flexibility of an animation (Wang & Lee 2008, Sec. 3.1.1, Eq. 1).
//!
//! For edge-adjacent triangles $i, j$ (the set $U$) and frames $f = 1 \dots k$ with deformation
//! gradients $D_{fi}$ (3 × 3, reference → frame, [`crate::transfer::GradientOperator`]):
//! $$G_{ij} = \max_{f} \|D_{fi} - D_{fj}\|_F^2, \qquad
//! \text{flex}_i = \frac{1}{|U_i|} \sum_{j \in U_i} G_{ij}.$$
//! Dimensionless (gradients are), non-negative; 0 where neighbours move as one rigid piece,
//! large across joints. A triangle without neighbours has flexibility 0. High values show
//! where the correspondence needs markers (the paper's Fig. 3); thresholded by γ they give the
//! [`super::Partitions`]. [`Flexibility::map_to_target`] carries it through a correspondence
//! (mean over a target triangle's matched source triangles), as Sec. 3.2.1 requires.

use super::SynthError;
use crate::mesh::{Point, Topology, TriMesh};
use crate::transfer::{Correspondence, GradientOperator};
use nalgebra::Matrix3;

/// Flexibility of every triangle of one mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Flexibility {
    /// $\text{flex}_i$, one per triangle, ≥ 0.
    pub values: Vec<f64>,
}

/// Running maximum of Eq. 1 over frames, one entry per adjacent pair: build once, add frames.
#[derive(Clone, Debug)]
pub struct FlexibilityAccumulator {
    pairs: Vec<[u32; 2]>,
    max_sq: Vec<f64>,
    num_triangles: usize,
    frames: usize,
}

impl FlexibilityAccumulator {
    /// Lists the edge-adjacent triangle pairs of `topology` over `num_triangles` triangles.
    pub fn new(topology: &Topology, num_triangles: usize) -> Self {
        let mut pairs = Vec::new();
        for i in 0..num_triangles {
            for &j in topology.face_neighbors(i) {
                if (i as u32) < j {
                    pairs.push([i as u32, j]);
                }
            }
        }
        let n = pairs.len();
        Self {
            pairs,
            max_sq: vec![0.0; n],
            num_triangles,
            frames: 0,
        }
    }

    /// Adds one frame's gradients (one per triangle).
    pub fn add(&mut self, gradients: &[Matrix3<f64>]) -> Result<(), SynthError> {
        if gradients.len() != self.num_triangles {
            return Err(SynthError::Length {
                what: "frame gradients",
                expected: self.num_triangles,
                found: gradients.len(),
            });
        }
        for (p, m) in self.pairs.iter().zip(&mut self.max_sq) {
            let d = (gradients[p[0] as usize] - gradients[p[1] as usize]).norm_squared();
            if d > *m {
                *m = d;
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The mean of $G_{ij}$ over each triangle's neighbours.
    pub fn finish(&self) -> Flexibility {
        let mut sum = vec![0.0; self.num_triangles];
        let mut count = vec![0u32; self.num_triangles];
        for (p, &g) in self.pairs.iter().zip(&self.max_sq) {
            for &t in p {
                sum[t as usize] += g;
                count[t as usize] += 1;
            }
        }
        let values = sum
            .iter()
            .zip(&count)
            .map(|(&s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
            .collect();
        Flexibility { values }
    }
}

impl Flexibility {
    /// Flexibility of the animation `frames` (positions over `reference`'s connectivity).
    pub fn from_frames(reference: &TriMesh, frames: &[Vec<Point>]) -> Result<Self, SynthError> {
        let op = GradientOperator::new(reference);
        let topo = Topology::new(reference.num_vertices(), &reference.triangles);
        let mut acc = FlexibilityAccumulator::new(&topo, reference.num_triangles());
        for (i, f) in frames.iter().enumerate() {
            acc.add(&op.gradients_at(i, f)?)?;
        }
        Ok(acc.finish())
    }

    /// The flexibility of each target triangle: the mean over its matched source triangles.
    pub fn map_to_target(&self, correspondence: &Correspondence) -> Result<Self, SynthError> {
        if self.values.len() != correspondence.source_triangles {
            return Err(SynthError::Length {
                what: "source flexibility",
                expected: correspondence.source_triangles,
                found: self.values.len(),
            });
        }
        let values = (0..correspondence.target_triangles)
            .map(|t| {
                let m = correspondence.matches_of(t);
                m.iter().map(|&s| self.values[s as usize]).sum::<f64>() / m.len().max(1) as f64
            })
            .collect();
        Ok(Self { values })
    }

    /// Largest value (0 for an empty mesh).
    pub fn max(&self) -> f64 {
        self.values.iter().copied().fold(0.0, f64::max)
    }
}

/// One-shot [`Flexibility::from_frames`].
pub fn flexibility(reference: &TriMesh, frames: &[Vec<Point>]) -> Result<Flexibility, SynthError> {
    Flexibility::from_frames(reference, frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn rigid_motion_is_stiff_and_a_bend_is_flexible_at_the_joint() {
        let bar = generate::bar(4.0, 0.5, 2, 16);
        let rot = generate::rotate(&bar.positions, [0.3, 0.1, 0.2], [1.0, 2.0, 0.5], 1.2);
        let f = flexibility(&bar, &[bar.positions.clone(), rot]).unwrap();
        assert!(f.max() < 1e-20, "rigid: {}", f.max());
        // Bend the right half by 90° over a short joint around x = 2.
        let bent = generate::bend(&bar.positions, 1.9, 0.2, std::f64::consts::FRAC_PI_2);
        let f = flexibility(&bar, &[bent]).unwrap();
        for (t, &v) in f.values.iter().enumerate() {
            let c = (0..3)
                .map(|k| bar.positions[bar.triangles[t][k] as usize][0])
                .sum::<f64>()
                / 3.0;
            if !(1.5..=2.6).contains(&c) {
                assert!(v < 1e-12, "triangle {t} at x = {c} has {v}");
            }
        }
        assert!(f.max() > 0.1, "joint flexibility {}", f.max());
    }

    #[test]
    fn maps_through_the_identity() {
        let m = generate::uv_sphere(1.0, 6, 8);
        let f = Flexibility {
            values: (0..m.num_triangles()).map(|t| t as f64).collect(),
        };
        assert_eq!(f.map_to_target(&Correspondence::identity(&m)).unwrap(), f);
    }
}
