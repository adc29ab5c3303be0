//! Writing: the points as one scan, or one scan per scan index, with every property.

use super::{EXTENSION, integer_range};
use crate::DataError;
use crate::table::{Column, PositionType, Property, ScalarType, TableView};
use e57::{
    ColorLimits, E57Writer, Extension, IntensityLimits, Record, RecordDataType, RecordName,
    RecordValue,
};
use std::hash::{DefaultHasher, Hash, Hasher};
use std::io::{Read, Seek, Write};
use std::ops::Range;
use std::path::Path;

/// Where the values of one record of the written scan come from.
enum Source<'a> {
    /// Coordinate `axis` of the position.
    Axis(usize),
    /// The Cartesian invalid state: 0, a valid position, for every point (the table holds
    /// no others).
    ValidPosition,
    /// A property's values as they are.
    Values(&'a Column),
    /// A property's values in a standard field: 0 where NaN, which the field's flag marks.
    Valid(&'a Column),
    /// A standard field's invalid flag: 1 where any of the columns is NaN.
    Invalid(Vec<&'a Column>),
}

/// The records of the written scans, where their values come from, and the limits viewers
/// scale the standard fields by.
struct Layout<'a> {
    records: Vec<Record>,
    sources: Vec<Source<'a>>,
    intensity_limits: Option<IntensityLimits>,
    colour_limits: Option<ColorLimits>,
}

impl<'a> Layout<'a> {
    /// The layout for `view`; with `split`, its `scan` property is not an attribute, since
    /// the scans hold it.
    fn of(view: &TableView<'a>, split: bool) -> Self {
        let mut fields: Vec<(Record, Source)> = (position_records(view).into_iter())
            .enumerate()
            .map(|(axis, record)| (record, Source::Axis(axis)))
            .collect();
        // pye57's `read_scan` refuses a scan without it.
        let state = Record {
            name: RecordName::CartesianInvalidState,
            data_type: RecordDataType::Integer { min: 0, max: 2 },
        };
        fields.push((state, Source::ValidPosition));
        let property = |name: &str| {
            (view.properties.iter())
                .find(|p| p.name == name)
                .map(|p| &p.values)
        };
        let mut standard = if split { vec!["scan"] } else { Vec::new() };
        let mut intensity_limits = None;
        if let Some(intensity) = property("intensity") {
            standard.push("intensity");
            let name = RecordName::Intensity;
            fields.push((record(name, intensity), Source::Valid(intensity)));
            fields.extend(invalid_flag(RecordName::IsIntensityInvalid, &[intensity]));
            intensity_limits = limits(intensity).map(|(min, max)| IntensityLimits {
                intensity_min: Some(min),
                intensity_max: Some(max),
            });
        }
        let mut colour_limits = None;
        if let (Some(r), Some(g), Some(b)) = (property("red"), property("green"), property("blue"))
        {
            standard.extend(["red", "green", "blue"]);
            use RecordName::{ColorBlue, ColorGreen, ColorRed};
            for (name, c) in [(ColorRed, r), (ColorGreen, g), (ColorBlue, b)] {
                fields.push((record(name, c), Source::Valid(c)));
            }
            fields.extend(invalid_flag(RecordName::IsColorInvalid, &[r, g, b]));
            if let (Some(r), Some(g), Some(b)) = (limits(r), limits(g), limits(b)) {
                colour_limits = Some(ColorLimits {
                    red_min: Some(r.0),
                    red_max: Some(r.1),
                    green_min: Some(g.0),
                    green_max: Some(g.1),
                    blue_min: Some(b.0),
                    blue_max: Some(b.1),
                });
            }
        }
        let others = (view.properties.iter()).filter(|p| !standard.contains(&p.name.as_str()));
        for p in others {
            let name = RecordName::Unknown {
                namespace: EXTENSION.0.to_string(),
                name: p.name.clone(),
            };
            fields.push((record(name, &p.values), Source::Values(&p.values)));
        }
        let (records, sources) = fields.into_iter().unzip();
        Layout {
            records,
            sources,
            intensity_limits,
            colour_limits,
        }
    }

    /// The record values of point `i` of `view`.
    fn values(&self, view: &TableView<'_>, i: usize) -> Vec<RecordValue> {
        let p = view.position(i);
        (self.records.iter().zip(&self.sources))
            .map(|(record, source)| {
                let ty = &record.data_type;
                match source {
                    Source::Axis(axis) => encode(p[*axis], ty),
                    Source::ValidPosition => RecordValue::Integer(0),
                    Source::Values(column) => encode(column.get_f64(i), ty),
                    Source::Valid(column) => {
                        let v = column.get_f64(i);
                        encode(if v.is_nan() { 0.0 } else { v }, ty)
                    }
                    Source::Invalid(columns) => {
                        RecordValue::Integer(columns.iter().any(|c| c.get_f64(i).is_nan()).into())
                    }
                }
            })
            .collect()
    }
}

/// Writes `view` to the empty `file` (see the module documentation); `path` names it in
/// errors.
pub(crate) fn write_to<W: Read + Write + Seek>(
    file: &mut W,
    view: &TableView<'_>,
    path: &Path,
) -> Result<(), DataError> {
    view.check(path)?;
    let e57 = |e: e57::Error| DataError::InvalidOutput {
        path: path.to_path_buf(),
        what: format!("E57: {e}"),
    };
    let runs = scan_runs(view);
    let several = runs.len() > 1;
    let layout = Layout::of(view, several);
    let points = points_hash(view, &layout.records);
    let mut writer = E57Writer::new(file, &guid(&points, 0)).map_err(e57)?;
    if (layout.records.iter()).any(|r| matches!(r.name, RecordName::Unknown { .. })) {
        let extension = Extension::new(EXTENSION.0, EXTENSION.1);
        writer.register_extension(extension).map_err(e57)?;
    }
    let stem = (path.file_stem()).map_or(String::new(), |s| s.to_string_lossy().into_owned());
    for (k, run) in runs.into_iter().enumerate() {
        let scan_guid = guid(&points, k as u64 + 1);
        let records = layout.records.clone();
        let mut scan = writer.add_pointcloud(&scan_guid, records).map_err(e57)?;
        scan.set_name(Some(if several {
            format!("{stem} {k}")
        } else {
            stem.clone()
        }));
        scan.set_intensity_limits(layout.intensity_limits.clone());
        scan.set_color_limits(layout.colour_limits.clone());
        for i in run {
            scan.add_point(layout.values(view, i)).map_err(e57)?;
        }
        scan.finalize().map_err(e57)?;
    }
    writer.finalize().map_err(e57)
}

/// The coordinate records: floats of the input's width, or the input's scaled integers with
/// the range the points use.
fn position_records(view: &TableView<'_>) -> [Record; 3] {
    use RecordName::{CartesianX, CartesianY, CartesianZ};
    let names = [CartesianX, CartesianY, CartesianZ];
    let data_types = match view.position_type {
        PositionType::F32 => [RecordDataType::F32; 3],
        PositionType::F64 => [RecordDataType::F64; 3],
        PositionType::Scaled { scale, offset } => {
            let mut range = [(0i64, 0i64); 3];
            for i in 0..view.len() {
                let p = view.position(i);
                for a in 0..3 {
                    let step = ((p[a] - offset[a]) / scale[a]).round() as i64;
                    range[a] = if i == 0 {
                        (step, step)
                    } else {
                        (range[a].0.min(step), range[a].1.max(step))
                    };
                }
            }
            std::array::from_fn(|a| RecordDataType::ScaledInteger {
                min: range[a].0,
                max: range[a].1,
                scale: scale[a],
                offset: offset[a],
            })
        }
    };
    let [x, y, z] = names;
    let [tx, ty, tz] = data_types;
    [(x, tx), (y, ty), (z, tz)].map(|(name, data_type)| Record { name, data_type })
}

/// The invalid flag `name` for a float `columns` that hold a NaN; none otherwise.
fn invalid_flag<'a>(name: RecordName, columns: &[&'a Column]) -> Option<(Record, Source<'a>)> {
    let has_nan =
        |c: &&Column| c.scalar_type().is_float() && (0..c.len()).any(|i| c.get_f64(i).is_nan());
    columns.iter().any(has_nan).then(|| {
        let flag = RecordDataType::Integer { min: 0, max: 1 };
        (
            Record {
                name,
                data_type: flag,
            },
            Source::Invalid(columns.to_vec()),
        )
    })
}

