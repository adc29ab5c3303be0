//! E57 (ASTM E2807), the exchange format of terrestrial laser scanners: read and written.
//!
//! Reading: a file holds one or more scans, each in its own frame with a pose. Reading
//! converts spherical coordinates to Cartesian where a scan stores only those, applies each
//! scan's pose, and concatenates the scans in file order as one cloud of `f64` positions.
//! Kept per point, as the file's values, when any scan has them: `intensity` (float; NaN
//! where a scan or point has none), `red`, `green`, `blue` (the smallest integer type that
//! holds every scan's colour range, as scanners write them, else float; 0 or NaN where a scan
//! or point has none), `scan` (uint, the scan's 0-based index) when the file holds several,
//! and every extension attribute, named without its namespace (0 or NaN where a scan has
//! none).
//!
//! A point the file marks as having no position (scanners store their no-return pixels so, or
//! a direction without a range) gets NaN coordinates: an error naming it, unless read with
//! [`crate::format::read_finite`], which leaves such points out and counts them, as it does
//! the NaN points of organised PCL clouds.
//!
//! Writing: one scan in the file's frame, or one per index of a `scan` property as reading a
//! file of several scans gives it (uint, in scan order); positions as the input stored them
//! (single or double floats, or scaled integers with a LAS input's scale and offset), with
//! `cartesianInvalidState` 0 (valid) at every point, which pye57's `read_scan` requires;
//! `intensity` and `red`, `green`, `blue` in the standard fields (a NaN as the field's
//! invalid flag), so every E57 viewer shows them; every other property, the detection
//! results among them, as an attribute of the `bounded` extension (namespace
//! `urn:bounded-rs:point-attributes`), which other readers skip and this one reads back
//! under its name. E57 has no standard field for a class or a probability. libE57Format
//! (and pye57 through it) reads such a field by its prefixed name, `bounded:p_sharp`:
//!
//! ```text
//! e57 = pye57.E57("out.e57"); header = e57.get_header(0); n = header.point_count
//! p_sharp = numpy.empty(n, numpy.float32)
//! buffers = pye57.libe57.VectorSourceDestBuffer()
//! buffers.append(pye57.libe57.SourceDestBuffer(e57.image_file, "bounded:p_sharp", p_sharp, n, True, True))
//! header.points.reader(buffers).read()
//! ```

mod read;
#[cfg(test)]
mod tests;
mod write;

pub(crate) use read::read_properties;
pub(crate) use write::write_to;

use crate::table::ScalarType;

/// The XML namespace (prefix and URI) of the attributes written beyond the standard's.
const EXTENSION: (&str, &str) = ("bounded", "urn:bounded-rs:point-attributes");

/// The values an integer column type holds; `None` for floats.
fn integer_range(ty: ScalarType) -> Option<(i64, i64)> {
    use ScalarType::*;
    Some(match ty {
        U8 => (0, u8::MAX.into()),
        I8 => (i8::MIN.into(), i8::MAX.into()),
        U16 => (0, u16::MAX.into()),
        I16 => (i16::MIN.into(), i16::MAX.into()),
        U32 => (0, u32::MAX.into()),
        I32 => (i32::MIN.into(), i32::MAX.into()),
        F32 | F64 => return None,
    })
}
