//! Where each field lives in a LAS point record, and the Extra Bytes descriptors.

use crate::table::{Column, Endian, ScalarType};
use las::point::Format as LasFormat;
use las::{Header, Vlr};
/// Where a LAS field lives in a point record.
#[derive(Debug, Clone, Copy)]
pub(super) enum Slot {
    /// A whole little-endian value at byte `at`.
    Plain { ty: ScalarType, at: usize },
    /// `width` bits from bit `shift` of byte `at`; an `optional` flag is left out on reading
    /// when no point sets it, to keep outputs uncluttered.
    Bits {
        at: usize,
        shift: u8,
        width: u8,
        optional: bool,
    },
}

impl Slot {
    /// The type of the decoded values (bit fields decode to `u8`).
    pub(super) fn scalar_type(self) -> ScalarType {
        match self {
            Slot::Plain { ty, .. } => ty,
            Slot::Bits { .. } => ScalarType::U8,
        }
    }

    /// Stores `value` in `record` (`as` conversion; a bit field keeps the low bits and leaves
    /// the other bits of its byte alone).
    #[inline]
    pub(super) fn put(self, value: f64, record: &mut [u8]) {
        match self {
            Slot::Plain { ty, at } => ty.encode_f64(value, &mut record[at..], Endian::Little),
            Slot::Bits {
                at, shift, width, ..
            } => {
                let mask = low_bits(width) << shift;
                record[at] = (record[at] & !mask) | (((value as u8) << shift) & mask);
            }
        }
    }
}

/// A byte with the low `width` bits set.
fn low_bits(width: u8) -> u8 {
    (1u8 << width) - 1
}

/// The value of the bit field `shift`, `width` of `byte`.
pub(super) fn bits_of(byte: u8, shift: u8, width: u8) -> u8 {
    (byte >> shift) & low_bits(width)
}

