//! XYZ / TXT / CSV text reader and writer.
//!
//! One point per line, values separated by whitespace or commas (detected from the first
//! data line). An optional header line names the columns: it is recognised by a `#` or `//`
//! prefix (CloudCompare's convention) or by a token that is not a number. Columns named
//! `x`, `y`, `z` (any case) are the position; without such names the first three columns
//! are. Every other column is kept as an `f64` property (named `column_<n>`, 1-based, when
//! there is no header), which reproduces any decimal text value exactly on output. Blank
//! lines and later `#` / `//` comment lines are skipped, and so is a UTF-8 byte-order mark at
//! the start. The file is streamed line by line.
//!
//! Writing emits a header line (`//x y z ...` for `.xyz`/`.txt`; `x,y,z,...` for `.csv`,
//! or `//x,y,z,...` when [`TableView::csv_comment_header`](crate::table::TableView) says so).

use crate::DataError;
use crate::records::{parse_row, read_line};
use crate::table::{Column, PointTable, Property, ScalarType, TableView};
use std::io::{BufRead, Write};
use std::path::Path;

/// Value separator of a text file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Separator {
    /// One space (read: any run of whitespace).
    Space,
    /// A comma (surrounding whitespace is ignored when reading).
    Comma,
}

impl Separator {
    fn char(self) -> char {
        match self {
            Separator::Space => ' ',
            Separator::Comma => ',',
        }
    }

    fn split(self, line: &str) -> Box<dyn Iterator<Item = &str> + '_> {
        match self {
            Separator::Space => Box::new(line.split_ascii_whitespace()),
            Separator::Comma => Box::new(line.split(',').map(str::trim)),
        }
    }
}

fn is_comment(line: &str) -> bool {
    let t = line.trim_start();
    t.starts_with('#') || t.starts_with("//")
}

/// Reads a text point file from `input`; `path` names it in errors.
pub fn read_from(input: impl BufRead, path: &Path) -> Result<PointTable, DataError> {
    crate::table::from_properties(read_properties(input, path)?, path)
}

/// The columns of the text file `input`, positions among them, not yet checked.
pub(crate) fn read_properties(
    mut input: impl BufRead,
    path: &Path,
) -> Result<Vec<Property>, DataError> {
    let mut buf = Vec::new();
    let mut line_no = 0;
    let mut header: Option<String> = None;
    let mut columns: Vec<Column> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let mut separator = Separator::Space;
    while read_line(&mut input, &mut buf, path)?.is_some() {
        line_no += 1;
        let text = std::str::from_utf8(&buf)
            .map_err(|_| DataError::malformed(path, format!("line {line_no}: not text")))?;
        // A byte-order mark (editors on Windows write one) is no part of the first value.
        let text = match line_no {
            1 => text.strip_prefix('\u{feff}').unwrap_or(text),
            _ => text,
        };
        if text.trim().is_empty() {
            continue;
        }
        if columns.is_empty() {
            let looks_numeric = text
                .split(|c: char| c == ',' || c.is_ascii_whitespace())
                .filter(|t| !t.is_empty())
                .all(|t| t.parse::<f64>().is_ok());
            if header.is_none() && (is_comment(text) || !looks_numeric) {
                let t = text.trim_start();
                header = Some(
                    t.trim_start_matches('#')
                        .trim_start_matches("//")
                        .to_string(),
                );
                continue;
            }
            if is_comment(text) {
                continue;
            }
            separator = if text.contains(',') {
                Separator::Comma
            } else {
                Separator::Space
            };
            let width = separator.split(text).count();
            names = column_names(header.as_deref(), separator, width)
                .map_err(|what| DataError::malformed(path, format!("header line: {what}")))?;
            columns = (0..width)
                .map(|_| Column::with_capacity(ScalarType::F64, 1 << 16))
                .collect();
        } else if is_comment(text) {
            continue;
        }
        parse_row(separator.split(text), &mut columns, line_no, path)?;
    }
    if columns.is_empty() {
        return Err(DataError::Geom {
            path: path.to_path_buf(),
            source: bounded_geom::GeomError::Empty,
        });
    }
    let properties = names
        .into_iter()
        .zip(columns)
        .map(|(name, values)| Property::new(name, values))
        .collect();
    Ok(properties)
}

