//! `bounded.Model` (a model file, or the embedded one) and `bounded.Detection` (the result of
//! `bounded.detect`).

use crate::errors;
use bounded_geom::Class;
use bounded_nn::{Classifier, Decision, Detector, EmbeddedModel};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A BoundED model: its networks (one or two stages), the scales and features it was trained
/// with.
///
/// ``Model.embedded()`` is the model built into the package (what ``detect`` uses when no model
/// is given), ``Model.embedded("band")`` the other one; ``Model.load(path)`` reads a
/// ``.bmodel`` file written by ``bounded train``.
#[pyclass(frozen, module = "bounded")]
pub struct Model {
    detector: Detector,
    /// Where it came from, for `repr`: the path, or `embedded NAME`.
    source: String,
}

#[pymethods]
impl Model {
    /// A model built into the package: ``"row"`` (the default) calls one row of points along
    /// each crease, as the PCEDNet and ABC clouds are labelled; ``"band"`` calls a band 3
    /// spacings wide, as feature curves are often labelled. Both have two stages at 16 scales
    /// from 128 down to 10 neighbours, trained on generated clouds only.
    ///
    /// Raises ``ValueError`` for another name.
    #[staticmethod]
    #[pyo3(signature = (name = "row"))]
    pub fn embedded(name: &str) -> PyResult<Self> {
        let which: EmbeddedModel = name.parse().map_err(errors::value)?;
        Ok(Self {
            detector: Detector::embedded_model(which).map_err(errors::value)?,
            source: format!("embedded {which}"),
        })
    }

    /// Reads the model file at ``path`` (a ``.bmodel`` written by ``bounded train``).
    ///
    /// Raises ``FileNotFoundError`` (or another ``OSError``) when the file cannot be read,
    /// ``ValueError`` when it is not a model this build can run.
    #[staticmethod]
    pub fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let detector = py
            .detach(|| Detector::load(&path))
            .map_err(|e| errors::model_file(&path, e))?;
        Ok(Self {
            detector,
            source: path.display().to_string(),
        })
    }

    /// The neighbourhood sizes the model was trained with, largest first.
    #[getter]
    fn scales(&self) -> Vec<usize> {
        self.detector.feature_config().scales.clone()
    }

    /// The names of the features of one scale, in the order of ``features``' last axis.
    #[getter]
    fn feature_names(&self) -> Vec<String> {
        self.detector.classifier().file().feature_names.clone()
    }

    /// The decision the model records, chosen on validation clouds when it was trained: a
    /// sensitivity, or ``None`` for the most probable class. ``detect`` applies it unless
    /// given a ``sensitivity``.
    #[getter]
    fn sensitivity(&self) -> Option<f32> {
        self.detector.classifier().file().sensitivity
    }

    /// The number of networks run one after the other: 1, or 2 for an auto-context model.
    #[getter]
    fn stages(&self) -> usize {
        1 + usize::from(self.detector.classifier().second_stage().is_some())
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({}, scales={:?}, stages={})",
            self.source,
            self.scales(),
            self.stages()
        )
    }
}

/// ``sensitivity`` as Python passes it: a number strictly between 0 and 1, or ``"argmax"``.
#[derive(FromPyObject)]
pub enum Sensitivity {
    /// A sensitivity.
    Value(f32),
    /// A named rule: only ``"argmax"``, the most probable class.
    Name(String),
}

impl Model {
    /// A detector of this model with the options of one `detect` call.
    pub fn detector(
        &self,
        scales: Option<&[usize]>,
        fast: bool,
        sensitivity: Option<Sensitivity>,
    ) -> PyResult<Detector> {
        let file = self.detector.classifier().file().clone();
        let mut detector = Classifier::from_file(file)
            .and_then(Detector::new)
            .map_err(errors::value)?;
        if let Some(scales) = scales {
            detector = detector.with_scales(scales).map_err(errors::value)?;
        }
        if fast {
            detector = detector.first_stage_only().map_err(errors::value)?;
        }
        let decision = match sensitivity {
            Some(Sensitivity::Value(s)) => Decision::Sensitivity(s),
            Some(Sensitivity::Name(name)) => name.parse().map_err(errors::value)?,
            None => return Ok(detector),
        };
        detector.with_decision(decision).map_err(errors::value)
    }
}

/// The result of ``detect``: a class and three class probabilities per point, in input order.
///
/// ``classes`` is a uint8 array of n codes (``NON_EDGE`` 0, ``SHARP`` 1, ``BOUNDARY`` 2);
/// ``probabilities`` a float32 (n, 3) array whose columns are non-edge, sharp edge, boundary.
#[pyclass(frozen, module = "bounded")]
pub struct Detection {
    /// Class code per point.
    #[pyo3(get)]
    classes: Py<PyArray1<u8>>,
    /// Probabilities per point: non-edge, sharp edge, boundary.
    #[pyo3(get)]
    probabilities: Py<PyArray2<f32>>,
    /// Points per class, for `repr`.
    counts: [usize; 3],
}

#[pymethods]
impl Detection {
    /// Code of a point on no edge.
    #[classattr]
    const NON_EDGE: u8 = Class::NonEdge as u8;
    /// Code of a point on a sharp edge (a crease or corner).
    #[classattr]
    const SHARP: u8 = Class::Sharp as u8;
    /// Code of a point on a boundary (the border of an open surface).
    #[classattr]
    const BOUNDARY: u8 = Class::Boundary as u8;

    fn __len__(&self) -> usize {
        self.counts.iter().sum()
    }

    fn __repr__(&self) -> String {
        let [non_edge, sharp, boundary] = self.counts;
        format!(
            "Detection({} points: {sharp} sharp edge, {boundary} boundary, {non_edge} non-edge)",
            self.__len__()
        )
    }
}

impl Detection {
    /// The arrays of `detection`, handed to numpy without a copy.
    pub fn new(py: Python<'_>, detection: bounded_nn::Detection) -> PyResult<Self> {
        let counts = detection.class_counts();
        let n = detection.classes.len();
        let classes = PyArray1::from_vec(py, detection.codes());
        let probabilities =
            PyArray1::from_vec(py, detection.probabilities.into_flattened()).reshape([n, 3])?;
        Ok(Self {
            classes: classes.unbind(),
            probabilities: probabilities.unbind(),
            counts,
        })
    }
}
