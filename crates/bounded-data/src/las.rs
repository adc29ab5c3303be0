//! LAS / LAZ reader and writer (ASPRS LAS 1.0-1.4, via the `las` crate).
//!
//! Reading decodes the point records column by column: coordinates as scaled integers
//! (the scale and offset are kept in [`PositionType::Scaled`]), and every other field as a
//! property: `intensity`, `return_number`, `number_of_returns`, `classification`,
//! `scan_angle_rank` (formats 0-5, degrees) or `scan_angle` (formats 6-10, units of
//! 0.006 degrees), `user_data`, `point_source_id`, `gps_time`, `red`/`green`/`blue`, `nir`,
//! and the one-bit flags (`synthetic`, `key_point`, `withheld`, `overlap`,
//! `scanner_channel`, `scan_direction`, `edge_of_flight_line`) when any point sets them.
//! Extra Bytes are decoded by their Extra Bytes VLR into named properties (untyped or
//! 64-bit ones as one `u8` property per byte). Waveform packet fields are not kept.
//!
//! Writing produces LAS 1.4 with point format 6, 7 (with colour) or 8 (with NIR), so that
//! classification codes above 31 fit. A `class` property (BoundED classes) goes to the
//! Classification field with these codes:
//!
//! | BoundED class | LAS Classification |
//! |---|---|
//! | non-edge (0) | 1, "unclassified" |
//! | sharp edge (1) | 64, first user-definable code |
//! | boundary (2) | 65, user-definable |
//!
//! and an input `classification` is then kept as the extra-bytes property
//! `input_classification`. Every property that is not a LAS field (for example `p_nonedge`,
//! `p_sharp`, `p_boundary`) is written as Extra Bytes with an Extra Bytes VLR (user
//! `LASF_Spec`, record 4), which PDAL and CloudCompare read as named dimensions. 8-bit
//! colours are scaled to LAS's 16-bit range (x 257). Coordinates of a LAS input keep its
//! scale and offset; other clouds get their bounding-box centre as offset and a power-of-ten
//! scale fine enough for the cloud's `f32` precision.

use crate::DataError;
use crate::table::{Column, Endian, PointTable, PositionType, Property, ScalarType, TableView};
use las::point::Format as LasFormat;
use las::{Builder, PointDataBuilder, Reader, Transform, Vector, Version, Vlr, Writer};
use std::io::{Read, Seek, Write};
use std::path::Path;

/// LAS Classification code of BoundED's non-edge class ("unclassified").
pub const CODE_NON_EDGE: u8 = 1;
/// LAS Classification code of BoundED's sharp-edge class (user-definable range).
pub const CODE_SHARP: u8 = 64;
/// LAS Classification code of BoundED's boundary class (user-definable range).
pub const CODE_BOUNDARY: u8 = 65;

/// Where a LAS field lives in a point record.
#[derive(Debug, Clone, Copy)]
enum Slot {
    /// A whole little-endian value at byte `at`.
    Plain { ty: ScalarType, at: usize },
    /// `width` bits from bit `shift` of byte `at`.
    Bits { at: usize, shift: u8, width: u8 },
}

