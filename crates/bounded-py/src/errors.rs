//! The library errors as Python exceptions, with the messages the CLI prints.
//!
//! A file that cannot be opened is an `OSError` of the matching kind (`FileNotFoundError`,
//! `PermissionError`, ...); bad content, bad settings and clouds the model cannot label are
//! `ValueError`s.

use bounded_data::DataError;
use bounded_geom::GeomError;
use bounded_nn::{EmbeddedModel, NnError};
use pyo3::PyErr;
use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyNotADirectoryError, PyOSError,
    PyPermissionError, PyValueError,
};
use std::io::ErrorKind;

/// An `OSError` of the kind of `error`, with `message`.
fn os_error(error: &std::io::Error, message: String) -> PyErr {
    match error.kind() {
        ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        ErrorKind::AlreadyExists => PyFileExistsError::new_err(message),
        ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
        ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// A reading or writing error; its message names the file.
pub fn data(error: DataError) -> PyErr {
    match &error {
        DataError::Io { source, .. } => os_error(source, error.to_string()),
        DataError::Geom {
            source: GeomError::NonFinite { .. },
            ..
        } => PyValueError::new_err(format!(
            "{error} (drop_non_finite=True leaves such points out)"
        )),
        _ => PyValueError::new_err(error.to_string()),
    }
}

/// A model, feature or detection error (bad settings, too few points).
pub fn value(error: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// A model file that cannot be loaded, named as the CLI names it; a missing file named as an
/// embedded model is pointed to `Model.embedded`.
pub fn model_file(path: &std::path::Path, error: NnError) -> PyErr {
    let hint = EmbeddedModel::named_by(path).map_or(String::new(), |m| {
        format!(" (Model.embedded(\"{m}\") is the embedded model)")
    });
    let message = format!("cannot load model {}: {error}{hint}", path.display());
    match &error {
        NnError::Io(source) => os_error(source, message),
        _ => PyValueError::new_err(message),
    }
}

/// A cloud that cannot be built from the positions given (empty, non-finite).
pub fn geom(error: GeomError) -> PyErr {
    PyValueError::new_err(format!("xyz: {error}"))
}
