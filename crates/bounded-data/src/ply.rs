//! PLY (Stanford polygon format) reader and writer.
//!
//! Reads ascii, binary little- and big-endian files with any scalar vertex properties.
//! Elements other than `vertex` (faces, the `camera` element of PCL-written files) are
//! skipped, comments and `obj_info` lines ignored, CRLF line ends tolerated. Binary data is
//! decoded in blocks of records, column by column, so throughput is limited by memory
//! bandwidth rather than per-value dispatch; ascii data is streamed line by line.
//!
//! Writing uses the sized type names (`uint8`, `uint16`, `float32`, ...) of the PLY
//! specification, which CloudCompare, MeshLab, Open3D, meshio and plyfile all read (Open3D
//! skips and meshio refuses the classic `ushort` and `short`), except `double` for 64-bit
//! floats: meshio's binary reader has no `float64`. It reads no 16-bit signed type under
//! either name either, so `int16` columns (the scan angle of LAS 1.4 clouds) are written as
//! `int32`, which holds their values: they read back as 32-bit.

use crate::DataError;
use crate::error::quoted;
use crate::table::{Column, Endian, PointTable, Property, ScalarType, TableView};
use std::io::{BufRead, Read, Write};
use std::path::Path;

/// The three PLY encodings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Text, one element item per line.
    Ascii,
    /// Binary, least significant byte first (the default for writing).
    BinaryLittleEndian,
    /// Binary, most significant byte first.
    BinaryBigEndian,
}

impl Encoding {
    fn header_name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }

    fn endian(self) -> Option<Endian> {
        match self {
            Encoding::Ascii => None,
            Encoding::BinaryLittleEndian => Some(Endian::Little),
            Encoding::BinaryBigEndian => Some(Endian::Big),
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<(String, Kind)>,
}

#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Lines read, for ascii line numbers.
    lines: usize,
    /// Bytes read, for binary byte offsets.
    bytes: u64,
}

fn scalar_type(name: &str) -> Option<ScalarType> {
    Some(match name {
        "char" | "int8" => ScalarType::I8,
        "uchar" | "uint8" => ScalarType::U8,
        "short" | "int16" => ScalarType::I16,
        "ushort" | "uint16" => ScalarType::U16,
        "int" | "int32" => ScalarType::I32,
        "uint" | "uint32" => ScalarType::U32,
        "float" | "float32" => ScalarType::F32,
        "double" | "float64" => ScalarType::F64,
        _ => return None,
    })
}

/// The type name that every reader takes (see the module documentation).
fn type_name(ty: ScalarType) -> &'static str {
    match ty {
        ScalarType::I8 => "int8",
        ScalarType::U8 => "uint8",
        ScalarType::I16 => "int16",
        ScalarType::U16 => "uint16",
        ScalarType::I32 => "int32",
        ScalarType::U32 => "uint32",
        ScalarType::F32 => "float32",
        ScalarType::F64 => "double",
    }
}

