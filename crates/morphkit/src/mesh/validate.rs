//! Input validation: what is an error and what is only a warning.
//!
//! | problem | outcome | why |
//! |---|---|---|
//! | index out of range | [`MeshError::IndexOutOfRange`] | nothing downstream can interpret it |
//! | NaN or infinite coordinate | [`MeshError::NonFinite`] | it would poison every solve |
//! | triangle repeating a vertex | warning | exporters write them; it has no area, so solvers leave it out ([`super::Weld::shapes`]) and writers keep it |
//! | zero-area triangle (collinear vertices) | warning | real scans have them; algorithms guard against them |
//! | duplicate triangle | warning | reported; springs deduplicate edges anyway |
//! | duplicate (coincident) vertex positions | warning | seams in UV-split meshes are common and legitimate |
//! | vertex used by no triangle | warning | algorithms that need every vertex reject it themselves |

use super::{norm, triangle_normal, TriMesh};

/// A mesh that cannot be used at all.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MeshError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has only {num_vertices} vertices")]
    IndexOutOfRange {
        /// Offending triangle.
        triangle: usize,
        /// Offending vertex index.
        index: u32,
        /// Vertex count.
        num_vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {value}")]
    NonFinite {
        /// Offending vertex.
        vertex: usize,
        /// The bad value.
        value: f64,
    },
    /// The mesh has no triangles (or only triangles that use a vertex twice).
    #[error("the mesh has no triangles with three distinct vertices")]
    NoTriangles,
}

/// Something odd about a mesh that does not stop it from being used.
#[derive(Debug, Clone, PartialEq)]
pub enum ValidationWarning {
    /// Triangles that use a vertex twice (or three times): no area by construction.
    RepeatedVertexTriangles(Vec<usize>),
    /// Triangles whose area is below `1e-12 ×` the squared bounding-box diagonal.
    DegenerateTriangles(Vec<usize>),
    /// Pairs `(first, duplicate)` of triangles with the same vertex set.
    DuplicateTriangles(Vec<(usize, usize)>),
    /// Pairs `(first, duplicate)` of vertices at exactly the same position.
    DuplicateVertices(Vec<(usize, usize)>),
    /// Vertices used by no triangle.
    IsolatedVertices(Vec<usize>),
}

impl std::fmt::Display for ValidationWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        fn list<T: std::fmt::Debug>(v: &[T]) -> String {
            let head: Vec<String> = v.iter().take(5).map(|x| format!("{x:?}")).collect();
            let more = if v.len() > 5 {
                format!(", … ({} in all)", v.len())
            } else {
                String::new()
            };
            format!("{}{more}", head.join(", "))
        }
        match self {
            Self::RepeatedVertexTriangles(v) => write!(
                f,
                "{} triangles use a vertex twice (left out of solves, kept in outputs): {}",
                v.len(),
                list(v)
            ),
            Self::DegenerateTriangles(v) => {
                write!(f, "{} zero-area triangles: {}", v.len(), list(v))
            }
            Self::DuplicateTriangles(v) => {
                write!(f, "{} duplicate triangles: {}", v.len(), list(v))
            }
            Self::DuplicateVertices(v) => write!(f, "{} coincident vertices: {}", v.len(), list(v)),
            Self::IsolatedVertices(v) => {
                write!(f, "{} vertices used by no triangle: {}", v.len(), list(v))
            }
        }
    }
}

/// The warnings found by [`validate`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ValidationReport {
    /// Every warning, at most one per kind.
    pub warnings: Vec<ValidationWarning>,
}

impl ValidationReport {
    /// Vertices used by no triangle.
    pub fn isolated_vertices(&self) -> &[usize] {
        self.warnings
            .iter()
            .find_map(|w| match w {
                ValidationWarning::IsolatedVertices(v) => Some(v.as_slice()),
                _ => None,
            })
            .unwrap_or(&[])
    }
}