/// The standard fields of `format` (after x, y, z), and the record length without extras.
fn fields(format: &LasFormat) -> (Vec<(&'static str, Slot)>, usize) {
    use ScalarType::{F64, I8, I16, U8, U16};
    let plain = |ty, at| Slot::Plain { ty, at };
    let bits = |at, shift, width| Slot::Bits { at, shift, width };
    let mut f = vec![("intensity", plain(U16, 12))];
    let mut end;
    if format.is_extended {
        f.extend([
            ("return_number", bits(14, 0, 4)),
            ("number_of_returns", bits(14, 4, 4)),
            ("synthetic", bits(15, 0, 1)),
            ("key_point", bits(15, 1, 1)),
            ("withheld", bits(15, 2, 1)),
            ("overlap", bits(15, 3, 1)),
            ("scanner_channel", bits(15, 4, 2)),
            ("scan_direction", bits(15, 6, 1)),
            ("edge_of_flight_line", bits(15, 7, 1)),
            ("classification", plain(U8, 16)),
            ("user_data", plain(U8, 17)),
            ("scan_angle", plain(I16, 18)),
            ("point_source_id", plain(U16, 20)),
            ("gps_time", plain(F64, 22)),
        ]);
        end = 30;
    } else {
        f.extend([
            ("return_number", bits(14, 0, 3)),
            ("number_of_returns", bits(14, 3, 3)),
            ("scan_direction", bits(14, 6, 1)),
            ("edge_of_flight_line", bits(14, 7, 1)),
            ("classification", bits(15, 0, 5)),
            ("synthetic", bits(15, 5, 1)),
            ("key_point", bits(15, 6, 1)),
            ("withheld", bits(15, 7, 1)),
            ("scan_angle_rank", plain(I8, 16)),
            ("user_data", plain(U8, 17)),
            ("point_source_id", plain(U16, 18)),
        ]);
        end = 20;
        if format.has_gps_time {
            f.push(("gps_time", plain(F64, end)));
            end += 8;
        }
    }
    if format.has_color {
        f.extend([
            ("red", plain(U16, end)),
            ("green", plain(U16, end + 2)),
            ("blue", plain(U16, end + 4)),
        ]);
        end += 6;
    }
    if format.has_nir {
        f.push(("nir", plain(U16, end)));
        end += 2;
    }
    if format.has_waveform {
        end += 29;
    }
    (f, end)
}

/// Flags dropped on reading when no point sets them, to keep outputs uncluttered.
const OPTIONAL_FLAGS: [&str; 7] = [
    "synthetic",
    "key_point",
    "withheld",
    "overlap",
    "scanner_channel",
    "scan_direction",
    "edge_of_flight_line",
];

fn las_error(path: &Path, e: las::Error) -> DataError {
    match e {
        las::Error::Io(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => {
            DataError::io(path, e)
        }
        e => DataError::malformed(path, format!("LAS: {e}")),
    }
}

/// Reads a LAS or LAZ file from `input`; `path` names it in errors.
pub fn read_from<R: Read + Seek + Send + Sync + 'static>(
    input: R,
    path: &Path,
) -> Result<PointTable, DataError> {
    let mut reader = Reader::new(input).map_err(|e| las_error(path, e))?;
    let header = reader.header().clone();
    let format = *header.point_format();
    let (standard, base_len) = fields(&format);
    let record_len = usize::from(format.len());
    if base_len + usize::from(format.extra_bytes) != record_len {
        return Err(DataError::malformed(
            path,
            "LAS: inconsistent point record length",
        ));
    }
    let extras = extra_fields(&header, base_len, usize::from(format.extra_bytes));
    let mut names: Vec<String> = ["x", "y", "z"].map(String::from).to_vec();
    let mut slots = vec![
        Slot::Plain {
            ty: ScalarType::I32,
            at: 0,
        },
        Slot::Plain {
            ty: ScalarType::I32,
            at: 4,
        },
        Slot::Plain {
            ty: ScalarType::I32,
            at: 8,
        },
    ];
    names.extend(standard.iter().map(|(n, _)| n.to_string()));
    slots.extend(standard.iter().map(|(_, s)| *s));
    names.extend(extras.iter().map(|(n, _)| n.clone()));
    slots.extend(extras.iter().map(|(_, s)| *s));
    let total = header.number_of_points();
    let capacity = usize::try_from(total.min(4096)).unwrap_or(0);
    let mut columns: Vec<Column> = slots
        .iter()
        .map(|s| match *s {
            Slot::Plain { ty, .. } => Column::with_capacity(ty, capacity),
            Slot::Bits { .. } => Column::with_capacity(ScalarType::U8, capacity),
        })
        .collect();
    let mut data = PointDataBuilder::new().for_header(&header).build();
    let mut done = 0u64;
    while done < total {
        let n = reader
            .fill_points(crate::records::block_len(record_len) as u64, &mut data)
            .map_err(|e| {
                DataError::malformed(
                    path,
                    format!("LAS: point data ends within point {done} of {total}: {e}"),
                )
            })?;
        if n == 0 {
            return Err(DataError::malformed(
                path,
                format!("LAS: only {done} of {total} points"),
            ));
        }
        let bytes = data.raw_bytes();
        for (column, slot) in columns.iter_mut().zip(&slots) {
            decode(column, *slot, bytes, record_len);
        }
        done += n;
    }
    let t = header.transforms();
    let (Column::I32(x), Column::I32(y), Column::I32(z)) = (&columns[0], &columns[1], &columns[2])
    else {
        return Err(DataError::malformed(
            path,
            "LAS: coordinates not decoded as integers",
        ));
    };
    let cloud = bounded_geom::PointCloud::from_iter_f64(x.len(), |i| {
        [t.x.direct(x[i]), t.y.direct(y[i]), t.z.direct(z[i])]
    })
    .map_err(|source| DataError::Geom {
        path: path.to_path_buf(),
        source,
    })?;
    let properties = names
        .into_iter()
        .zip(columns)
        .skip(3)
        .filter(|(name, values)| match values {
            Column::U8(v) if OPTIONAL_FLAGS.contains(&name.as_str()) => v.iter().any(|&b| b != 0),
            _ => true,
        })
        .map(|(name, values)| Property::new(name, values))
        .collect();
    Ok(PointTable {
        cloud,
        position_type: PositionType::Scaled {
            scale: [t.x.scale, t.y.scale, t.z.scale],
            offset: [t.x.offset, t.y.offset, t.z.offset],
        },
        properties,
    })
}

fn decode(column: &mut Column, slot: Slot, bytes: &[u8], stride: usize) {
    match (slot, column) {
        (Slot::Plain { at, .. }, column) => {
            column.decode_strided(bytes, stride, at, Endian::Little)
        }
        (Slot::Bits { at, shift, width }, Column::U8(v)) => {
            let mask = (1u8 << width) - 1;
            v.extend(bytes.chunks_exact(stride).map(|r| (r[at] >> shift) & mask));
        }
        (Slot::Bits { .. }, _) => unreachable!("bit fields are decoded into u8 columns"),
    }
}

/// Size of one Extra Bytes descriptor.
const DESCRIPTOR: usize = 192;

/// The Extra Bytes of each record as named fields, from the Extra Bytes VLR; bytes not
/// described by a typed descriptor become one `u8` field per byte.
fn extra_fields(header: &las::Header, base: usize, len: usize) -> Vec<(String, Slot)> {
    let mut out = Vec::new();
    let mut at = 0;
    let descriptors = header
        .all_vlrs()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
        .map(|v| v.data.clone())
        .unwrap_or_default();
    for d in descriptors.chunks_exact(DESCRIPTOR) {
        let name: String = String::from_utf8_lossy(&d[4..36])
            .trim_end_matches('\0')
            .chars()
            .map(|c| {
                if c.is_whitespace() || c == ',' {
                    '_'
                } else {
                    c
                }
            })
            .collect();
        let name = if name.is_empty() {
            format!("extra_{at}")
        } else {
            name
        };
        let (ty, size) = match d[2] {
            0 => (None, usize::from(d[3])),
            1 => (Some(ScalarType::U8), 1),
            2 => (Some(ScalarType::I8), 1),
            3 => (Some(ScalarType::U16), 2),
            4 => (Some(ScalarType::I16), 2),
            5 => (Some(ScalarType::U32), 4),
            6 => (Some(ScalarType::I32), 4),
            7 | 8 => (None, 8),
            9 => (Some(ScalarType::F32), 4),
            10 => (Some(ScalarType::F64), 8),
            _ => break, // deprecated array types: the rest stays raw bytes
        };
        if at + size > len {
            break;
        }
        match ty {
            Some(ty) => out.push((name, Slot::Plain { ty, at: base + at })),
            None => out.extend((0..size).map(|k| {
                (
                    format!("{name}_{k}"),
                    Slot::Plain {
                        ty: ScalarType::U8,
                        at: base + at + k,
                    },
                )
            })),
        }
        at += size;
    }
    out.extend((at..len).map(|k| {
        (
            format!("extra_{k}"),
            Slot::Plain {
                ty: ScalarType::U8,
                at: base + k,
            },
        )
    }));
    out
}

/// Extra Bytes VLR data type code of `ty`.
fn extra_type_code(ty: ScalarType) -> u8 {
    match ty {
        ScalarType::U8 => 1,
        ScalarType::I8 => 2,
        ScalarType::U16 => 3,
        ScalarType::I16 => 4,
        ScalarType::U32 => 5,
        ScalarType::I32 => 6,
        ScalarType::F32 => 9,
        ScalarType::F64 => 10,
    }
}

/// Writes `view` as LAS 1.4 (or LAZ when `compressed`) to `out` and returns `out`, flushed;
/// `path` names the file in errors.
pub fn write_to<W: Write + Seek + Send + Sync + 'static>(
    out: W,
    view: &TableView<'_>,
    compressed: bool,
    path: &Path,
) -> Result<W, DataError> {
    let invalid = |what: String| DataError::InvalidOutput {
        path: path.to_path_buf(),
        what,
    };
    view.check().map_err(invalid)?;
    let find = |name: &str| {
        view.properties
            .iter()
            .find(|p| p.name == name)
            .map(|p| &p.values)
    };
    let has_class = find("class").is_some();
    let mut format = LasFormat::new(if find("nir").is_some() {
        8
    } else if find("red").is_some() && find("green").is_some() && find("blue").is_some() {
        7
    } else {
        6
    })
    .map_err(|e| las_error(path, e))?;
    let (standard, base_len) = fields(&format);
    // Properties that are not standard fields become Extra Bytes.
    let mut extras: Vec<(String, &Column)> = Vec::new();
    for p in &view.properties {
        let standard_name = standard.iter().any(|(n, _)| *n == p.name)
            || matches!(p.name.as_str(), "class" | "scan_angle_rank");
        if p.name == "classification" && has_class {
            extras.push(("input_classification".into(), &p.values));
        } else if !standard_name {
            if p.name.len() > 32 {
                return Err(invalid(format!(
                    "property name '{}' is longer than the 32 bytes of a LAS Extra Bytes name",
                    p.name
                )));
            }
            extras.push((p.name.clone(), &p.values));
        }
    }
    let extra_len: usize = extras.iter().map(|(_, c)| c.scalar_type().size()).sum();
    format.extra_bytes = u16::try_from(extra_len)
        .map_err(|_| invalid(format!("{extra_len} extra bytes per point")))?;
    format.is_compressed = compressed;
    let transforms = transforms(view);
    let mut builder = Builder::default();
    builder.version = Version::new(1, 4);
    builder.point_format = format;
    builder.transforms = transforms;
    builder.generating_software = "BoundED-rs".into();
    if !extras.is_empty() {
        builder.vlrs.push(extra_bytes_vlr(&extras));
    }
    let header = builder.into_header().map_err(|e| las_error(path, e))?;
    let mut writer = Writer::new(out, header).map_err(|e| las_error(path, e))?;
    let record_len = usize::from(format.len());
    let mut first = 0;
    while first < view.len() {
        let n = (view.len() - first).min(crate::records::block_len(record_len));
        let mut bytes = vec![0u8; n * record_len];
        encode_positions(view, first, &mut bytes, record_len, &transforms).map_err(&invalid)?;
        for (name, slot) in &standard {
            encode_standard(view, name, *slot, first, &mut bytes, record_len);
        }
        let mut at = base_len;
        for (_, column) in &extras {
            column.encode_strided(first, &mut bytes, record_len, at, Endian::Little);
            at += column.scalar_type().size();
        }
        let data = PointDataBuilder::new()
            .for_header(writer.header())
            .build_from_bytes(bytes)
            .map_err(|e| las_error(path, e))?;
        writer.write_points(&data).map_err(|e| las_error(path, e))?;
        first += n;
    }
    writer.close().map_err(|e| las_error(path, e))?;
    let mut inner = writer.into_inner().map_err(|e| las_error(path, e))?;
    inner.flush().map_err(|e| DataError::io(path, e))?;
    Ok(inner)
}

