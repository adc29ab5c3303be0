//! numpy arrays to and from the library's types: positions, clouds and property columns.
//!
//! Inputs are read where they lie (any strides, C or Fortran order), each value copied once
//! into the library's own layout; outputs hand the library's vectors to numpy without a copy.

use bounded_data::table::{Column, PointTable, PositionType};
use bounded_geom::PointCloud;
use numpy::ndarray::ArrayView2;
use numpy::{
    PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// `value` as a numpy array: itself, or `numpy.asarray(value)` for other array-likes (lists).
fn ndarray<'py>(value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(array) = value.cast::<PyUntypedArray>() {
        return Ok(array.clone());
    }
    let numpy = value.py().import("numpy")?;
    Ok(numpy
        .call_method1("asarray", (value,))?
        .cast_into::<PyUntypedArray>()?)
}

/// The dtype of `array` as numpy prints it (`float32`, `int64`, `>f4`).
fn dtype_name(array: &Bound<'_, PyUntypedArray>) -> String {
    array
        .dtype()
        .str()
        .map_or_else(|_| "unknown".into(), |s| s.to_string())
}

/// An (n, 3) array of positions, float32 or float64, borrowed from numpy.
pub enum Xyz<'py> {
    /// float32 coordinates: used as they are (as the CLI uses a file's float coordinates).
    F32(PyReadonlyArray2<'py, f32>),
    /// float64 coordinates: re-centred on their bounding box, so UTM-sized ones keep their
    /// precision (as the CLI does with a file's doubles).
    F64(PyReadonlyArray2<'py, f64>),
}

impl<'py> Xyz<'py> {
    /// Checks that `value` is an (n, 3) float32 or float64 array and borrows it.
    pub fn borrow(value: &Bound<'py, PyAny>) -> PyResult<Self> {
        let array = ndarray(value)?;
        let shape = array.shape();
        if shape.len() != 2 || shape[1] != 3 {
            return Err(PyValueError::new_err(format!(
                "xyz must be an (n, 3) array of positions; got shape {shape:?}"
            )));
        }
        if let Ok(a) = array.cast::<numpy::PyArray2<f32>>() {
            return Ok(Xyz::F32(a.try_readonly()?));
        }
        if let Ok(a) = array.cast::<numpy::PyArray2<f64>>() {
            return Ok(Xyz::F64(a.try_readonly()?));
        }
        Err(PyTypeError::new_err(format!(
            "xyz must be float32 or float64; got dtype {} (convert it with .astype(numpy.float64))",
            dtype_name(&array)
        )))
    }

    /// The point cloud of these positions.
    pub fn cloud(&self) -> PyResult<PointCloud> {
        match self {
            Xyz::F32(a) => {
                let v = a.as_array();
                let points = (0..v.nrows()).map(|i| row(&v, i)).collect();
                PointCloud::from_local([0.0; 3], points)
            }
            Xyz::F64(a) => {
                let v = a.as_array();
                PointCloud::from_iter_f64(v.nrows(), |i| row(&v, i))
            }
        }
        .map_err(crate::errors::geom)
    }

    /// The x, y and z columns, of the array's type.
    pub fn columns(&self) -> [Column; 3] {
        match self {
            Xyz::F32(a) => [0, 1, 2].map(|axis| Column::F32(a.as_array().column(axis).to_vec())),
            Xyz::F64(a) => [0, 1, 2].map(|axis| Column::F64(a.as_array().column(axis).to_vec())),
        }
    }
}

/// Row `i` of an (n, 3) view.
fn row<T: Copy>(v: &ArrayView2<'_, T>, i: usize) -> [T; 3] {
    [v[[i, 0]], v[[i, 1]], v[[i, 2]]]
}

/// The positions of `table` as an (n, 3) array: float32 when the file stored floats, else
/// float64, each exactly as the file holds it.
pub fn positions<'py>(py: Python<'py>, table: &PointTable) -> PyResult<Bound<'py, PyAny>> {
    let view = table.view();
    let n = table.len();
    let flat = (0..n).flat_map(|i| view.position(i));
    Ok(match table.position_type {
        PositionType::F32 => {
            let values = flat.map(|c| c as f32).collect();
            PyArray1::from_vec(py, values).reshape([n, 3])?.into_any()
        }
        PositionType::F64 | PositionType::Scaled { .. } => {
            PyArray1::from_vec(py, flat.collect()).reshape([n, 3])?.into_any()
        }
    })
}

/// `column` as a 1-D numpy array of its type, without a copy.
pub fn column_array(py: Python<'_>, column: Column) -> Bound<'_, PyAny> {
    match column {
        Column::U8(v) => PyArray1::from_vec(py, v).into_any(),
        Column::I8(v) => PyArray1::from_vec(py, v).into_any(),
        Column::U16(v) => PyArray1::from_vec(py, v).into_any(),
        Column::I16(v) => PyArray1::from_vec(py, v).into_any(),
        Column::U32(v) => PyArray1::from_vec(py, v).into_any(),
        Column::I32(v) => PyArray1::from_vec(py, v).into_any(),
        Column::F32(v) => PyArray1::from_vec(py, v).into_any(),
        Column::F64(v) => PyArray1::from_vec(py, v).into_any(),
    }
}

/// The values of the 1-D array `values` for the property `name`; booleans become 0 / 1.
pub fn column(name: &str, values: &Bound<'_, PyAny>) -> PyResult<Column> {
    let array = ndarray(values)?;
    if array.ndim() != 1 {
        return Err(PyValueError::new_err(format!(
            "field '{name}' must be a 1-D array, one value per point; got shape {:?}",
            array.shape()
        )));
    }
    /// The values of `array` when its dtype is `T`.
    fn typed<T: numpy::Element + Copy>(array: &Bound<'_, PyUntypedArray>) -> Option<Vec<T>> {
        let typed = array.cast::<PyArray1<T>>().ok()?;
        let values: PyReadonlyArray1<'_, T> = typed.try_readonly().ok()?;
        Some(values.as_array().to_vec())
    }
    let column = None
        .or_else(|| typed(&array).map(Column::U8))
        .or_else(|| typed(&array).map(Column::I8))
        .or_else(|| typed(&array).map(Column::U16))
        .or_else(|| typed(&array).map(Column::I16))
        .or_else(|| typed(&array).map(Column::U32))
        .or_else(|| typed(&array).map(Column::I32))
        .or_else(|| typed(&array).map(Column::F32))
        .or_else(|| typed(&array).map(Column::F64))
        .or_else(|| typed::<bool>(&array).map(|v| Column::U8(v.into_iter().map(u8::from).collect())));
    column.ok_or_else(|| {
        PyTypeError::new_err(format!(
            "field '{name}' has dtype {}; the formats store uint8, int8, uint16, int16, uint32, \
             int32, float32 and float64 (convert it with .astype(numpy.int32), for example)",
            dtype_name(&array)
        ))
    })
}
