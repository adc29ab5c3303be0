//! Format dispatch by file extension and atomic (temp file + rename) writing.
//!
//! Every write goes through [`bounded_geom::atomic`]: a temporary file in the target
//! directory takes the target's place (an atomic rename or exchange) only once complete, so
//! an interrupted or failed write never leaves a partial file.
//!
//! Annotated outputs add these properties to every input property (input properties of the
//! same names are replaced, not duplicated):
//!
//! | property | type | meaning |
//! |---|---|---|
//! | `class` | uchar | 0 non-edge, 1 sharp edge, 2 boundary |
//! | `p_nonedge`, `p_sharp`, `p_boundary` | float | class probabilities |
//! | `red`, `green`, `blue` | uchar | sharp (255,0,0), boundary (0,255,0), non-edge (160,160,160) |
//!
//! LAS stores `class` in the Classification field instead (see [`crate::las`]).
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
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

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
}

impl Format {
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
            _ => Err(DataError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
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

/// Reads `path`; with `drop_non_finite`, points with a non-finite coordinate are left out
/// and counted. LAS coordinates are integers, always finite.
fn read_with(path: &Path, drop_non_finite: bool) -> Result<(PointTable, usize), DataError> {
    let format = Format::from_path(path)?;
    let file = File::open(path).map_err(|e| DataError::io(path, e))?;
    let buffered = |file| BufReader::with_capacity(1 << 20, file);
    let mut properties = match format {
        Format::Ply => crate::ply::read_properties(buffered(file), path)?,
        Format::Pcd => crate::pcd::read_properties(buffered(file), path)?,
        Format::Xyz(_) => crate::xyz::read_properties(buffered(file), path)?,
        // Unbuffered: the E57 reader seeks to every 1 KiB page, which empties a `BufReader`.
        Format::E57 => crate::e57::read_properties(file, path)?,
        Format::Las { .. } => return Ok((crate::las::read_from(buffered(file), path)?, 0)),
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
    bounded_geom::atomic::write_with(path, |file: &mut File| match format {
        // Unbuffered: the E57 writer writes whole 1 KiB pages and seeks back to finish.
        Format::E57 => crate::e57::write_to(file, view, path),
        Format::Ply => {
            crate::ply::write_to(file, view, crate::ply::Encoding::BinaryLittleEndian, path)
        }
        Format::Pcd => crate::pcd::write_to(file, view, path),
        Format::Xyz(separator) => crate::xyz::write_to(file, view, separator, path),
        Format::Las { compressed } => {
            let file = file.try_clone().map_err(|e| DataError::io(path, e))?;
            let out = BufWriter::with_capacity(1 << 20, file);
            crate::las::write_to(out, view, compressed, path).map(drop)
        }
    })
}

/// Writes `table` with the detection results: `class`, `p_nonedge`, `p_sharp`, `p_boundary`
/// and a class colour per point (see the module documentation).
///
/// `classes` and `probabilities` must have one entry per point.
pub fn write_annotated(
    path: &Path,
    table: &PointTable,
    classes: &[Class],
    probabilities: &[[f32; 3]],
) -> Result<(), DataError> {
    if classes.len() != table.len() || probabilities.len() != table.len() {
        return Err(DataError::InvalidOutput {
            path: path.to_path_buf(),
            what: format!(
                "{} classes and {} probabilities for {} points",
                classes.len(),
                probabilities.len(),
                table.len()
            ),
        });
    }
    let added = annotation(classes, probabilities);
    let mut view = table.view();
    view.properties
        .retain(|p| !ANNOTATION.contains(&p.name.as_str()));
    view.properties.extend(&added);
    write_view(path, &view)
}

/// The properties [`write_annotated`] adds, replacing input properties of the same names.
pub const ANNOTATION: [&str; 7] = [
    "class",
    "p_nonedge",
    "p_sharp",
    "p_boundary",
    "red",
    "green",
    "blue",
];

/// Drops the properties of `table` that [`write_annotated`] would replace (see
/// [`ANNOTATION`]), so that their memory is free while the cloud is labelled; the annotated
/// output is the same.
pub fn drop_annotated(table: &mut PointTable) {
    (table.properties).retain(|p| !ANNOTATION.contains(&p.name.as_str()));
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

/// The annotation columns, filled in one parallel pass: at 10M points they are 160 MB of
/// fresh pages, whose faults and stores would otherwise be a fifth of a LAS write.
fn annotation(classes: &[Class], probabilities: &[[f32; 3]]) -> Vec<Property> {
    let n = classes.len();
    let mut class = vec![0u8; n];
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0f32; n]);
    let mut rgb: [Vec<u8>; 3] = std::array::from_fn(|_| vec![0u8; n]);
    let [p0, p1, p2] = &mut p;
    let [r, g, b] = &mut rgb;
    const CHUNK: usize = 1 << 14;
    (
        class.par_chunks_mut(CHUNK),
        p0.par_chunks_mut(CHUNK),
        p1.par_chunks_mut(CHUNK),
        p2.par_chunks_mut(CHUNK),
        (
            r.par_chunks_mut(CHUNK),
            g.par_chunks_mut(CHUNK),
            b.par_chunks_mut(CHUNK),
        ),
        (classes.par_chunks(CHUNK), probabilities.par_chunks(CHUNK)),
    )
        .into_par_iter()
        .for_each(|(class, p0, p1, p2, (r, g, b), (classes, probabilities))| {
            for k in 0..classes.len() {
                let [red, green, blue] = class_colour(classes[k]);
                [class[k], r[k], g[k], b[k]] = [classes[k] as u8, red, green, blue];
                [p0[k], p1[k], p2[k]] = probabilities[k];
            }
        });
    let [p0, p1, p2] = p.map(Column::F32);
    let [r, g, b] = rgb.map(Column::U8);
    let columns = [Column::U8(class), p0, p1, p2, r, g, b];
    (ANNOTATION.into_iter().zip(columns))
        .map(|(name, values)| Property::new(name, values))
        .collect()
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
    fn annotation_columns_hold_each_point_across_parallel_chunks() {
        let n = 40_000;
        let classes: Vec<Class> = (0..n).map(|i| Class::ALL[i * 7 % 3]).collect();
        let probabilities: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.5, -(i as f32)]).collect();
        let columns = annotation(&classes, &probabilities);
        let value = |name: &str, i: usize| {
            let p = columns.iter().find(|p| p.name == name).unwrap();
            assert_eq!(p.values.len(), n, "{name}");
            p.values.get_f64(i)
        };
        for i in [0, 1, 16_383, 16_384, 16_385, 32_768, n - 1] {
            let colour = class_colour(classes[i]).map(f64::from);
            assert_eq!(value("class", i), classes[i] as u8 as f64, "{i}");
            assert_eq!(
                [value("red", i), value("green", i), value("blue", i)],
                colour
            );
            let p = ["p_nonedge", "p_sharp", "p_boundary"].map(|name| value(name, i) as f32);
            assert_eq!(p, probabilities[i], "{i}");
        }
    }

