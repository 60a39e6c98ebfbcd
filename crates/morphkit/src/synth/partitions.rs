//! Stiff and flexible partitions of a target mesh (Wang & Lee 2008, Sec. 3.2.1).
//!
//! Start with one partition per triangle and merge edge-adjacent partitions while the two
//! triangles on the shared edge both have flexibility below γ (default 0.1, the paper's
//! value). Merging to a fixed point is a union–find over the edges whose two triangles are
//! both stiff-ish, so the result does not depend on the merge order. A partition of more than
//! one triangle is **stiff** (it copies a source deformation); a single triangle is
//! **flexible** (it blends between stiff partitions through the weights of Eq. 5). Partition
//! ids are numbered in order of their lowest triangle, so they are deterministic.

use super::{Flexibility, SynthError};
use crate::mesh::Topology;

/// The paper's flexibility threshold γ.
pub const GAMMA: f64 = 0.1;

/// A partition of the triangles into stiff and flexible parts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Partitions {
    /// Partition id of each triangle.
    label: Vec<u32>,
    /// Triangle count of each partition.
    size: Vec<u32>,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

impl Partitions {
    /// Partitions by threshold `gamma` over the edge adjacency of `topology`.
    pub fn new(
        flexibility: &Flexibility,
        topology: &Topology,
        gamma: f64,
    ) -> Result<Self, SynthError> {
        if !(gamma.is_finite() && gamma > 0.0) {
            return Err(SynthError::Parameter {
                name: "gamma",
                value: gamma,
                why: "must be positive",
            });
        }
        let nf = flexibility.values.len();
        if nf != topology.num_triangles() {
            return Err(SynthError::Length {
                what: "flexibility (one value per triangle)",
                expected: topology.num_triangles(),
                found: nf,
            });
        }
        if let Some((t, &f)) = flexibility
            .values
            .iter()
            .enumerate()
            .find(|(_, f)| !(f.is_finite() && **f >= 0.0))
        {
            return Err(SynthError::Value {
                what: "flexibility",
                index: t,
                value: f,
                why: "must be a finite number >= 0",
            });
        }
        let below: Vec<bool> = flexibility.values.iter().map(|&f| f < gamma).collect();
        let mut parent: Vec<u32> = (0..nf as u32).collect();
        for i in 0..nf {
            if !below[i] {
                continue;
            }
            for &j in topology.face_neighbors(i) {
                if (j as usize) > i && below[j as usize] {
                    let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j));
                    if a != b {
                        // Keep the lower root, so that roots are lowest triangles.
                        parent[a.max(b) as usize] = a.min(b);
                    }
                }
            }
        }
        let mut id_of_root = vec![u32::MAX; nf];
        let mut label = Vec::with_capacity(nf);
        let mut size = Vec::new();
        for t in 0..nf {
            let r = find(&mut parent, t as u32) as usize;
            if id_of_root[r] == u32::MAX {
                id_of_root[r] = size.len() as u32;
                size.push(0);
            }
            let id = id_of_root[r];
            size[id as usize] += 1;
            label.push(id);
        }
        Ok(Self { label, size })
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.label.len()
    }

    /// Number of partitions (stiff and flexible).
    pub fn num_partitions(&self) -> usize {
        self.size.len()
    }

    /// Partition of triangle `t`.
    pub fn label(&self, t: usize) -> usize {
        self.label[t] as usize
    }

    /// Partition id of every triangle.
    pub fn labels(&self) -> &[u32] {
        &self.label
    }

    /// Triangle count of partition `p`.
    pub fn size(&self, p: usize) -> usize {
        self.size[p] as usize
    }

    /// True when partition `p` has more than one triangle.
    pub fn is_stiff(&self, p: usize) -> bool {
        self.size[p] > 1
    }

    /// True when triangle `t` lies in a stiff partition.
    pub fn is_stiff_triangle(&self, t: usize) -> bool {
        self.is_stiff(self.label(t))
    }

    /// Number of stiff partitions.
    pub fn num_stiff(&self) -> usize {
        self.size.iter().filter(|&&s| s > 1).count()
    }

    /// Triangles in stiff partitions, as a mask.
    pub fn stiff_mask(&self) -> Vec<bool> {
        (0..self.label.len())
            .map(|t| self.is_stiff_triangle(t))
            .collect()
    }
}

/// One-shot [`Partitions::new`] from a triangle list.
pub fn partitions(
    flexibility: &Flexibility,
    num_vertices: usize,
    triangles: &[[u32; 3]],
    gamma: f64,
) -> Result<Partitions, SynthError> {
    Partitions::new(flexibility, &Topology::new(num_vertices, triangles), gamma)
}

/// Test helper: the partitions of `mesh` whose triangles have the flexibilities `values`, at
/// the default threshold [`GAMMA`].
#[cfg(test)]
pub(crate) fn partitions_of(mesh: &crate::mesh::TriMesh, values: Vec<f64>) -> Partitions {
    partitions(
        &Flexibility { values },
        mesh.num_vertices(),
        &mesh.triangles,
        GAMMA,
    )
    .expect("valid test flexibilities")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_flexible_band_splits_a_strip_into_two_stiff_parts() {
        // 10 × 1 grid: 20 triangles in a row of squares; squares 4 and 5 are flexible.
        let g = generate::grid(10, 1, 10.0, 1.0);
        let values = (0..20)
            .map(|t| if (8..12).contains(&t) { 0.5 } else { 0.01 })
            .collect();
        let p = partitions_of(&g, values);
        assert_eq!(p.num_stiff(), 2);
        assert_eq!(p.num_partitions(), 2 + 4);
        assert_eq!(p.label(0), 0);
        assert_eq!(p.size(p.label(0)), 8);
        assert_eq!(p.size(p.label(19)), 8);
        assert!(!p.is_stiff_triangle(9));
        assert!(p.is_stiff_triangle(12) && p.label(12) != p.label(0));
        assert!(partitions(
            &Flexibility {
                values: vec![0.0; 20]
            },
            g.num_vertices(),
            &g.triangles,
            -1.0
        )
        .is_err());
    }

    /// Issue 39: a wrong length panicked (index out of bounds) and NaN was accepted.
    #[test]
    fn flexibility_of_the_wrong_length_or_not_finite_is_an_error_naming_it() {
        let g = generate::grid(10, 1, 10.0, 1.0);
        let run = |values: Vec<f64>| {
            partitions(&Flexibility { values }, g.num_vertices(), &g.triangles, 0.1)
                .unwrap_err()
                .to_string()
        };
        let e = run(vec![0.0; 19]);
        assert!(e.contains("has 19 entries, expected 20"), "{e}");
        let mut v = vec![0.0; 20];
        v[7] = f64::NAN;
        let e = run(v);
        assert!(e.contains("flexibility[7] = NaN"), "{e}");
        let mut v = vec![0.0; 20];
        v[3] = -1.0;
        assert!(run(v).contains("flexibility[3] = -1"));
    }
}
