//! The crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong in planning or labelling a survey.
#[derive(Debug, thiserror::Error)]
pub enum SurveyError {
    /// Reading or writing a file failed (the error names it).
    #[error(transparent)]
    Data(#[from] bounded_data::DataError),
    /// Labelling a tile failed.
    #[error("{path}: {source}")]
    Detect {
        /// The tile's input.
        path: PathBuf,
        /// What failed.
        source: bounded_nn::NnError,
    },
    /// Outputs that cannot be written as asked (checked before any work).
    #[error("{0}")]
    Outputs(String),
    /// No file can be created where an output goes.
    #[error(transparent)]
    Write(#[from] bounded_geom::atomic::WriteError),
    /// A survey of no input, or with one file twice.
    #[error("invalid survey: {0}")]
    Invalid(String),
    /// A point lies outside the bounds its file's header declares: the plan, which trusts
    /// them, could miss it in the halos of other tiles.
    #[error(
        "{path}: point {index} at {position:?} lies outside the bounds {lo:?} to {hi:?} the \
         header declares; repair the header's bounds (for example with PDAL or lasinfo \
         -repair_bb) and run again"
    )]
    OutsideBounds {
        /// The file.
        path: PathBuf,
        /// The point's index in the file.
        index: usize,
        /// Its position.
        position: [f64; 3],
        /// The declared lower corner.
        lo: [f64; 3],
        /// The declared upper corner.
        hi: [f64; 3],
    },
    /// The positions of a tile and its halo do not fit the survey's frame (never for
    /// surveys of ordinary extents; see [`crate::Plan::frame`]).
    #[error("{path}: the tile's offsets do not fit the survey's frame: {what}")]
    Frame {
        /// The tile's input.
        path: PathBuf,
        /// What failed.
        what: String,
    },
    /// A tile failed after the outputs `written` were (they stay, complete).
    #[error(
        "{source} ({} of {total} outputs were written before this failure and stay complete: {})",
        .written.len(),
        names(.written)
    )]
    Stopped {
        /// The outputs written before the failure.
        written: Vec<PathBuf>,
        /// The outputs of the run.
        total: usize,
        /// The tile's failure.
        source: Box<SurveyError>,
    },
}

/// `paths`, comma-separated.
fn names(paths: &[PathBuf]) -> String {
    let names: Vec<_> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(", ")
}
