//! PCD (Point Cloud Library) reader and writer.
//!
//! Reads `DATA ascii`, `binary` and `binary_compressed` (LZF, field-major layout) files with
//! fields of any PCL type (`I`/`U` of 1, 2, 4 bytes, `F` of 4 or 8 bytes). A field with
//! `COUNT` n > 1 becomes n properties `name_0 .. name_{n-1}`; `_` padding fields are dropped;
//! PCL's packed `rgb` / `rgba` field becomes `red`, `green`, `blue` (and `alpha`) so colours
//! survive conversion to other formats. Writing produces `DATA binary` and packs 8-bit
//! `red`/`green`/`blue` back into `rgb`, which PCL and CloudCompare display. Positions are
//! written as `F 4` when every coordinate is a single float or the decimal of one (`0.1`,
//! `1.811728`: a text cloud's coordinates of up to 7 digits print back the same from the
//! single float), since PCL's `PointXYZ` tools load nothing else and its filters misread
//! `F 8` positions; else as `F 8`, which keeps every coordinate (UTM-sized or finely
//! quantised clouds). Annotated outputs write `class` as `F 4`, since PCL's filters
//! (`pcl_passthrough_filter -field class`) read the field they filter on as a float.

use crate::DataError;
use crate::error::quoted;
use crate::records::{read_line, read_records, read_text_rows, truncated};
use crate::table::{Column, Endian, PointTable, PositionType, Property, ScalarType, TableView};
use std::io::{BufRead, Read, Write};
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

#[derive(Debug)]
struct Field {
    name: String,
    ty: ScalarType,
    count: usize,
}

#[derive(Debug)]
struct Header {
    fields: Vec<Field>,
    points: usize,
    data: Data,
    lines: usize,
    bytes: u64,
}

fn pcd_type(kind: &str, size: &str) -> Option<ScalarType> {
    Some(match (kind, size) {
        ("I", "1") => ScalarType::I8,
        ("I", "2") => ScalarType::I16,
        ("I", "4") => ScalarType::I32,
        ("U", "1") => ScalarType::U8,
        ("U", "2") => ScalarType::U16,
        ("U", "4") => ScalarType::U32,
        ("F", "4") => ScalarType::F32,
        ("F", "8") => ScalarType::F64,
        _ => return None,
    })
}

fn type_letter(ty: ScalarType) -> char {
    match ty {
        ScalarType::I8 | ScalarType::I16 | ScalarType::I32 => 'I',
        ScalarType::U8 | ScalarType::U16 | ScalarType::U32 => 'U',
        ScalarType::F32 | ScalarType::F64 => 'F',
    }
}

