//! Format dispatch by file extension and atomic (temp file + rename) writing.
//!
//! Every write goes to a temporary file in the target directory that takes the target's
//! place (an atomic rename or exchange) only once complete, so an interrupted or failed
//! write never leaves a partial file.
//!
//! Annotated outputs ([`write_annotated`]) add the detection results to every input
//! property: see [`crate::annotate`].
//!
//! ```
//! use bounded_data::LabelledCloud;
//! use bounded_data::format::{read, write_labelled};
//! use bounded_data::labels::{Convention, from_table};
//! use bounded_geom::{Class, PointCloud};
//!
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("two.ply");
//! let cloud = PointCloud::from_f64(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]).unwrap();
//! let labelled = LabelledCloud { cloud, labels: vec![Class::Sharp, Class::NonEdge] };
//! write_labelled(&path, &labelled).unwrap();
//! let table = read(&path).unwrap();
//! assert_eq!(table.len(), 2);
//! assert_eq!(from_table(table, Convention::ClassProperty, &path).unwrap(), labelled);
//! ```

use crate::table::{Column, PointTable, PositionType, Property, TableView};
use crate::{DataError, LabelledCloud};
use bounded_geom::Class;
use std::fs::File;
use std::io::{BufReader, BufWriter, Cursor, Read, Seek, Write};
use std::path::Path;

pub use crate::annotate::{
    drop_annotated, write_annotated, write_annotated_to, write_annotated_with,
};

/// A supported point-cloud file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Stanford PLY (`.ply`), written as binary little endian.
    Ply,
    /// PCL's PCD (`.pcd`), written as `DATA binary`.
    Pcd,
    /// ASPRS LAS (`.las`), or LAZ (`.laz`) when `compressed`.
    Las {
        /// LAZ (LASzip-compressed) rather than plain LAS.
        compressed: bool,
    },
    /// Text, one point per line (`.xyz`, `.txt` space-separated, `.csv` comma-separated).
    Xyz(crate::xyz::Separator),
    /// ASTM E57 (`.e57`). Read: the scans in the file's frame (poses applied, spherical
    /// coordinates converted), joined in file order, with `intensity` (float, NaN where
    /// absent), `red`, `green`, `blue` (the file's values, as integers when its colour
    /// records are), `scan` (the index, when there are several) and every extension
    /// attribute. Points the file marks as having no position come as NaN coordinates, which
    /// [`read_finite`] leaves out. Written as one scan (one per `scan` index, as read):
    /// intensity and colours in the standard fields, the other properties as attributes of
    /// a `bounded` extension.
    E57,
    /// NumPy (`.npy`), read only: a 2-D little-endian `float32` or `float64` array, one point
    /// per row (C or Fortran order), x, y, z then properties `column_4`, ...
    Npy,
}

