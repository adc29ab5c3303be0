use std::path::PathBuf;
use thiserror::Error;

/// Errors of reading, writing and generating point clouds.
///
/// Every variant names the file it concerns, so a command-line user sees which input is bad.
#[derive(Debug, Error)]
pub enum DataError {
    /// An I/O failure on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file's content does not follow its format.
    #[error("{path}: {what}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, in words (with the line or byte offset where known).
        what: String,
    },
    /// The file extension names no supported format.
    #[error(
        "{path}: unknown point-cloud format (supported: .ply .pcd .xyz .txt .csv .las .laz .e57)"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The positions read do not form a valid cloud (empty, NaN / infinite coordinates).
    #[error("{path}: {source}")]
    Geom {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: bounded_geom::GeomError,
    },
    /// The labels of a labelled cloud cannot be derived (unknown colour, bad class value).
    #[error("{path}: labels: {what}")]
    Labels {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the point and value.
        what: String,
    },
    /// A generator setting is out of range (noise level or outlier fraction negative,
    /// non-finite, or a fraction above 1).
    #[error("generator: {what}")]
    Generator {
        /// Which setting and value, and the range it must lie in.
        what: String,
    },
    /// A write request is inconsistent (e.g. fewer classes than points).
    #[error("{path}: cannot write: {what}")]
    InvalidOutput {
        /// The file that was to be written.
        path: PathBuf,
        /// What is inconsistent.
        what: String,
    },
    /// A picture could not be encoded as PNG.
    #[error("{path}: cannot write the PNG picture: {source}")]
    Png {
        /// The picture file.
        path: PathBuf,
        /// The encoder's error.
        source: png::EncodingError,
    },
    /// A dataset directory that is missing or holds no clouds.
    #[error("{path}: {what}")]
    Dataset {
        /// The directory.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

impl DataError {
    /// A [`DataError::Malformed`] for `path`.
    pub(crate) fn malformed(path: &std::path::Path, what: impl Into<String>) -> Self {
        Self::Malformed {
            path: path.to_path_buf(),
            what: what.into(),
        }
    }

    /// A [`DataError::Io`] for `path`.
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