/// The record named `name` that holds `column`'s values exactly.
fn record(name: RecordName, column: &Column) -> Record {
    let data_type = match integer_range(column.scalar_type()) {
        Some((min, max)) => RecordDataType::Integer { min, max },
        None if column.scalar_type() == ScalarType::F32 => RecordDataType::F32,
        None => RecordDataType::F64,
    };
    Record { name, data_type }
}

/// The limits viewers scale an integer standard field by: its type's range.
fn limits(column: &Column) -> Option<(RecordValue, RecordValue)> {
    let (min, max) = integer_range(column.scalar_type())?;
    Some((RecordValue::Integer(min), RecordValue::Integer(max)))
}

/// `v` stored as a record of type `ty`.
fn encode(v: f64, ty: &RecordDataType) -> RecordValue {
    match *ty {
        RecordDataType::Single { .. } => RecordValue::Single(v as f32),
        RecordDataType::Double { .. } => RecordValue::Double(v),
        RecordDataType::ScaledInteger { scale, offset, .. } => {
            RecordValue::ScaledInteger(((v - offset) / scale).round() as i64)
        }
        RecordDataType::Integer { .. } => RecordValue::Integer(v as i64),
    }
}

/// The points of each scan: runs of one index when `view` has the scan indices the reader
/// gives a file of several scans (`scan`, uint, non-decreasing), else all in one.
fn scan_runs(view: &TableView<'_>) -> Vec<Range<usize>> {
    let scan = match view.properties.iter().find(|p| p.name == "scan") {
        Some(Property {
            values: Column::U32(scan),
            ..
        }) if scan.is_sorted() => Some(scan),
        _ => None,
    };
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..=view.len() {
        let next_scan = scan.is_some_and(|s| i < s.len() && s[i] != s[start]);
        if i == view.len() || next_scan {
            runs.push(start..i);
            start = i;
        }
    }
    runs
}

/// A hash of the points (the count and up to 4096 positions as written by `records`), from
/// which the GUIDs come, so that the same cloud is written to the same bytes.
fn points_hash(view: &TableView<'_>, records: &[Record]) -> DefaultHasher {
    let mut hasher = DefaultHasher::new();
    view.len().hash(&mut hasher);
    for i in (0..view.len()).step_by((view.len() / 4096).max(1)) {
        let p = view.position(i);
        for (v, record) in p.iter().zip(records) {
            match encode(*v, &record.data_type) {
                RecordValue::Single(v) => v.to_bits().hash(&mut hasher),
                RecordValue::Double(v) => v.to_bits().hash(&mut hasher),
                RecordValue::ScaledInteger(v) | RecordValue::Integer(v) => v.hash(&mut hasher),
            }
        }
    }
    hasher
}

/// GUID number `part` (0 the file's, then the scans') from the hash of the points.
fn guid(points: &DefaultHasher, part: u64) -> String {
    let mut hasher = points.clone();
    part.hash(&mut hasher);
    let a = hasher.finish();
    part.hash(&mut hasher);
    let b = hasher.finish();
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}