/// The input's scale and offset, or for other clouds the bounding-box centre as offset and
/// the smallest power-of-ten scale not finer than a thousandth of the `f32` resolution.
fn transforms(view: &TableView<'_>) -> Vector<Transform> {
    let (scale, offset) = match view.position_type {
        PositionType::Scaled { scale, offset } => (scale, offset),
        _ => {
            let extent = view
                .cloud
                .points()
                .iter()
                .flat_map(|p| p.map(f32::abs))
                .fold(0f32, f32::max);
            // i32 covers +-2.1e9 steps: keep the largest offset below 1e9 steps.
            let exponent = (f64::from(extent).max(1e-3) / 1e9).log10().ceil();
            let s = 10f64.powf(exponent.max(-9.0));
            ([s; 3], view.cloud.origin())
        }
    };
    let t = |a: usize| Transform {
        scale: scale[a],
        offset: offset[a],
    };
    Vector {
        x: t(0),
        y: t(1),
        z: t(2),
    }
}

fn encode_positions(
    view: &TableView<'_>,
    first: usize,
    bytes: &mut [u8],
    stride: usize,
    t: &Vector<Transform>,
) -> Result<(), String> {
    let axes = [t.x, t.y, t.z];
    for (k, record) in bytes.chunks_exact_mut(stride).enumerate() {
        let p = view.position(first + k);
        for a in 0..3 {
            let steps = ((p[a] - axes[a].offset) / axes[a].scale).round();
            if !(f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&steps) {
                return Err(format!(
                    "point {} does not fit the LAS scale {} and offset {}",
                    first + k,
                    axes[a].scale,
                    axes[a].offset
                ));
            }
            record[4 * a..4 * a + 4].copy_from_slice(&(steps as i32).to_le_bytes());
        }
    }
    Ok(())
}