fn parse_header(input: &mut impl BufRead, path: &Path) -> Result<Header, DataError> {
    let mut buf = Vec::new();
    let (mut lines, mut bytes) = (0, 0u64);
    let mut names: Vec<String> = Vec::new();
    let mut sizes: Vec<String> = Vec::new();
    let mut kinds: Vec<String> = Vec::new();
    let mut counts: Option<Vec<usize>> = None;
    let (mut width, mut height, mut points) = (None, None, None);
    let data = loop {
        let n = read_line(input, &mut buf, path)?
            .ok_or_else(|| DataError::malformed(path, "the PCD header ends before 'DATA'"))?;
        lines += 1;
        bytes += n as u64;
        let line = String::from_utf8_lossy(&buf);
        let bad = |what: &str| {
            DataError::malformed(
                path,
                format!("header line {lines}: {what}: {}", quoted(&line)),
            )
        };
        let number = |w: &str| w.parse::<usize>().map_err(|_| bad("not a count"));
        let mut words = line.split_ascii_whitespace();
        let Some(key) = words.next() else { continue };
        let rest = || words.clone().map(str::to_string).collect::<Vec<_>>();
        match key.to_ascii_uppercase().as_str() {
            k if k.starts_with('#') => {}
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => names = rest(),
            "SIZE" => sizes = rest(),
            "TYPE" => kinds = rest(),
            "COUNT" => counts = Some(rest().iter().map(|w| number(w)).collect::<Result<_, _>>()?),
            "WIDTH" => width = Some(number(words.next().unwrap_or(""))?),
            "HEIGHT" => height = Some(number(words.next().unwrap_or(""))?),
            "POINTS" => points = Some(number(words.next().unwrap_or(""))?),
            "DATA" => {
                break match words.next() {
                    Some("ascii") => Data::Ascii,
                    Some("binary") => Data::Binary,
                    Some("binary_compressed") => Data::Compressed,
                    _ => return Err(bad("unknown DATA encoding")),
                };
            }
            _ => return Err(bad("unrecognised header line")),
        }
    };
    let counts = counts.unwrap_or_else(|| vec![1; names.len()]);
    if names.is_empty() || [sizes.len(), kinds.len(), counts.len()] != [names.len(); 3] {
        return Err(DataError::malformed(
            path,
            format!(
                "the PCD header lists {} FIELDS, {} SIZE, {} TYPE and {} COUNT entries",
                names.len(),
                sizes.len(),
                kinds.len(),
                counts.len()
            ),
        ));
    }
    let mut fields = Vec::with_capacity(names.len());
    for (((name, size), kind), count) in names.into_iter().zip(&sizes).zip(&kinds).zip(counts) {
        let ty = pcd_type(kind, size).ok_or_else(|| {
            DataError::malformed(
                path,
                format!(
                    "field {} has unsupported TYPE {} SIZE {}",
                    quoted(&name),
                    quoted(kind),
                    quoted(size)
                ),
            )
        })?;
        if count == 0 || count > 4096 {
            return Err(DataError::malformed(
                path,
                format!("field {} has COUNT {count}", quoted(&name)),
            ));
        }
        fields.push(Field { name, ty, count });
    }
    let points = match (points, width, height) {
        (Some(p), Some(w), Some(h)) if w.checked_mul(h) != Some(p) => {
            return Err(DataError::malformed(
                path,
                format!("POINTS {p} differs from WIDTH {w} x HEIGHT {h}"),
            ));
        }
        (Some(p), _, _) => p,
        (None, Some(w), Some(h)) => w
            .checked_mul(h)
            .ok_or_else(|| DataError::malformed(path, "WIDTH x HEIGHT overflows"))?,
        _ => return Err(DataError::malformed(path, "the PCD header has no POINTS")),
    };
    Ok(Header {
        fields,
        points,
        data,
        lines,
        bytes,
    })
}

/// Reads a PCD file from `input`; `path` names it in errors.
pub fn read_from(input: impl BufRead, path: &Path) -> Result<PointTable, DataError> {
    crate::table::from_properties(read_properties(input, path)?, path)
}

/// The fields of the PCD file `input`, positions among them, not yet checked (packed
/// colours unpacked).
pub(crate) fn read_properties(
    mut input: impl BufRead,
    path: &Path,
) -> Result<Vec<Property>, DataError> {
    let header = parse_header(&mut input, path)?;
    let mut names = Vec::new();
    let mut types = Vec::new();
    for f in &header.fields {
        for k in 0..f.count {
            names.push(if f.count == 1 {
                f.name.clone()
            } else {
                format!("{}_{k}", f.name)
            });
            types.push(f.ty);
        }
    }
    for axis in ["x", "y", "z"] {
        if !names.iter().any(|n| n == axis) {
            return Err(DataError::malformed(
                path,
                format!("the PCD file has no '{axis}' field"),
            ));
        }
    }
    let n = header.points;
    let mut columns: Vec<Column> = types
        .iter()
        .map(|&ty| Column::with_capacity(ty, n.min(4096)))
        .collect();
    match header.data {
        Data::Ascii => {
            let mut line = header.lines;
            read_text_rows(&mut input, n, &mut columns, &mut line, "points", path)?
        }
        Data::Binary => read_records(
            &mut input,
            n,
            &types,
            &mut columns,
            Endian::Little,
            header.bytes,
            path,
        )?,
        Data::Compressed => read_compressed(&mut input, &header, &mut columns, path)?,
    }
    let mut properties: Vec<Property> = names
        .into_iter()
        .zip(columns)
        .filter(|(name, _)| name != "_")
        .map(|(name, values)| Property::new(name, values))
        .collect();
    unpack_colours(&mut properties);
    Ok(properties)
}

