//! LAS / LAZ reader and writer (ASPRS LAS 1.0-1.4).
//!
//! The `las` crate reads and writes the header and the VLRs and compresses LAZ. Uncompressed
//! point records are read and written here, in blocks of whole records at the fixed byte
//! offsets of each field and decoded / encoded in parallel while the next block is read or
//! the previous one written: several times faster than going through the crate's point
//! buffers, and the point count is checked against the file size before anything is
//! allocated for it.
//!
//! Reading decodes the point records column by column: coordinates as scaled integers
//! (the scale and offset are kept in
//! [`PositionType::Scaled`](crate::table::PositionType::Scaled)), and every other field as a
//! property: `intensity`, `return_number`, `number_of_returns`, `classification`,
//! `scan_angle_rank` (formats 0-5, degrees) or `scan_angle` (formats 6-10, units of
//! 0.006 degrees), `user_data`, `point_source_id`, `gps_time`, `red`/`green`/`blue`, `nir`,
//! and the one-bit flags (`synthetic`, `key_point`, `withheld`, `overlap`,
//! `scanner_channel`, `scan_direction`, `edge_of_flight_line`) when any point sets them.
//! Extra Bytes are decoded by their Extra Bytes VLR into named properties: arrays of two or
//! three values (the deprecated data types 11-30, which laspy writes) as `name_0`, `name_1`,
//! `name_2`, untyped or 64-bit ones as one `u8` property per byte (`name_0`, `name_1`, ...).
//! A property name that repeats another, or names a coordinate, is refused. Waveform packet
//! fields are not kept.
//!
//! The point count of a LAS 1.4 file is its 64-bit count, which the specification requires
//! to be correct whatever the legacy 32-bit one says (as laspy and PDAL read it; the `las`
//! crate prefers a non-zero legacy count). A legacy count only is read as the count.
//!
//! Writing produces LAS 1.4 with point format 6, 7 (with colour) or 8 (with NIR), so that
//! classification codes above 31 fit. A property named like a field of the format fills it
//! (`classification`, `intensity`, `gps_time`, `red`, ...; a legacy `scan_angle_rank` becomes
//! `scan_angle`); every other property (for example `p_nonedge`, `p_sharp`, `p_boundary`) is
//! written as Extra Bytes with an Extra Bytes VLR (user `LASF_Spec`, record 4), which PDAL,
//! laspy and CloudCompare read as named dimensions. 8-bit colours are scaled to LAS's 16-bit
//! range (x 257). Annotated outputs put the class in the Classification field, with these
//! codes by default, or in an Extra Bytes field `class` (see
//! [`ClassTarget`](crate::annotate::ClassTarget)):
//!
//! | BoundED class | LAS Classification |
//! |---|---|
//! | non-edge (0) | 1, "unclassified" |
//! | sharp edge (1) | 64, first user-definable code |
//! | boundary (2) | 65, user-definable |
//!
//! Coordinates of a LAS input keep its scale and offset; other clouds get their bounding-box
//! centre as offset and a power-of-ten scale fine enough for the cloud's `f32` precision.

mod header;
mod layout;
mod read;
#[cfg(test)]
mod tests;
mod write;

use crate::DataError;
use std::path::Path;

pub use header::InputHeader;
pub use read::{quiet_decoder_panics, read_chunks, read_from};
pub use write::{ChunkWriter, write_to};

/// LAS Classification code of BoundED's non-edge class ("unclassified").
pub const CODE_NON_EDGE: u8 = 1;
/// LAS Classification code of BoundED's sharp-edge class (user-definable range).
pub const CODE_SHARP: u8 = 64;
/// LAS Classification code of BoundED's boundary class (user-definable range).
pub const CODE_BOUNDARY: u8 = 65;

/// The coordinate bounds a LAS or LAZ file's header declares, corner `lo` to `hi`, and its
/// point count (LAS 1.4: the 64-bit one, as the reader takes it), read without any point:
/// what a planner of tiles needs from each file of a survey. The bounds are only as right
/// as the file's writer made them; a reader of the points can check them.
pub fn header_bounds(path: &Path) -> Result<([f64; 3], [f64; 3], u64), DataError> {
    let file = std::fs::File::open(path).map_err(|e| DataError::io(path, e))?;
    let raw = las::raw::Header::read_from(std::io::BufReader::new(file))
        .map_err(|e| las_error(path, e))?;
    let lo = [raw.min_x, raw.min_y, raw.min_z];
    let hi = [raw.max_x, raw.max_y, raw.max_z];
    let count = match raw.large_file {
        Some(large) if large.number_of_point_records != 0 => large.number_of_point_records,
        _ => u64::from(raw.number_of_point_records),
    };
    if count > 0 && !(0..3).all(|a| lo[a].is_finite() && hi[a].is_finite() && lo[a] <= hi[a]) {
        return Err(DataError::malformed(
            path,
            format!("LAS: the header's bounds {lo:?} to {hi:?} are not a box"),
        ));
    }
    Ok((lo, hi, count))
}

fn las_error(path: &Path, e: las::Error) -> DataError {
    match e {
        las::Error::Io(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => {
            DataError::io(path, e)
        }
        e => DataError::malformed(path, format!("LAS: {e}")),
    }
}
