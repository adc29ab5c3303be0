//! E57 reader (ASTM E2807), the exchange format of terrestrial laser scanners. Read only:
//! annotated outputs go to PLY or LAS, which every viewer opens with the added properties.
//!
//! A file holds one or more scans, each in its own frame with a pose. Reading converts
//! spherical coordinates to Cartesian where a scan stores only those, applies each scan's
//! pose, and concatenates the scans in file order as one cloud of `f64` positions. Kept per
//! point, as the file's values, when any scan has them: `intensity` (float; NaN where a scan
//! or point has none), `red`, `green`, `blue` (uchar or ushort when every scan's colour
//! records are integers within that range, as scanners write them, else float; 0 or NaN
//! where a scan or point has none), and `scan` (uint, the scan's 0-based index) when the file
//! holds several.
//!
//! A point the file marks as having no position (scanners store their no-return pixels so, or
//! a direction without a range) gets NaN coordinates: an error naming it, unless read with
//! [`crate::format::read_finite`], which leaves such points out and counts them, as it does
//! the NaN points of organised PCL clouds.

use crate::DataError;
use crate::table::{Column, Property, ScalarType};
use e57::{E57Reader, PointCloud, Record, RecordDataType, RecordName, RecordValue};
use std::io::{Read, Seek};
use std::path::Path;

/// Points reserved up front at most: a corrupt point count must not exhaust memory.
const MAX_RESERVED: usize = 1 << 22;

/// The points of every scan in `input` as columns, positions among them, not yet checked.
pub(crate) fn read_properties<R: Read + Seek>(
    input: R,
    path: &Path,
) -> Result<Vec<Property>, DataError> {
    let e57 = |e: e57::Error| DataError::malformed(path, format!("E57: {e}"));
    let mut reader = E57Reader::new(input).map_err(e57)?;
    let scans = reader.pointclouds();
    if scans.is_empty() {
        return Err(DataError::malformed(path, "E57: the file holds no scan"));
    }
    let total = scans
        .iter()
        .map(|s| s.records)
        .fold(0u64, u64::saturating_add);
    let reserve = usize::try_from(total)
        .unwrap_or(usize::MAX)
        .min(MAX_RESERVED);
    let mut columns = Columns {
        xyz: std::array::from_fn(|_| Vec::with_capacity(reserve)),
        intensity: scans
            .iter()
            .any(|s| s.has_intensity())
            .then(|| Vec::with_capacity(reserve)),
        colour: colour_type(&scans)
            .map(|ty| std::array::from_fn(|_| Column::with_capacity(ty, reserve))),
        scan: (scans.len() > 1).then(|| Vec::with_capacity(reserve)),
    };
    for (index, scan) in scans.iter().enumerate() {
        let layout = Layout::of(scan);
        // The raw reader: the crate's simple one fails on packets that complete no point.
        for values in reader.pointcloud_raw(scan).map_err(e57)? {
            let point = layout.point(&values.map_err(e57)?).map_err(e57)?;
            columns.push(point, index as u32);
        }
    }
    Ok(columns.into_properties())
}

/// The column type for the colours of `scans`, if any has colours: the smallest unsigned
/// integer type that holds every colour record's range, or float.
fn colour_type(scans: &[PointCloud]) -> Option<ScalarType> {
    use RecordName::{ColorBlue, ColorGreen, ColorRed};
    let widest = (scans.iter().flat_map(|s| &s.prototype))
        .filter(|r| matches!(r.name, ColorRed | ColorGreen | ColorBlue))
        .map(|r| match r.data_type {
            RecordDataType::Integer { min, max } if min >= 0 => max,
            _ => i64::MAX,
        })
        .max()?;
    Some(if widest <= 0xff {
        ScalarType::U8
    } else if widest <= 0xffff {
        ScalarType::U16
    } else {
        ScalarType::F32
    })
}

