use super::read::colour_type;
use crate::DataError;
use crate::format::{self, Format};
use crate::table::{Column, ExactPositions, PointTable, PositionType, Property, ScalarType};
use e57::{
    E57Reader, E57Writer, PointCloud, Quaternion, Record, RecordDataType, RecordName, RecordValue,
    Transform, Translation,
};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

fn record(name: RecordName, data_type: RecordDataType) -> Record {
    Record { name, data_type }
}

/// Two scans: three Cartesian points with intensity, colour and an extension attribute under
/// a pose (a quarter turn about z, then a shift), and three spherical points without any,
/// the last marked invalid.
fn write_two_scans(path: &Path) {
    let mut writer = E57Writer::from_file(path, "file").unwrap();
    writer
        .register_extension(e57::Extension::new("ext", "urn:test"))
        .unwrap();
    let quality = RecordName::Unknown {
        namespace: "ext".into(),
        name: "quality".into(),
    };
    let prototype = vec![
        Record::CARTESIAN_X_F64,
        Record::CARTESIAN_Y_F64,
        Record::CARTESIAN_Z_F64,
        record(RecordName::Intensity, RecordDataType::F32),
        record(RecordName::ColorRed, RecordDataType::U8),
        record(RecordName::ColorGreen, RecordDataType::U8),
        record(RecordName::ColorBlue, RecordDataType::U8),
        record(quality, RecordDataType::Integer { min: 0, max: 1000 }),
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
        values.push(RecordValue::Integer(1000));
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
    let quality = Column::U16(vec![1000, 1000, 1000, 0, 0]);
    assert_eq!(table.property("quality"), Some(&quality));
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
    assert_eq!(colour_type(&[scan(&[signed])]), Some(ScalarType::I16));
    assert_eq!(
        colour_type(&[scan(&[RecordDataType::F32])]),
        Some(ScalarType::F32)
    );
    let double = [scan(&[RecordDataType::U8]), scan(&[RecordDataType::F64])];
    assert_eq!(colour_type(&double), Some(ScalarType::F64));
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

/// Every column type, NaN in float columns (the standard intensity among them).
fn sample_properties() -> Vec<Property> {
    vec![
        Property::new("intensity", Column::F32(vec![0.5, f32::NAN, 7.0])),
        Property::new("red", Column::U8(vec![255, 0, 9])),
        Property::new("green", Column::U8(vec![0, 128, 9])),
        Property::new("blue", Column::U8(vec![0, 0, 255])),
        Property::new("class", Column::U8(vec![1, 0, 2])),
        Property::new("p_sharp", Column::F32(vec![0.75, f32::NAN, -0.0])),
        Property::new("offset", Column::I8(vec![-128, 0, 127])),
        Property::new("count", Column::U16(vec![0, 1, 65535])),
        Property::new("level", Column::I16(vec![-32768, 0, 32767])),
        // Not in scan order: an attribute like any other.
        Property::new("scan", Column::U32(vec![2, 1, u32::MAX])),
        Property::new("id", Column::I32(vec![i32::MIN, 0, i32::MAX])),
        Property::new("time", Column::F64(vec![1e300, -2.5, 0.1])),
    ]
}

/// Columns equal value for value, NaN equal to NaN.
fn same_values(a: &Column, b: &Column) -> bool {
    a.scalar_type() == b.scalar_type()
        && a.len() == b.len()
        && (0..a.len()).all(|i| a.get_f64(i).to_bits() == b.get_f64(i).to_bits())
}

#[test]
fn written_tables_read_back_with_every_property_and_position() {
    let dir = tempfile::tempdir().unwrap();
    let floats = [
        [0.001f32, 4.675, -1234.5677],
        [100.0, 0.3, 7.1],
        [1e-6, 9.9, 0.0],
    ];
    let cloud = bounded_geom::PointCloud::from_f64(&floats.map(|p| p.map(f64::from))).unwrap();
    let mut table = PointTable::new(cloud);
    table.properties = sample_properties();
    let path = dir.path().join("all.e57");
    format::write(&path, &table).unwrap();
    let back = format::read(&path).unwrap();
    for i in 0..3 {
        let written = table.view().position(i).map(|c| f64::from(c as f32));
        assert_eq!(back.view().position(i), written, "{i}");
    }
    let names = |t: &PointTable| {
        t.properties
            .iter()
            .map(|p| p.name.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&back), names(&table));
    for p in &table.properties {
        let got = back.property(&p.name).unwrap();
        assert!(same_values(got, &p.values), "{}: {got:?}", p.name);
    }
    // Float positions stay single floats; the standard fields are standard, the rest in the
    // extension; NaN intensity is flagged.
    let reader = E57Reader::from_file(&path).unwrap();
    let prototype = &reader.pointclouds()[0].prototype;
    assert_eq!(
        format!("{:?}", prototype[0]),
        format!("{:?}", Record::CARTESIAN_X_F32)
    );
    let standard = [
        // pye57's `read_scan` requires it.
        RecordName::CartesianInvalidState,
        RecordName::Intensity,
        RecordName::IsIntensityInvalid,
        RecordName::ColorRed,
        RecordName::ColorGreen,
        RecordName::ColorBlue,
    ];
    assert!(
        standard
            .iter()
            .all(|n| prototype.iter().any(|r| r.name == *n))
    );
    assert!(
        !prototype
            .iter()
            .any(|r| r.name == RecordName::IsColorInvalid)
    );
    let class = prototype.iter().find(|r| {
        matches!(&r.name, RecordName::Unknown { namespace, name }
            if namespace == "bounded" && name == "class")
    });
    assert_eq!(
        format!("{:?}", class.unwrap().data_type),
        format!("{:?}", RecordDataType::U8)
    );

    // Read back, the cloud writes the same bytes (the scan is named after the file).
    assert_eq!(back.position_type, PositionType::F32);
    std::fs::create_dir(dir.path().join("again")).unwrap();
    let again = dir.path().join("again/all.e57");
    format::write(&again, &back).unwrap();
    assert!(std::fs::read(&again).unwrap() == std::fs::read(&path).unwrap());
}

#[test]
fn scaled_positions_are_written_as_scaled_integers() {
    let dir = tempfile::tempdir().unwrap();
    let (scale, offset) = ([0.01, 0.01, 0.001], [500_000.0, 4_000_000.0, 0.0]);
    let steps = [[1, 12_345, -7], [90_037, 80_000, 100_250], [-3, 0, 0]];
    let exact: Vec<[f64; 3]> = (steps.iter())
        .map(|s| std::array::from_fn(|a| scale[a] * f64::from(s[a]) + offset[a]))
        .collect();
    let mut table = PointTable::new(bounded_geom::PointCloud::from_f64(&exact).unwrap());
    table.position_type = PositionType::Scaled { scale, offset };
    table.exact_positions = Some(ExactPositions::Scaled {
        scale,
        offset,
        steps: steps.to_vec(),
    });
    let path = dir.path().join("utm.e57");
    format::write(&path, &table).unwrap();
    let back = format::read(&path).unwrap();
    let positions: Vec<[f64; 3]> = (0..3).map(|i| back.view().position(i)).collect();
    assert_eq!(positions, exact);
    let reader = E57Reader::from_file(&path).unwrap();
    let x = &reader.pointclouds()[0].prototype[0];
    let want = RecordDataType::ScaledInteger {
        min: -3,
        max: 90_037,
        scale: 0.01,
        offset: 500_000.0,
    };
    assert_eq!(format!("{:?}", x.data_type), format!("{want:?}"));
}

#[test]
fn names_outside_xml_and_clashing_attributes_are_named_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = bounded_geom::PointCloud::from_f64(&[[0.0; 3], [1.0; 3]]).unwrap();
    let mut table = PointTable::new(cloud);
    table.set_property(Property::new("a.b", Column::U8(vec![1, 2])));
    let path = dir.path().join("out.e57");
    let e = format::write(&path, &table).unwrap_err();
    assert!(matches!(e, DataError::InvalidOutput { .. }), "{e}");
    let message = e.to_string();
    assert!(
        message.contains("out.e57") && message.contains("a.b"),
        "{e}"
    );
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());

    // Another writer's extension attribute named like a coordinate.
    let mut writer = E57Writer::from_file(&path, "file").unwrap();
    let extension = e57::Extension::new("ext", "urn:test");
    writer.register_extension(extension).unwrap();
    let x = RecordName::Unknown {
        namespace: "ext".into(),
        name: "x".into(),
    };
    let prototype = vec![
        Record::CARTESIAN_X_F64,
        Record::CARTESIAN_Y_F64,
        Record::CARTESIAN_Z_F64,
        record(x, RecordDataType::U8),
    ];
    let mut scan = writer.add_pointcloud("scan", prototype).unwrap();
    let mut point = vec![RecordValue::Double(0.0); 3];
    point.push(RecordValue::Integer(1));
    scan.add_point(point).unwrap();
    scan.finalize().unwrap();
    writer.finalize().unwrap();
    let e = format::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("out.e57") && e.contains("'ext:x' clashes"),
        "{e}"
    );
}

