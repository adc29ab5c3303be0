//! Progress of a detection, only when asked: a Python callback, or a line on `sys.stderr`.
//!
//! The detector reports from the thread that called it, with the GIL released; each report
//! takes the GIL back for as long as the callback or the write takes.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyBool;

/// Where progress goes.
pub enum Progress {
    /// Nowhere.
    Off,
    /// `callback(points done, points)` after every block; its first exception is kept, the
    /// later reports skipped, and the exception raised once the detection is done.
    Callback {
        callback: Py<PyAny>,
        failure: Option<PyErr>,
    },
    /// A percentage on `sys.stderr`, rewritten in place, whenever it changes.
    Stderr { percent: Option<usize> },
}

impl Progress {
    /// `progress` as given to `detect`: `None` or `False`, `True`, or a callable.
    pub fn new(progress: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(progress) = progress.filter(|p| !p.is_none()) else {
            return Ok(Progress::Off);
        };
        if let Ok(flag) = progress.cast::<PyBool>() {
            return Ok(if flag.is_true() {
                Progress::Stderr { percent: None }
            } else {
                Progress::Off
            });
        }
        if progress.is_callable() {
            return Ok(Progress::Callback {
                callback: progress.clone().unbind(),
                failure: None,
            });
        }
        Err(PyTypeError::new_err(
            "progress must be None, a bool, or a callable taking (points done, points)",
        ))
    }

    /// Reports `done` of `total` points (called with the GIL released).
    pub fn report(&mut self, done: usize, total: usize) {
        match self {
            Progress::Off => {}
            Progress::Callback { failure: Some(_), .. } => {}
            Progress::Callback { callback, failure } => {
                *failure = Python::attach(|py| callback.call1(py, (done, total)).err());
            }
            Progress::Stderr { percent } => {
                let now = done * 100 / total.max(1);
                if *percent != Some(now) {
                    *percent = Some(now);
                    let line = format!("\rdetect: {now:3}% of {total} points");
                    // Progress is best effort: a closed stderr must not fail the detection.
                    Python::attach(|py| write_stderr(py, &line)).ok();
                }
            }
        }
    }

    /// Ends the report: raises a callback's exception, or ends the stderr line.
    pub fn finish(self, py: Python<'_>) -> PyResult<()> {
        match self {
            Progress::Off => Ok(()),
            Progress::Callback { failure, .. } => failure.map_or(Ok(()), Err),
            Progress::Stderr { percent } => match percent {
                Some(_) => write_stderr(py, "\n").or(Ok(())),
                None => Ok(()),
            },
        }
    }
}

/// Writes `text` to Python's `sys.stderr` (which a notebook shows, unlike the process's).
fn write_stderr(py: Python<'_>, text: &str) -> PyResult<()> {
    let stderr = py.import("sys")?.getattr("stderr")?;
    stderr.call_method1("write", (text,))?;
    stderr.call_method0("flush")?;
    Ok(())
}