/// Where a scan's values are in its records, and its pose.
struct Layout {
    prototype: Vec<Record>,
    cartesian: Option<[usize; 3]>,
    cartesian_invalid: Option<usize>,
    spherical: Option<[usize; 3]>,
    spherical_invalid: Option<usize>,
    intensity: Option<usize>,
    intensity_invalid: Option<usize>,
    colour: Option<[usize; 3]>,
    colour_invalid: Option<usize>,
    /// Row-major rotation of the pose, then its translation.
    rotation: [[f64; 3]; 3],
    translation: [f64; 3],
}

/// One point of a scan: its position in the file's frame (NaN without one), intensity and
/// colour (NaN without).
struct Point {
    xyz: [f64; 3],
    intensity: f32,
    colour: [f64; 3],
}

impl Layout {
    fn of(scan: &PointCloud) -> Layout {
        let at = |name: RecordName| scan.prototype.iter().position(|r| r.name == name);
        let three = |a, b, c| Some([at(a)?, at(b)?, at(c)?]);
        let (rotation, translation) = match &scan.transform {
            Some(t) => {
                let q = &t.rotation;
                let rotation = bounded_geom::rotation_of_quaternion([q.w, q.x, q.y, q.z]);
                let shift = &t.translation;
                (rotation, [shift.x, shift.y, shift.z])
            }
            None => (
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [0.0; 3],
            ),
        };
        use RecordName::*;
        Layout {
            prototype: scan.prototype.clone(),
            cartesian: three(CartesianX, CartesianY, CartesianZ),
            cartesian_invalid: at(CartesianInvalidState),
            spherical: three(SphericalRange, SphericalAzimuth, SphericalElevation),
            spherical_invalid: at(SphericalInvalidState),
            intensity: at(Intensity),
            intensity_invalid: at(IsIntensityInvalid),
            colour: three(ColorRed, ColorGreen, ColorBlue),
            colour_invalid: at(IsColorInvalid),
            rotation,
            translation,
        }
    }

    fn point(&self, values: &[RecordValue]) -> e57::Result<Point> {
        let value = |i: usize| values[i].to_f64(&self.prototype[i].data_type);
        // A missing invalid-state field means valid; 0 is valid in every such field.
        let valid = |flag: Option<usize>| -> e57::Result<bool> {
            flag.map_or(Ok(true), |i| {
                Ok(values[i].to_i64(&self.prototype[i].data_type)? == 0)
            })
        };
        let local = match (self.cartesian, self.spherical) {
            (Some([x, y, z]), _) if valid(self.cartesian_invalid)? => {
                Some([value(x)?, value(y)?, value(z)?])
            }
            (_, Some([r, a, e])) if valid(self.spherical_invalid)? => {
                let (range, azimuth, elevation) = (value(r)?, value(a)?, value(e)?);
                Some([
                    range * elevation.cos() * azimuth.cos(),
                    range * elevation.cos() * azimuth.sin(),
                    range * elevation.sin(),
                ])
            }
            _ => None,
        };
        let xyz = local.map_or([f64::NAN; 3], |p| {
            std::array::from_fn(|a| {
                let row = self.rotation[a];
                row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + self.translation[a]
            })
        });
        let intensity = match self.intensity {
            Some(i) if valid(self.intensity_invalid)? => value(i)? as f32,
            _ => f32::NAN,
        };
        let colour = match self.colour {
            Some([r, g, b]) if valid(self.colour_invalid)? => [value(r)?, value(g)?, value(b)?],
            _ => [f64::NAN; 3],
        };
        Ok(Point {
            xyz,
            intensity,
            colour,
        })
    }
}

/// The columns being filled, one value per point in each.
struct Columns {
    xyz: [Vec<f64>; 3],
    intensity: Option<Vec<f32>>,
    colour: Option<[Column; 3]>,
    scan: Option<Vec<u32>>,
}