/// The standard fields of `format` (after x, y, z), and the record length without extras.
pub(super) fn fields(format: &LasFormat) -> (Vec<(&'static str, Slot)>, usize) {
    use ScalarType::{F64, I8, I16, U8, U16};
    let plain = |ty, at| Slot::Plain { ty, at };
    let bits = |at, shift, width| Slot::Bits {
        at,
        shift,
        width,
        optional: false,
    };
    let flag = |at, shift, width| Slot::Bits {
        at,
        shift,
        width,
        optional: true,
    };
    let mut f = vec![("intensity", plain(U16, 12))];
    let mut end;
    if format.is_extended {
        f.extend([
            ("return_number", bits(14, 0, 4)),
            ("number_of_returns", bits(14, 4, 4)),
            ("synthetic", flag(15, 0, 1)),
            ("key_point", flag(15, 1, 1)),
            ("withheld", flag(15, 2, 1)),
            ("overlap", flag(15, 3, 1)),
            ("scanner_channel", flag(15, 4, 2)),
            ("scan_direction", flag(15, 6, 1)),
            ("edge_of_flight_line", flag(15, 7, 1)),
            ("classification", plain(U8, 16)),
            ("user_data", plain(U8, 17)),
            ("scan_angle", plain(I16, 18)),
            ("point_source_id", plain(U16, 20)),
            ("gps_time", plain(F64, 22)),
        ]);
        end = 30;
    } else {
        f.extend([
            ("return_number", bits(14, 0, 3)),
            ("number_of_returns", bits(14, 3, 3)),
            ("scan_direction", flag(14, 6, 1)),
            ("edge_of_flight_line", flag(14, 7, 1)),
            ("classification", bits(15, 0, 5)),
            ("synthetic", flag(15, 5, 1)),
            ("key_point", flag(15, 6, 1)),
            ("withheld", flag(15, 7, 1)),
            ("scan_angle_rank", plain(I8, 16)),
            ("user_data", plain(U8, 17)),
            ("point_source_id", plain(U16, 18)),
        ]);
        end = 20;
        if format.has_gps_time {
            f.push(("gps_time", plain(F64, end)));
            end += 8;
        }
    }
    if format.has_color {
        f.extend([
            ("red", plain(U16, end)),
            ("green", plain(U16, end + 2)),
            ("blue", plain(U16, end + 4)),
        ]);
        end += 6;
    }
    if format.has_nir {
        f.push(("nir", plain(U16, end)));
        end += 2;
    }
    if format.has_waveform {
        end += 29;
    }
    (f, end)
}

/// Size of one Extra Bytes descriptor.
const DESCRIPTOR: usize = 192;

/// The Extra Bytes of each record as named fields, from the Extra Bytes VLR: a typed value
/// as `name`, an array of two or three (the deprecated codes 11-30) as `name_0`, `name_1`,
/// `name_2`; bytes not described by a typed descriptor (and 64-bit integers) become one `u8`
/// field per byte, `name_0`, `name_1`, ...
pub(super) fn extra_fields(header: &Header, base: usize, len: usize) -> Vec<(String, Slot)> {
    let mut out = Vec::new();
    let mut at = 0;
    let descriptors = header
        .all_vlrs()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
        .map(|v| v.data.clone())
        .unwrap_or_default();
    for d in descriptors.chunks_exact(DESCRIPTOR) {
        let name: String = String::from_utf8_lossy(&d[4..36])
            .trim_end_matches('\0')
            .chars()
            .map(|c| {
                if c.is_whitespace() || c == ',' {
                    '_'
                } else {
                    c
                }
            })
            .collect();
        let name = if name.is_empty() {
            format!("extra_{at}")
        } else {
            name
        };
        // Codes 11-30 (deprecated since LAS 1.4 R14, still written by laspy): arrays of two
        // or three values of the type of code 1-10.
        let (code, count) = match d[2] {
            0..=10 => (d[2], 1),
            11..=30 => ((d[2] - 1) % 10 + 1, usize::from((d[2] - 1) / 10 + 1)),
            _ => break, // undefined codes: the rest stays raw bytes
        };
        let (ty, width) = match code {
            0 => (None, usize::from(d[3])),
            1 => (Some(ScalarType::U8), 1),
            2 => (Some(ScalarType::I8), 1),
            3 => (Some(ScalarType::U16), 2),
            4 => (Some(ScalarType::I16), 2),
            5 => (Some(ScalarType::U32), 4),
            6 => (Some(ScalarType::I32), 4),
            9 => (Some(ScalarType::F32), 4),
            10 => (Some(ScalarType::F64), 8),
            _ => (None, 8), // 7, 8: 64-bit integers
        };
        let size = width * count;
        if at + size > len {
            break;
        }
        match ty {
            Some(ty) if count == 1 => out.push((name, Slot::Plain { ty, at: base + at })),
            Some(ty) => out.extend((0..count).map(|k| {
                let at = base + at + k * width;
                (format!("{name}_{k}"), Slot::Plain { ty, at })
            })),
            None => out.extend((0..size).map(|k| {
                (
                    format!("{name}_{k}"),
                    Slot::Plain {
                        ty: ScalarType::U8,
                        at: base + at + k,
                    },
                )
            })),
        }
        at += size;
    }
    out.extend((at..len).map(|k| {
        (
            format!("extra_{k}"),
            Slot::Plain {
                ty: ScalarType::U8,
                at: base + k,
            },
        )
    }));
    out
}

/// Extra Bytes VLR data type code of `ty`.
fn extra_type_code(ty: ScalarType) -> u8 {
    match ty {
        ScalarType::U8 => 1,
        ScalarType::I8 => 2,
        ScalarType::U16 => 3,
        ScalarType::I16 => 4,
        ScalarType::U32 => 5,
        ScalarType::I32 => 6,
        ScalarType::F32 => 9,
        ScalarType::F64 => 10,
    }
}

/// The Extra Bytes VLR (user `LASF_Spec`, record 4) describing `extras` in order.
pub(super) fn extra_bytes_vlr(extras: &[(String, &Column)]) -> Vlr {
    let mut data = Vec::with_capacity(extras.len() * DESCRIPTOR);
    for (name, column) in extras {
        let mut d = [0u8; DESCRIPTOR];
        d[2] = extra_type_code(column.scalar_type());
        d[4..4 + name.len()].copy_from_slice(name.as_bytes());
        let description = match name.as_str() {
            "p_nonedge" => "probability of non-edge",
            "p_sharp" => "probability of sharp edge",
            "p_boundary" => "probability of boundary",
            _ => "",
        };
        d[160..160 + description.len()].copy_from_slice(description.as_bytes());
        data.extend_from_slice(&d);
    }
    Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "Extra Bytes".into(),
        data,
    }
}