fn read_compressed(
    input: &mut impl Read,
    header: &Header,
    columns: &mut [Column],
    path: &Path,
) -> Result<(), DataError> {
    let at = header.bytes;
    let mut sizes = [0u8; 8];
    input.read_exact(&mut sizes).map_err(|e| {
        truncated(
            path,
            format!("the compressed block header is missing (byte offset {at})"),
            e,
        )
    })?;
    let word = |k: usize| u32::from_le_bytes([sizes[k], sizes[k + 1], sizes[k + 2], sizes[k + 3]]);
    let (packed_len, unpacked_len) = (word(0) as usize, word(4) as usize);
    let record: usize = header.fields.iter().map(|f| f.ty.size() * f.count).sum();
    let expected = header.points.checked_mul(record);
    if expected != Some(unpacked_len) {
        return Err(DataError::malformed(
            path,
            format!(
                "binary_compressed: uncompressed size {unpacked_len} differs from {} points x {record} bytes",
                header.points
            ),
        ));
    }
    let mut packed = Vec::new();
    input
        .take(packed_len as u64)
        .read_to_end(&mut packed)
        .map_err(|e| DataError::io(path, e))?;
    if packed.len() < packed_len {
        return Err(DataError::malformed(
            path,
            format!(
                "binary_compressed: {} of {packed_len} compressed bytes present (from byte offset {})",
                packed.len(),
                at + 8
            ),
        ));
    }
    let data = lzf_decompress(&packed, unpacked_len)
        .map_err(|what| DataError::malformed(path, format!("binary_compressed: {what}")))?;
    // Field-major: all points' values of field 0, then of field 1, ...
    let mut start = 0;
    let mut column = columns.iter_mut();
    for f in &header.fields {
        let stride = f.ty.size() * f.count;
        let block = &data[start..start + stride * header.points];
        for k in 0..f.count {
            if let Some(c) = column.next() {
                c.decode_strided(block, stride, k * f.ty.size(), Endian::Little);
            }
        }
        start += block.len();
    }
    Ok(())
}

/// Decompresses LZF (liblzf's format, as used by PCL) into exactly `len` bytes.
///
/// A control byte below 32 starts a run of `ctrl + 1` literal bytes; otherwise its top 3
/// bits (plus an extra byte when they are all set) give a back-reference length - 2 and its
/// low 5 bits with the next byte the distance - 1.
pub(crate) fn lzf_decompress(input: &[u8], len: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(len.min(input.len().saturating_mul(64)));
    let mut ip = 0;
    let byte = |ip: usize| {
        input
            .get(ip)
            .copied()
            .ok_or_else(|| format!("compressed data ends early (at byte {ip})"))
    };
    while ip < input.len() {
        let ctrl = usize::from(input[ip]);
        ip += 1;
        if ctrl < 32 {
            let run = ctrl + 1;
            let literal = input
                .get(ip..ip + run)
                .ok_or_else(|| format!("literal run past the end (at byte {ip})"))?;
            if out.len() + run > len {
                return Err(format!("data decompresses to more than {len} bytes"));
            }
            out.extend_from_slice(literal);
            ip += run;
        } else {
            let mut run = ctrl >> 5;
            if run == 7 {
                run += usize::from(byte(ip)?);
                ip += 1;
            }
            run += 2;
            let distance = ((ctrl & 0x1f) << 8) + usize::from(byte(ip)?) + 1;
            ip += 1;
            let from = out
                .len()
                .checked_sub(distance)
                .ok_or_else(|| format!("back-reference before the start (at byte {ip})"))?;
            if out.len() + run > len {
                return Err(format!("data decompresses to more than {len} bytes"));
            }
            // Byte by byte: the source may overlap the bytes being produced.
            for k in from..from + run {
                out.push(out[k]);
            }
        }
    }
    if out.len() != len {
        return Err(format!(
            "data decompresses to {} bytes, expected {len}",
            out.len()
        ));
    }
    Ok(out)
}

