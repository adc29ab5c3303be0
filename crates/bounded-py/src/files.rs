//! `bounded.read` and `bounded.write`: every format the CLI reads and writes, by extension.

use crate::convert::{Xyz, column, column_array, positions};
use crate::errors;
use bounded_data::format;
use bounded_data::table::{Property, from_properties};
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ffi::CString;
use std::path::PathBuf;

/// Reads the point cloud at ``path``; the extension names the format (``.ply`` ``.pcd``
/// ``.xyz`` ``.txt`` ``.csv`` ``.las`` ``.laz`` ``.e57``).
///
/// Returns ``(xyz, fields)``: the positions as an (n, 3) array, float32 when the file stores
/// floats and float64 otherwise (doubles, LAS scaled integers), each exactly as stored; and a
/// dict of every other per-point property (``intensity``, ``red``, ``classification``, ...)
/// as 1-D arrays of the file's types, in file order. ``write(path, xyz, **fields)`` writes
/// them back.
///
/// A point with a NaN or infinite coordinate is an error naming it; ``drop_non_finite=True``
/// leaves such points out instead, with a warning that says how many.
///
/// Raises ``FileNotFoundError`` (or another ``OSError``) when the file cannot be opened,
/// ``ValueError`` naming the file and the problem when its content is not a valid cloud.
#[pyfunction]
#[pyo3(signature = (path, *, drop_non_finite = false))]
pub fn read(
    py: Python<'_>,
    path: PathBuf,
    drop_non_finite: bool,
) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyDict>)> {
    let (table, dropped) = py
        .detach(|| match drop_non_finite {
            true => format::read_finite(&path),
            false => format::read(&path).map(|table| (table, 0)),
        })
        .map_err(errors::data)?;
    if dropped > 0 {
        let points = if dropped == 1 { "point" } else { "points" };
        let message = format!(
            "{}: left out {dropped} {points} with a NaN or infinite coordinate",
            path.display()
        );
        let message = CString::new(message).unwrap_or_default();
        PyErr::warn(py, &py.get_type::<PyUserWarning>(), &message, 1)?;
    }
    let xyz = positions(py, &table)?;
    let fields = PyDict::new(py);
    for property in table.properties {
        fields.set_item(property.name, column_array(py, property.values))?;
    }
    Ok((xyz, fields))
}

/// Writes the cloud of ``xyz`` and ``fields`` to ``path``, in the format its extension names.
///
/// ``xyz`` is an (n, 3) float32 or float64 array, stored as floats or doubles (LAS: on a grid
/// finer than float32 resolves); every keyword is a per-point property, a 1-D array of n
/// values of type uint8, int8, uint16, int16, uint32, int32, float32, float64 (or bool,
/// stored as uint8). LAS maps the standard names (``intensity``, ``classification``,
/// ``red``, ...) to its own fields and stores the others as Extra Bytes.
///
/// The file is written to a temporary file first and renamed, so a failure never leaves a
/// half-written file. Raises ``ValueError`` (bad name, wrong length, unknown extension),
/// ``TypeError`` (a dtype no format stores) or ``OSError``.
#[pyfunction]
#[pyo3(signature = (path, xyz, /, **fields))]
pub fn write(
    py: Python<'_>,
    path: PathBuf,
    xyz: &Bound<'_, PyAny>,
    fields: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let names = ["x", "y", "z"];
    let mut properties: Vec<Property> = (names.into_iter())
        .zip(Xyz::borrow(xyz)?.columns())
        .map(|(name, values)| Property::new(name, values))
        .collect();
    for (name, values) in fields.into_iter().flatten() {
        let name: String = name.extract()?;
        properties.push(Property::new(&name, column(&name, &values)?));
    }
    py.detach(|| {
        let table = from_properties(properties, &path)?;
        format::write(&path, &table)
    })
    .map_err(errors::data)
}
