//! Typed errors of animation synthesis. Every variant names the offending index or file; the
//! recipe loader ([`super::recipe`]) wraps them with the recipe line that caused them.

use crate::io::IoError;
use crate::sparse::SolveError;
use crate::transfer::{CorrespondenceError, MarkerError, TransferError};

/// Why a synthesis step failed.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A scribble file is not `{"triangles": [...]}` or `{"vertices": [...]}`.
    #[error("scribble: {0}")]
    ScribbleParse(String),
    /// A scribble lists no element.
    #[error("scribble: it is empty (list at least one 0-based triangle or vertex)")]
    EmptyScribble,
    /// A scribbled index does not exist on the target.
    #[error("scribble: {what} {index} is out of range (the target has {count} {what}s; indices are 0-based)")]
    ScribbleOutOfRange {
        /// `"triangle"` or `"vertex"`.
        what: &'static str,
        /// The bad index.
        index: u32,
        /// How many there are.
        count: usize,
    },
    /// A vertex scribble covers no whole triangle.
    #[error("scribble: the {vertices} scribbled vertices contain no whole triangle")]
    ScribbleCoversNoTriangle {
        /// Number of scribbled vertices.
        vertices: usize,
    },
    /// Intelligent scribbling kept nothing: no stiff partition is more than half scribbled.
    #[error("scribble: none of the {stiff} stiff partitions is more than half scribbled ({scribbled} triangles scribbled), so nothing is selected; scribble more of a part, or lower gamma")]
    NothingSelected {
        /// Scribbled triangles.
        scribbled: usize,
        /// Stiff partitions on the target.
        stiff: usize,
    },
    /// A per-triangle or per-vertex array has the wrong length.
    #[error("{what}: has {found} entries, expected {expected}")]
    Length {
        /// What was checked.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Found length.
        found: usize,
    },
    /// An index names no element.
    #[error(
        "{what}[{position}] = {index} is not a {element} index (the mesh has {count} {element}s)"
    )]
    Index {
        /// What was checked.
        what: &'static str,
        /// Where in the list.
        position: usize,
        /// The index given.
        index: usize,
        /// `vertex` or `triangle`.
        element: &'static str,
        /// How many there are.
        count: usize,
    },
    /// A per-element value is not finite or outside its range.
    #[error("{what}[{index}] = {value}: {why}")]
    Value {
        /// What was checked.
        what: &'static str,
        /// The element.
        index: usize,
        /// Its value.
        value: f64,
        /// The allowed range.
        why: &'static str,
    },
    /// A parameter is outside its range.
    #[error("{name} = {value}: {why}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        why: &'static str,
    },
    /// A blend weight left [0, 1] by more than round-off (a solver failure, not user input).
    #[error("blend weight of triangle {triangle} is {value}, outside [0, 1]")]
    WeightOutOfRange {
        /// The triangle.
        triangle: usize,
        /// Its weight.
        value: f64,
    },
    /// A later blend layer at weight 1 would erase an earlier layer that also has weight 1.
    #[error("layer {second} ({second_mode}) fully covers {count} triangles (first: {triangle}) that layer {first} ({first_mode}) also drives at weight 1, at output frame {frame}: a blend layer replaces what is below it; make the later one compound, or split the scribbles or the frame ranges")]
    ContradictingLayers {
        /// The earlier layer (0-based).
        first: usize,
        /// Its mode.
        first_mode: &'static str,
        /// The later layer.
        second: usize,
        /// Its mode.
        second_mode: &'static str,
        /// Triangles both select.
        count: usize,
        /// The first of them.
        triangle: usize,
        /// The first output frame where both are active.
        frame: usize,
    },
    /// A layer's frames do not fit its source reference.
    #[error("layer {layer}: {source}")]
    Layer {
        /// The layer (0-based).
        layer: usize,
        /// What went wrong.
        #[source]
        source: TransferError,
    },
    /// A step of building layer `layer` failed.
    #[error("layer {layer}: {source}")]
    InLayer {
        /// The layer (0-based).
        layer: usize,
        /// What went wrong.
        #[source]
        source: Box<SynthError>,
    },
    /// Pose edit `pose` failed.
    #[error("pose {pose}: {source}")]
    InPose {
        /// The pose edit (0-based).
        pose: usize,
        /// What went wrong.
        #[source]
        source: Box<SynthError>,
    },
    /// Transfer (gradients, correspondence check or solve) failed.
    #[error(transparent)]
    Transfer(#[from] TransferError),
    /// Correspondence failed.
    #[error(transparent)]
    Correspondence(#[from] CorrespondenceError),
    /// Bad markers.
    #[error(transparent)]
    Markers(#[from] MarkerError),
    /// A sparse solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] IoError),
}