/// Writes the standard field `name` of points `first..` from its property (or its
/// default: one return of one, everything else zero).
fn encode_standard(
    view: &TableView<'_>,
    name: &str,
    slot: Slot,
    first: usize,
    bytes: &mut [u8],
    stride: usize,
) {
    let find = |n: &str| {
        view.properties
            .iter()
            .find(|p| p.name == n)
            .map(|p| &p.values)
    };
    let column = find(name);
    let value: Box<dyn Fn(usize) -> f64 + '_> = if name == "classification"
        && let Some(class) = find("class")
    {
        Box::new(move |i| f64::from(class_code(class.get_f64(i))))
    } else if name == "scan_angle"
        && column.is_none()
        && let Some(rank) = find("scan_angle_rank")
    {
        Box::new(move |i| (rank.get_f64(i) / 0.006).round())
    } else if let Some(c) = column {
        let eight_bit_colour =
            matches!(name, "red" | "green" | "blue") && c.scalar_type() == ScalarType::U8;
        match slot {
            _ if eight_bit_colour => Box::new(move |i| c.get_f64(i) * 257.0),
            Slot::Plain { ty, at } if ty == c.scalar_type() => {
                c.encode_strided(first, bytes, stride, at, Endian::Little);
                return;
            }
            _ => Box::new(move |i| c.get_f64(i)),
        }
    } else if matches!(name, "return_number" | "number_of_returns") {
        Box::new(|_| 1.0)
    } else {
        return;
    };
    for (k, record) in bytes.chunks_exact_mut(stride).enumerate() {
        let v = value(first + k);
        match slot {
            Slot::Plain { ty, at } => ty.encode_f64(v, &mut record[at..], Endian::Little),
            Slot::Bits { at, shift, width } => {
                let mask = (1u8 << width) - 1;
                record[at] |= ((v as u8) & mask) << shift;
            }
        }
    }
}