/// Checks a mesh; errors for what makes it unusable, a report of warnings otherwise.
pub fn validate(mesh: &TriMesh) -> Result<ValidationReport, MeshError> {
    let nv = mesh.num_vertices();
    if mesh.triangles.is_empty() {
        return Err(MeshError::NoTriangles);
    }
    for (v, p) in mesh.positions.iter().enumerate() {
        if let Some(&value) = p.iter().find(|x| !x.is_finite()) {
            return Err(MeshError::NonFinite { vertex: v, value });
        }
    }
    let mut used = vec![false; nv];
    let mut repeated = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &i in tri {
            if i as usize >= nv {
                return Err(MeshError::IndexOutOfRange {
                    triangle: t,
                    index: i,
                    num_vertices: nv,
                });
            }
            used[i as usize] = true;
        }
        if tri[0] == tri[1] || tri[0] == tri[2] || tri[1] == tri[2] {
            repeated.push(t);
        }
    }
    if repeated.len() == mesh.num_triangles() {
        return Err(MeshError::NoTriangles);
    }
    let mut report = ValidationReport::default();
    if !repeated.is_empty() {
        report
            .warnings
            .push(ValidationWarning::RepeatedVertexTriangles(repeated));
    }
    let d = mesh.bbox_diagonal();
    let area_tol = 1e-12 * d * d;
    let degenerate: Vec<usize> = (0..mesh.num_triangles())
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t];
            a != b
                && b != c
                && c != a
                && 0.5 * norm(triangle_normal(&mesh.positions, mesh.triangles[t])) <= area_tol
        })
        .collect();
    if !degenerate.is_empty() {
        report
            .warnings
            .push(ValidationWarning::DegenerateTriangles(degenerate));
    }
    let mut seen =
        super::FastMap::with_capacity_and_hasher(mesh.num_triangles(), Default::default());
    let mut dup_tris = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut key = *tri;
        key.sort_unstable();
        if let Some(&first) = seen.get(&key) {
            dup_tris.push((first, t));
        } else {
            seen.insert(key, t);
        }
    }
    if !dup_tris.is_empty() {
        report
            .warnings
            .push(ValidationWarning::DuplicateTriangles(dup_tris));
    }
    let mut seen_pos = super::FastMap::with_capacity_and_hasher(nv, Default::default());
    let mut dup_v = Vec::new();
    for (v, p) in mesh.positions.iter().enumerate() {
        let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
        if let Some(&first) = seen_pos.get(&key) {
            dup_v.push((first, v));
        } else {
            seen_pos.insert(key, v);
        }
    }
    if !dup_v.is_empty() {
        report
            .warnings
            .push(ValidationWarning::DuplicateVertices(dup_v));
    }
    let isolated: Vec<usize> = (0..nv).filter(|&v| !used[v]).collect();
    if !isolated.is_empty() {
        report
            .warnings
            .push(ValidationWarning::IsolatedVertices(isolated));
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> TriMesh {
        TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
    }

    #[test]
    fn index_out_of_range_names_triangle_and_index() {
        let mut m = tri();
        m.triangles.push([0, 1, 7]);
        let e = validate(&m).unwrap_err();
        assert_eq!(
            e,
            MeshError::IndexOutOfRange {
                triangle: 1,
                index: 7,
                num_vertices: 3
            }
        );
    }

    #[test]
    fn nan_is_an_error() {
        let mut m = tri();
        m.positions[2][1] = f64::NAN;
        assert!(matches!(
            validate(&m),
            Err(MeshError::NonFinite { vertex: 2, .. })
        ));
    }

    #[test]
    fn warnings_for_degenerate_duplicate_and_isolated() {
        let mut m = tri();
        m.positions.push([2.0, 0.0, 0.0]); // collinear with 0 and 1
        m.positions.push([5.0, 5.0, 5.0]); // isolated
        m.triangles.push([0, 1, 3]);
        m.triangles.push([2, 0, 1]);
        let r = validate(&m).unwrap();
        assert!(r
            .warnings
            .contains(&ValidationWarning::DegenerateTriangles(vec![1])));
        assert!(r
            .warnings
            .contains(&ValidationWarning::DuplicateTriangles(vec![(0, 2)])));
        assert_eq!(r.isolated_vertices(), &[4]);
    }

    /// Issue 37: a triangle that uses a vertex twice made readers refuse the whole file.
    #[test]
    fn a_triangle_that_uses_a_vertex_twice_is_a_warning_and_only_such_triangles_an_error() {
        let mut m = tri();
        m.triangles.push([1, 1, 2]);
        m.triangles.push([0, 2, 2]);
        let r = validate(&m).unwrap();
        assert!(r
            .warnings
            .contains(&ValidationWarning::RepeatedVertexTriangles(vec![1, 2])));
        // They are not also listed as zero-area triangles.
        assert!(!r
            .warnings
            .iter()
            .any(|w| matches!(w, ValidationWarning::DegenerateTriangles(_))));
        let only = TriMesh::new(m.positions.clone(), vec![[0, 0, 1]]);
        assert_eq!(validate(&only), Err(MeshError::NoTriangles));
    }
}