/// Splits PCL's packed `rgb` (0x00RRGGBB) / `rgba` (0xAARRGGBB) field into byte channels.
fn unpack_colours(properties: &mut Vec<Property>) {
    let Some(at) = properties.iter().position(|p| {
        matches!(p.name.as_str(), "rgb" | "rgba")
            && matches!(p.values, Column::F32(_) | Column::U32(_) | Column::I32(_))
    }) else {
        return;
    };
    let packed = properties.remove(at);
    let bits: Vec<u32> = match &packed.values {
        Column::F32(v) => v.iter().map(|f| f.to_bits()).collect(),
        Column::U32(v) => v.clone(),
        Column::I32(v) => v.iter().map(|&i| i as u32).collect(),
        _ => return,
    };
    let channel = |shift: u32| Column::U8(bits.iter().map(|b| (b >> shift) as u8).collect());
    let mut channels = vec![
        Property::new("red", channel(16)),
        Property::new("green", channel(8)),
        Property::new("blue", channel(0)),
    ];
    if packed.name == "rgba" {
        channels.push(Property::new("alpha", channel(24)));
    }
    properties.retain(|p| !channels.iter().any(|c| c.name == p.name));
    properties.splice(at.min(properties.len())..at.min(properties.len()), channels);
}

/// Writes `view` as a `DATA binary` PCD to `out`; `path` names the file in errors.
pub fn write_to(out: impl Write, view: &TableView<'_>, path: &Path) -> Result<(), DataError> {
    view.check(path)?;
    let packed = pack_colours(view);
    let mut view = view.clone();
    if let Some(rgb) = &packed {
        view.properties
            .retain(|p| !matches!(p.name.as_str(), "red" | "green" | "blue" | "rgb"));
        view.properties.push(rgb);
    }
    let mut out = std::io::BufWriter::with_capacity(1 << 20, out);
    write_body(&mut out, &view).map_err(|e| DataError::io(path, e))?;
    out.flush().map_err(|e| DataError::io(path, e))
}

/// `F32` when every coordinate is a single float or the decimal of one, as PCL's `PointXYZ`
/// types and tools need (they find no `x` of another type), else `F64`, which loses nothing.
fn position_type(view: &TableView<'_>) -> ScalarType {
    use rayon::prelude::*;
    // The shortest decimal of the single float (what `Display` prints) read as a double.
    let decimal = |c: f64| f64::from(c as f32) == c || (c as f32).to_string().parse() == Ok(c);
    let single = |i| view.position(i).into_iter().all(decimal);
    if view.position_type == PositionType::F32 || (0..view.len()).into_par_iter().all(single) {
        ScalarType::F32
    } else {
        ScalarType::F64
    }
}

/// `red`, `green`, `blue` byte channels packed into PCL's `rgb` float, if all three exist.
fn pack_colours(view: &TableView<'_>) -> Option<Property> {
    let channel = |name: &str| {
        view.properties.iter().find_map(|p| match &p.values {
            Column::U8(v) if p.name == name => Some(v),
            _ => None,
        })
    };
    let (r, g, b) = (channel("red")?, channel("green")?, channel("blue")?);
    let rgb = (0..view.len())
        .map(|i| f32::from_bits(u32::from(r[i]) << 16 | u32::from(g[i]) << 8 | u32::from(b[i])))
        .collect();
    Some(Property::new("rgb", Column::F32(rgb)))
}

