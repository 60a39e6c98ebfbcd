//! Element inversion, the paper's known limitation (Ma et al. 2012, Sec. 5, "Limitations"):
//! a mass–spring system may have several equilibria, and the one found may turn elements
//! inside out.
//!
//! Per frame two counts: interior tetrahedra (of the lattice or of `tetgen`) whose signed
//! volume is not positive (they are all positive in the base, see [`lattice`](super::lattice)
//! and [`tetgen`](super::tetgen)), and surface triangles whose normal
//! points against the same triangle's normal in the linear blend of the same weights
//! ($n_t \cdot n_t^{\text{lin}} < 0$; triangles degenerate in the linear blend are not
//! counted).

use super::lattice::tet_volume6;
use crate::mesh::{dot, triangle_normal, Point};

/// Inverted elements of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Inversions {
    /// Interior tetrahedra with non-positive volume.
    pub tetrahedra: usize,
    /// Interior tetrahedra in all.
    pub tetrahedra_total: usize,
    /// Surface triangles whose normal flips against the linear blend's.
    pub triangles: usize,
}

/// Counts inversions of `extended` (surface then extra vertices) against `linear` (surface).
pub fn count_inversions(
    extended: &[Point],
    triangles: &[[u32; 3]],
    tets: &[[u32; 4]],
    linear: &[Point],
) -> Inversions {
    let tetrahedra = tets
        .iter()
        .filter(|t| tet_volume6(|v| extended[v as usize], **t) <= 0.0)
        .count();
    let flipped = triangles
        .iter()
        .filter(|&&t| {
            let a = triangle_normal(extended, t);
            let b = triangle_normal(linear, t);
            dot(a, a) > 0.0 && dot(b, b) > 0.0 && dot(a, b) < 0.0
        })
        .count();
    Inversions {
        tetrahedra,
        tetrahedra_total: tets.len(),
        triangles: flipped,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mirrored_tet_and_a_flipped_triangle_are_counted() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let tri = [[0u32, 1, 2]];
        let tet = [[0u32, 1, 2, 3]];
        assert_eq!(
            count_inversions(&p, &tri, &tet, &p),
            Inversions {
                tetrahedra: 0,
                tetrahedra_total: 1,
                triangles: 0
            }
        );
        let mut q = p.clone();
        q[3][2] = -1.0;
        q[2][2] = 0.0;
        let mut lin = p.clone();
        lin[1] = [-1.0, 0.0, 0.0];
        let c = count_inversions(&q, &tri, &tet, &lin);
        assert_eq!((c.tetrahedra, c.triangles), (1, 1));
    }
}