impl Columns {
    fn push(&mut self, point: Point, scan: u32) {
        for (column, v) in self.xyz.iter_mut().zip(point.xyz) {
            column.push(v);
        }
        if let Some(column) = &mut self.intensity {
            column.push(point.intensity);
        }
        if let Some(columns) = &mut self.colour {
            for (column, v) in columns.iter_mut().zip(point.colour) {
                column.push_f64(v);
            }
        }
        if let Some(column) = &mut self.scan {
            column.push(scan);
        }
    }

    fn into_properties(self) -> Vec<Property> {
        let [x, y, z] = self.xyz;
        let mut properties = vec![
            Property::new("x", Column::F64(x)),
            Property::new("y", Column::F64(y)),
            Property::new("z", Column::F64(z)),
        ];
        if let Some(intensity) = self.intensity {
            properties.push(Property::new("intensity", Column::F32(intensity)));
        }
        if let Some([r, g, b]) = self.colour {
            properties.push(Property::new("red", r));
            properties.push(Property::new("green", g));
            properties.push(Property::new("blue", b));
        }
        if let Some(scan) = self.scan {
            properties.push(Property::new("scan", Column::U32(scan)));
        }
        properties
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::{self, Format};
    use crate::table::PointTable;
    use e57::{
        E57Writer, Quaternion, Record, RecordDataType, RecordName, RecordValue, Transform,
        Translation,
    };
    use std::f64::consts::FRAC_PI_2;

    fn record(name: RecordName, data_type: RecordDataType) -> Record {
        Record { name, data_type }
    }

    /// Two scans: three Cartesian points with intensity and colour under a pose (a quarter
    /// turn about z, then a shift), and three spherical points without either, the last
    /// marked invalid.
    fn write_two_scans(path: &Path) {
        let mut writer = E57Writer::from_file(path, "file").unwrap();
        let prototype = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            record(RecordName::Intensity, RecordDataType::F32),
            record(RecordName::ColorRed, RecordDataType::U8),
            record(RecordName::ColorGreen, RecordDataType::U8),
            record(RecordName::ColorBlue, RecordDataType::U8),
        ];
        let mut scan = writer.add_pointcloud("scan0", prototype).unwrap();
        let half = std::f64::consts::FRAC_1_SQRT_2;
        scan.set_transform(Some(Transform {
            rotation: Quaternion {
                w: half,
                x: 0.0,
                y: 0.0,
                z: half,
            },
            translation: Translation {
                x: 10.0,
                y: 20.0,
                z: 30.0,
            },
        }));
        let points = [
            ([1.0, 0.0, 0.0], 0.5, [255, 0, 0]),
            ([0.0, 2.0, 0.0], 100.0, [0, 128, 0]),
            ([0.0, 0.0, 3.0], 7.0, [0, 0, 1]),
        ];
        for (xyz, intensity, rgb) in points {
            let mut values: Vec<RecordValue> = xyz.map(RecordValue::Double).to_vec();
            values.push(RecordValue::Single(intensity));
            values.extend(rgb.map(RecordValue::Integer));
            scan.add_point(values).unwrap();
        }
        scan.finalize().unwrap();
        let prototype = vec![
            record(RecordName::SphericalRange, RecordDataType::F64),
            record(RecordName::SphericalAzimuth, RecordDataType::F64),
            record(RecordName::SphericalElevation, RecordDataType::F64),
            record(
                RecordName::SphericalInvalidState,
                RecordDataType::Integer { min: 0, max: 2 },
            ),
        ];
        let mut scan = writer.add_pointcloud("scan1", prototype).unwrap();
        for (range, azimuth, invalid) in [(2.0, 0.0, 0), (1.0, FRAC_PI_2, 0), (5.0, 1.0, 2)] {
            scan.add_point(vec![
                RecordValue::Double(range),
                RecordValue::Double(azimuth),
                RecordValue::Double(0.0),
                RecordValue::Integer(invalid),
            ])
            .unwrap();
        }
        scan.finalize().unwrap();
        writer.finalize().unwrap();
    }