fn write_body(out: &mut impl Write, view: &TableView<'_>) -> std::io::Result<()> {
    let position = position_type(view);
    let types: Vec<ScalarType> = [position; 3]
        .into_iter()
        .chain(view.properties.iter().map(|p| p.values.scalar_type()))
        .collect();
    let names = ["x", "y", "z"]
        .into_iter()
        .chain(view.properties.iter().map(|p| p.name.as_str()));
    writeln!(
        out,
        "# .PCD v0.7 - Point Cloud Data file format (written by BoundED-rs)"
    )?;
    writeln!(out, "VERSION 0.7")?;
    writeln!(out, "FIELDS {}", names.collect::<Vec<_>>().join(" "))?;
    let list = |f: &dyn Fn(ScalarType) -> String| {
        types.iter().map(|&t| f(t)).collect::<Vec<_>>().join(" ")
    };
    writeln!(out, "SIZE {}", list(&|t| t.size().to_string()))?;
    writeln!(out, "TYPE {}", list(&|t| type_letter(t).to_string()))?;
    writeln!(out, "COUNT {}", list(&|_| "1".to_string()))?;
    writeln!(out, "WIDTH {}", view.len())?;
    writeln!(out, "HEIGHT 1")?;
    writeln!(out, "VIEWPOINT 0 0 0 1 0 0 0")?;
    writeln!(out, "POINTS {}", view.len())?;
    writeln!(out, "DATA binary")?;
    crate::records::write_records(out, view, position, Endian::Little)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bounded_geom::PointCloud;
    use std::io::Cursor;

    #[test]
    fn lzf_literals_and_overlapping_back_reference() {
        // "abc" as a literal run, then a back-reference of length 5 at distance 3.
        let packed = [2, b'a', b'b', b'c', (3 << 5), 2];
        assert_eq!(lzf_decompress(&packed, 8).unwrap(), b"abcabcab");
        assert!(lzf_decompress(&packed, 7).is_err());
        assert!(lzf_decompress(&[2, b'a'], 3).is_err());
        assert!(lzf_decompress(&[(1 << 5), 9], 3).is_err());
    }

    fn sample() -> PointTable {
        let cloud =
            PointCloud::from_f64(&[[0.5, -1.25, 2.0], [1.5, 3.0, -4.0], [0.0, 0.0, 0.0]]).unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("red", Column::U8(vec![255, 0, 1])));
        t.set_property(Property::new("green", Column::U8(vec![0, 255, 2])));
        t.set_property(Property::new("blue", Column::U8(vec![0, 0, 3])));
        t.set_property(Property::new(
            "curvature",
            Column::F64(vec![0.5, 1e-9, -2.0]),
        ));
        t
    }

    #[test]
    fn binary_round_trip_packs_and_unpacks_rgb() {
        let t = sample();
        let mut bytes = Vec::new();
        write_to(&mut bytes, &t.view(), Path::new("t.pcd")).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(
            text.contains("FIELDS x y z intensity curvature rgb\n"),
            "{text}"
        );
        let back = read_from(Cursor::new(bytes), Path::new("t.pcd")).unwrap();
        assert_eq!(back.cloud, t.cloud);
        for name in ["intensity", "red", "green", "blue", "curvature"] {
            assert_eq!(back.property(name), t.property(name), "{name}");
        }
    }

    #[test]
    fn positions_are_single_floats_when_they_keep_the_decimals() {
        let fields = |t: &PointTable| {
            let mut bytes = Vec::new();
            write_to(&mut bytes, &t.view(), Path::new("t.pcd")).unwrap();
            let text = String::from_utf8_lossy(&bytes);
            let line = |key: &str| {
                text.lines()
                    .find(|l| l.starts_with(key))
                    .unwrap()
                    .to_string()
            };
            let back = read_from(Cursor::new(bytes.clone()), Path::new("t.pcd")).unwrap();
            let view = back.view();
            let positions: Vec<[f64; 3]> = (0..back.len()).map(|i| view.position(i)).collect();
            (line("SIZE"), positions)
        };
        // Doubles that are single floats (halves, quarters).
        let text = |t: &str| {
            crate::xyz::read_from(Cursor::new(t.to_string()), Path::new("t.xyz")).unwrap()
        };
        let t = text("0.5 -1.25 2\n1.5 3 -4\n");
        assert_eq!(t.position_type, crate::table::PositionType::F64);
        assert_eq!(
            fields(&t),
            (
                "SIZE 4 4 4".into(),
                vec![[0.5, -1.25, 2.0], [1.5, 3.0, -4.0]]
            )
        );
        // Decimals of single floats: stored as those floats.
        let t = text("0.1 0 0\n1.811728 0 -2.5e-7\n");
        assert_eq!(
            fields(&t),
            (
                "SIZE 4 4 4".into(),
                vec![
                    [f64::from(0.1f32), 0.0, 0.0],
                    [f64::from(1.811728f32), 0.0, f64::from(-2.5e-7f32)]
                ]
            )
        );
        // One coordinate that no single float prints as (9 digits, a UTM easting in mm).
        for odd in ["0.123456789", "500000.123"] {
            let t = text(&format!("0.1 0 0\n{odd} 0 0\n"));
            let (size, positions) = fields(&t);
            assert_eq!(size, "SIZE 8 8 8", "{odd}");
            assert_eq!(positions[1][0], odd.parse::<f64>().unwrap());
        }
    }

    #[test]
    fn ascii_and_compressed_with_counts_and_padding() {
        let ascii = "# c\nVERSION .7\nFIELDS x y z n _\nSIZE 4 4 8 2 1\nTYPE F F F I U\n\
            COUNT 1 1 1 2 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 -4 5 0\n\r\n6 7 8 9 10 0\n";
        let t = read_from(Cursor::new(ascii), Path::new("a.pcd")).unwrap();
        assert_eq!(t.cloud.position_f64(1), [6.0, 7.0, 8.0]);
        assert_eq!(t.property("n_0"), Some(&Column::I16(vec![-4, 9])));
        assert_eq!(t.property("n_1"), Some(&Column::I16(vec![5, 10])));
        assert_eq!(t.properties.len(), 2);
        // Field-major data: x of both points, then y, then z (u8 each), as one literal run.
        let mut c = b"VERSION .7\nFIELDS x y z\nSIZE 1 1 1\nTYPE U U U\nWIDTH 2\nHEIGHT 1\n\
            POINTS 2\nDATA binary_compressed\n"
            .to_vec();
        c.extend(7u32.to_le_bytes());
        c.extend(6u32.to_le_bytes());
        c.extend([5, 1, 2, 3, 4, 5, 6]);
        let t = read_from(Cursor::new(c), Path::new("c.pcd")).unwrap();
        assert_eq!(t.cloud.position_f64(0), [1.0, 3.0, 5.0]);
        assert_eq!(t.cloud.position_f64(1), [2.0, 4.0, 6.0]);
    }

    #[test]
    fn malformed_files_give_named_errors() {
        let head = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
        let cases: Vec<(String, &str)> = vec![
            ("FIELDS x y z\n".into(), "ends before 'DATA'"),
            (
                head.replace("SIZE 4 4 4", "SIZE 4 4") + "DATA ascii\n",
                "3 FIELDS, 2 SIZE",
            ),
            (
                head.replace("TYPE F F F", "TYPE F F Q") + "DATA ascii\n",
                "unsupported TYPE 'Q'",
            ),
            (
                head.replace("POINTS 2", "POINTS 3") + "DATA ascii\n",
                "POINTS 3 differs",
            ),
            (format!("{head}DATA ascii\n1 2 3\n"), "after 1 of 2 points"),
            (
                format!("{head}DATA ascii\n1 2 3\n1 2 x\n"),
                "line 9, value 3: 'x'",
            ),
            (format!("{head}DATA ascii\n1 2 3\n1 2 inf\n"), "non-finite"),
            (
                format!("{head}DATA binary\n\0\0\0\0"),
                "ends within point 0 of 2",
            ),
            (
                format!("{head}DATA binary\n{}", "\0".repeat(20)),
                "ends within point 1 of 2 (at byte offset 93)",
            ),
            (
                format!("{head}DATA binary_compressed\n\x05\0\0\0\x18\0\0\0\x01"),
                "1 of 5 compressed",
            ),
            (
                format!("{head}DATA binary_compressed\n\0\0\0\0\x09\0\0\0"),
                "size 9 differs",
            ),
            (format!("{head}DATA zip\n"), "unknown DATA"),
        ];
        for (text, expected) in cases {
            let e = read_from(Cursor::new(text.into_bytes()), Path::new("bad.pcd")).unwrap_err();
            let msg = e.to_string();
            assert!(
                msg.starts_with("bad.pcd: ") && msg.contains(expected),
                "{msg}"
            );
        }
    }

    #[test]
    fn real_scans_load_with_their_point_counts() {
        let dir = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/datasets/scans"
        ));
        if !dir.exists() {
            eprintln!("skipped: {} is missing", dir.display());
            return;
        }
        for (file, count) in [
            ("room_scan1.pcd", 112_586),
            ("CSite1_red1-utm.pcd", 522_674),
        ] {
            let t = crate::format::read(&dir.join(file)).unwrap();
            assert_eq!(t.len(), count, "{file}");
        }
    }
}
