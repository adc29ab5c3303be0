//! `plan_survey` and `detect_tile`: one tile of a survey labelled with its halo, for
//! `bounded.distributed` to run as one task per tile. Types only: the plan, the halo, its
//! proof and the writing are `bounded-survey`'s.

use crate::errors;
use crate::model::{Model, Sensitivity};
use bounded_survey::{Input, Options, Plan, ReadOptions, SurveyError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// One input of a plan as Python holds it: path, lower corner, upper corner, point count.
type PlannedInput = (PathBuf, [f64; 3], [f64; 3], u64);

/// A survey error as a Python exception (the file's, for reading and writing).
fn survey_error(error: SurveyError) -> PyErr {
    match error {
        SurveyError::Data(e) => errors::data(e),
        e => errors::value(e),
    }
}

/// Plans the survey of the files ``inputs``: one tile each, in this order, with the bounds
/// of its points (a LAS or LAZ header's, or one read of any other format).
///
/// Returns a list of ``(path, lower corner, upper corner, points)`` tuples, plain data that
/// ``detect_tile`` takes back in any process.
#[pyfunction]
#[pyo3(signature = (inputs, *, drop_non_finite = false))]
pub fn plan_survey(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    drop_non_finite: bool,
) -> PyResult<Vec<PlannedInput>> {
    let plan = py
        .detach(|| Plan::of(&inputs, ReadOptions { drop_non_finite }))
        .map_err(survey_error)?;
    Ok((plan.inputs().iter())
        .map(|i| (i.path.clone(), i.lo, i.hi, i.points))
        .collect())
}

/// Labels tile ``tile`` of ``plan`` (as ``plan_survey`` returns it) with the halo that makes
/// its labels those of the whole survey labelled as one cloud, and writes it to ``output``
/// (atomically, so a retried task rewrites the same file). The options are ``detect``'s
/// and ``bounded detect``'s (``model`` a model file's path, ``embedded`` the name of an
/// embedded model, ``Model.embedded``'s); ``radius`` is the first halo radius (default: estimated);
/// ``block_points`` is ``bounded detect --block-points``: a plan of one LAS or LAZ file of
/// more points is labelled in spatial blocks of about this many, in a block's memory.
///
/// Returns a dict of what it took: ``points``, ``halo`` (the points of the halo that
/// proved the tile), ``labelled``, ``radius``, ``attempts``, ``detection_seconds``,
/// ``seconds``. The GIL is released while it works.
#[pyfunction]
#[pyo3(signature = (
    plan, tile, output, *, model = None, embedded = None, scales = None, sensitivity = None,
    fast = false, drop_non_finite = false, radius = None, block_points = None, threads = None
))]
#[allow(clippy::too_many_arguments)] // Python keyword arguments, one per option.
pub fn detect_tile<'py>(
    py: Python<'py>,
    plan: Vec<PlannedInput>,
    tile: usize,
    output: PathBuf,
    model: Option<PathBuf>,
    embedded: Option<String>,
    scales: Option<Vec<usize>>,
    sensitivity: Option<Sensitivity>,
    fast: bool,
    drop_non_finite: bool,
    radius: Option<f64>,
    block_points: Option<usize>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let inputs = (plan.into_iter())
        .map(|(path, lo, hi, points)| Input {
            path,
            lo,
            hi,
            points,
        })
        .collect();
    let plan = Plan::new(inputs).map_err(survey_error)?;
    let model = match (model, embedded) {
        (Some(path), None) => Model::load(py, path)?,
        (None, name) => Model::embedded(name.as_deref().unwrap_or("row"))?,
        (Some(_), Some(_)) => {
            return Err(errors::value(
                "give a model file or an embedded model, not both",
            ));
        }
    };
    let detector = model.detector(scales.as_deref(), fast, sensitivity)?;
    let options = Options {
        read: ReadOptions { drop_non_finite },
        radius,
        block_points: block_points.unwrap_or(bounded_survey::BLOCK_POINTS),
        ..Options::default()
    };
    let report = py
        .detach(|| {
            crate::on_threads(threads, || {
                bounded_survey::detect_tile(&plan, tile, &detector, &output, &options, &mut |_| {})
            })
        })?
        .map_err(survey_error)?;
    let dict = PyDict::new(py);
    dict.set_item("points", report.points)?;
    dict.set_item("halo", report.halo)?;
    dict.set_item("labelled", report.labelled)?;
    dict.set_item("radius", report.radius)?;
    dict.set_item("attempts", report.attempts)?;
    dict.set_item("detection_seconds", report.detection.as_secs_f64())?;
    dict.set_item("seconds", report.elapsed.as_secs_f64())?;
    Ok(dict)
}
