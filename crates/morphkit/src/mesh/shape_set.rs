//! Shape sets: several shapes (blendshape targets, animation frames) over one connectivity.

use super::{Point, TriMesh};

/// Why shapes could not be put into one [`ShapeSet`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ShapeSetError {
    /// A shape set needs at least one shape.
    #[error("a shape set needs at least one shape")]
    Empty,
    /// A shape has another vertex count than the first shape.
    #[error("{name}: has {found} vertices, the base '{base}' has {expected}")]
    VertexCount {
        /// Name (usually the file) of the offending shape.
        name: String,
        /// Name of the base shape.
        base: String,
        /// Vertex count of the base.
        expected: usize,
        /// Vertex count of the offending shape.
        found: usize,
    },
    /// A shape has another triangle count than the first shape.
    #[error("{name}: has {found} triangles, the base '{base}' has {expected}")]
    TriangleCount {
        /// Name (usually the file) of the offending shape.
        name: String,
        /// Name of the base shape.
        base: String,
        /// Triangle count of the base.
        expected: usize,
        /// Triangle count of the offending shape.
        found: usize,
    },
    /// A shape's triangle differs from the base's triangle with the same index.
    #[error("{name}: triangle {index} is {found:?}, the base '{base}' has {expected:?} (different connectivity)")]
    Connectivity {
        /// Name (usually the file) of the offending shape.
        name: String,
        /// Name of the base shape.
        base: String,
        /// Index of the first differing triangle.
        index: usize,
        /// The base's triangle.
        expected: [u32; 3],
        /// The offending triangle.
        found: [u32; 3],
    },
    /// Positions given for a shape do not match the vertex count.
    #[error("shape '{name}': {found} positions given for {expected} vertices")]
    PositionCount {
        /// Name of the shape.
        name: String,
        /// Vertex count of the connectivity.
        expected: usize,
        /// Number of positions given.
        found: usize,
    },
}

/// Shapes that share one connectivity: blendshape targets or the frames of an animation.
///
/// Shape 0 is the *base* (the neutral face, the reference pose). All shapes have the same vertex
/// count and identical triangle lists; construction verifies this.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSet {
    connectivity: TriMesh,
    names: Vec<String>,
    shapes: Vec<Vec<Point>>,
}

impl ShapeSet {
    /// Builds a set from named meshes, checking vertex counts and triangle lists against the
    /// first mesh. The first mesh's polygon information is kept.
    pub fn from_meshes(meshes: Vec<(String, TriMesh)>) -> Result<Self, ShapeSetError> {
        let mut it = meshes.into_iter();
        let (base_name, base) = it.next().ok_or(ShapeSetError::Empty)?;
        let mut set = ShapeSet {
            names: vec![base_name],
            shapes: vec![base.positions.clone()],
            connectivity: base,
        };
        for (name, m) in it {
            set.check_connectivity(&name, &m)?;
            set.names.push(name);
            set.shapes.push(m.positions);
        }
        Ok(set)
    }

    /// Builds a set from one connectivity and per-shape positions.
    pub fn new(
        connectivity: TriMesh,
        shapes: Vec<(String, Vec<Point>)>,
    ) -> Result<Self, ShapeSetError> {
        if shapes.is_empty() {
            return Err(ShapeSetError::Empty);
        }
        let nv = connectivity.num_vertices();
        let mut names = Vec::with_capacity(shapes.len());
        let mut pos = Vec::with_capacity(shapes.len());
        for (name, p) in shapes {
            if p.len() != nv {
                return Err(ShapeSetError::PositionCount {
                    name,
                    expected: nv,
                    found: p.len(),
                });
            }
            names.push(name);
            pos.push(p);
        }
        let mut connectivity = connectivity;
        connectivity.positions = pos[0].clone();
        Ok(ShapeSet {
            connectivity,
            names,
            shapes: pos,
        })
    }