impl Format {
    /// The format whose signature `head` (a file's first bytes) starts with: PLY (`ply`),
    /// LAS (`LASF`; LAZ is read by the same reader), E57 (`ASTM-E57`), NumPy (`\x93NUMPY`),
    /// PCD (a `VERSION` or `FIELDS` line after any `#` comment lines); anything else is
    /// taken as text (such as xyz with a `#` header), whose reader names what it cannot parse.
    pub fn sniff(head: &[u8]) -> Format {
        let text = |t: &str| head.starts_with(t.as_bytes());
        if text("ply") {
            Format::Ply
        } else if text("LASF") {
            Format::Las { compressed: false }
        } else if text("ASTM-E57") {
            Format::E57
        } else if head.starts_with(b"\x93NUMPY") {
            Format::Npy
        } else if pcd_header(head) {
            Format::Pcd
        } else {
            Format::Xyz(crate::xyz::Separator::Space)
        }
    }

    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, DataError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("ply") => Ok(Format::Ply),
            Some("pcd") => Ok(Format::Pcd),
            Some("xyz" | "txt") => Ok(Format::Xyz(crate::xyz::Separator::Space)),
            Some("las") => Ok(Format::Las { compressed: false }),
            Some("laz") => Ok(Format::Las { compressed: true }),
            Some("csv") => Ok(Format::Xyz(crate::xyz::Separator::Comma)),
            Some("e57") => Ok(Format::E57),
            Some("npy") => Ok(Format::Npy),
            _ => Err(DataError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Whether the first line of `head` that is not a `#` comment starts a PCD header.
fn pcd_header(head: &[u8]) -> bool {
    let mut lines = head.split(|&b| b == b'\n');
    lines
        .find(|l| !l.starts_with(b"#"))
        .is_some_and(|l| l.starts_with(b"VERSION") || l.starts_with(b"FIELDS"))
}

/// Reads the cloud at `path`, in the format named by its extension, with every property.
///
/// A point with a NaN or infinite coordinate is an error naming it; [`read_finite`] leaves
/// such points out instead.
pub fn read(path: &Path) -> Result<PointTable, DataError> {
    read_with(path, false).map(|(table, _)| table)
}

/// Reads the cloud at `path` like [`read`], but leaves out the points with a NaN or infinite
/// coordinate (the invalid pixels of organised PCL clouds, for example) and returns how many
/// it left out. The other points keep their order and every property.
pub fn read_finite(path: &Path) -> Result<(PointTable, usize), DataError> {
    read_with(path, true)
}

/// Reads a cloud in `format` from `input` (standard input, say), which is read to its end
/// first, since the LAS and E57 readers seek; `name` names it in errors.
pub fn read_from(input: impl Read, format: Format, name: &Path) -> Result<PointTable, DataError> {
    read_stream(input, Some(format), false, name).map(|(table, _, _)| table)
}

/// Reads a cloud from `input` like [`read_from`], in `format` or, without one, in the format
/// its first bytes name ([`Format::sniff`]); `drop_non_finite` as for [`read_finite`].
/// Returns the table, the format read and how many points were left out.
pub fn read_stream(
    input: impl Read,
    format: Option<Format>,
    drop_non_finite: bool,
    name: &Path,
) -> Result<(PointTable, Format, usize), DataError> {
    let mut bytes = Vec::new();
    BufReader::new(input)
        .read_to_end(&mut bytes)
        .map_err(|e| DataError::io(name, e))?;
    let format = format.unwrap_or_else(|| Format::sniff(&bytes));
    let (table, dropped) = read_source(Cursor::new(bytes), format, name, drop_non_finite)?;
    Ok((table, format, dropped))
}

/// Reads `path`; with `drop_non_finite`, points with a non-finite coordinate are left out
/// and counted.
fn read_with(path: &Path, drop_non_finite: bool) -> Result<(PointTable, usize), DataError> {
    let format = Format::from_path(path)?;
    let file = File::open(path).map_err(|e| DataError::io(path, e))?;
    read_source(file, format, path, drop_non_finite)
}

/// Reads the cloud in `format` from `input`; `path` names it in errors. LAS coordinates are
/// integers, always finite.
fn read_source<R: Read + Seek + Send + Sync + 'static>(
    input: R,
    format: Format,
    path: &Path,
    drop_non_finite: bool,
) -> Result<(PointTable, usize), DataError> {
    let buffered = |input| BufReader::with_capacity(1 << 20, input);
    let mut properties = match format {
        Format::Ply => crate::ply::read_properties(buffered(input), path)?,
        Format::Pcd => crate::pcd::read_properties(buffered(input), path)?,
        Format::Xyz(_) => crate::xyz::read_properties(buffered(input), path)?,
        // Unbuffered: the E57 reader seeks to every 1 KiB page, which empties a `BufReader`.
        Format::E57 => crate::e57::read_properties(input, path)?,
        Format::Npy => crate::npy::read_properties(buffered(input), path)?,
        Format::Las { .. } => return Ok((crate::las::read_from(buffered(input), path)?, 0)),
    };
    let dropped = if drop_non_finite {
        crate::table::drop_non_finite(&mut properties)
    } else {
        0
    };
    Ok((crate::table::from_properties(properties, path)?, dropped))
}

/// Writes `table` unchanged to `path`, in the format named by its extension.
pub fn write(path: &Path, table: &PointTable) -> Result<(), DataError> {
    write_view(path, &table.view())
}

/// Writes `view` to `path`, in the format named by its extension.
pub fn write_view(path: &Path, view: &TableView<'_>) -> Result<(), DataError> {
    let format = Format::from_path(path)?;
    bounded_geom::atomic::write_with(path, |file: &mut File| {
        let file = file.try_clone().map_err(|e| DataError::io(path, e))?;
        encode(file, view, format, path).map(drop)
    })
}

/// Writes `view` in `format` to `out` (standard output, say): encoded in memory first, since
/// the LAS and E57 writers seek back; `name` names the output in errors.
pub fn write_to(
    mut out: impl Write,
    view: &TableView<'_>,
    format: Format,
    name: &Path,
) -> Result<(), DataError> {
    let bytes = encode(Cursor::new(Vec::new()), view, format, name)?.into_inner();
    out.write_all(&bytes)
        .and_then(|()| out.flush())
        .map_err(|e| DataError::io(name, e))
}

/// Encodes `view` in `format` into `out` and returns it; `path` names the output in errors.
fn encode<W: Read + Write + Seek + Send + Sync + 'static>(
    mut out: W,
    view: &TableView<'_>,
    format: Format,
    path: &Path,
) -> Result<W, DataError> {
    match format {
        // Unbuffered: the E57 writer writes whole 1 KiB pages and seeks back to finish.
        Format::E57 => crate::e57::write_to(&mut out, view, path)?,
        Format::Ply => crate::ply::write_to(
            &mut out,
            view,
            crate::ply::Encoding::BinaryLittleEndian,
            path,
        )?,
        Format::Pcd => crate::pcd::write_to(&mut out, view, path)?,
        Format::Xyz(separator) => crate::xyz::write_to(&mut out, view, separator, path)?,
        Format::Las { compressed } => {
            let buffered = BufWriter::with_capacity(1 << 20, out);
            let buffered = crate::las::write_to(buffered, view, compressed, path)?;
            out = (buffered.into_inner()).map_err(|e| DataError::io(path, e.into_error()))?;
        }
        Format::Npy => {
            return Err(DataError::InvalidOutput {
                path: path.to_path_buf(),
                what:
                    "npy is an input format; write .ply, .pcd, .xyz, .txt, .csv, .las, .laz or .e57"
                        .into(),
            });
        }
    }
    Ok(out)
}

