use bounded_geom::GeomError;
use thiserror::Error;

/// Errors of feature extraction.
#[derive(Debug, Error, PartialEq)]
pub enum FeatureError {
    /// The cloud or its neighbourhood search failed (e.g. fewer points than the
    /// largest scale).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// Fewer distinct positions than the largest scale needs (repeated points count once).
    #[error(
        "the cloud has {points} points but only {distinct} distinct positions, and the largest scale needs {k} neighbours; choose scales of at most {distinct}"
    )]
    TooFewDistinctPoints {
        /// Number of points in the cloud.
        points: usize,
        /// Number of distinct positions among them.
        distinct: usize,
        /// Neighbours requested.
        k: usize,
    },
    /// The scale list is unusable.
    #[error("invalid scales {scales:?}: {reason}")]
    InvalidScales {
        /// The scales given.
        scales: Vec<usize>,
        /// What is wrong with them.
        reason: &'static str,
    },
    /// The first classifier's probabilities do not cover the cloud.
    #[error("context of {probabilities} probabilities given for a cloud of {points} points")]
    ContextLength {
        /// Number of points in the cloud.
        points: usize,
        /// Number of probability triples given.
        probabilities: usize,
    },
    /// No feature group is selected.
    #[error("no feature group selected: at least one of the groups must be on")]
    NoFeatureGroups,
}