#[test]
fn a_lone_colour_channel_is_kept_as_an_attribute() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = bounded_geom::PointCloud::from_f64(&[[0.0; 3], [1.0; 3]]).unwrap();
    let mut table = PointTable::new(cloud);
    let red = Property::new("red", Column::U8(vec![3, 4]));
    table.set_property(red.clone());
    let path = dir.path().join("red.e57");
    format::write(&path, &table).unwrap();
    assert_eq!(format::read(&path).unwrap().properties, [red]);
}

#[test]
fn scans_read_from_e57_are_written_as_scans() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.e57");
    write_two_scans(&path);
    let (table, _) = format::read_finite(&path).unwrap();
    let out = dir.path().join("out.e57");
    format::write(&out, &table).unwrap();
    let reader = E57Reader::from_file(&out).unwrap();
    let sizes: Vec<u64> = reader.pointclouds().iter().map(|s| s.records).collect();
    assert_eq!(sizes, [3, 2]);
    let no_scan_attribute = (reader.pointclouds().iter().flat_map(|s| &s.prototype))
        .all(|r| !matches!(&r.name, RecordName::Unknown { name, .. } if name == "scan"));
    assert!(no_scan_attribute);
    let back = format::read(&out).unwrap();
    assert_eq!(back.properties.len(), table.properties.len());
    for (got, want) in back.properties.iter().zip(&table.properties) {
        assert!(
            got.name == want.name && same_values(&got.values, &want.values),
            "{got:?}"
        );
    }
    let positions = |t: &PointTable| {
        (0..t.len())
            .map(|i| t.view().position(i))
            .collect::<Vec<_>>()
    };
    assert_eq!(positions(&back), positions(&table));
}
