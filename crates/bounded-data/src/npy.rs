//! NumPy `.npy` reader: a 2-D array of little-endian `float32` or `float64`, one point per
//! row, in C or Fortran order (NumPy format versions 1 to 3).
//!
//! The first three columns are x, y, z; further columns become properties `column_4`,
//! `column_5`, ... (1-based, as in text files without a header), of the array's type. Any
//! other array (big-endian, integer, structured, fewer than 3 columns, not 2-D) is refused
//! with an error that names the file and says what it holds.

use crate::DataError;
use crate::table::{Column, Endian, Property, ScalarType};
use std::io::Read;
use std::path::Path;

/// The longest header accepted (NumPy pads its headers to a multiple of 64 bytes).
const MAX_HEADER: usize = 1 << 16;

/// The array's element type, order and shape, from the header dictionary.
#[derive(Debug, PartialEq)]
struct Header {
    ty: ScalarType,
    fortran: bool,
    rows: usize,
    columns: usize,
}

/// Reads the columns of the `.npy` file `input`, positions among them, not yet checked (see
/// [`crate::table::from_properties`]).
pub(crate) fn read_properties(
    mut input: impl Read,
    path: &Path,
) -> Result<Vec<Property>, DataError> {
    let bad = |what: String| DataError::malformed(path, format!("npy: {what}"));
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => bad("the file ends within its header".into()),
        _ => DataError::io(path, e),
    };
    let mut magic = [0u8; 8];
    input.read_exact(&mut magic).map_err(io)?;
    if &magic[..6] != b"\x93NUMPY" {
        return Err(bad("not a NumPy .npy file (no \\x93NUMPY magic)".into()));
    }
    let header_len = match magic[6] {
        1 => {
            let mut len = [0u8; 2];
            input.read_exact(&mut len).map_err(io)?;
            usize::from(u16::from_le_bytes(len))
        }
        2 | 3 => {
            let mut len = [0u8; 4];
            input.read_exact(&mut len).map_err(io)?;
            u32::from_le_bytes(len) as usize
        }
        v => return Err(bad(format!("unsupported format version {v}"))),
    };
    if header_len > MAX_HEADER {
        return Err(bad(format!("a header of {header_len} bytes")));
    }
    let mut text = vec![0u8; header_len];
    input.read_exact(&mut text).map_err(io)?;
    let header = parse_header(&String::from_utf8_lossy(&text)).map_err(bad)?;
    let size = header.ty.size();
    let values = header
        .rows
        .checked_mul(header.columns)
        .ok_or_else(|| bad("shape overflows".into()))?;
    // Read at most what the shape says, then check: a corrupt shape must not allocate.
    let mut data = Vec::new();
    (input.take((values as u64).saturating_mul(size as u64)))
        .read_to_end(&mut data)
        .map_err(|e| DataError::io(path, e))?;
    if data.len() != values * size {
        return Err(bad(format!(
            "the data ends after {} of {} rows",
            data.len() / size / header.columns,
            header.rows
        )));
    }
    let (rows, row_len) = (header.rows, header.columns * size);
    let properties = (0..header.columns)
        .map(|c| {
            let mut column = Column::with_capacity(header.ty, rows);
            if header.fortran {
                // Column-major: the column's values one after another.
                let values = &data[c * rows * size..(c + 1) * rows * size];
                column.decode_strided(values, size, 0, Endian::Little);
            } else {
                column.decode_strided(&data, row_len, c * size, Endian::Little);
            }
            let name = match c {
                0 => "x".to_string(),
                1 => "y".to_string(),
                2 => "z".to_string(),
                _ => format!("column_{}", c + 1),
            };
            Property::new(name, column)
        })
        .collect();
    Ok(properties)
}

