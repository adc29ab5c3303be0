//! Fuzzes the LAZ decompression path of the reader: a valid LAZ header and VLRs (of a
//! generated 300-point cloud in three colours) followed by any bytes as the point data and
//! chunk table must give a table or an error, never a panic, an abort or a huge allocation.
//! The `las` target mutates whole files, whose mutations mostly break the header first.
#![no_main]

use bounded_data::table::{Column, PointTable, Property};
use bounded_geom::PointCloud;
use libfuzzer_sys::fuzz_target;
use std::io::Cursor;
use std::path::Path;
use std::sync::OnceLock;

/// The header and VLRs of a LAZ file of a small cloud (up to its point data).
fn head() -> &'static [u8] {
    static HEAD: OnceLock<Vec<u8>> = OnceLock::new();
    HEAD.get_or_init(|| {
        let n = 300;
        let cloud = PointCloud::from_iter_f64(n, |i| {
            [i as f64 * 0.1, (i % 17) as f64 * 0.2, (i % 5) as f64]
        })
        .unwrap();
        let mut table = PointTable::new(cloud);
        for (name, k) in [("red", 1), ("green", 2), ("blue", 3)] {
            let values = (0..n).map(|i| (i * k % 256) as u8).collect();
            table.set_property(Property::new(name, Column::U8(values)));
        }
        let out = Cursor::new(Vec::new());
        let bytes = bounded_data::las::write_to(out, &table.view(), true, Path::new("seed.laz"))
            .unwrap()
            .into_inner();
        let data = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
        bytes[..data].to_vec()
    })
}

fuzz_target!(|data: &[u8]| {
    // libfuzzer-sys's hook aborts on every panic, caught or not: the reader's own catch of
    // the laz decoder's panics (an error) must get through, and every other panic aborts.
    bounded_data::las::quiet_decoder_panics();
    let bytes = [head(), data].concat();
    let _ = bounded_data::las::read_from(Cursor::new(bytes), Path::new("fuzz.laz"));
});