    /// Checks that `mesh` has this set's connectivity; the error names `name`.
    pub fn check_connectivity(&self, name: &str, mesh: &TriMesh) -> Result<(), ShapeSetError> {
        let base = &self.connectivity;
        if mesh.num_vertices() != base.num_vertices() {
            return Err(ShapeSetError::VertexCount {
                name: name.to_string(),
                base: self.names[0].clone(),
                expected: base.num_vertices(),
                found: mesh.num_vertices(),
            });
        }
        if let Some((index, (e, f))) = base
            .triangles
            .iter()
            .zip(&mesh.triangles)
            .enumerate()
            .find(|(_, (e, f))| e != f)
        {
            return Err(ShapeSetError::Connectivity {
                name: name.to_string(),
                base: self.names[0].clone(),
                index,
                expected: *e,
                found: *f,
            });
        }
        if mesh.num_triangles() != base.num_triangles() {
            return Err(ShapeSetError::TriangleCount {
                name: name.to_string(),
                base: self.names[0].clone(),
                expected: base.num_triangles(),
                found: mesh.num_triangles(),
            });
        }
        Ok(())
    }

    /// Appends a shape with the same vertex count.
    pub fn push(&mut self, name: String, positions: Vec<Point>) -> Result<(), ShapeSetError> {
        if positions.len() != self.connectivity.num_vertices() {
            return Err(ShapeSetError::PositionCount {
                name,
                expected: self.connectivity.num_vertices(),
                found: positions.len(),
            });
        }
        self.names.push(name);
        self.shapes.push(positions);
        Ok(())
    }

    /// Number of shapes (at least 1).
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// Always false: a shape set holds at least its base.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// The shared connectivity, with the base shape's positions.
    pub fn base(&self) -> &TriMesh {
        &self.connectivity
    }

    /// Shared triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.connectivity.triangles
    }

    /// Number of vertices of every shape.
    pub fn num_vertices(&self) -> usize {
        self.connectivity.num_vertices()
    }

    /// Positions of shape `i`.
    pub fn positions(&self, i: usize) -> &[Point] {
        &self.shapes[i]
    }

    /// All shapes' positions.
    pub fn all_positions(&self) -> &[Vec<Point>] {
        &self.shapes
    }

    /// Name of shape `i`.
    pub fn name(&self, i: usize) -> &str {
        &self.names[i]
    }

    /// All names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Shape `i` as a stand-alone mesh.
    pub fn mesh(&self, i: usize) -> TriMesh {
        self.connectivity.with_positions(self.shapes[i].clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriMesh {
        TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn rejects_different_connectivity_naming_the_face() {
        let a = quad();
        let mut b = quad();
        b.triangles[1] = [0, 3, 2];
        let err =
            ShapeSet::from_meshes(vec![("a.obj".into(), a), ("b.obj".into(), b)]).unwrap_err();
        assert_eq!(
            err,
            ShapeSetError::Connectivity {
                name: "b.obj".into(),
                base: "a.obj".into(),
                index: 1,
                expected: [0, 2, 3],
                found: [0, 3, 2]
            }
        );
        assert!(err.to_string().contains("b.obj: triangle 1"));
    }

    #[test]
    fn rejects_vertex_count_mismatch() {
        let a = quad();
        let mut b = quad();
        b.positions.push([2.0, 0.0, 0.0]);
        let err = ShapeSet::from_meshes(vec![("a".into(), a), ("b".into(), b)]).unwrap_err();
        assert!(matches!(
            err,
            ShapeSetError::VertexCount {
                expected: 4,
                found: 5,
                ..
            }
        ));
    }

    #[test]
    fn keeps_shapes_in_order() {
        let a = quad();
        let mut b = quad();
        b.positions[2] = [2.0, 2.0, 0.0];
        let s = ShapeSet::from_meshes(vec![("a".into(), a), ("b".into(), b)]).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s.positions(1)[2], [2.0, 2.0, 0.0]);
        assert_eq!(s.mesh(1).triangles, s.triangles());
    }
}