fn parse_header(input: &mut impl BufRead, path: &Path) -> Result<Header, DataError> {
    let mut buf = Vec::new();
    let mut header = Header {
        encoding: Encoding::Ascii,
        elements: Vec::new(),
        lines: 0,
        bytes: 0,
    };
    let mut format_seen = false;
    loop {
        let n = crate::records::read_line(input, &mut buf, path)?
            .ok_or_else(|| DataError::malformed(path, "the PLY header ends before 'end_header'"))?;
        header.lines += 1;
        header.bytes += n as u64;
        let line = String::from_utf8_lossy(&buf);
        let bad = |what: &str| {
            DataError::malformed(
                path,
                format!("header line {}: {what}: {}", header.lines, quoted(&line)),
            )
        };
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if header.lines == 1 {
            if words != ["ply"] {
                return Err(bad("not a PLY file (the first line must be 'ply')"));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment" | "obj_info", ..] => {}
            ["format", encoding, version] => {
                header.encoding = match *encoding {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    _ => return Err(bad("unknown format")),
                };
                if !version.starts_with('1') {
                    return Err(bad("unsupported PLY version"));
                }
                format_seen = true;
            }
            ["element", name, count] => {
                let count = count
                    .parse::<u64>()
                    .map_err(|_| bad("element count is not a non-negative integer"))?;
                header.elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let (name, kind) = match rest {
                    ["list", count, item, name] => {
                        let (Some(count), Some(item)) = (scalar_type(count), scalar_type(item))
                        else {
                            return Err(bad("unknown property type"));
                        };
                        if count.is_float() {
                            return Err(bad("list count type must be an integer"));
                        }
                        (name, Kind::List { count, item })
                    }
                    [ty, name] => {
                        let ty = scalar_type(ty).ok_or_else(|| bad("unknown property type"))?;
                        (name, Kind::Scalar(ty))
                    }
                    _ => return Err(bad("unrecognised header line")),
                };
                header
                    .elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?
                    .properties
                    .push((name.to_string(), kind));
            }
            ["end_header"] => break,
            _ => return Err(bad("unrecognised header line")),
        }
    }
    if !format_seen {
        return Err(DataError::malformed(
            path,
            "the PLY header has no 'format' line",
        ));
    }
    Ok(header)
}

/// Reads a PLY file from `input`; `path` names it in errors.
pub fn read_from(input: impl BufRead, path: &Path) -> Result<PointTable, DataError> {
    crate::table::from_properties(read_properties(input, path)?, path)
}

/// The vertex properties of the PLY file `input`, positions among them, not yet checked
/// (see [`crate::table::from_properties`]).
pub(crate) fn read_properties(
    mut input: impl BufRead,
    path: &Path,
) -> Result<Vec<Property>, DataError> {
    let header = parse_header(&mut input, path)?;
    let Some(vertex_at) = header.elements.iter().position(|e| e.name == "vertex") else {
        return Err(DataError::malformed(
            path,
            "the PLY file has no 'vertex' element",
        ));
    };
    let vertex = &header.elements[vertex_at];
    let mut types = Vec::with_capacity(vertex.properties.len());
    for (name, kind) in &vertex.properties {
        match kind {
            Kind::Scalar(ty) => types.push(*ty),
            Kind::List { .. } => {
                return Err(DataError::malformed(
                    path,
                    format!(
                        "vertex property {} is a list; vertex lists are not supported",
                        quoted(name)
                    ),
                ));
            }
        }
    }
    for axis in ["x", "y", "z"] {
        if !vertex.properties.iter().any(|(n, _)| n == axis) {
            return Err(DataError::malformed(
                path,
                format!("the vertex element has no '{axis}' property"),
            ));
        }
    }
    let count = usize::try_from(vertex.count)
        .map_err(|_| DataError::malformed(path, "vertex count too large"))?;
    // Never trust the header count for allocation: a corrupt count must not exhaust memory.
    let mut columns: Vec<Column> = types
        .iter()
        .map(|&ty| Column::with_capacity(ty, count.min(4096)))
        .collect();
    match header.encoding.endian() {
        None => {
            let mut line = header.lines;
            let mut buf = Vec::new();
            for element in &header.elements[..vertex_at] {
                skip_ascii_items(&mut input, element, &mut line, &mut buf, path)?;
            }
            crate::records::read_text_rows(
                &mut input,
                count,
                &mut columns,
                &mut line,
                "vertices",
                path,
            )?;
        }
        Some(endian) => {
            let mut offset = header.bytes;
            for element in &header.elements[..vertex_at] {
                skip_binary_items(&mut input, element, endian, &mut offset, path)?;
            }
            crate::records::read_records(
                &mut input,
                count,
                &types,
                &mut columns,
                endian,
                offset,
                path,
            )?;
        }
    }
    let properties = vertex
        .properties
        .iter()
        .zip(columns)
        .map(|((name, _), values)| Property::new(name.clone(), values))
        .collect();
    Ok(properties)
}

fn skip_ascii_items(
    input: &mut impl BufRead,
    element: &Element,
    line: &mut usize,
    buf: &mut Vec<u8>,
    path: &Path,
) -> Result<(), DataError> {
    for i in 0..element.count {
        *line += 1;
        input
            .read_until(b'\n', buf)
            .map_err(|e| DataError::io(path, e))
            .and_then(|n| {
                if n == 0 {
                    Err(DataError::malformed(
                        path,
                        format!(
                            "the file ends at line {line} inside element {} (item {i} of {})",
                            quoted(&element.name),
                            element.count
                        ),
                    ))
                } else {
                    Ok(())
                }
            })?;
        buf.clear();
    }
    Ok(())
}

fn skip_binary_items(
    input: &mut impl BufRead,
    element: &Element,
    endian: Endian,
    offset: &mut u64,
    path: &Path,
) -> Result<(), DataError> {
    let fixed: Option<u64> = element
        .properties
        .iter()
        .map(|(_, k)| match k {
            Kind::Scalar(ty) => Some(ty.size() as u64),
            Kind::List { .. } => None,
        })
        .sum();
    let ends = |at: u64| {
        format!(
            "the data ends inside element {} (byte offset {at})",
            quoted(&element.name)
        )
    };
    if let Some(stride) = fixed {
        let len = stride.saturating_mul(element.count);
        let copied = std::io::copy(&mut input.by_ref().take(len), &mut std::io::sink())
            .map_err(|e| DataError::io(path, e))?;
        *offset += copied;
        if copied < len {
            return Err(DataError::malformed(path, ends(*offset)));
        }
        return Ok(());
    }
    let mut scratch = [0u8; 8];
    for _ in 0..element.count {
        for (_, kind) in &element.properties {
            let skip = match *kind {
                Kind::Scalar(ty) => ty.size() as u64,
                Kind::List { count, item } => {
                    let bytes = &mut scratch[..count.size()];
                    input
                        .read_exact(bytes)
                        .map_err(|e| crate::records::truncated(path, ends(*offset), e))?;
                    *offset += count.size() as u64;
                    let mut c = Column::with_capacity(count, 1);
                    c.decode_packed(bytes, endian);
                    let n = c.get_f64(0);
                    if n < 0.0 {
                        return Err(DataError::malformed(
                            path,
                            format!("negative list length at byte offset {offset}"),
                        ));
                    }
                    n as u64 * item.size() as u64
                }
            };
            let copied = std::io::copy(&mut input.by_ref().take(skip), &mut std::io::sink())
                .map_err(|e| DataError::io(path, e))?;
            *offset += copied;
            if copied < skip {
                return Err(DataError::malformed(path, ends(*offset)));
            }
        }
    }
    Ok(())
}

/// Writes `view` as PLY with `encoding` to `out`; `path` names the file in errors.
pub fn write_to(
    out: impl Write,
    view: &TableView<'_>,
    encoding: Encoding,
    path: &Path,
) -> Result<(), DataError> {
    view.check(path)?;
    // meshio's binary reader has no 16-bit signed type: such columns go out as int32, which
    // holds every value.
    let widened: Vec<Option<Property>> = (view.properties.iter())
        .map(|p| match &p.values {
            Column::I16(v) => Some(Property::new(
                p.name.clone(),
                Column::I32(v.iter().map(|&x| i32::from(x)).collect()),
            )),
            _ => None,
        })
        .collect();
    let mut view = view.clone();
    for (p, wide) in view.properties.iter_mut().zip(&widened) {
        if let Some(wide) = wide {
            *p = wide;
        }
    }
    let mut out = std::io::BufWriter::with_capacity(1 << 20, out);
    write_body(&mut out, &view, encoding).map_err(|e| DataError::io(path, e))?;
    out.flush().map_err(|e| DataError::io(path, e))
}

fn write_body(
    out: &mut impl Write,
    view: &TableView<'_>,
    encoding: Encoding,
) -> std::io::Result<()> {
    let position = view.position_type.float_type();
    writeln!(out, "ply")?;
    writeln!(out, "format {} 1.0", encoding.header_name())?;
    writeln!(out, "comment written by BoundED-rs")?;
    writeln!(out, "element vertex {}", view.len())?;
    for axis in ["x", "y", "z"] {
        writeln!(out, "property {} {axis}", type_name(position))?;
    }
    for p in &view.properties {
        writeln!(
            out,
            "property {} {}",
            type_name(p.values.scalar_type()),
            p.name
        )?;
    }
    writeln!(out, "end_header")?;
    match encoding.endian() {
        None => crate::records::write_text_rows(out, view, ' '),
        Some(endian) => crate::records::write_records(out, view, position, endian),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::PositionType;
    use bounded_geom::PointCloud;
    use std::io::Cursor;

    fn sample() -> PointTable {
        let cloud =
            PointCloud::from_f64(&[[0.5, -1.25, 2.0], [1.5, 3.0, -4.0], [0.0, 0.0, 0.0]]).unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("offset", Column::I8(vec![-128, 0, 127])));
        t.set_property(Property::new("time", Column::F64(vec![1e-300, 2.5, -3.0])));
        t.set_property(Property::new("nx", Column::F32(vec![0.25, -0.5, 1.0])));
        t
    }

    fn round_trip(table: &PointTable, encoding: Encoding) -> PointTable {
        let mut bytes = Vec::new();
        write_to(&mut bytes, &table.view(), encoding, Path::new("t.ply")).unwrap();
        read_from(Cursor::new(bytes), Path::new("t.ply")).unwrap()
    }

    #[test]
    fn round_trips_all_encodings_with_properties() {
        let t = sample();
        for encoding in [
            Encoding::Ascii,
            Encoding::BinaryLittleEndian,
            Encoding::BinaryBigEndian,
        ] {
            assert_eq!(round_trip(&t, encoding), t, "{encoding:?}");
        }
    }

    #[test]
    fn int16_columns_are_written_as_int32_with_their_values() {
        let mut t = sample();
        t.set_property(Property::new("angle", Column::I16(vec![-32768, 5, 32767])));
        for encoding in [Encoding::Ascii, Encoding::BinaryBigEndian] {
            let back = round_trip(&t, encoding);
            let angle = back.property("angle").unwrap();
            assert_eq!(*angle, Column::I32(vec![-32768, 5, 32767]), "{encoding:?}");
            assert_eq!(back.property("intensity"), t.property("intensity"));
        }
    }

    #[test]
    fn headers_use_the_sized_type_names() {
        let mut bytes = Vec::new();
        let t = sample();
        write_to(
            &mut bytes,
            &t.view(),
            Encoding::BinaryLittleEndian,
            Path::new("t.ply"),
        )
        .unwrap();
        let text = String::from_utf8_lossy(&bytes);
        let header = text.split("end_header").next().unwrap();
        let types: Vec<&str> = (header.lines())
            .filter_map(|l| l.strip_prefix("property ")?.split(' ').next())
            .collect();
        assert_eq!(
            types,
            [
                "float32", "float32", "float32", "uint16", "int8", "double", "float32"
            ]
        );
    }

    #[test]
    fn double_positions_keep_utm_precision() {
        let cloud =
            PointCloud::from_f64(&[[5_403_150.123, 1.0, 2.0], [5_403_151.0, 1.0, 2.0]]).unwrap();
        let t = PointTable::new(cloud);
        assert_eq!(t.position_type, PositionType::F64);
        let back = round_trip(&t, Encoding::BinaryLittleEndian);
        assert_eq!(back.position_type, PositionType::F64);
        assert!((back.cloud.position_f64(0)[0] - 5_403_150.123).abs() < 1e-6);
    }

    #[test]
    fn reads_crlf_ascii_skipping_other_elements_and_comments() {
        let text = "ply\r\nformat ascii 1.0\r\ncomment hi\r\nelement face 1\r\n\
            property list uchar int vertex_indices\r\nelement vertex 2\r\nproperty float x\r\n\
            property float y\r\nproperty float z\r\nproperty uchar red\r\nelement camera 1\r\n\
            property float focal\r\nend_header\r\n3 0 1 2\r\n1 2 3 255\r\n4 5 6 0\r\n9\r\n";
        let t = read_from(Cursor::new(text), Path::new("c.ply")).unwrap();
        assert_eq!(t.cloud.position_f64(1), [4.0, 5.0, 6.0]);
        assert_eq!(t.property("red"), Some(&Column::U8(vec![255, 0])));
    }

    #[test]
    fn skips_binary_list_element_before_vertices() {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement face 2\n\
            property list uchar int vertex_indices\nelement vertex 1\nproperty double x\n\
            property double y\nproperty double z\nend_header\n"
            .to_vec();
        bytes.extend([1, 0, 0, 0, 9]); // face with one index
        bytes.extend([0]); // face with no index
        for c in [1.0f64, 2.0, 3.0] {
            bytes.extend(c.to_be_bytes());
        }
        let t = read_from(Cursor::new(bytes), Path::new("l.ply")).unwrap();
        assert_eq!(t.cloud.position_f64(0), [1.0, 2.0, 3.0]);
    }

    fn error_of(bytes: &[u8]) -> String {
        read_from(Cursor::new(bytes.to_vec()), Path::new("bad.ply"))
            .unwrap_err()
            .to_string()
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
        property float y\nproperty float z\nend_header\n";

    #[test]
    fn malformed_files_give_named_errors() {
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"plx\n".to_vec(), "first line must be 'ply'"),
            (
                b"ply\nformat ascii 1.0\nelement vertex 2\n".to_vec(),
                "before 'end_header'",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex two\nend_header\n".to_vec(),
                "header line 3",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"
                    .to_vec(),
                "no 'y' property",
            ),
            (
                format!("{HEAD}1 2 3\n").into_bytes(),
                "after 1 of 2 vertices",
            ),
            (
                format!("{HEAD}1 2 3\n1 2\n").into_bytes(),
                "line 9: expected 3 values, found 2",
            ),
            (
                format!("{HEAD}1 2 3\n1 2 3 4\n").into_bytes(),
                "line 9: more than 3 values",
            ),
            (
                format!("{HEAD}1 2 3\n1 two 3\n").into_bytes(),
                "line 9, value 2: 'two'",
            ),
            (
                format!("{HEAD}1 2 3\n1 nan 3\n").into_bytes(),
                "point 1 has a non-finite",
            ),
            (HEAD.replace("vertex 2", "vertex 0").into_bytes(), "empty"),
            (
                HEAD.replace("element vertex 2\n", "").into_bytes(),
                "header line 3: property before any element",
            ),
            (
                HEAD.replace("float y", "float32x y").into_bytes(),
                "header line 5: unknown property type",
            ),
            (
                HEAD.replace("float z", "list float int z").into_bytes(),
                "header line 6: list count type must be an integer",
            ),
            (
                HEAD.replace("float z", "list uchar z").into_bytes(),
                "header line 6: unrecognised header line",
            ),
            (
                format!("{}\0\0\0\0", HEAD.replace("ascii", "binary_little_endian")).into_bytes(),
                "ends within point 0 of 2 (at byte offset 119)",
            ),
            (
                // 5 whole points of 12 bytes and 4 bytes of the sixth.
                [
                    HEAD.replace("ascii", "binary_little_endian")
                        .replace("vertex 2", "vertex 10")
                        .into_bytes(),
                    vec![0; 64],
                ]
                .concat(),
                "ends within point 5 of 10 (at byte offset 180)",
            ),
        ];
        for (bytes, expected) in cases {
            let msg = error_of(&bytes);
            assert!(
                msg.starts_with("bad.ply: ") && msg.contains(expected),
                "{msg}"
            );
        }
    }

    fn dataset(sub: &str) -> Option<std::path::PathBuf> {
        let dir = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/datasets"
        ));
        let p = dir.join(sub);
        if p.exists() {
            Some(p)
        } else {
            eprintln!("skipped: {} is missing", p.display());
            None
        }
    }

    #[test]
    fn real_pcednet_and_bazazian_files_load_with_labels() {
        use crate::labels::{Convention, load};
        let Some(p) = dataset("pcednet/default/TwoPlane90.ply") else {
            return;
        };
        let l = load(&p, Convention::PCEDNET).unwrap();
        let [n, s, b] = l.class_counts();
        assert!(n > 0 && s > 0 && b == 0, "{n} {s} {b}");
        let Some(p) = dataset("bazazian/StairsCube.ply") else {
            return;
        };
        let l = load(&p, Convention::Bazazian).unwrap();
        // Counted with awk on the file: 1361 red, 2257 white.
        assert_eq!(l.class_counts(), [2257, 1361, 0]);
    }
}