    #[test]
    fn scans_are_posed_and_joined_with_their_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.e57");
        write_two_scans(&path);
        assert_eq!(Format::from_path(&path).unwrap(), Format::E57);

        // The invalid point is refused by default, naming it, and left out on request.
        let e = format::read(&path).unwrap_err().to_string();
        assert!(e.contains("two.e57") && e.contains("point 5"), "{e}");
        let (table, dropped) = format::read_finite(&path).unwrap();
        assert_eq!(dropped, 1);
        let expected = [
            [10.0, 21.0, 30.0],
            [8.0, 20.0, 30.0],
            [10.0, 20.0, 33.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert_eq!(table.len(), expected.len());
        for (i, want) in expected.iter().enumerate() {
            let got = table.cloud.position_f64(i);
            assert!(
                (0..3).all(|a| (got[a] - want[a]).abs() < 1e-9),
                "{i}: {got:?}"
            );
        }
        let Some(Column::F32(intensity)) = table.property("intensity") else {
            panic!("no float intensity");
        };
        assert_eq!(intensity[..3], [0.5, 100.0, 7.0]);
        assert!(intensity[3..].iter().all(|v| v.is_nan()));
        let rgb = ["red", "green", "blue"].map(|c| table.property(c).cloned());
        assert_eq!(
            rgb,
            [
                Some(Column::U8(vec![255, 0, 0, 0, 0])),
                Some(Column::U8(vec![0, 128, 0, 0, 0])),
                Some(Column::U8(vec![0, 0, 1, 0, 0])),
            ]
        );
        assert_eq!(
            table.property("scan"),
            Some(&Column::U32(vec![0, 0, 0, 1, 1]))
        );
    }

    #[test]
    fn colours_take_the_smallest_type_that_holds_every_scan_range() {
        let scan = |types: &[RecordDataType]| {
            let mut scan = PointCloud::default();
            let names = [
                RecordName::ColorRed,
                RecordName::ColorGreen,
                RecordName::ColorBlue,
            ];
            scan.prototype = (names.into_iter().zip(types.iter().cycle().cloned()))
                .map(|(name, data_type)| record(name, data_type))
                .collect();
            scan
        };
        let wide = RecordDataType::Integer { min: 0, max: 4095 };
        let signed = RecordDataType::Integer { min: -1, max: 255 };
        assert_eq!(
            colour_type(&[scan(&[RecordDataType::U8])]),
            Some(ScalarType::U8)
        );
        let u8_and_12_bit = [scan(&[RecordDataType::U8]), scan(&[wide])];
        assert_eq!(colour_type(&u8_and_12_bit), Some(ScalarType::U16));
        assert_eq!(colour_type(&[scan(&[signed])]), Some(ScalarType::F32));
        assert_eq!(
            colour_type(&[scan(&[RecordDataType::F32])]),
            Some(ScalarType::F32)
        );
        assert_eq!(colour_type(&[PointCloud::default()]), None);
    }

    #[test]
    fn truncated_and_foreign_files_are_named_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.e57");
        write_two_scans(&path);
        let bytes = std::fs::read(&path).unwrap();
        for (name, content) in [
            ("cut.e57", &bytes[..bytes.len() / 2]),
            ("empty.e57", &[][..]),
            ("text.e57", &b"ply\nformat ascii 1.0\nend_header\n"[..]),
        ] {
            let bad = dir.path().join(name);
            std::fs::write(&bad, content).unwrap();
            let e = format::read(&bad).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("E57"), "{e}");
        }
    }

    #[test]
    fn e57_is_not_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.e57");
        let cloud = bounded_geom::PointCloud::from_f64(&[[0.0; 3], [1.0; 3]]).unwrap();
        let e = format::write(&path, &PointTable::new(cloud)).unwrap_err();
        assert!(matches!(e, DataError::InvalidOutput { .. }), "{e}");
        assert!(e.to_string().contains("out.e57"), "{e}");
        assert!(Format::for_output(&path).is_err());
        assert!(!path.exists());
    }
}
