//! Errors of the output writers and readers. Every one is a failure of the run that
//! writes (or reads back) the file, never bad input.

use std::path::PathBuf;

/// Everything that can go wrong while writing (or reading back) an output file. Messages name
/// the file and carry the offending values.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The operating system refused a read, write, sync or rename.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned (the target, not the temporary file).
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The data handed to a writer is inconsistent (wrong lengths, indices out of range, …).
    #[error("{}: {message}", path.display())]
    InvalidData {
        /// The file that was to be written.
        path: PathBuf,
        /// What is wrong, with the values.
        message: String,
    },
    /// A file read back (Matrix Market, OBJ) is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file read.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// JSON serialization failed.
    #[error("{}: JSON serialization failed: {source}", path.display())]
    Json {
        /// The file that was to be written.
        path: PathBuf,
        /// serde_json's error.
        #[source]
        source: serde_json::Error,
    },
    /// plotters could not draw or encode the figure.
    #[error("{}: plotting failed: {message}", path.display())]
    Plot {
        /// The figure file.
        path: PathBuf,
        /// plotters' (or the PNG encoder's) message.
        message: String,
    },
    /// A sparse matrix could not be built from what was read.
    #[error("{}: {source}", path.display())]
    Linalg {
        /// The file read.
        path: PathBuf,
        /// The linear-algebra error.
        #[source]
        source: nurbspring_linalg::LinalgError,
    },
}

impl OutputError {
    /// Shorthand for [`OutputError::InvalidData`].
    pub(crate) fn invalid(path: &std::path::Path, message: impl Into<String>) -> Self {
        OutputError::InvalidData {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    /// Shorthand for [`OutputError::Parse`].
    pub(crate) fn parse(path: &std::path::Path, line: usize, message: impl Into<String>) -> Self {
        OutputError::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    /// Shorthand for [`OutputError::Io`].
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
