//! Reading: every scan posed into the file's frame and joined in file order.

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
        attributes: Vec::new(),
    };
    let mut taken = vec!["x", "y", "z"];
    if columns.intensity.is_some() {
        taken.push("intensity");
    }
    if columns.colour.is_some() {
        taken.extend(["red", "green", "blue"]);
    }
    if columns.scan.is_some() {
        taken.push("scan");
    }
    let names = attribute_names(&scans, &taken).map_err(|e| DataError::malformed(path, e))?;
    for name in names {
        let types = (scans.iter().flat_map(|s| &s.prototype))
            .filter(|r| matches!(&r.name, RecordName::Unknown { name: n, .. } if *n == name))
            .map(|r| &r.data_type);
        let ty = column_type(types).unwrap_or(ScalarType::F64);
        (columns.attributes).push((name, Column::with_capacity(ty, reserve)));
    }
    for (index, scan) in scans.iter().enumerate() {
        let layout = Layout::of(scan, &columns.attributes);
        // The raw reader: the crate's simple one fails on packets that complete no point.
        for values in reader.pointcloud_raw(scan).map_err(e57)? {
            let values = values.map_err(e57)?;
            let point = layout.point(&values).map_err(e57)?;
            columns.push(point, index as u32);
            let attributes = columns.attributes.iter_mut().zip(&layout.attributes);
            for ((_, column), &at) in attributes {
                column.push_f64(match at {
                    Some(i) => values[i]
                        .to_f64(&layout.prototype[i].data_type)
                        .map_err(e57)?,
                    None => f64::NAN,
                });
            }
        }
    }
    Ok(columns.into_properties())
}

/// The names of the attributes outside the standard (extensions') in `scans`, in order of
/// first appearance; an error when one takes a name in `taken` (the columns the standard
/// fields are read into) or repeats within a scan.
fn attribute_names(scans: &[PointCloud], taken: &[&str]) -> Result<Vec<String>, String> {
    let mut names: Vec<String> = Vec::new();
    for scan in scans {
        let mut in_scan = Vec::new();
        for record in &scan.prototype {
            let RecordName::Unknown { namespace, name } = &record.name else {
                continue;
            };
            if taken.iter().any(|r| r.eq_ignore_ascii_case(name)) || in_scan.contains(&name) {
                return Err(format!(
                    "E57: the attribute {} clashes with another field of that name",
                    crate::error::quoted(&format!("{namespace}:{name}"))
                ));
            }
            in_scan.push(name);
            if !names.contains(name) {
                names.push(name.clone());
            }
        }
    }
    Ok(names)
}

/// The column type for the colours of `scans`, if any has colours.
pub(super) fn colour_type(scans: &[PointCloud]) -> Option<ScalarType> {
    use RecordName::{ColorBlue, ColorGreen, ColorRed};
    column_type(
        (scans.iter().flat_map(|s| &s.prototype))
            .filter(|r| matches!(r.name, ColorRed | ColorGreen | ColorBlue))
            .map(|r| &r.data_type),
    )
}

/// The column type that holds every value of records of `types` as the file stores it: the
/// smallest integer type that holds every integer range, `f32` for single floats, else
/// `f64`; `None` without any record.
fn column_type<'a>(types: impl IntoIterator<Item = &'a RecordDataType>) -> Option<ScalarType> {
    let (mut range, mut singles, mut others) = (None, false, false);
    for ty in types {
        match *ty {
            RecordDataType::Integer { min, max } => {
                range = Some(range.map_or((min, max), |(lo, hi): (i64, i64)| {
                    (lo.min(min), hi.max(max))
                }))
            }
            RecordDataType::Single { .. } => singles = true,
            _ => others = true,
        }
    }
    Some(match (range, singles, others) {
        (None, false, false) => return None,
        (Some((min, max)), false, false) => integer_type(min, max).unwrap_or(ScalarType::F64),
        (None, true, false) => ScalarType::F32,
        _ => ScalarType::F64,
    })
}

/// The smallest integer column type that holds `min..=max`.
fn integer_type(min: i64, max: i64) -> Option<ScalarType> {
    use ScalarType::*;
    [U8, I8, U16, I16, U32, I32]
        .into_iter()
        .find(|&ty| super::integer_range(ty).is_some_and(|(lo, hi)| lo <= min && max <= hi))
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
    /// Where each of the file's extension attributes is in this scan's records, if it is.
    attributes: Vec<Option<usize>>,
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
    fn of(scan: &PointCloud, attributes: &[(String, Column)]) -> Layout {
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
            attributes: (attributes.iter())
                .map(|(name, _)| {
                    (scan.prototype.iter())
                        .position(|r| matches!(&r.name, Unknown { name: n, .. } if n == name))
                })
                .collect(),
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
    /// The extension attributes by name.
    attributes: Vec<(String, Column)>,
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

    /// The columns as properties; coordinates as `f32` when every one is a float exactly
    /// (as single-precision records without a pose give), so that they take half the memory
    /// and are written back as floats.
    fn into_properties(self) -> Vec<Property> {
        let exact_f32 = |c: &Vec<f64>| {
            c.iter()
                .all(|&v| f64::from(v as f32).to_bits() == v.to_bits() || v.is_nan())
        };
        let floats = self.xyz.iter().all(exact_f32);
        let [x, y, z] = self.xyz.map(|c| {
            if floats {
                Column::F32(c.into_iter().map(|v| v as f32).collect())
            } else {
                Column::F64(c)
            }
        });
        let mut properties = vec![
            Property::new("x", x),
            Property::new("y", y),
            Property::new("z", z),
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
        (properties).extend((self.attributes.into_iter()).map(|(n, c)| Property::new(n, c)));
        properties
    }
}
