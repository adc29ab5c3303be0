//! The Python module `bounded`: BoundED's sharp-edge and boundary detection on numpy arrays.
//!
//! A thin layer: it converts numpy arrays to the library's types and back, maps the library's
//! errors to Python exceptions, and releases the GIL while the library works; detection,
//! features and formats are the library crates' (`bounded-nn`, `bounded-features`,
//! `bounded-data`, `bounded-survey`). Built and installed with maturin (`pip install
//! crates/bounded-py`) as the extension `bounded._bounded`, which the package `bounded`
//! (python/bounded) re-exports beside its pure-Python `bounded.distributed`; the Python API
//! is documented in python/bounded/__init__.pyi and README.md beside this crate.

mod convert;
mod errors;
mod files;
mod model;
mod progress;
mod survey;

use bounded_features::{DEFAULT_SCALES, FeatureConfig, FeatureGroups, extract};
use bounded_geom::Class;
use convert::Xyz;
use model::{Detection, Model, Sensitivity};
use numpy::{PyArray1, PyArrayMethods};
use progress::Progress;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::PathBuf;

/// The `model` argument of `detect`: a `Model`, or the path of a model file.
#[derive(FromPyObject)]
enum ModelArg<'py> {
    Loaded(Bound<'py, Model>),
    Path(PathBuf),
}

/// Runs `work` on a pool of `threads` threads, or on the default one (every core).
fn on_threads<T: Send>(threads: Option<usize>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    match threads {
        None => Ok(work()),
        Some(0) => Err(PyValueError::new_err("threads must be at least 1")),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map(|pool| pool.install(work))
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}"))),
    }
}