/// Writes a ground-truth labelled cloud: positions and a `class` (uchar) property.
pub fn write_labelled(path: &Path, labelled: &LabelledCloud) -> Result<(), DataError> {
    if labelled.labels.len() != labelled.cloud.len() {
        return Err(DataError::InvalidOutput {
            path: path.to_path_buf(),
            what: format!(
                "{} labels for {} points",
                labelled.labels.len(),
                labelled.cloud.len()
            ),
        });
    }
    let class = class_property(&labelled.labels);
    let view = TableView {
        cloud: &labelled.cloud,
        position_type: PositionType::for_cloud(&labelled.cloud),
        properties: vec![&class],
        exact_positions: None,
        las_header: None,
        csv_comment_header: false,
    };
    write_view(path, &view)
}

/// The colour of each class in annotated outputs.
pub fn class_colour(class: Class) -> [u8; 3] {
    match class {
        Class::NonEdge => [160, 160, 160],
        Class::Sharp => [255, 0, 0],
        Class::Boundary => [0, 255, 0],
    }
}

fn class_property(classes: &[Class]) -> Property {
    Property::new(
        "class",
        Column::U8(classes.iter().map(|&c| c as u8).collect()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::labels::{Convention, load};
    use crate::table::ExactPositions;
    use bounded_geom::PointCloud;

    fn sample() -> PointTable {
        let cloud =
            PointCloud::from_f64(&[[0.5, -1.25, 2.0], [1.5, 3.0, -4.0], [0.0, 0.0, 0.0]]).unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("red", Column::U8(vec![9, 9, 9])));
        t.set_property(Property::new("class", Column::U8(vec![2, 2, 2])));
        t
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/b.PLY")).unwrap(),
            Format::Ply
        );
        let laz = Format::from_path(Path::new("b.Laz")).unwrap();
        assert_eq!(laz, Format::Las { compressed: true });
        let e = Format::from_path(Path::new("cloud.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("cloud.obj: unknown point-cloud format"),
            "{e}"
        );
        assert!(Format::from_path(Path::new("noext")).is_err());
    }

    #[test]
    fn streams_are_read_in_the_format_their_first_bytes_name() {
        let dir = tempfile::tempdir().unwrap();
        let t = sample();
        for ext in ["ply", "pcd", "xyz", "csv", "las", "laz", "e57"] {
            let path = dir.path().join(format!("s.{ext}"));
            write(&path, &t).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            let (back, format, dropped) =
                read_stream(bytes.as_slice(), None, false, Path::new("-")).unwrap();
            let expected = match Format::from_path(&path).unwrap() {
                Format::Las { .. } => Format::Las { compressed: false },
                Format::Xyz(_) => Format::Xyz(crate::xyz::Separator::Space),
                f => f,
            };
            assert_eq!((format, dropped), (expected, 0), "{ext}");
            assert_eq!(positions(&back), positions(&read(&path).unwrap()), "{ext}");
        }
        let xyz = b"# x y z\n1 2 3\n4 5 6\n";
        assert_eq!(
            Format::sniff(xyz),
            Format::Xyz(crate::xyz::Separator::Space)
        );
        assert_eq!(Format::sniff(b"# .PCD v0.7\nVERSION 0.7\n"), Format::Pcd);
        let mut npy = b"\x93NUMPY".to_vec();
        npy.extend([1, 0]);
        assert_eq!(Format::sniff(&npy), Format::Npy);
        // Anything unrecognised goes to the text reader, which names what it cannot parse.
        let e = read_stream(&b"\x00\x01binary"[..], None, false, Path::new("-")).unwrap_err();
        assert!(e.to_string().starts_with("-:"), "{e}");
    }

    /// Every position as the writers see it.
    fn positions(t: &PointTable) -> Vec<[f64; 3]> {
        let view = t.view();
        (0..t.len()).map(|i| view.position(i)).collect()
    }

    /// A LAS file of `xyz` on the grid of `scale` (offset 0), written by the las crate.
    fn las_file(path: &Path, xyz: &[[f64; 3]], scale: f64) {
        let mut builder = las::Builder::from((1, 4));
        let t = las::Transform { scale, offset: 0.0 };
        builder.transforms = las::Vector { x: t, y: t, z: t };
        let header = builder.into_header().unwrap();
        let mut writer = las::Writer::from_path(path, header).unwrap();
        for &[x, y, z] in xyz {
            writer
                .write_point(las::Point {
                    x,
                    y,
                    z,
                    ..Default::default()
                })
                .unwrap();
        }
        writer.close().unwrap();
    }

    #[test]
    fn outputs_keep_every_input_position_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let classes = [Class::NonEdge; 3];
        let probabilities = [[1.0, 0.0, 0.0]; 3];
        // Float PLY far from its bounding-box centre: offsets from the centre would round
        // 0.001 and 4.675.
        let floats: [[f32; 3]; 3] = [
            [0.001, 4.675, -1234.5677],
            [100.0, 0.3, 7.1],
            [1e-6, 9.9, 0.0],
        ];
        let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
            property float x\nproperty float y\nproperty float z\nend_header\n"
            .to_vec();
        ply.extend(floats.iter().flatten().flat_map(|v| v.to_le_bytes()));
        std::fs::write(dir.path().join("floats.ply"), ply).unwrap();
        // Text with UTM-sized doubles.
        let doubles = [
            [500_000.01, 4_000_000.123, 100.5],
            [500_900.37, 4_000_800.001, 99.25],
            [500_450.0, 4_000_000.0, 0.1],
        ];
        let text: String = doubles
            .iter()
            .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
            .collect();
        std::fs::write(dir.path().join("doubles.xyz"), text).unwrap();
        // LAS on a grid finer than f32 offsets resolve over 200 units.
        let fine = [
            [0.1234567, 200.0, 3.0],
            [199.9999999, 0.0000001, 1.5],
            [50.0, 60.0, 70.0],
        ];
        las_file(&dir.path().join("fine.las"), &fine, 1e-7);
        let inputs: [(&str, Vec<[f64; 3]>); 3] = [
            (
                "floats.ply",
                floats.iter().map(|p| p.map(f64::from)).collect(),
            ),
            ("doubles.xyz", doubles.to_vec()),
            ("fine.las", fine.to_vec()),
        ];
        for (name, expected) in inputs {
            let input = read(&dir.path().join(name)).unwrap();
            // Within a rounding of the decimal literals, then bit for bit from here on.
            let read_back = positions(&input);
            for (p, q) in read_back.iter().zip(&expected) {
                assert!(
                    (0..3).all(|a| (p[a] - q[a]).abs() < 1e-9),
                    "{name}: {p:?} {q:?}"
                );
            }
            for ext in ["ply", "pcd", "xyz", "las", "e57"] {
                if ext == "las" && !name.ends_with("las") {
                    continue; // LAS output quantises other inputs onto its own grid.
                }
                let path = dir.path().join(format!("{name}.out.{ext}"));
                write_annotated(&path, &input, &classes, &probabilities).unwrap();
                let mut back = positions(&read(&path).unwrap());
                if ext == "xyz" && name.ends_with("ply") {
                    // Text prints the shortest decimal of each float; it reads back as f64.
                    back.iter_mut()
                        .for_each(|p| *p = p.map(|c| f64::from(c as f32)));
                }
                assert_eq!(back, read_back, "{name} -> {ext}");
            }
        }
    }

    #[test]
    fn non_finite_points_are_refused_or_left_out_on_request() {
        let dir = tempfile::tempdir().unwrap();
        let rows = [
            "0 0 0 7",
            "nan nan nan 8",
            "1 0 0 9",
            "0 inf 0 10",
            "0 1 -inf 11",
            "0 0 1 12",
        ];
        let ply = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
                   property float z\nproperty uchar tag\nend_header\n";
        let pcd = "VERSION 0.7\nFIELDS x y z tag\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 1\n\
                   WIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n";
        let xyz = "x y z tag\n";
        for (name, header) in [("o.ply", ply), ("o.pcd", pcd), ("o.xyz", xyz)] {
            let path = dir.path().join(name);
            std::fs::write(&path, format!("{header}{}\n", rows.join("\n"))).unwrap();
            let refused = read(&path).unwrap_err();
            assert!(
                refused
                    .to_string()
                    .contains("point 1 has a non-finite coordinate"),
                "{name}: {refused}"
            );
            let (table, dropped) = read_finite(&path).unwrap();
            assert_eq!(dropped, 3, "{name}");
            let positions: Vec<_> = (0..table.len())
                .map(|i| table.cloud.position_f64(i))
                .collect();
            assert_eq!(
                positions,
                [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
                "{name}"
            );
            let tag: Vec<_> = (0..3)
                .map(|i| table.property("tag").unwrap().get_f64(i))
                .collect();
            assert_eq!(tag, [7.0, 9.0, 12.0], "{name}");
        }
        let all_bad = dir.path().join("bad.xyz");
        std::fs::write(&all_bad, "nan 0 0\n0 nan 0\n").unwrap();
        assert!(read_finite(&all_bad).is_err());
    }

    #[test]
    fn exact_positions_are_kept_only_when_offsets_lose_digits() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("small.xyz"), "0.5 1.25 2\n-3 4 5.75\n").unwrap();
        std::fs::write(dir.path().join("utm.xyz"), "500000.01 1 2\n500900.37 4 5\n").unwrap();
        las_file(
            &dir.path().join("coarse.las"),
            &[[1.25, 2.0, 3.0], [500.5, 0.0, 0.01]],
            0.01,
        );
        let exact = |name: &str| read(&dir.path().join(name)).unwrap().exact_positions;
        assert_eq!(exact("small.xyz"), None);
        assert_eq!(
            exact("utm.xyz"),
            Some(ExactPositions::Float(vec![
                [500000.01, 1.0, 2.0],
                [500900.37, 4.0, 5.0]
            ]))
        );
        assert_eq!(exact("coarse.las"), None);
        las_file(
            &dir.path().join("fine.las"),
            &[[0.1234567, 200.0, 3.0], [199.9999999, 0.0, 1.5]],
            1e-7,
        );
        // LAS keeps its integers (12 bytes a point), not the doubles they stand for.
        assert_eq!(
            exact("fine.las"),
            Some(ExactPositions::Scaled {
                scale: [1e-7; 3],
                offset: [0.0; 3],
                steps: vec![
                    [1_234_567, 2_000_000_000, 30_000_000],
                    [1_999_999_999, 0, 15_000_000]
                ],
            })
        );
    }

    #[test]
    fn labelled_output_round_trips_through_the_class_loader() {
        let dir = tempfile::tempdir().unwrap();
        let cloud = PointCloud::from_f64(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
        let labelled = LabelledCloud {
            cloud,
            labels: vec![Class::Boundary, Class::NonEdge, Class::Sharp],
        };
        for ext in ["ply", "pcd", "csv"] {
            let path = dir.path().join(format!("l.{ext}"));
            write_labelled(&path, &labelled).unwrap();
            assert_eq!(
                load(&path, Convention::ClassProperty).unwrap(),
                labelled,
                "{ext}"
            );
        }
    }

    #[test]
    fn failed_writes_leave_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let t = sample();
        let path = dir.path().join("out.ply");
        // Too few classes: rejected before any file exists.
        let e = write_annotated(&path, &t, &[Class::Sharp], &[[0.0; 3]]).unwrap_err();
        assert!(
            e.to_string()
                .contains("1 classes and 1 probabilities for 3 points"),
            "{e}"
        );
        // A property of the wrong length fails inside the writer, after the temp file exists.
        let mut bad = t.clone();
        bad.properties
            .push(Property::new("short", Column::U8(vec![1])));
        for ext in ["ply", "pcd", "xyz", "las", "e57"] {
            let path = dir.path().join(format!("out.{ext}"));
            let e = write(&path, &bad).unwrap_err().to_string();
            assert!(e.contains("'short' has 1 values for 3 points"), "{e}");
        }
        for (name, expected) in [
            ("y", "property name 'y' is used twice"),
            ("red", "property name 'red' is used twice"),
            (
                "a b",
                "property name 'a b' is empty or has a space or comma",
            ),
        ] {
            let mut bad = t.clone();
            bad.properties
                .push(Property::new(name, Column::U8(vec![1, 2, 3])));
            let e = write(&dir.path().join("out.xyz"), &bad).unwrap_err();
            assert!(e.to_string().ends_with(expected), "{e}");
        }
        assert_eq!(entries(dir.path()), Vec::<String>::new());
        // An existing file is left untouched by a failed overwrite.
        write(&path, &t).unwrap();
        let before = std::fs::read(&path).unwrap();
        assert!(write(&path, &bad).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), before);
        assert_eq!(entries(dir.path()), ["out.ply"]);
        let missing = dir.path().join("no/such/dir/out.ply");
        assert!(matches!(write(&missing, &t), Err(DataError::Io { .. })));
    }

    #[test]
    fn replacing_leaves_only_the_new_file() {
        let dir = tempfile::tempdir().unwrap();
        let (old, new) = (
            sample(),
            PointTable::new(PointCloud::from_f64(&[[7.0; 3]]).unwrap()),
        );
        let path = dir.path().join("out.ply");
        write(&path, &old).unwrap();
        write(&path, &new).unwrap();
        assert_eq!(read(&path).unwrap().cloud, new.cloud);
        assert_eq!(entries(dir.path()), ["out.ply"], "the old file is gone");
        // A directory is never swapped away.
        let sub = dir.path().join("sub.ply");
        std::fs::create_dir(&sub).unwrap();
        assert!(matches!(write(&sub, &old), Err(DataError::Io { .. })));
        assert!(sub.is_dir());
        assert_eq!(entries(dir.path()), ["out.ply", "sub.ply"]);
        // A symlink is replaced by the new file, as by a rename; its target is untouched.
        #[cfg(unix)]
        {
            let target = dir.path().join("target.ply");
            std::fs::rename(&path, &target).unwrap();
            std::os::unix::fs::symlink(&target, &path).unwrap();
            write(&path, &old).unwrap();
            assert!(std::fs::symlink_metadata(&path).unwrap().is_file());
            assert_eq!(read(&target).unwrap().cloud, new.cloud);
            assert_eq!(read(&path).unwrap().cloud, old.cloud);
        }
    }
}
