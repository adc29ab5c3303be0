use thiserror::Error;

/// Errors of point-cloud construction and neighbourhood search.
#[derive(Debug, Error, PartialEq)]
pub enum GeomError {
    /// The cloud has no points.
    #[error("the point cloud is empty")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a non-finite coordinate {value:?}")]
    NonFinite {
        /// Index of the offending point.
        index: usize,
        /// Its coordinates.
        value: [f64; 3],
    },
    /// Fewer points than neighbours asked for.
    #[error(
        "the cloud has {points} points but the largest scale needs {k} neighbours; choose scales of at most {points}"
    )]
    TooFewPoints {
        /// Number of points in the cloud.
        points: usize,
        /// Neighbours requested.
        k: usize,
    },
    /// More points than 32-bit neighbour indices can address.
    #[error("the cloud has {points} points; at most 4294967295 are supported")]
    TooManyPoints {
        /// Number of points in the cloud.
        points: usize,
    },
    /// A point index past the end of the cloud.
    #[error("point {index} does not exist: the cloud has {points} points")]
    NoSuchPoint {
        /// The index asked for.
        index: usize,
        /// Number of points in the cloud.
        points: usize,
    },
}