/// Finds the sharp edges and boundaries of the point cloud ``xyz``.
///
/// ``xyz`` is an (n, 3) float32 or float64 array (any memory layout). float32 coordinates are
/// used as they are; float64 ones are re-centred first, so UTM-sized coordinates keep their
/// precision. Both as the ``bounded detect`` command treats a file's floats and doubles, so
/// the same cloud gets the same result.
///
/// ``model`` is a ``Model`` or the path of a model file (default: the embedded model);
/// ``scales`` replaces the model's neighbourhood sizes (as many, largest first); ``fast`` runs
/// a two-stage model's first stage alone (about half the time); ``sensitivity`` in (0, 1)
/// labels a point sharp when its sharp probability reaches ``1 - sensitivity``, ``"argmax"``
/// gives it the most probable class (default: the model's ``sensitivity``). ``threads`` limits the worker threads (default: every core).
/// ``progress`` is ``True`` for a percentage on ``sys.stderr``, or a callable called as
/// ``progress(points_done, points)``.
///
/// Returns a ``Detection``. The GIL is released while it works, so other Python threads run,
/// and several threads can detect at once. Raises ``ValueError`` with the reason for a cloud
/// the model cannot label (NaN coordinates, fewer points than the largest scale) or bad
/// options, ``TypeError`` for an array of another dtype.
#[pyfunction]
#[pyo3(signature = (
    xyz, *, model = None, scales = None, sensitivity = None, fast = false, threads = None,
    progress = None
))]
#[allow(clippy::too_many_arguments)] // Python keyword arguments, one per option.
fn detect(
    py: Python<'_>,
    xyz: &Bound<'_, PyAny>,
    model: Option<ModelArg<'_>>,
    scales: Option<Vec<usize>>,
    sensitivity: Option<Sensitivity>,
    fast: bool,
    threads: Option<usize>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Detection> {
    let cloud = Xyz::borrow(xyz)?.cloud()?;
    let model = match model {
        Some(ModelArg::Loaded(model)) => model,
        Some(ModelArg::Path(path)) => Bound::new(py, Model::load(py, path)?)?,
        None => Bound::new(py, Model::embedded("row")?)?,
    };
    let detector = model.get().detector(scales.as_deref(), fast, sensitivity)?;
    let mut report = Progress::new(progress)?;
    let detection = py.detach(|| {
        on_threads(threads, || {
            detector.detect_with_progress(&cloud, &mut |done, total| report.report(done, total))
        })
    })?;
    report.finish(py)?;
    Detection::new(py, detection.map_err(errors::value)?)
}

/// The feature groups named in `groups` (default: BoundED's 12 features).
fn feature_groups(groups: Option<Vec<String>>) -> PyResult<FeatureGroups> {
    let Some(names) = groups else {
        return Ok(FeatureGroups::BOUNDED);
    };
    let mut selected = FeatureGroups::NONE;
    for name in &names {
        let flag = match name.as_str() {
            "sigma" => &mut selected.sigma,
            "sigma_u" => &mut selected.sigma_u,
            "sigma_l" => &mut selected.sigma_l,
            "d" => &mut selected.d,
            "s" => &mut selected.s,
            "c" => &mut selected.c,
            "h" => &mut selected.h,
            other => {
                return Err(PyValueError::new_err(format!(
                    "unknown feature group '{other}' (the groups: sigma, sigma_u, sigma_l, d, s, c, h)"
                )));
            }
        };
        *flag = true;
    }
    Ok(selected)
}

/// BoundED's multi-scale neighbourhood features of every point of ``xyz``.
///
/// Returns a float32 array of shape (n, len(scales), features per scale): point ``i``'s
/// features at scale ``j`` (``scales[j]`` neighbours, the point included; scales strictly
/// descending) are ``result[i, j]``, in the order ``feature_names(groups)`` gives. The
/// default groups are BoundED's 12 features: ``sigma_u`` (3), ``sigma_l`` (3), ``d`` (2),
/// ``s`` (2), ``c`` (2); ``groups`` selects others among ``sigma``, ``sigma_u``, ``sigma_l``,
/// ``d``, ``s``, ``c`` (kept in that order). ``xyz`` is treated as by ``detect``, and so are
/// ``threads``; the GIL is released while it works.
#[pyfunction]
#[pyo3(signature = (xyz, scales = DEFAULT_SCALES.to_vec(), groups = None, *, threads = None))]
fn features<'py>(
    py: Python<'py>,
    xyz: &Bound<'py, PyAny>,
    scales: Vec<usize>,
    groups: Option<Vec<String>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let cloud = Xyz::borrow(xyz)?.cloud()?;
    let config = FeatureConfig {
        scales,
        groups: feature_groups(groups)?,
        ..FeatureConfig::default()
    };
    let features = py
        .detach(|| on_threads(threads, || extract(&cloud, &config)))?
        .map_err(errors::value)?;
    let shape = [
        cloud.len(),
        config.scales.len(),
        config.features_per_scale(),
    ];
    Ok(PyArray1::from_vec(py, features.into_vec())
        .reshape(shape)?
        .into_any())
}

/// The names of the features of one scale for ``groups`` (default: BoundED's 12), in the
/// order of the last axis of ``features``.
#[pyfunction]
#[pyo3(signature = (groups = None))]
fn feature_names(groups: Option<Vec<String>>) -> PyResult<Vec<&'static str>> {
    Ok(feature_groups(groups)?.names())
}

/// BoundED: sharp edges and boundaries in 3D point clouds, from the point positions alone.
#[pymodule]
#[pyo3(name = "_bounded")]
fn bounded_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("NON_EDGE", Class::NonEdge as u8)?;
    m.add("SHARP", Class::Sharp as u8)?;
    m.add("BOUNDARY", Class::Boundary as u8)?;
    m.add(
        "CLASS_NAMES",
        PyTuple::new(m.py(), bounded_nn::CLASS_NAMES)?,
    )?;
    m.add_class::<Model>()?;
    m.add_class::<Detection>()?;
    m.add_function(wrap_pyfunction!(detect, m)?)?;
    m.add_function(wrap_pyfunction!(features, m)?)?;
    m.add_function(wrap_pyfunction!(feature_names, m)?)?;
    m.add_function(wrap_pyfunction!(files::read, m)?)?;
    m.add_function(wrap_pyfunction!(files::write, m)?)?;
    m.add_function(wrap_pyfunction!(survey::plan_survey, m)?)?;
    m.add_function(wrap_pyfunction!(survey::detect_tile, m)?)?;
    Ok(())
}
