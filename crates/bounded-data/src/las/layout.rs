//! Where each field lives in a LAS point record, and the Extra Bytes descriptors.

use crate::table::{Column, Endian, Property, ScalarType};
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
        let name = descriptor_name(d);
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

/// The name in the Extra Bytes descriptor `d`, with whitespace and commas as `_` (the
/// other formats separate names by them).
fn descriptor_name(d: &[u8]) -> String {
    String::from_utf8_lossy(&d[4..36])
        .trim_end_matches('\0')
        .chars()
        .map(|c| {
            if c.is_whitespace() || c == ',' {
                '_'
            } else {
                c
            }
        })
        .collect()
}

/// The type of a typed (one value) Extra Bytes data type code.
fn typed(code: u8) -> Option<ScalarType> {
    Some(match code {
        1 => ScalarType::U8,
        2 => ScalarType::I8,
        3 => ScalarType::U16,
        4 => ScalarType::I16,
        5 => ScalarType::U32,
        6 => ScalarType::I32,
        9 => ScalarType::F32,
        10 => ScalarType::F64,
        _ => return None,
    })
}

/// The scale and offset of the typed descriptor `d`, when its options bits 3 or 4 say the
/// stored value is `raw * scale + offset` (an absent one is 1 or 0).
fn scaling(d: &[u8]) -> Option<(f64, f64)> {
    let f64_at = |at: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&d[at..at + 8]);
        f64::from_le_bytes(b)
    };
    let (scaled, offset) = (d[3] & 0b1000 != 0, d[3] & 0b1_0000 != 0);
    (typed(d[2]).is_some() && (scaled || offset)).then(|| {
        let scale = if scaled { f64_at(112) } else { 1.0 };
        (scale, if offset { f64_at(136) } else { 0.0 })
    })
}

/// Replaces the raw values of the scaled typed Extra Bytes among `properties` (named as
/// [`extra_fields`] names them) by the values they stand for, `raw * scale + offset`, as
/// `f64`: a field "Deviation" stored as 127 with scale 0.01 reads as 1.27.
pub(super) fn apply_scaling(properties: &mut [Property], descriptors: &[u8]) {
    for d in descriptors.chunks_exact(DESCRIPTOR) {
        let Some((scale, offset)) = scaling(d) else {
            continue;
        };
        let name = descriptor_name(d);
        if let Some(p) = properties.iter_mut().find(|p| p.name == name) {
            let raw = &p.values;
            let values = (0..raw.len()).map(|i| raw.get_f64(i) * scale + offset);
            p.values = Column::F64(values.collect());
        }
    }
}

/// One Extra Bytes field of an output: its descriptor, the type it stores and the scale
/// and offset its values are stored with.
pub(super) struct Extra {
    pub(super) descriptor: [u8; DESCRIPTOR],
    pub(super) ty: ScalarType,
    pub(super) scaling: Option<(f64, f64)>,
}

/// The Extra Bytes field for the property `name` of `column`. The input's descriptor of
/// that name (among `input`, the input's descriptors) is written again as it is, with its
/// no-data value, limits and description, when it describes the column (a scaled field, or
/// one of the column's type); else a new descriptor of the column's type, keeping the
/// input's description if there is one.
pub(super) fn extra_field(name: &str, column: &Column, input: &[u8]) -> Extra {
    let found = (input.chunks_exact(DESCRIPTOR))
        .find(|d| typed(d[2]).is_some() && descriptor_name(d) == name);
    if let Some(d) = found {
        let ty = typed(d[2]).expect("typed above");
        let scaling = scaling(d);
        if scaling.is_some() || ty == column.scalar_type() {
            let descriptor = d.try_into().expect("a whole descriptor");
            return Extra {
                descriptor,
                ty,
                scaling,
            };
        }
    }
    let mut d = [0u8; DESCRIPTOR];
    d[2] = extra_type_code(column.scalar_type());
    d[4..4 + name.len()].copy_from_slice(name.as_bytes());
    match (found, name) {
        (Some(input), _) => d[160..].copy_from_slice(&input[160..]),
        (None, "p_nonedge") => describe(&mut d, "probability of non-edge"),
        (None, "p_sharp") => describe(&mut d, "probability of sharp edge"),
        (None, "p_boundary") => describe(&mut d, "probability of boundary"),
        (None, "class") => describe(&mut d, "0 non-edge, 1 sharp, 2 boundary"),
        _ => {}
    }
    Extra {
        descriptor: d,
        ty: column.scalar_type(),
        scaling: None,
    }
}

fn describe(d: &mut [u8; DESCRIPTOR], description: &str) {
    d[160..160 + description.len()].copy_from_slice(description.as_bytes());
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
pub(super) fn extra_bytes_vlr(extras: &[Extra]) -> Vlr {
    Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "Extra Bytes".into(),
        data: extras.iter().flat_map(|e| e.descriptor).collect(),
    }
}