    #[test]
    fn dropping_the_replaced_properties_first_writes_the_same_output() {
        let dir = tempfile::tempdir().unwrap();
        let classes = [Class::Sharp, Class::NonEdge, Class::Boundary];
        let probabilities = [[0.1, 0.8, 0.1], [0.9, 0.05, 0.05], [0.2, 0.2, 0.6]];
        let mut t = sample();
        let before: Vec<String> = t.properties.iter().map(|p| p.name.clone()).collect();
        let write = |t: &PointTable, name: &str| {
            let path = dir.path().join(name);
            write_annotated(&path, t, &classes, &probabilities).unwrap();
            std::fs::read(path).unwrap()
        };
        let whole = write(&t, "whole.ply");
        drop_annotated(&mut t);
        let kept: Vec<&str> = t.properties.iter().map(|p| p.name.as_str()).collect();
        let expected: Vec<&str> = before
            .iter()
            .map(String::as_str)
            .filter(|n| !ANNOTATION.contains(n))
            .collect();
        assert!(kept.len() < before.len(), "{before:?}");
        assert_eq!(kept, expected);
        assert_eq!(write(&t, "dropped.ply"), whole);
    }

    #[test]
    fn annotated_output_replaces_same_named_properties_in_every_format() {
        let dir = tempfile::tempdir().unwrap();
        let t = sample();
        let classes = [Class::Sharp, Class::NonEdge, Class::Boundary];
        let probabilities = [[0.1, 0.8, 0.1], [0.9, 0.05, 0.05], [0.2, 0.2, 0.6]];
        for ext in ["ply", "pcd", "xyz", "txt", "csv", "las", "laz", "e57"] {
            let path = dir.path().join(format!("out.{ext}"));
            write_annotated(&path, &t, &classes, &probabilities).unwrap();
            let back = read(&path).unwrap();
            assert_eq!(back.len(), 3, "{ext}");
            let names: Vec<&str> = back.properties.iter().map(|p| p.name.as_str()).collect();
            let red = back.property("red").unwrap();
            // LAS stores 16-bit colours.
            let full = if ext.starts_with("la") {
                65535.0
            } else {
                255.0
            };
            assert_eq!(
                [0, 1, 2].map(|i| red.get_f64(i)),
                [full, full * 160.0 / 255.0, 0.0],
                "{ext}"
            );
            assert_eq!(names.iter().filter(|n| **n == "red").count(), 1, "{ext}");
            assert_eq!(
                back.property("intensity").unwrap().get_f64(1),
                65535.0,
                "{ext}"
            );
            let p_sharp = back.property("p_sharp").unwrap();
            assert_eq!(p_sharp.get_f64(0) as f32, 0.8, "{ext}");
            if ext.starts_with("la") {
                let codes = back.property("classification").unwrap();
                assert_eq!([0, 1, 2].map(|i| codes.get_f64(i)), [64.0, 1.0, 65.0]);
                let original = back.property("input_classification");
                assert_eq!(
                    original, None,
                    "class, not classification, was in the input"
                );
            } else {
                let labels = crate::labels::from_table(back, Convention::ClassProperty, &path);
                assert_eq!(labels.unwrap().labels, classes, "{ext}");
            }
        }
        assert_eq!(entries(dir.path()).len(), 8, "no temporary files left");
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
