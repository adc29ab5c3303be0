//! The crate's one error type.

/// Everything that can go wrong in `bounded-nn`.
#[derive(Debug, thiserror::Error)]
pub enum NnError {
    /// A model or training configuration that cannot be built.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// Input arrays whose lengths do not fit together.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// Training data that cannot be trained on (empty, or a label outside 0..3).
    #[error("invalid training data: {0}")]
    Data(String),
    /// The bytes do not start with the model file magic.
    #[error("not a BoundED model file (bad magic)")]
    BadMagic,
    /// A model file written by another format version.
    #[error(
        "model file format version {found} is not supported (this build reads versions 1 to {expected})"
    )]
    UnsupportedVersion {
        /// Version found in the file.
        found: u32,
        /// Newest version this build reads.
        expected: u32,
    },
    /// A model file whose stored layer sizes contradict its own configuration.
    #[error("inconsistent model file: {0}")]
    InconsistentModel(String),
    /// The model file could not be encoded.
    #[error("cannot encode model file: {0}")]
    Encode(#[from] rmp_serde::encode::Error),
    /// The model file could not be decoded.
    #[error("cannot decode model file: {0}")]
    Decode(#[from] rmp_serde::decode::Error),
    /// Reading a model file failed.
    #[error("model file I/O: {0}")]
    Io(#[from] std::io::Error),
    /// Writing a model file failed (nothing was left at its path).
    #[error("cannot write the model file {0}")]
    Write(#[from] bounded_geom::atomic::WriteError),
    /// Feature extraction failed (bad scales, too few distinct positions).
    #[error(transparent)]
    Features(#[from] bounded_features::FeatureError),
    /// Work on one of several clouds failed (its features, its detection).
    #[error("{name}: {source}")]
    Cloud {
        /// The cloud's name.
        name: String,
        /// What failed.
        source: Box<NnError>,
    },
    /// A cloud smaller than the largest neighbourhood.
    #[error(
        "the cloud has {points} points, fewer than the largest scale ({scale} neighbours); \
         choose smaller scales or use a denser cloud"
    )]
    TooFewPoints {
        /// Points in the cloud.
        points: usize,
        /// The largest scale.
        scale: usize,
    },
    /// The networks gave a probability that is not a finite number (a broken model file).
    #[error("the model gave non-finite probabilities; the model file is unusable")]
    NonFinite,
    /// Burn reported an error while reading tensor data back.
    #[error("tensor read-back failed: {0}")]
    Tensor(String),
}
