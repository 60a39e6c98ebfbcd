//! Typed errors of the transfer pipeline. Every variant names the offending index.

use crate::mesh::MeshError;
use crate::sparse::SolveError;

/// Which mesh an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The source (animated) mesh.
    Source,
    /// The target mesh.
    Target,
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Side::Source => "source",
            Side::Target => "target",
        })
    }
}

/// Why a marker list cannot be used.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MarkerError {
    /// The marker file is not `{"pairs": [[source, target], ...]}`.
    #[error("markers: {0}")]
    Parse(String),
    /// A marker refers to a vertex that does not exist.
    #[error("marker {marker}: {side} vertex {vertex} is out of range (the {side} mesh has {num_vertices} vertices; indices are 0-based)")]
    OutOfRange {
        /// Index of the offending pair in the list.
        marker: usize,
        /// Mesh the index refers to.
        side: Side,
        /// The bad vertex index.
        vertex: u32,
        /// Vertex count of that mesh.
        num_vertices: usize,
    },
    /// Two markers use the same vertex on one side.
    #[error("markers {first} and {second} both use {side} vertex {vertex}")]
    Duplicate {
        /// The earlier marker.
        first: usize,
        /// The later marker.
        second: usize,
        /// Mesh of the repeated vertex.
        side: Side,
        /// The repeated vertex.
        vertex: u32,
    },
    /// Not enough markers to place the warped meshes in 3-D.
    #[error("{found} markers given, at least {minimum} are needed (fewer cannot span 3-D, so the warped meshes would be flat)")]
    TooFew {
        /// Markers given.
        found: usize,
        /// The minimum.
        minimum: usize,
    },
    /// The target markers are (nearly) coplanar, so the warped meshes would be flat.
    #[error("the target markers are coplanar (thickness {thickness:.3e} of the mesh size); add a marker off their plane")]
    Coplanar {
        /// Smallest standard deviation of the marker positions over the bounding-box diagonal.
        thickness: f64,
    },
}

/// Why a correspondence could not be computed or loaded.
#[derive(Debug, thiserror::Error)]
pub enum CorrespondenceError {
    /// Bad markers.
    #[error(transparent)]
    Markers(#[from] MarkerError),
    /// A mesh is unusable.
    #[error("{side} mesh: {source}")]
    Mesh {
        /// Which mesh.
        side: Side,
        /// What is wrong.
        #[source]
        source: MeshError,
    },
    /// A connected component holds no marker, so its least-squares mesh is undetermined.
    #[error("{side} mesh: connected component {component} (containing vertex {vertex}, {size} vertices) has no marker; add one")]
    ComponentWithoutMarker {
        /// Which mesh.
        side: Side,
        /// Component label.
        component: usize,
        /// Its lowest vertex.
        vertex: usize,
        /// Its vertex count.
        size: usize,
    },
    /// The least-squares solve failed.
    #[error("{side} least-squares mesh: {source}")]
    Solve {
        /// Which mesh.
        side: Side,
        /// The solver's error.
        #[source]
        source: SolveError,
    },
    /// A correspondence file does not fit the meshes or is malformed.
    #[error("correspondence: {0}")]
    Invalid(String),
    /// A correspondence marked as the identity is between meshes of different sizes.
    #[error("correspondence: marked as the identity, but the source has {source_vertices} vertices / {source_triangles} triangles and the target {target_vertices} / {target_triangles} (the identity needs equal counts)")]
    IdentityMismatch {
        /// Source vertex count recorded.
        source_vertices: usize,
        /// Source triangle count recorded.
        source_triangles: usize,
        /// Target vertex count recorded.
        target_vertices: usize,
        /// Target triangle count recorded.
        target_triangles: usize,
    },
    /// A correspondence marked as the identity does not match each target triangle to the
    /// source triangle with the same index only.
    #[error("correspondence: marked as the identity, but target triangle {target_triangle} matches source triangles {matches:?} (the identity matches it to [{target_triangle}] only)")]
    IdentityMatches {
        /// The first target triangle whose match list is not `[t]`.
        target_triangle: usize,
        /// Its match list.
        matches: Vec<u32>,
    },
}

/// Why a transfer could not be set up or run.
#[derive(Debug, thiserror::Error)]
pub enum TransferError {
    /// A mesh is unusable.
    #[error("{side} mesh: {source}")]
    Mesh {
        /// Which mesh.
        side: Side,
        /// What is wrong.
        #[source]
        source: MeshError,
    },
    /// The target has vertices used by no triangle: they have no gradient and would make the
    /// system singular.
    #[error("the target has {} vertices used by no triangle (first: {}); remove them", .vertices.len(), .vertices.iter().take(10).map(|v| v.to_string()).collect::<Vec<_>>().join(", "))]
    IsolatedVertices {
        /// The isolated vertices.
        vertices: Vec<usize>,
    },
    /// Every triangle around a target vertex is degenerate, so no gradient constrains it.
    #[error("target vertex {vertex} lies only on zero-area triangles and is unconstrained")]
    UnconstrainedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// The correspondence was made for other meshes.
    #[error("the correspondence was computed for a {side} mesh with {expected_vertices} vertices / {expected_triangles} triangles, this one has {found_vertices} / {found_triangles}")]
    CorrespondenceMismatch {
        /// Which mesh.
        side: Side,
        /// Vertices recorded in the correspondence.
        expected_vertices: usize,
        /// Triangles recorded in the correspondence.
        expected_triangles: usize,
        /// Vertices of the mesh given.
        found_vertices: usize,
        /// Triangles of the mesh given.
        found_triangles: usize,
    },
    /// A source frame has another vertex count than the source reference.
    #[error("source frame {frame}: {found} vertices, the source reference has {expected}")]
    FrameVertexCount {
        /// Frame index.
        frame: usize,
        /// Reference vertex count.
        expected: usize,
        /// Frame vertex count.
        found: usize,
    },
    /// A source frame has other triangles than the source reference.
    #[error("source frame {frame}: triangle {triangle} is {found:?}, the source reference has {expected:?} (frames must share the reference's connectivity)")]
    FrameConnectivity {
        /// Frame index.
        frame: usize,
        /// First differing triangle.
        triangle: usize,
        /// The reference's triangle (`[u32::MAX; 3]` when the frame has more triangles).
        expected: [u32; 3],
        /// The frame's triangle (`[u32::MAX; 3]` when the frame has fewer triangles).
        found: [u32; 3],
    },
    /// Wrong number of per-triangle gradients.
    #[error("{found} gradients given for {expected} triangles")]
    GradientCount {
        /// Triangles.
        expected: usize,
        /// Gradients given.
        found: usize,
    },
    /// A constraint vertex is out of range.
    #[error("constraint vertex {vertex} is out of range ({num_vertices} target vertices)")]
    ConstraintOutOfRange {
        /// The vertex.
        vertex: u32,
        /// Target vertex count.
        num_vertices: usize,
    },
    /// A frame or gradient contains NaN or infinity.
    #[error("non-finite value in {what} {index}")]
    NonFinite {
        /// What held it.
        what: &'static str,
        /// Its index.
        index: usize,
    },
    /// The sparse solve failed.
    #[error("transfer solve: {0}")]
    Solve(#[from] SolveError),
    /// The correspondence is malformed (fails [`super::Correspondence::validate`]).
    #[error(transparent)]
    Correspondence(#[from] CorrespondenceError),
    /// The source frames do not fit the source reference in a way the other variants do not
    /// describe.
    #[error("source frames: {0}")]
    Frames(#[from] crate::mesh::ShapeSetError),
}
