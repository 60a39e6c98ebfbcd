//! Errors of scenes: each names the scene file, the line and the offending key where the
//! problem comes from the file.

use super::obstacle::ObstacleError;
use super::pulls::PullError;
use crate::io::IoError;
use crate::springs::BlendError;
use std::path::PathBuf;

/// Why a scene cannot be loaded or blended.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file cannot be read.
    #[error("{file}: cannot read the scene: {cause}")]
    Read {
        /// The scene file.
        file: PathBuf,
        /// The system's message.
        cause: String,
    },
    /// The TOML is malformed or does not fit the schema (unknown key, wrong type…).
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message (it names the key).
        message: String,
    },
    /// A value in the scene is unusable.
    #[error("{file}:{line}: {key}: {message}")]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// 1-based line of the value.
        line: usize,
        /// The key, e.g. `obstacle[1].shape`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A file named in the scene cannot be read.
    #[error("{file}:{line}: {key}: {source}")]
    File {
        /// The scene file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The key naming the file.
        key: String,
        /// The reading error (it names the file).
        source: Box<IoError>,
    },
    /// An obstacle is unusable (programmatic use; scene files give [`SceneError::Invalid`]).
    #[error(transparent)]
    Obstacle(#[from] ObstacleError),
    /// A pull is unusable (programmatic use; scene files give [`SceneError::Invalid`]).
    #[error("pull {index}: {source}")]
    Pull {
        /// Index of the pull.
        index: usize,
        /// Why.
        source: PullError,
    },
    /// A pull's vertex cannot be pulled.
    #[error("pull {index}: vertex {vertex} {why}")]
    PullVertex {
        /// Index of the pull.
        index: usize,
        /// The vertex.
        vertex: u32,
        /// Why not.
        why: String,
    },
    /// The blend failed.
    #[error(transparent)]
    Blend(#[from] BlendError),
    /// The interior or the anchor could not be built.
    #[error(transparent)]
    Interior(#[from] crate::springs::interior::InteriorError),
}

/// 1-based line and column of byte `offset` in `text`.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::line_column;

    #[test]
    fn offsets_map_to_lines_and_columns() {
        let t = "a = 1\nbb = 2\n";
        assert_eq!(line_column(t, 0), (1, 1));
        assert_eq!(line_column(t, 6), (2, 1));
        assert_eq!(line_column(t, 9), (2, 4));
    }
}
