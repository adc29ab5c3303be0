//! Fuzzes the PLY reader: any bytes must give a table or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = bounded_data::ply::read_from(data, std::path::Path::new("fuzz.ply"));
});