/// LAS Classification code of a BoundED class code; other values pass through.
fn class_code(class: f64) -> u8 {
    match class as u8 {
        0 => CODE_NON_EDGE,
        1 => CODE_SHARP,
        2 => CODE_BOUNDARY,
        other => other,
    }
}

/// The Extra Bytes VLR (user `LASF_Spec`, record 4) describing `extras` in order.
fn extra_bytes_vlr(extras: &[(String, &Column)]) -> Vlr {
    let mut data = Vec::with_capacity(extras.len() * DESCRIPTOR);
    for (name, column) in extras {
        let mut d = [0u8; DESCRIPTOR];
        d[2] = extra_type_code(column.scalar_type());
        d[4..4 + name.len()].copy_from_slice(name.as_bytes());
        let description = match name.as_str() {
            "p_nonedge" => "probability of non-edge",
            "p_sharp" => "probability of sharp edge",
            "p_boundary" => "probability of boundary",
            _ => "",
        };
        d[160..160 + description.len()].copy_from_slice(description.as_bytes());
        data.extend_from_slice(&d);
    }
    Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "Extra Bytes".into(),
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bounded_geom::PointCloud;
    use std::io::Cursor;

    fn write_bytes(table: &PointTable, compressed: bool) -> Vec<u8> {
        write_to(
            Cursor::new(Vec::new()),
            &table.view(),
            compressed,
            Path::new("t.las"),
        )
        .unwrap()
        .into_inner()
    }

    fn sample() -> PointTable {
        let cloud = PointCloud::from_f64(&[
            [500_000.125, 5_403_150.5, 12.25],
            [500_010.0, 5_403_160.0, 13.0],
            [500_005.5, 5_403_155.75, 12.5],
        ])
        .unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("class", Column::U8(vec![0, 1, 2])));
        t.set_property(Property::new("p_sharp", Column::F32(vec![0.1, 0.9, 0.25])));
        t.set_property(Property::new("red", Column::U8(vec![255, 0, 160])));
        t.set_property(Property::new("green", Column::U8(vec![0, 255, 160])));
        t.set_property(Property::new("blue", Column::U8(vec![0, 0, 160])));
        t.set_property(Property::new("offset", Column::I16(vec![-5, 0, 5])));
        t
    }

    #[test]
    fn round_trip_las_and_laz_with_codes_and_extra_bytes() {
        let t = sample();
        for compressed in [false, true] {
            let bytes = write_bytes(&t, compressed);
            let back = read_from(Cursor::new(bytes), Path::new("t.las")).unwrap();
            for i in 0..3 {
                let (a, b) = (t.cloud.position_f64(i), back.cloud.position_f64(i));
                assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6), "{a:?} {b:?}");
            }
            let codes = [CODE_NON_EDGE, CODE_SHARP, CODE_BOUNDARY];
            assert_eq!(
                back.property("classification"),
                Some(&Column::U8(codes.to_vec()))
            );
            assert_eq!(back.property("intensity"), t.property("intensity"));
            assert_eq!(back.property("p_sharp"), t.property("p_sharp"));
            assert_eq!(back.property("offset"), t.property("offset"));
            assert_eq!(
                back.property("red"),
                Some(&Column::U16(vec![65535, 0, 160 * 257]))
            );
            assert_eq!(
                back.property("return_number"),
                Some(&Column::U8(vec![1; 3]))
            );
        }
    }

    #[test]
    fn las_in_las_out_keeps_fields_and_scale() {
        // A legacy format-3 file written by the las crate itself.
        let mut builder = Builder::from((1, 2));
        builder.point_format = LasFormat::new(3).unwrap();
        builder.transforms = Vector {
            x: Transform {
                scale: 0.01,
                offset: 100.0,
            },
            y: Transform {
                scale: 0.01,
                offset: 200.0,
            },
            z: Transform {
                scale: 0.001,
                offset: 0.0,
            },
        };
        let header = builder.into_header().unwrap();
        let mut writer = Writer::new(Cursor::new(Vec::new()), header).unwrap();
        for i in 0..4u8 {
            let point = las::Point {
                x: 100.0 + f64::from(i),
                y: 200.5,
                z: 0.125 * f64::from(i),
                intensity: 10 * u16::from(i),
                return_number: 1 + i % 2,
                number_of_returns: 2,
                classification: las::point::Classification::new(2 + i).unwrap(),
                is_withheld: i == 3,
                scan_angle: -f32::from(i),
                user_data: 7,
                point_source_id: 9,
                gps_time: Some(1e6 + f64::from(i)),
                color: Some(las::Color::new(1, 2, 3)),
                ..Default::default()
            };
            writer.write_point(point).unwrap();
        }
        let bytes = writer.into_inner().unwrap().into_inner();
        let first = read_from(Cursor::new(bytes), Path::new("in.las")).unwrap();
        assert_eq!(
            first.position_type,
            PositionType::Scaled {
                scale: [0.01, 0.01, 0.001],
                offset: [100.0, 200.0, 0.0]
            }
        );
        assert_eq!(
            first.property("classification"),
            Some(&Column::U8(vec![2, 3, 4, 5]))
        );
        assert_eq!(
            first.property("withheld"),
            Some(&Column::U8(vec![0, 0, 0, 1]))
        );
        assert_eq!(first.property("synthetic"), None);
        assert_eq!(
            first.property("scan_angle_rank"),
            Some(&Column::I8(vec![0, -1, -2, -3]))
        );
        let second = read_from(
            Cursor::new(write_bytes(&first, false)),
            Path::new("out.las"),
        )
        .unwrap();
        assert_eq!(second.position_type, first.position_type);
        assert_eq!(second.cloud, first.cloud);
        for p in &first.properties {
            if p.name != "scan_angle_rank" {
                assert_eq!(second.property(&p.name), Some(&p.values), "{}", p.name);
            }
        }
        // Legacy whole degrees become LAS 1.4 units of 0.006 degrees.
        assert_eq!(
            second.property("scan_angle"),
            Some(&Column::I16(vec![0, -167, -333, -500]))
        );
    }

    #[test]
    fn malformed_files_give_named_errors() {
        let bytes = write_bytes(&sample(), false);
        let cut = read_from(
            Cursor::new(bytes[..bytes.len() - 5].to_vec()),
            Path::new("bad.las"),
        );
        let msg = cut.unwrap_err().to_string();
        assert!(
            msg.starts_with("bad.las: LAS: point data ends within point 0 of 3"),
            "{msg}"
        );
        let msg = read_from(Cursor::new(b"LASX".to_vec()), Path::new("bad.las"))
            .unwrap_err()
            .to_string();
        assert!(msg.starts_with("bad.las: LAS: "), "{msg}");
    }
}