/// Column names from the header (or `x y z column_4 ...`), positions first when the header
/// does not name them.
fn column_names(
    header: Option<&str>,
    separator: Separator,
    width: usize,
) -> Result<Vec<String>, String> {
    if width < 3 {
        return Err(format!("{width} columns; at least x, y and z are needed"));
    }
    let Some(header) = header else {
        return Ok((1..=width)
            .map(|k| match k {
                1 => "x".into(),
                2 => "y".into(),
                3 => "z".into(),
                _ => format!("column_{k}"),
            })
            .collect());
    };
    let mut names: Vec<String> = separator
        .split(header)
        .filter(|n| !n.is_empty())
        .map(str::to_string)
        .collect();
    if names.len() != width {
        return Err(format!(
            "{} names for {width} columns: {}",
            names.len(),
            crate::error::quoted(header)
        ));
    }
    let named = ["x", "y", "z"]
        .iter()
        .all(|a| names.iter().any(|n| n.eq_ignore_ascii_case(a)));
    if !named {
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            names[k] = axis.into();
        }
    }
    Ok(names)
}

/// Writes `view` as text with a header line to `out`; `path` names the file in errors.
pub fn write_to(
    out: impl Write,
    view: &TableView<'_>,
    separator: Separator,
    path: &Path,
) -> Result<(), DataError> {
    view.check(path)?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, out);
    let s = separator.char();
    let names: Vec<&str> = ["x", "y", "z"]
        .into_iter()
        .chain(view.properties.iter().map(|p| p.name.as_str()))
        .collect();
    let prefix = if separator == Separator::Space || view.csv_comment_header {
        "//"
    } else {
        ""
    };
    writeln!(out, "{prefix}{}", names.join(&s.to_string()))
        .and_then(|()| crate::records::write_text_rows(&mut out, view, s))
        .and_then(|()| out.flush())
        .map_err(|e| DataError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::PositionType;
    use bounded_geom::PointCloud;
    use std::io::Cursor;

    fn read(text: &str) -> Result<PointTable, DataError> {
        read_from(Cursor::new(text.to_string()), Path::new("p.xyz"))
    }

    #[test]
    fn reads_whitespace_comma_header_and_extra_columns() {
        let t = read("1 2 3 0.5\n\n4\t5 6 7\n").unwrap();
        assert_eq!(t.cloud.position_f64(1), [4.0, 5.0, 6.0]);
        assert_eq!(t.property("column_4"), Some(&Column::F64(vec![0.5, 7.0])));
        let t = read("i, Z ,y,X\r\n1, 2, 3, 4\n5,6,7,8\n# end\n").unwrap();
        assert_eq!(t.cloud.position_f64(0), [4.0, 3.0, 2.0]);
        assert_eq!(t.property("i"), Some(&Column::F64(vec![1.0, 5.0])));
        let t = read("//lon lat h\n1 2 3\n").unwrap();
        assert_eq!(t.cloud.position_f64(0), [1.0, 2.0, 3.0]);
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        for text in ["\u{feff}1 2 3\n4 5 6\n", "\u{feff}x,y,z\n1,2,3\n4,5,6\n"] {
            let t = read(text).unwrap();
            assert_eq!(t.len(), 2, "{text:?}");
            assert_eq!(t.cloud.position_f64(0), [1.0, 2.0, 3.0]);
        }
        // Only at the start: elsewhere it is no number.
        let e = read("1 2 3\n\u{feff}4 5 6\n").unwrap_err().to_string();
        assert!(e.contains("line 2, value 1"), "{e}");
    }

    #[test]
    fn round_trips_space_and_comma() {
        let cloud = PointCloud::from_f64(&[[0.1, 5_403_150.25, 2.0], [1e-7, 3.0, -4.0]]).unwrap();
        let mut t = PointTable::new(cloud);
        t.position_type = PositionType::F64;
        t.set_property(Property::new("class", Column::F64(vec![2.0, 0.0])));
        t.set_property(Property::new("p", Column::F64(vec![0.123456789, 1e-30])));
        for separator in [Separator::Space, Separator::Comma] {
            let mut bytes = Vec::new();
            write_to(&mut bytes, &t.view(), separator, Path::new("o.csv")).unwrap();
            let back = read_from(Cursor::new(bytes), Path::new("o.csv")).unwrap();
            assert_eq!(back, t, "{separator:?}");
        }
    }

    #[test]
    fn malformed_files_give_named_errors() {
        let cases = [
            ("", "empty"),
            ("x y z\n", "empty"),
            ("1 2\n", "2 columns"),
            ("a b c d\n1 2 3\n", "4 names for 3 columns"),
            ("1 2 3\n1 2\n", "line 2: expected 3 values, found 2"),
            ("1 2 3\n1 2 3 4\n", "line 2: more than 3"),
            ("1 2 3\n1 2 zz\n", "line 2, value 3: 'zz'"),
            ("1 2 3\n1 NaN 3\n", "point 1 has a non-finite"),
        ];
        for (text, expected) in cases {
            let msg = read(text).unwrap_err().to_string();
            assert!(
                msg.starts_with("p.xyz: ") && msg.contains(expected),
                "{msg} / {expected}"
            );
        }
    }
}
