//! Deterministic "mutation fuzzing": every reader gets truncated and corrupted versions of
//! valid files and must return (an error or a table) without panicking.

use bounded_data::table::{Column, PointTable, Property};
use bounded_data::{las, pcd, ply, xyz};
use bounded_geom::PointCloud;
use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

type Reader = fn(&[u8]) -> bool;

fn table() -> PointTable {
    let cloud =
        PointCloud::from_f64(&[[0.5, -1.0, 2.0], [1.5, 3.0, -4.0], [0.0, 0.25, 0.0]]).unwrap();
    let mut t = PointTable::new(cloud);
    t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
    t.set_property(Property::new("red", Column::U8(vec![255, 0, 160])));
    t.set_property(Property::new("green", Column::U8(vec![0, 255, 160])));
    t.set_property(Property::new("blue", Column::U8(vec![0, 0, 160])));
    t.set_property(Property::new("p_sharp", Column::F32(vec![0.1, 0.9, 0.5])));
    t
}

fn read_ply(b: &[u8]) -> bool {
    ply::read_from(b, Path::new("f.ply")).is_ok()
}
fn read_pcd(b: &[u8]) -> bool {
    pcd::read_from(b, Path::new("f.pcd")).is_ok()
}
fn read_xyz(b: &[u8]) -> bool {
    xyz::read_from(b, Path::new("f.xyz")).is_ok()
}
fn read_las(b: &[u8]) -> bool {
    las::read_from(Cursor::new(b.to_vec()), Path::new("f.las")).is_ok()
}

fn valid_files() -> Vec<(&'static str, Vec<u8>, Reader)> {
    let t = table();
    let view = t.view();
    let p = Path::new("f");
    let mut files: Vec<(&'static str, Vec<u8>, Reader)> = Vec::new();
    for (name, encoding) in [
        ("ply ascii", ply::Encoding::Ascii),
        ("ply le", ply::Encoding::BinaryLittleEndian),
        ("ply be", ply::Encoding::BinaryBigEndian),
    ] {
        let mut b = Vec::new();
        ply::write_to(&mut b, &view, encoding, p).unwrap();
        files.push((name, b, read_ply));
    }
    let mut b = Vec::new();
    pcd::write_to(&mut b, &view, p).unwrap();
    files.push(("pcd binary", b, read_pcd));
    let mut b = b"VERSION .7\nFIELDS x y z rgb\nSIZE 1 1 1 4\nTYPE U U U U\nCOUNT 1 1 1 1\n\
        WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary_compressed\n"
        .to_vec();
    b.extend(12u32.to_le_bytes());
    b.extend(14u32.to_le_bytes());
    b.extend([5, 1, 2, 3, 4, 5, 6, 1, 7, 8, 0x80, 1]); // 8 literal bytes + a back-reference of 6
    files.push(("pcd compressed", b, read_pcd));
    for separator in [xyz::Separator::Space, xyz::Separator::Comma] {
        let mut b = Vec::new();
        xyz::write_to(&mut b, &view, separator, p).unwrap();
        files.push(("xyz", b, read_xyz));
    }
    for compressed in [false, true] {
        let b = las::write_to(Cursor::new(Vec::new()), &view, compressed, p).unwrap();
        files.push((
            if compressed { "laz" } else { "las" },
            b.into_inner(),
            read_las,
        ));
    }
    files
}

/// Bytes whose corruption is tested: all, except for LAZ only the 375-byte header. The laz
/// crate trusts the layer sizes of LAS 1.4 compressed chunks and allocates what a corrupt
/// size says (gigabytes, slowly), a known limitation of that dependency.
fn corruptible(name: &str, valid: &[u8]) -> usize {
    if name == "laz" { 375 } else { valid.len() }
}

#[test]
fn truncated_and_corrupted_files_never_panic() {
    let files = valid_files();
    for (name, valid, read) in &files {
        assert!(read(valid), "{name}: the unmodified file must read");
    }
    // Silence the default hook: a panic is reported by the assertion below instead.
    std::panic::set_hook(Box::new(|_| {}));
    let mut panics = Vec::new();
    let mut reads = 0;
    for (name, valid, read) in files {
        let mut variants: Vec<(String, Vec<u8>)> = (0..valid.len())
            .map(|n| (format!("truncated to {n}"), valid[..n].to_vec()))
            .collect();
        for i in 0..corruptible(name, &valid) {
            for (what, value) in [("bit flip", valid[i] ^ (1 << (i % 8))), ("0xff", 0xff)] {
                let mut b = valid.clone();
                b[i] = value;
                variants.push((format!("{what} at {i}"), b));
            }
        }
        for (what, bytes) in variants {
            reads += 1;
            if catch_unwind(AssertUnwindSafe(|| read(&bytes))).is_err() {
                panics.push(format!("{name}: {what}"));
            }
        }
    }
    let _ = std::panic::take_hook();
    assert!(reads > 3000, "{reads}");
    assert!(
        panics.is_empty(),
        "{} panics, e.g. {:?}",
        panics.len(),
        &panics[..panics.len().min(10)]
    );
}
