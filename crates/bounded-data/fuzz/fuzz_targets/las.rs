//! Fuzzes the LAS / LAZ reader: any bytes must give a table or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let input = std::io::Cursor::new(data.to_vec());
    let _ = bounded_data::las::read_from(input, std::path::Path::new("fuzz.las"));
});
