//! The error type of the I/O layer: every variant names the file it is about.

use crate::mesh::{MeshError, ShapeSetError};
use std::path::{Path, PathBuf};

/// Why a mesh or animation file could not be read or written.
///
/// Every message starts with the file's path. Text parse errors name the 1-based line, binary
/// parse errors the byte offset or the element index. Messages are complete in themselves: the
/// underlying cause is part of the message and kept in a `cause` field, not repeated as an
/// [`std::error::Error::source`], so that an error chain prints it once.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused an operation (open, read, create, rename, …).
    #[error("{}: cannot {action}: {cause}", path.display())]
    Os {
        /// The file or directory.
        path: PathBuf,
        /// What was being done, e.g. "read the file".
        action: &'static str,
        /// The operating-system error.
        cause: std::io::Error,
    },
    /// The file has no content at all.
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A directory was given where a file is expected.
    #[error("{}: is a directory, expected a file", path.display())]
    IsDirectory {
        /// The directory.
        path: PathBuf,
    },
    /// The extension names no supported format for this operation.
    #[error("{}: unsupported format; expected {expected}", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The formats accepted here, in words.
        expected: &'static str,
    },
    /// A text file is malformed at a line.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A binary file is malformed or truncated at a byte offset.
    #[error("{}: at byte {offset}: {message}", path.display())]
    Binary {
        /// The file.
        path: PathBuf,
        /// 0-based byte offset where the problem was found.
        offset: u64,
        /// What is wrong.
        message: String,
    },
    /// The file parses but its content is inconsistent (a glTF element, a count that disagrees).
    #[error("{}: {message}", path.display())]
    Content {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the element.
        message: String,
    },
    /// The glTF loader rejected the file.
    #[error("{}: invalid glTF: {cause}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The loader's error.
        cause: ::gltf::Error,
    },
    /// The mesh read from the file is unusable (see [`crate::mesh::validate`]).
    #[error("{}: {cause}", path.display())]
    InvalidMesh {
        /// The file.
        path: PathBuf,
        /// What validation found.
        cause: MeshError,
    },
    /// Meshes that should share one connectivity do not. The shape name in the message is the
    /// offending file's path.
    #[error("{cause}")]
    ShapeSet {
        /// The offending file.
        path: PathBuf,
        /// The mismatch, naming the file and the first differing triangle.
        cause: ShapeSetError,
    },
    /// An output path is one of the input files (or a directory holding one).
    #[error("{}: refusing to overwrite the input {}", path.display(), input.display())]
    WouldOverwriteInput {
        /// The output path.
        path: PathBuf,
        /// The input it would overwrite.
        input: PathBuf,
    },
    /// A PC2 point cache needs a reference mesh for its connectivity.
    #[error("{}: a PC2 point cache has no faces; give a reference mesh for its connectivity", path.display())]
    NeedsReference {
        /// The PC2 file.
        path: PathBuf,
    },
}

impl IoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Os { path, .. }
            | Self::Empty { path }
            | Self::IsDirectory { path }
            | Self::UnknownFormat { path, .. }
            | Self::Parse { path, .. }
            | Self::Binary { path, .. }
            | Self::Content { path, .. }
            | Self::Gltf { path, .. }
            | Self::InvalidMesh { path, .. }
            | Self::ShapeSet { path, .. }
            | Self::WouldOverwriteInput { path, .. }
            | Self::NeedsReference { path } => path,
        }
    }

    /// The same error about `path` instead (for a write staged to a temporary file).
    pub fn at_path(mut self, path: &Path) -> Self {
        match &mut self {
            Self::Os { path: p, .. }
            | Self::Empty { path: p }
            | Self::IsDirectory { path: p }
            | Self::UnknownFormat { path: p, .. }
            | Self::Parse { path: p, .. }
            | Self::Binary { path: p, .. }
            | Self::Content { path: p, .. }
            | Self::Gltf { path: p, .. }
            | Self::InvalidMesh { path: p, .. }
            | Self::ShapeSet { path: p, .. }
            | Self::WouldOverwriteInput { path: p, .. }
            | Self::NeedsReference { path: p } => *p = path.to_path_buf(),
        }
        self
    }

    pub(crate) fn os(path: &Path, action: &'static str, cause: std::io::Error) -> Self {
        Self::Os {
            path: path.to_path_buf(),
            action,
            cause,
        }
    }

    pub(crate) fn parse(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    pub(crate) fn binary(path: &Path, offset: u64, message: impl Into<String>) -> Self {
        Self::Binary {
            path: path.to_path_buf(),
            offset,
            message: message.into(),
        }
    }

    pub(crate) fn content(path: &Path, message: impl Into<String>) -> Self {
        Self::Content {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}