/// The element type, order and shape of a header dictionary such as
/// `{'descr': '<f4', 'fortran_order': False, 'shape': (100, 3), }`.
fn parse_header(text: &str) -> Result<Header, String> {
    let value = |key: &str| {
        let at = text
            .find(&format!("'{key}'"))
            .ok_or_else(|| format!("the header has no '{key}': {}", text.trim()))?;
        let rest = text[at + key.len() + 2..].trim_start();
        rest.strip_prefix(':')
            .map(str::trim_start)
            .ok_or_else(|| format!("the header's '{key}' has no value"))
    };
    let descr = value("descr")?;
    let descr = descr
        .strip_prefix('\'')
        .and_then(|d| d.split('\'').next())
        .ok_or_else(|| {
            format!(
                "a dtype of {} (a structured array?); expected '<f4' or '<f8'",
                first_token(descr)
            )
        })?;
    let ty = match descr {
        "<f4" => ScalarType::F32,
        "<f8" => ScalarType::F64,
        ">f4" | ">f8" => {
            return Err(format!(
                "big-endian data ('{descr}'); save it little-endian"
            ));
        }
        other => {
            return Err(format!(
                "dtype '{other}'; expected float32 ('<f4') or float64 ('<f8')"
            ));
        }
    };
    let fortran = match value("fortran_order")? {
        v if v.starts_with("True") => true,
        v if v.starts_with("False") => false,
        v => return Err(format!("fortran_order {}", first_token(v))),
    };
    let shape = value("shape")?;
    let inner = shape
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| format!("shape {}", first_token(shape)))?;
    let dims: Vec<usize> = inner
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map(|d| d.parse().map_err(|_| format!("shape ({inner})")))
        .collect::<Result<_, _>>()?;
    match dims[..] {
        [rows, columns] if columns >= 3 => Ok(Header {
            ty,
            fortran,
            rows,
            columns,
        }),
        _ => Err(format!(
            "an array of shape ({inner}); expected (points, 3) or more columns"
        )),
    }
}

fn first_token(text: &str) -> &str {
    text.split([',', '}']).next().unwrap_or(text).trim()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version-1 `.npy` file of `header` (padded as NumPy pads it) and `data`.
    fn npy(header: &str, data: &[u8]) -> Vec<u8> {
        let mut h = header.to_string();
        while !(10 + h.len() + 1).is_multiple_of(64) {
            h.push(' ');
        }
        h.push('\n');
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend((h.len() as u16).to_le_bytes());
        bytes.extend(h.as_bytes());
        bytes.extend(data);
        bytes
    }

    fn read(bytes: &[u8]) -> Result<Vec<Property>, DataError> {
        read_properties(bytes, Path::new("a.npy"))
    }

    fn values(p: &Property) -> Vec<f64> {
        (0..p.values.len()).map(|i| p.values.get_f64(i)).collect()
    }

    #[test]
    fn reads_c_and_fortran_order_float32_and_float64() {
        // Two points with four columns: rows (1, 2, 3, 4) and (5, 6, 7, 8).
        let rows = [[1.0f64, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]];
        let c: Vec<u8> = rows
            .iter()
            .flatten()
            .flat_map(|v| (*v as f32).to_le_bytes())
            .collect();
        let f: Vec<u8> = (0..4)
            .flat_map(|k| rows.iter().map(move |r| r[k]))
            .flat_map(|v| v.to_le_bytes())
            .collect();
        for (bytes, ty) in [
            (
                npy(
                    "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 4), }",
                    &c,
                ),
                ScalarType::F32,
            ),
            (
                npy(
                    "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 4), }",
                    &f,
                ),
                ScalarType::F64,
            ),
        ] {
            let p = read(&bytes).unwrap();
            let names: Vec<&str> = p.iter().map(|p| p.name.as_str()).collect();
            assert_eq!(names, ["x", "y", "z", "column_4"]);
            assert_eq!(values(&p[0]), [1.0, 5.0]);
            assert_eq!(values(&p[2]), [3.0, 7.0]);
            assert_eq!(values(&p[3]), [4.0, 8.0]);
            assert_eq!(p[3].values.scalar_type(), ty);
        }
    }

    #[test]
    fn other_arrays_are_refused_with_what_they_hold() {
        let data = [0u8; 96];
        let cases = [
            (
                "{'descr': '>f8', 'fortran_order': False, 'shape': (4, 3), }",
                "big-endian data ('>f8')",
            ),
            (
                "{'descr': '<i4', 'fortran_order': False, 'shape': (4, 3), }",
                "dtype '<i4'",
            ),
            (
                "{'descr': [('x', '<f4')], 'fortran_order': False, 'shape': (4,), }",
                "structured array",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 2), }",
                "shape (4, 2)",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (12,), }",
                "shape (12,)",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (5, 3), }",
                "ends after 4 of 5 rows",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (9999999999999, 3), }",
                "ends after 4 of",
            ),
        ];
        for (header, expected) in cases {
            let e = read(&npy(header, &data)).unwrap_err().to_string();
            assert!(
                e.starts_with("a.npy: ") && e.contains(expected),
                "{e} / {expected}"
            );
        }
        let e = read(b"PK\x03\x04 not npy").unwrap_err().to_string();
        assert!(e.contains("not a NumPy .npy file"), "{e}");
        let e = read(b"\x93NUMPY\x01\x00\xff").unwrap_err().to_string();
        assert!(e.contains("ends within its header"), "{e}");
    }
}
