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
//! (the scale and offset are kept in [`PositionType::Scaled`]), and every other field as a
//! property: `intensity`, `return_number`, `number_of_returns`, `classification`,
//! `scan_angle_rank` (formats 0-5, degrees) or `scan_angle` (formats 6-10, units of
//! 0.006 degrees), `user_data`, `point_source_id`, `gps_time`, `red`/`green`/`blue`, `nir`,
//! and the one-bit flags (`synthetic`, `key_point`, `withheld`, `overlap`,
//! `scanner_channel`, `scan_direction`, `edge_of_flight_line`) when any point sets them.
//! Extra Bytes are decoded by their Extra Bytes VLR into named properties (untyped or
//! 64-bit ones as one `u8` property per byte). Waveform packet fields are not kept.
//!
//! Writing produces LAS 1.4 with point format 6, 7 (with colour) or 8 (with NIR), so that
//! classification codes above 31 fit. A `class` property (BoundED classes) goes to the
//! Classification field with these codes:
//!
//! | BoundED class | LAS Classification |
//! |---|---|
//! | non-edge (0) | 1, "unclassified" |
//! | sharp edge (1) | 64, first user-definable code |
//! | boundary (2) | 65, user-definable |
//!
//! and an input `classification` is then kept as the extra-bytes property
//! `input_classification`. Every property that is not a LAS field (for example `p_nonedge`,
//! `p_sharp`, `p_boundary`) is written as Extra Bytes with an Extra Bytes VLR (user
//! `LASF_Spec`, record 4), which PDAL and CloudCompare read as named dimensions. 8-bit
//! colours are scaled to LAS's 16-bit range (x 257). Coordinates of a LAS input keep its
//! scale and offset; other clouds get their bounding-box centre as offset and a power-of-ten
//! scale fine enough for the cloud's `f32` precision.

use crate::DataError;
use crate::records::{BLOCK, block_len, pipelined, truncated};
use crate::table::{
    Column, Endian, ExactCloud, ExactPositions, PointTable, PositionType, Property, ScalarType,
    TableView,
};
use las::point::Format as LasFormat;
use las::raw::header::LargeFile;
use las::{
    Builder, Header, LazParallelism, PointDataBuilder, Reader, ReaderOptions, Transform, Vector,
    Version, Vlr, Writer, WriterOptions,
};
use rayon::prelude::*;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

/// LAS Classification code of BoundED's non-edge class ("unclassified").
pub const CODE_NON_EDGE: u8 = 1;
/// LAS Classification code of BoundED's sharp-edge class (user-definable range).
pub const CODE_SHARP: u8 = 64;
/// LAS Classification code of BoundED's boundary class (user-definable range).
pub const CODE_BOUNDARY: u8 = 65;

/// Records encoded per parallel task when writing: small enough to spread a block over the
/// cores, large enough to amortise the per-field dispatch.
const TASK: usize = 4096;

/// Records per block when writing LAZ, at most 32 MiB: the LAZ compressor works on whole
/// chunks of 50,000 points in parallel, so a block spans ten of them to keep every core busy
/// (blocks of 64k records would hand it one chunk at a time).
fn laz_block_len(stride: usize) -> usize {
    ((32 << 20) / stride.max(1)).clamp(1, 1 << 19)
}

/// Where a LAS field lives in a point record.
#[derive(Debug, Clone, Copy)]
enum Slot {
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
    fn scalar_type(self) -> ScalarType {
        match self {
            Slot::Plain { ty, .. } => ty,
            Slot::Bits { .. } => ScalarType::U8,
        }
    }

    /// Stores `value` in `record` (`as` conversion; a bit field keeps the low bits and leaves
    /// the other bits of its byte alone).
    #[inline]
    fn put(self, value: f64, record: &mut [u8]) {
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
fn bits_of(byte: u8, shift: u8, width: u8) -> u8 {
    (byte >> shift) & low_bits(width)
}

/// The standard fields of `format` (after x, y, z), and the record length without extras.
fn fields(format: &LasFormat) -> (Vec<(&'static str, Slot)>, usize) {
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

fn las_error(path: &Path, e: las::Error) -> DataError {
    match e {
        las::Error::Io(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => {
            DataError::io(path, e)
        }
        e => DataError::malformed(path, format!("LAS: {e}")),
    }
}

/// Reads a LAS or LAZ file from `input`; `path` names it in errors.
pub fn read_from<R: Read + Seek + Send + Sync + 'static>(
    input: R,
    path: &Path,
) -> Result<PointTable, DataError> {
    read_in_blocks(input, path, BLOCK)
}

/// [`read_from`] with at most `max_block` records per block (tests set it small to cross
/// block boundaries with a few points).
fn read_in_blocks<R: Read + Seek + Send + Sync + 'static>(
    mut input: R,
    path: &Path,
    max_block: usize,
) -> Result<PointTable, DataError> {
    check_evlr_lengths(&mut input, path)?;
    let header = Header::new(&mut input).map_err(|e| las_error(path, e))?;
    let (names, slots, record_len) = record_fields(&header, path)?;
    let total = usize::try_from(header.number_of_points()).map_err(|_| {
        DataError::malformed(
            path,
            format!(
                "LAS: {} points do not fit in memory",
                header.number_of_points()
            ),
        )
    })?;
    let blocks = Blocks {
        total,
        record_len,
        block_len: block_len(record_len).min(max_block),
    };
    let decoded = if header.point_format().is_compressed {
        read_laz(input, blocks, &slots, path)?
    } else {
        read_las(input, blocks, &slots, path)?
    };
    into_table(header.transforms(), names, &slots, decoded, path)
}

/// Checks that every extended VLR fits in the file, then rewinds `input`: the las crate
/// allocates an EVLR's stated length (up to 2^64 bytes) before reading it, so a corrupt
/// length must fail here, not exhaust memory (found by fuzzing).
fn check_evlr_lengths(mut input: impl Read + Seek, path: &Path) -> Result<(), DataError> {
    let io = |e| DataError::io(path, e);
    let raw = las::raw::Header::read_from(&mut input).map_err(|e| las_error(path, e))?;
    let end = input.seek(SeekFrom::End(0)).map_err(io)?;
    if let Some(evlr) = raw.evlr.filter(|e| e.number_of_evlrs > 0) {
        let mut at = evlr.start_of_first_evlr;
        for k in 0..evlr.number_of_evlrs {
            // An EVLR header: reserved (2), user id (16), record id (2), length (8),
            // description (32).
            let mut head = [0u8; 60];
            input.seek(SeekFrom::Start(at)).map_err(io)?;
            input.read_exact(&mut head).map_err(|e| {
                truncated(
                    path,
                    format!("LAS: extended VLR {k} starts past the end"),
                    e,
                )
            })?;
            let mut length = [0u8; 8];
            length.copy_from_slice(&head[20..28]);
            let length = u64::from_le_bytes(length);
            at = at
                .checked_add(60)
                .and_then(|a| a.checked_add(length))
                .filter(|&a| a <= end)
                .ok_or_else(|| {
                    DataError::malformed(
                        path,
                        format!(
                            "LAS: extended VLR {k} claims {length} bytes, past the end of the {end}-byte file"
                        ),
                    )
                })?;
        }
    }
    input.rewind().map_err(io)
}

/// The names and slots of the fields of the records of `header` after x, y, z (the standard
/// fields, the Extra Bytes), and the record length.
fn record_fields(
    header: &Header,
    path: &Path,
) -> Result<(Vec<String>, Vec<Slot>, usize), DataError> {
    let format = header.point_format();
    let (standard, base_len) = fields(format);
    let record_len = usize::from(format.len());
    let extra_len = usize::from(format.extra_bytes);
    if base_len + extra_len != record_len {
        return Err(DataError::malformed(
            path,
            "LAS: inconsistent point record length",
        ));
    }
    let (names, slots) = standard
        .into_iter()
        .map(|(n, s)| (n.to_string(), s))
        .chain(extra_fields(header, base_len, extra_len))
        .unzip();
    Ok((names, slots, record_len))
}

/// Reads the `total` uncompressed records that start at the position of `input`, after
/// checking that the file holds them: a corrupt count fails before anything is allocated.
fn read_las(
    mut input: impl Read + Seek,
    blocks: Blocks,
    slots: &[Slot],
    path: &Path,
) -> Result<Decoded, DataError> {
    let Blocks {
        total, record_len, ..
    } = blocks;
    let io = |e| DataError::io(path, e);
    let start = input.stream_position().map_err(io)?;
    let end = input.seek(SeekFrom::End(0)).map_err(io)?;
    input.seek(SeekFrom::Start(start)).map_err(io)?;
    let held = end.saturating_sub(start) / record_len as u64;
    if held < total as u64 {
        return Err(DataError::malformed(
            path,
            format!(
                "LAS: point data ends within point {held} of {total} (the file is {end} bytes)"
            ),
        ));
    }
    decode_blocks(blocks, total, slots, |block, first| {
        input.read_exact(block).map_err(|e| {
            let what = format!("LAS: point data ends within point {first} of {total}");
            truncated(path, what, e)
        })
    })
}

/// Decompresses the `total` records of the LAZ file `input`. The columns grow with the
/// records actually decoded (the compressed size does not bound the count), so a corrupt
/// count ends in an error where the compressed data ends, not in a huge allocation.
fn read_laz<R: Read + Seek + Send + Sync + 'static>(
    mut input: R,
    blocks: Blocks,
    slots: &[Slot],
    path: &Path,
) -> Result<Decoded, DataError> {
    let Blocks {
        total, record_len, ..
    } = blocks;
    input.rewind().map_err(|e| DataError::io(path, e))?;
    // The sequential decompressor: the parallel one cannot read files without a chunk table
    // and sizes its buffers from the table's counts before checking them against the file,
    // and here it would only compete with the column decoding for the same cores.
    let options = ReaderOptions::default().with_laz_parallelism(LazParallelism::No);
    let mut reader = Reader::with_options(input, options).map_err(|e| las_error(path, e))?;
    let mut data = PointDataBuilder::new().for_header(reader.header()).build();
    decode_blocks(blocks, 0, slots, |block, first| {
        let ends = |what: String| {
            let what = format!("LAS: point data ends within point {first} of {total}{what}");
            DataError::malformed(path, what)
        };
        reader
            .fill_points((block.len() / record_len) as u64, &mut data)
            .map_err(|e| ends(format!(": {e}")))?;
        let bytes = data.raw_bytes();
        if bytes.len() != block.len() {
            return Err(ends(String::new()));
        }
        block.copy_from_slice(bytes);
        Ok(())
    })
}

/// How the point records of a file are split into blocks.
#[derive(Debug, Clone, Copy)]
struct Blocks {
    /// The number of records.
    total: usize,
    record_len: usize,
    /// Records per block.
    block_len: usize,
}

/// Decoded point records: the coordinates as scaled integers, and one column per field.
struct Decoded {
    xyz: Vec<[i32; 3]>,
    columns: Vec<Column>,
}

/// Decodes the records of `blocks` (x, y, z and one column per slot, each made with room for
/// `capacity` values), block by block: `fill(block, first)` fills `block` with the records
/// from `first` on while the previous block is decoded, its columns in parallel.
fn decode_blocks(
    blocks: Blocks,
    capacity: usize,
    slots: &[Slot],
    fill: impl FnMut(&mut [u8], usize) -> Result<(), DataError>,
) -> Result<Decoded, DataError> {
    let columns = slots
        .iter()
        .map(|&s| {
            let optional = matches!(s, Slot::Bits { optional: true, .. });
            Column::with_capacity(s.scalar_type(), if optional { 0 } else { capacity })
        })
        .collect();
    let mut out = Decoded {
        xyz: Vec::with_capacity(capacity),
        columns,
    };
    let Blocks {
        total,
        record_len,
        block_len,
    } = blocks;
    pipelined(total, block_len, record_len, fill, |block, first| {
        let (xyz, columns) = (&mut out.xyz, &mut out.columns);
        rayon::join(
            || xyz.extend(block.chunks_exact(record_len).map(coordinates)),
            || {
                columns
                    .par_iter_mut()
                    .zip(slots)
                    .for_each(|(column, &slot)| decode(column, slot, block, record_len, first))
            },
        );
        Ok(())
    })?;
    Ok(out)
}

/// The x, y, z scaled integers at the start of `record`.
fn coordinates(record: &[u8]) -> [i32; 3] {
    std::array::from_fn(|a| {
        let mut v = [0u8; 4];
        v.copy_from_slice(&record[4 * a..4 * a + 4]);
        i32::from_le_bytes(v)
    })
}

/// Appends the field `slot` of the records `bytes` (from record `first` on) to `column`; an
/// optional flag stays empty while no point sets it, as in most files.
fn decode(column: &mut Column, slot: Slot, bytes: &[u8], stride: usize, first: usize) {
    match (slot, column) {
        (Slot::Plain { at, .. }, column) => {
            column.decode_strided(bytes, stride, at, Endian::Little)
        }
        (
            Slot::Bits {
                at,
                shift,
                width,
                optional,
            },
            Column::U8(v),
        ) => {
            let values = bytes
                .chunks_exact(stride)
                .map(|r| bits_of(r[at], shift, width));
            if optional && v.is_empty() {
                if values.clone().all(|b| b == 0) {
                    return;
                }
                v.resize(first, 0);
            }
            v.extend(values);
        }
        (Slot::Bits { .. }, _) => unreachable!("bit fields are decoded into u8 columns"),
    }
}

/// The table of the `decoded` records with the fields `names`, `slots`; the coordinates are
/// scaled by the transforms `t`, and optional flags no point sets (empty columns) are left out.
fn into_table(
    t: &Vector<Transform>,
    names: Vec<String>,
    slots: &[Slot],
    decoded: Decoded,
    path: &Path,
) -> Result<PointTable, DataError> {
    let (cloud, exact_positions) = cloud_of(decoded.xyz, t).map_err(|source| DataError::Geom {
        path: path.to_path_buf(),
        source,
    })?;
    let columns = decoded.columns;
    let properties = names
        .into_iter()
        .zip(columns)
        .zip(slots)
        .filter(|((_, values), slot)| {
            !(matches!(slot, Slot::Bits { optional: true, .. }) && values.is_empty())
        })
        .map(|((name, values), _)| Property::new(name, values))
        .collect();
    Ok(PointTable {
        cloud,
        position_type: PositionType::Scaled {
            scale: [t.x.scale, t.y.scale, t.z.scale],
            offset: [t.x.offset, t.y.offset, t.z.offset],
        },
        properties,
        exact_positions,
    })
}

/// The cloud of the scaled integer coordinates `xyz`, exactly as
/// [`PointCloud::from_iter_f64`](bounded_geom::PointCloud::from_iter_f64) builds it from the
/// scaled coordinates, without its two passes over them and its second allocation: the
/// bounding box comes from the integer extremes (scaling is monotonic) and the integers turn
/// into offsets from its centre in place (`[i32; 3]` and `[f32; 3]` have the same layout, so
/// the collect reuses the allocation). Also a copy of the integers, when some integer does
/// not come back from its `f32` offset on the same scale and offset (a scale finer than
/// `f32` resolves over the cloud's extent; see `PointTable::exact_positions`): a parallel
/// pass before the in-place one checks that, as the integers are gone after it.
fn cloud_of(
    xyz: Vec<[i32; 3]>,
    t: &Vector<Transform>,
) -> Result<ExactCloud, bounded_geom::GeomError> {
    let axes = [t.x, t.y, t.z];
    let absolute = move |p: [i32; 3]| std::array::from_fn::<f64, 3, _>(|a| axes[a].direct(p[a]));
    let (lo, hi) = xyz.par_iter().map(|&p| (p, p)).reduce(
        || ([i32::MAX; 3], [i32::MIN; 3]),
        |(l0, h0), (l1, h1)| {
            (
                std::array::from_fn(|a| l0[a].min(l1[a])),
                std::array::from_fn(|a| h0[a].max(h1[a])),
            )
        },
    );
    let (lo, hi) = (absolute(lo), absolute(hi));
    let origin: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a].min(hi[a]) + lo[a].max(hi[a])));
    if xyz.is_empty() || !origin.iter().all(|o| o.is_finite()) {
        // Let the general constructor name the empty cloud or the first non-finite point.
        let cloud = bounded_geom::PointCloud::from_iter_f64(xyz.len(), |i| absolute(xyz[i]))?;
        return Ok((cloud, None));
    }
    let local = move |p: [i32; 3]| {
        let p = absolute(p);
        std::array::from_fn::<f32, 3, _>(|a| (p[a] - origin[a]) as f32)
    };
    // What the writer makes of the offset on the same scale and offset.
    let returns = |p: [i32; 3]| {
        let q = local(p);
        (0..3).all(|a| {
            let steps = (origin[a] + f64::from(q[a]) - axes[a].offset) / axes[a].scale;
            steps.round() == f64::from(p[a])
        })
    };
    let exact = (!xyz.par_iter().all(|&p| returns(p))).then(|| ExactPositions::Scaled {
        scale: axes.map(|t| t.scale),
        offset: axes.map(|t| t.offset),
        steps: xyz.clone(),
    });
    let points = xyz.into_iter().map(local).collect();
    Ok((bounded_geom::PointCloud::from_local(origin, points)?, exact))
}

/// Size of one Extra Bytes descriptor.
const DESCRIPTOR: usize = 192;

/// The Extra Bytes of each record as named fields, from the Extra Bytes VLR; bytes not
/// described by a typed descriptor become one `u8` field per byte.
fn extra_fields(header: &Header, base: usize, len: usize) -> Vec<(String, Slot)> {
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
        let (ty, size) = match d[2] {
            0 => (None, usize::from(d[3])),
            1 => (Some(ScalarType::U8), 1),
            2 => (Some(ScalarType::I8), 1),
            3 => (Some(ScalarType::U16), 2),
            4 => (Some(ScalarType::I16), 2),
            5 => (Some(ScalarType::U32), 4),
            6 => (Some(ScalarType::I32), 4),
            7 | 8 => (None, 8),
            9 => (Some(ScalarType::F32), 4),
            10 => (Some(ScalarType::F64), 8),
            _ => break, // deprecated array types: the rest stays raw bytes
        };
        if at + size > len {
            break;
        }
        match ty {
            Some(ty) => out.push((name, Slot::Plain { ty, at: base + at })),
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

/// Writes `view` as LAS 1.4 (or LAZ when `compressed`) to `out` and returns `out`, flushed;
/// `path` names the file in errors.
pub fn write_to<W: Write + Seek + Send + Sync + 'static>(
    out: W,
    view: &TableView<'_>,
    compressed: bool,
    path: &Path,
) -> Result<W, DataError> {
    view.check(path)?;
    let plan = Plan::new(view, compressed, path)?;
    let mut out = if compressed {
        write_laz(out, view, &plan, path)?
    } else {
        write_las(out, view, &plan, path)?
    };
    out.flush().map_err(|e| DataError::io(path, e))?;
    Ok(out)
}

fn invalid(path: &Path, what: String) -> DataError {
    DataError::InvalidOutput {
        path: path.to_path_buf(),
        what,
    }
}

/// The property `name` of `view`.
fn property<'a>(view: &TableView<'a>, name: &str) -> Option<&'a Column> {
    view.properties
        .iter()
        .find(|p| p.name == name)
        .map(|p| &p.values)
}

/// How the points of a table become LAS records.
struct Plan<'a> {
    /// The header, without point counts and bounds.
    header: Header,
    record_len: usize,
    /// A record with every field at its default: one return of one, everything else zero.
    template: Vec<u8>,
    /// The fields after x, y, z that a property fills, with that property.
    fields: Vec<(Slot, Source<'a>)>,
    /// The return number bit field (byte, shift, width) when a property fills it, counted
    /// per record for the header; `None` when every record keeps the template's return 1.
    counted_returns: Option<(usize, u8, u8)>,
}

impl<'a> Plan<'a> {
    fn new(view: &TableView<'a>, compressed: bool, path: &Path) -> Result<Self, DataError> {
        let mut format = LasFormat::new(if property(view, "nir").is_some() {
            8
        } else if ["red", "green", "blue"]
            .iter()
            .all(|c| property(view, c).is_some())
        {
            7
        } else {
            6
        })
        .map_err(|e| las_error(path, e))?;
        let (standard, base_len) = fields(&format);
        let extras = extra_properties(view, &standard, path)?;
        let mut fields: Vec<(Slot, Source<'a>)> = standard
            .iter()
            .filter_map(|&(name, slot)| Some((slot, Source::of(view, name)?)))
            .collect();
        let mut at = base_len;
        for &(_, column) in &extras {
            let ty = column.scalar_type();
            let source = Source {
                column,
                conversion: Conversion::None,
            };
            fields.push((Slot::Plain { ty, at }, source));
            at += ty.size();
        }
        format.extra_bytes = u16::try_from(at - base_len)
            .map_err(|_| invalid(path, format!("{} extra bytes per point", at - base_len)))?;
        format.is_compressed = compressed;
        let mut builder = Builder::default();
        builder.version = Version::new(1, 4);
        builder.point_format = format;
        builder.transforms = transforms(view);
        builder.generating_software = "BoundED-rs".into();
        if !extras.is_empty() {
            builder.vlrs.push(extra_bytes_vlr(&extras));
        }
        let header = builder.into_header().map_err(|e| las_error(path, e))?;
        let default = |name: &str| standard.iter().find(|(n, _)| *n == name).map(|f| f.1);
        let (
            Some(
                return_number @ Slot::Bits {
                    at: return_at,
                    shift,
                    width,
                    ..
                },
            ),
            Some(number_of_returns),
        ) = (default("return_number"), default("number_of_returns"))
        else {
            unreachable!("every point format has return numbers in a bit field")
        };
        let mut template = vec![0u8; usize::from(format.len())];
        return_number.put(1.0, &mut template);
        number_of_returns.put(1.0, &mut template);
        Ok(Plan {
            header,
            record_len: template.len(),
            template,
            fields,
            counted_returns: Source::of(view, "return_number").map(|_| (return_at, shift, width)),
        })
    }

    /// Encodes points `first..` into `records` (whole records) and returns their statistics.
    fn encode(
        &self,
        view: &TableView<'_>,
        first: usize,
        records: &mut [u8],
    ) -> Result<Stats, String> {
        let stride = self.record_len;
        // The template into the first record, then doubling copies: one memcpy per
        // record would be a call per 48 bytes.
        records[..stride].copy_from_slice(&self.template);
        let mut filled = stride;
        while filled < records.len() {
            let len = filled.min(records.len() - filled);
            records.copy_within(..len, filled);
            filled += len;
        }
        let (min, max) = encode_positions(view, first, records, stride, self.header.transforms())?;
        for (slot, source) in &self.fields {
            source.encode(*slot, first, records, stride);
        }
        let count = (records.len() / stride) as u64;
        let mut by_return = [0; 16];
        match self.counted_returns {
            Some((at, shift, width)) => {
                for record in records.chunks_exact(stride) {
                    by_return[usize::from(bits_of(record[at], shift, width))] += 1;
                }
            }
            None => by_return[1] = count,
        }
        Ok(Stats {
            count,
            min,
            max,
            by_return,
        })
    }
}

/// The properties of `view` that are not standard fields of a format with the `standard`
/// fields, with their Extra Bytes names.
fn extra_properties<'a>(
    view: &TableView<'a>,
    standard: &[(&str, Slot)],
    path: &Path,
) -> Result<Vec<(String, &'a Column)>, DataError> {
    let has_class = property(view, "class").is_some();
    let mut extras = Vec::new();
    for p in &view.properties {
        let standard_name = standard.iter().any(|(n, _)| *n == p.name)
            || matches!(p.name.as_str(), "class" | "scan_angle_rank");
        if p.name == "classification" && has_class {
            extras.push(("input_classification".into(), &p.values));
        } else if !standard_name {
            if p.name.len() > 32 {
                return Err(invalid(
                    path,
                    format!(
                        "property name '{}' is longer than the 32 bytes of a LAS Extra Bytes name",
                        p.name
                    ),
                ));
            }
            extras.push((p.name.clone(), &p.values));
        }
    }
    Ok(extras)
}

/// Where the values of a written field come from.
#[derive(Clone, Copy)]
struct Source<'a> {
    column: &'a Column,
    conversion: Conversion,
}

/// How property values become field values.
#[derive(Clone, Copy, PartialEq)]
enum Conversion {
    /// None: the value itself (`as` conversion when the types differ).
    None,
    /// BoundED class to LAS Classification code.
    ClassCode,
    /// 8-bit colour to LAS's 16 bits.
    Colour,
    /// Legacy scan angle rank (degrees) to LAS 1.4 units of 0.006 degrees.
    ScanAngle,
}

impl Conversion {
    fn apply(self, value: f64) -> f64 {
        match self {
            Conversion::None => value,
            Conversion::ClassCode => f64::from(class_code(value as u8)),
            Conversion::Colour => value * 257.0,
            Conversion::ScanAngle => (value / 0.006).round(),
        }
    }
}

impl<'a> Source<'a> {
    /// The property of `view` that fills the standard field `name`, if any.
    fn of(view: &TableView<'a>, name: &str) -> Option<Self> {
        let with = |column, conversion| Some(Source { column, conversion });
        let own = property(view, name);
        match (name, own) {
            ("classification", _) if property(view, "class").is_some() => {
                with(property(view, "class")?, Conversion::ClassCode)
            }
            ("scan_angle", None) => with(property(view, "scan_angle_rank")?, Conversion::ScanAngle),
            ("red" | "green" | "blue", Some(c)) if c.scalar_type() == ScalarType::U8 => {
                with(c, Conversion::Colour)
            }
            (_, Some(c)) => with(c, Conversion::None),
            (_, None) => None,
        }
    }

    /// Writes the values of points `first..` into the field `slot` of `records`: the
    /// annotated outputs' class codes and 8-bit colours through typed loops, any other
    /// conversion through `f64`.
    fn encode(self, slot: Slot, first: usize, records: &mut [u8], stride: usize) {
        let n = records.len() / stride;
        match (slot, self.conversion, self.column) {
            (Slot::Plain { ty, at }, Conversion::None, column) if ty == column.scalar_type() => {
                column.encode_strided(first, records, stride, at, Endian::Little);
            }
            (
                Slot::Plain {
                    ty: ScalarType::U8,
                    at,
                },
                Conversion::ClassCode,
                Column::U8(v),
            ) => {
                put_each(&v[first..first + n], records, stride, at, |c| {
                    [CLASS_CODES[usize::from(c)]]
                });
            }
            (
                Slot::Plain {
                    ty: ScalarType::U16,
                    at,
                },
                Conversion::Colour,
                Column::U8(v),
            ) => {
                put_each(&v[first..first + n], records, stride, at, |c| {
                    (u16::from(c) * 257).to_le_bytes()
                });
            }
            _ => self.column.for_each_f64(first, n, |k, v| {
                slot.put(self.conversion.apply(v), &mut records[k * stride..]);
            }),
        }
    }
}

/// Writes `f(value)` at byte `at` of each record of `stride` bytes of `records`, one record
/// per value.
fn put_each<T: Copy, const N: usize>(
    values: &[T],
    records: &mut [u8],
    stride: usize,
    at: usize,
    f: impl Fn(T) -> [u8; N],
) {
    for (record, &v) in records.chunks_exact_mut(stride).zip(values) {
        record[at..at + N].copy_from_slice(&f(v));
    }
}

/// What the header says about the records: their count, coordinate bounds (in scaled
/// integers) and count per return number.
#[derive(Debug, Clone, Copy)]
struct Stats {
    count: u64,
    min: [i32; 3],
    max: [i32; 3],
    by_return: [u64; 16],
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            count: 0,
            min: [i32::MAX; 3],
            max: [i32::MIN; 3],
            by_return: [0; 16],
        }
    }
}

impl Stats {
    fn merge(mut self, other: Stats) -> Self {
        self.count += other.count;
        for a in 0..3 {
            self.min[a] = self.min[a].min(other.min[a]);
            self.max[a] = self.max[a].max(other.max[a]);
        }
        for (n, m) in self.by_return.iter_mut().zip(other.by_return) {
            *n += m;
        }
        self
    }

    /// The raw form of `header` with these counts and bounds, as the las crate's writer
    /// sets them (legacy counts too while they fit; return number 0 is not counted).
    fn raw_header(&self, header: &Header) -> las::Result<las::raw::Header> {
        let mut raw = header.clone().into_raw()?;
        let by_return: [u64; 15] = std::array::from_fn(|k| self.by_return[k + 1]);
        raw.number_of_point_records = u32::try_from(self.count).unwrap_or(0);
        raw.number_of_points_by_return =
            std::array::from_fn(|k| u32::try_from(by_return[k]).unwrap_or(0));
        raw.large_file = Some(LargeFile {
            number_of_point_records: self.count,
            number_of_points_by_return: by_return,
        });
        if self.count > 0 {
            let t = header.transforms();
            let [x, y, z] = [t.x, t.y, t.z];
            [raw.min_x, raw.min_y, raw.min_z] = [
                x.direct(self.min[0]),
                y.direct(self.min[1]),
                z.direct(self.min[2]),
            ];
            [raw.max_x, raw.max_y, raw.max_z] = [
                x.direct(self.max[0]),
                y.direct(self.max[1]),
                z.direct(self.max[2]),
            ];
        }
        Ok(raw)
    }
}

/// Encodes the points of `view` block by block (each block in parallel tasks of [`TASK`]
/// records), hands each block to `sink` while the next one is encoded, and returns the
/// statistics of all records.
fn encode_blocks(
    view: &TableView<'_>,
    plan: &Plan<'_>,
    path: &Path,
    block_len: usize,
    mut sink: impl FnMut(&[u8]) -> Result<(), DataError> + Send,
) -> Result<Stats, DataError> {
    let stride = plan.record_len;
    let mut stats = Stats::default();
    let encode = |block: &mut [u8], first: usize| {
        let block_stats = block
            .par_chunks_mut(TASK * stride)
            .enumerate()
            .map(|(k, records)| plan.encode(view, first + k * TASK, records))
            .try_reduce(Stats::default, |a, b| Ok(a.merge(b)))
            .map_err(|what| invalid(path, what))?;
        stats = stats.merge(block_stats);
        Ok(())
    };
    pipelined(view.len(), block_len, stride, encode, |block, _| {
        sink(block)
    })?;
    Ok(stats)
}

/// Writes uncompressed LAS: header and VLRs, the records, then the header again with the
/// counts and bounds of the records (same size, so it overwrites the first one exactly).
fn write_las<W: Write + Seek + Send>(
    mut out: W,
    view: &TableView<'_>,
    plan: &Plan<'_>,
    path: &Path,
) -> Result<W, DataError> {
    let io = |e| DataError::io(path, e);
    let las = |e| las_error(path, e);
    plan.header.write_to(&mut out).map_err(las)?;
    let block_len = block_len(plan.record_len);
    let stats = encode_blocks(view, plan, path, block_len, |block| {
        out.write_all(block).map_err(io)
    })?;
    let raw = stats.raw_header(&plan.header).map_err(las)?;
    out.rewind().map_err(io)?;
    raw.write_to(&mut out).map_err(las)?;
    out.seek(SeekFrom::End(0)).map_err(io)?;
    Ok(out)
}

/// Writes LAZ through the las crate's writer, which compresses the records (chunks in
/// parallel) and counts them.
fn write_laz<W: Write + Seek + Send + Sync + 'static>(
    out: W,
    view: &TableView<'_>,
    plan: &Plan<'_>,
    path: &Path,
) -> Result<W, DataError> {
    let las = |e| las_error(path, e);
    let options = WriterOptions::default().with_laz_parallelism(LazParallelism::Yes);
    let mut writer = Writer::with_options(out, plan.header.clone(), options).map_err(las)?;
    encode_blocks(view, plan, path, laz_block_len(plan.record_len), |block| {
        let data = PointDataBuilder::new()
            .for_header(writer.header())
            .build_from_bytes(block.to_vec())
            .map_err(las)?;
        writer.write_points(&data).map_err(las)
    })?;
    writer.close().map_err(las)?;
    writer.into_inner().map_err(las)
}

/// The input's scale and offset, or for other clouds the bounding-box centre as offset and
/// the smallest power-of-ten scale not finer than a thousandth of the `f32` resolution.
fn transforms(view: &TableView<'_>) -> Vector<Transform> {
    let (scale, offset) = match view.position_type {
        PositionType::Scaled { scale, offset } => (scale, offset),
        _ => {
            let extent = view
                .cloud
                .points()
                .par_iter()
                .map(|p| p.map(f32::abs).into_iter().fold(0f32, f32::max))
                .reduce(|| 0f32, f32::max);
            // i32 covers +-2.1e9 steps: keep the largest offset below 1e9 steps.
            let exponent = (f64::from(extent).max(1e-3) / 1e9).log10().ceil();
            let s = 10f64.powf(exponent.max(-9.0));
            ([s; 3], view.cloud.origin())
        }
    };
    let t = |a: usize| Transform {
        scale: scale[a],
        offset: offset[a],
    };
    Vector {
        x: t(0),
        y: t(1),
        z: t(2),
    }
}

/// Writes the scaled integer coordinates of points `first..` into `records` and returns
/// their smallest and largest value per axis. The divisions run over runs of one axis (they
/// vectorise); the values match `((x - offset) / scale).round()` exactly, for `x` the exact
/// input position if the table keeps it, else `origin + offset from it`.
fn encode_positions(
    view: &TableView<'_>,
    first: usize,
    records: &mut [u8],
    stride: usize,
    t: &Vector<Transform>,
) -> Result<([i32; 3], [i32; 3]), String> {
    const RUN: usize = 256;
    let axes = [t.x, t.y, t.z];
    let origin = view.cloud.origin();
    let n = records.len() / stride;
    let points = &view.cloud.points()[first..first + n];
    let (mut min, mut max) = ([i32::MAX; 3], [i32::MIN; 3]);
    let (mut steps, mut exact) = ([0f64; RUN], [0f64; RUN]);
    for (run, (points, records)) in points
        .chunks(RUN)
        .zip(records.chunks_mut(RUN * stride))
        .enumerate()
    {
        for a in 0..3 {
            let (o, Transform { scale, offset }) = (origin[a], axes[a]);
            match view.exact_positions {
                Some(positions) => {
                    let exact = &mut exact[..points.len()];
                    positions.axis(a, first + run * RUN, exact);
                    for (s, x) in steps.iter_mut().zip(&*exact) {
                        *s = (x - offset) / scale;
                    }
                }
                None => {
                    for (s, p) in steps.iter_mut().zip(points) {
                        *s = (o + f64::from(p[a]) - offset) / scale;
                    }
                }
            }
            for (k, (record, &x)) in records.chunks_exact_mut(stride).zip(&steps).enumerate() {
                let v = round_i32(x).ok_or_else(|| {
                    format!(
                        "point {} does not fit the LAS scale {scale} and offset {offset}",
                        first + run * RUN + k
                    )
                })?;
                (min[a], max[a]) = (min[a].min(v), max[a].max(v));
                record[4 * a..4 * a + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    Ok((min, max))
}

/// `x.round()` (half away from zero) as an `i32`, or `None` when that is out of range or
/// `x` is NaN. Truncates and corrects instead of calling `round`: without SSE4.1, x86-64 has
/// no rounding instruction and `f64::round` is a libm call per coordinate.
fn round_i32(x: f64) -> Option<i32> {
    // Within this range the truncation and the remainder are exact (NaN is outside).
    if x.is_nan() || x.abs() >= 4e9 {
        return None;
    }
    let t = x as i64;
    let rest = x - t as f64;
    let rounded = if rest >= 0.5 {
        t + 1
    } else if rest <= -0.5 {
        t - 1
    } else {
        t
    };
    i32::try_from(rounded).ok()
}

/// LAS Classification code of a BoundED class code; other values pass through.
const fn class_code(class: u8) -> u8 {
    match class {
        0 => CODE_NON_EDGE,
        1 => CODE_SHARP,
        2 => CODE_BOUNDARY,
        other => other,
    }
}

/// [`class_code`] of every `u8`, for a table look-up per point.
const CLASS_CODES: [u8; 256] = {
    let mut codes = [0u8; 256];
    let mut class = 0;
    while class < 256 {
        codes[class] = class_code(class as u8);
        class += 1;
    }
    codes
};

/// The Extra Bytes VLR (user `LASF_Spec`, record 4) describing `extras` in order.
fn extra_bytes_vlr(extras: &[(String, &Column)]) -> Vlr {
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

#[cfg(test)]
mod tests {
    use super::*;
    use bounded_geom::PointCloud;
    use std::io::Cursor;

    fn write_bytes(table: &PointTable, compressed: bool) -> Vec<u8> {
        write_to(
            Cursor::new(Vec::new()),
            &table.view(),
            compressed,
            Path::new("t.las"),
        )
        .unwrap()
        .into_inner()
    }

    fn sample() -> PointTable {
        let cloud = PointCloud::from_f64(&[
            [500_000.125, 5_403_150.5, 12.25],
            [500_010.0, 5_403_160.0, 13.0],
            [500_005.5, 5_403_155.75, 12.5],
        ])
        .unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("class", Column::U8(vec![0, 1, 2])));
        t.set_property(Property::new("p_sharp", Column::F32(vec![0.1, 0.9, 0.25])));
        t.set_property(Property::new("red", Column::U8(vec![255, 0, 160])));
        t.set_property(Property::new("green", Column::U8(vec![0, 255, 160])));
        t.set_property(Property::new("blue", Column::U8(vec![0, 0, 160])));
        t.set_property(Property::new("offset", Column::I16(vec![-5, 0, 5])));
        t
    }

    #[test]
    fn round_trip_las_and_laz_with_codes_and_extra_bytes() {
        let t = sample();
        for compressed in [false, true] {
            let bytes = write_bytes(&t, compressed);
            let back = read_from(Cursor::new(bytes), Path::new("t.las")).unwrap();
            for i in 0..3 {
                let (a, b) = (t.cloud.position_f64(i), back.cloud.position_f64(i));
                assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6), "{a:?} {b:?}");
            }
            let codes = [CODE_NON_EDGE, CODE_SHARP, CODE_BOUNDARY];
            assert_eq!(
                back.property("classification"),
                Some(&Column::U8(codes.to_vec()))
            );
            assert_eq!(back.property("intensity"), t.property("intensity"));
            assert_eq!(back.property("p_sharp"), t.property("p_sharp"));
            assert_eq!(back.property("offset"), t.property("offset"));
            assert_eq!(
                back.property("red"),
                Some(&Column::U16(vec![65535, 0, 160 * 257]))
            );
            assert_eq!(
                back.property("return_number"),
                Some(&Column::U8(vec![1; 3]))
            );
        }
    }

    #[test]
    fn laz_of_several_chunks_reads_back_like_las() {
        // Two whole chunks of 50,000 points, compressed side by side, and a partial third.
        let n = 130_000;
        let cloud = PointCloud::from_iter_f64(n, |i| {
            [i as f64 * 0.01, (i % 977) as f64 * 0.02, (i % 13) as f64]
        })
        .unwrap();
        let mut t = PointTable::new(cloud);
        let intensity = (0..n).map(|i| (i * 7919 % 65536) as u16).collect();
        t.set_property(Property::new("intensity", Column::U16(intensity)));
        let read = |compressed| {
            read_from(Cursor::new(write_bytes(&t, compressed)), Path::new("t.las")).unwrap()
        };
        let (las, laz) = (read(false), read(true));
        assert_eq!(laz.property("intensity"), t.property("intensity"));
        assert_eq!(las, laz);
    }

    #[test]
    fn las_in_las_out_keeps_fields_and_scale() {
        // A legacy format-3 file written by the las crate itself.
        let mut builder = Builder::from((1, 2));
        builder.point_format = LasFormat::new(3).unwrap();
        builder.transforms = Vector {
            x: Transform {
                scale: 0.01,
                offset: 100.0,
            },
            y: Transform {
                scale: 0.01,
                offset: 200.0,
            },
            z: Transform {
                scale: 0.001,
                offset: 0.0,
            },
        };
        let header = builder.into_header().unwrap();
        let mut writer = Writer::new(Cursor::new(Vec::new()), header).unwrap();
        for i in 0..4u8 {
            let point = las::Point {
                x: 100.0 + f64::from(i),
                y: 200.5,
                z: 0.125 * f64::from(i),
                intensity: 10 * u16::from(i),
                return_number: 1 + i % 2,
                number_of_returns: 2,
                classification: las::point::Classification::new(2 + i).unwrap(),
                is_withheld: i == 3,
                scan_angle: -f32::from(i),
                user_data: 7,
                point_source_id: 9,
                gps_time: Some(1e6 + f64::from(i)),
                color: Some(las::Color::new(1, 2, 3)),
                ..Default::default()
            };
            writer.write_point(point).unwrap();
        }
        let bytes = writer.into_inner().unwrap().into_inner();
        let first = read_from(Cursor::new(bytes), Path::new("in.las")).unwrap();
        assert_eq!(
            first.position_type,
            PositionType::Scaled {
                scale: [0.01, 0.01, 0.001],
                offset: [100.0, 200.0, 0.0]
            }
        );
        assert_eq!(
            first.property("classification"),
            Some(&Column::U8(vec![2, 3, 4, 5]))
        );
        assert_eq!(
            first.property("withheld"),
            Some(&Column::U8(vec![0, 0, 0, 1]))
        );
        assert_eq!(first.property("synthetic"), None);
        assert_eq!(
            first.property("scan_angle_rank"),
            Some(&Column::I8(vec![0, -1, -2, -3]))
        );
        let second = read_from(
            Cursor::new(write_bytes(&first, false)),
            Path::new("out.las"),
        )
        .unwrap();
        assert_eq!(second.position_type, first.position_type);
        assert_eq!(second.cloud, first.cloud);
        for p in &first.properties {
            if p.name != "scan_angle_rank" {
                assert_eq!(second.property(&p.name), Some(&p.values), "{}", p.name);
            }
        }
        // Legacy whole degrees become LAS 1.4 units of 0.006 degrees.
        assert_eq!(
            second.property("scan_angle"),
            Some(&Column::I16(vec![0, -167, -333, -500]))
        );
    }

    #[test]
    fn malformed_files_give_named_errors() {
        let bytes = write_bytes(&sample(), false);
        let cut = read_from(
            Cursor::new(bytes[..bytes.len() - 5].to_vec()),
            Path::new("bad.las"),
        );
        let msg = cut.unwrap_err().to_string();
        assert!(
            msg.starts_with("bad.las: LAS: point data ends within point 2 of 3"),
            "{msg}"
        );
        let msg = read_from(Cursor::new(b"LASX".to_vec()), Path::new("bad.las"))
            .unwrap_err()
            .to_string();
        assert!(msg.starts_with("bad.las: LAS: "), "{msg}");
    }

    #[test]
    fn an_extended_vlr_longer_than_the_file_fails_before_allocating() {
        let mut bytes = write_bytes(&sample(), false);
        let start = bytes.len() as u64;
        // LAS 1.4 header: start of the first EVLR (u64) at 235, their number (u32) at 243.
        bytes[235..243].copy_from_slice(&start.to_le_bytes());
        bytes[243..247].copy_from_slice(&1u32.to_le_bytes());
        let mut evlr = [0u8; 60];
        evlr[20..28].copy_from_slice(&0xFFFF_FF00u64.to_le_bytes());
        bytes.extend_from_slice(&evlr);
        let msg = read_from(Cursor::new(bytes), Path::new("evlr.las"))
            .unwrap_err()
            .to_string();
        let expected = "evlr.las: LAS: extended VLR 0 claims 4294967040 bytes, past the end";
        assert!(msg.starts_with(expected), "{msg}");
    }

    #[test]
    fn a_point_count_beyond_the_file_fails_early() {
        for (compressed, name) in [(false, "bad.las"), (true, "bad.laz")] {
            let mut bytes = write_bytes(&sample(), compressed);
            // The legacy point count, which readers take first when it is not zero.
            bytes[107..111].copy_from_slice(&u32::MAX.to_le_bytes());
            let msg = read_from(Cursor::new(bytes), Path::new(name))
                .unwrap_err()
                .to_string();
            let at = if compressed { 0 } else { 3 };
            let expected = format!(
                "{name}: LAS: point data ends within point {at} of {}",
                u32::MAX
            );
            assert!(msg.starts_with(&expected), "{msg}");
        }
    }

    /// Extra Bytes of the test files: a `u16` then an `f32`.
    const EXTRAS: [(&str, ScalarType); 2] = [("a", ScalarType::U16), ("b", ScalarType::F32)];

    /// Reads `bytes` with [`read_from`] and with the las crate and checks that every field of
    /// every point agrees (the Extra Bytes laid out as `extras`); returns the table.
    fn assert_agrees_with_las_crate(bytes: &[u8], extras: &[(&str, ScalarType)]) -> PointTable {
        let table = read_from(Cursor::new(bytes.to_vec()), Path::new("t.las")).unwrap();
        let mut reader = Reader::new(Cursor::new(bytes.to_vec())).unwrap();
        let extended = reader.header().point_format().is_extended;
        let data = reader.read_all().unwrap();
        let points: Vec<las::Point> = data.points().map(Result::unwrap).collect();
        assert_eq!(points.len(), table.len());
        let value = |name: &str, i: usize| table.property(name).map(|c| c.get_f64(i));
        for (i, p) in points.iter().enumerate() {
            let at = table.cloud.position_f64(i);
            for (a, b) in at.into_iter().zip([p.x, p.y, p.z]) {
                assert!((a - b).abs() < 1e-6, "point {i}: {at:?} {p:?}");
            }
            let angle = if extended {
                ("scan_angle", (f64::from(p.scan_angle) / 0.006).round())
            } else {
                ("scan_angle_rank", f64::from(p.scan_angle))
            };
            let mut expected = vec![
                ("intensity", f64::from(p.intensity)),
                ("return_number", f64::from(p.return_number)),
                ("number_of_returns", f64::from(p.number_of_returns)),
                ("classification", f64::from(u8::from(p.classification))),
                ("user_data", f64::from(p.user_data)),
                ("point_source_id", f64::from(p.point_source_id)),
                angle,
            ];
            expected.extend(p.gps_time.map(|t| ("gps_time", t)));
            if let Some(c) = p.color {
                expected.extend(
                    [("red", c.red), ("green", c.green), ("blue", c.blue)]
                        .map(|(n, v)| (n, f64::from(v))),
                );
            }
            expected.extend(p.nir.map(|n| ("nir", f64::from(n))));
            let mut at = 0;
            for &(name, ty) in extras {
                let mut column = Column::with_capacity(ty, 1);
                let bytes = &p.extra_bytes[at..at + ty.size()];
                column.decode_strided(bytes, ty.size(), 0, Endian::Little);
                expected.push((name, column.get_f64(0)));
                at += ty.size();
            }
            for (name, v) in expected {
                assert_eq!(value(name, i), Some(v), "{name} of point {i}");
            }
            let flags = [
                ("synthetic", p.is_synthetic),
                ("key_point", p.is_key_point),
                ("withheld", p.is_withheld),
                ("overlap", p.is_overlap && extended),
                ("edge_of_flight_line", p.is_edge_of_flight_line),
                (
                    "scan_direction",
                    p.scan_direction == las::point::ScanDirection::LeftToRight,
                ),
            ];
            for (name, set) in flags {
                let v = value(name, i).unwrap_or(0.0);
                assert_eq!(v, f64::from(u8::from(set)), "{name} of point {i}");
            }
            let channel = value("scanner_channel", i).unwrap_or(0.0);
            assert_eq!(
                channel,
                f64::from(p.scanner_channel),
                "channel of point {i}"
            );
        }
        table
    }

    /// A point of `format` whose fields all vary with `i`.
    fn las_point(format: &LasFormat, i: u8) -> las::Point {
        let extended = format.is_extended;
        let mut extra_bytes = (300 * u16::from(i)).to_le_bytes().to_vec();
        extra_bytes.extend((0.5 - f32::from(i)).to_le_bytes());
        las::Point {
            x: 100.0 + f64::from(i),
            y: 200.5 - f64::from(i),
            z: 0.125 * f64::from(i),
            intensity: 1000 * u16::from(i),
            return_number: 1 + i % if extended { 15 } else { 7 },
            number_of_returns: if extended { 15 } else { 7 },
            scan_direction: if i.is_multiple_of(2) {
                las::point::ScanDirection::LeftToRight
            } else {
                las::point::ScanDirection::RightToLeft
            },
            is_edge_of_flight_line: i.is_multiple_of(3),
            classification: las::point::Classification::new(2 + i).unwrap(),
            is_synthetic: i == 1,
            is_key_point: i == 2,
            is_withheld: i == 3,
            is_overlap: extended && i == 4,
            scanner_channel: if extended { i % 4 } else { 0 },
            scan_angle: if extended {
                -0.006 * 7.0 * f32::from(i)
            } else {
                -f32::from(i)
            },
            user_data: 7 + i,
            point_source_id: 9 * u16::from(i),
            gps_time: format.has_gps_time.then(|| 1e6 + f64::from(i)),
            color: format
                .has_color
                .then(|| las::Color::new(u16::from(i), 2, 65535)),
            nir: format.has_nir.then(|| 40_000 + u16::from(i)),
            extra_bytes,
            ..Default::default()
        }
    }

    #[test]
    fn fast_rounding_and_cloud_match_the_general_ones() {
        let edges = [i32::MIN, i32::MAX].map(f64::from);
        let mut xs = vec![
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.49999999999999994,
            -7.25,
            1e12,
            f64::NAN,
        ];
        xs.extend(
            edges
                .iter()
                .flat_map(|&e| [e, e - 0.5, e + 0.5, e - 0.49, e + 0.49]),
        );
        for x in xs {
            let r = x.round();
            let expected = (f64::from(i32::MIN)..=f64::from(i32::MAX))
                .contains(&r)
                .then_some(r as i32);
            assert_eq!(round_i32(x), expected, "{x}");
        }
        let xyz = vec![[3, -7, i32::MAX], [-12, 5, 0], [1, 1, i32::MIN]];
        for scale in [0.01, -0.003] {
            let axis = Transform { scale, offset: 5e5 };
            let t = Vector {
                x: axis,
                y: axis,
                z: axis,
            };
            let general = PointCloud::from_iter_f64(3, |i| xyz[i].map(|v| axis.direct(v)));
            assert_eq!(cloud_of(xyz.clone(), &t).unwrap().0, general.unwrap());
        }
    }

    #[test]
    fn small_blocks_read_like_one_block_with_a_flag_first_set_in_a_later_block() {
        for compressed in [false, true] {
            let mut builder = Builder::from((1, 4));
            builder.point_format = LasFormat::new(6).unwrap();
            builder.point_format.is_compressed = compressed;
            let mut writer =
                Writer::new(Cursor::new(Vec::new()), builder.into_header().unwrap()).unwrap();
            for i in 0..10u8 {
                let point = las::Point {
                    x: f64::from(i),
                    y: -0.5 * f64::from(i),
                    z: 1e3,
                    is_synthetic: i == 7,
                    return_number: 1,
                    number_of_returns: 1,
                    gps_time: Some(f64::from(i)),
                    ..Default::default()
                };
                writer.write_point(point).unwrap();
            }
            let bytes = writer.into_inner().unwrap().into_inner();
            let read = |max_block| {
                read_in_blocks(Cursor::new(bytes.clone()), Path::new("t.las"), max_block).unwrap()
            };
            // Blocks of 3 records: the flag is first set in the third block.
            let (small, whole) = (read(3), read(BLOCK));
            let mut synthetic = vec![0u8; 10];
            synthetic[7] = 1;
            assert_eq!(small.property("synthetic"), Some(&Column::U8(synthetic)));
            assert_eq!(small.property("withheld"), None);
            assert_eq!(small, whole);
            assert_eq!(small.cloud.position_f64(9), [9.0, -4.5, 1e3]);
        }
    }

    #[test]
    fn files_of_the_las_crate_read_the_same_in_every_format() {
        let a = Column::U16(Vec::new());
        let b = Column::F32(Vec::new());
        for id in [0, 1, 2, 3, 6, 7, 8] {
            let mut builder = Builder::from((1, 4));
            builder.point_format = LasFormat::new(id).unwrap();
            builder.point_format.extra_bytes = 6;
            builder
                .vlrs
                .push(extra_bytes_vlr(&[("a".into(), &a), ("b".into(), &b)]));
            let format = builder.point_format;
            let mut writer =
                Writer::new(Cursor::new(Vec::new()), builder.into_header().unwrap()).unwrap();
            for i in 0..6 {
                writer.write_point(las_point(&format, i)).unwrap();
            }
            let bytes = writer.into_inner().unwrap().into_inner();
            let table = assert_agrees_with_las_crate(&bytes, &EXTRAS);
            assert!(table.property("synthetic").is_some(), "format {id}");
        }
    }

    #[test]
    fn files_of_the_fast_writer_read_the_same_with_the_las_crate() {
        let mut t = sample();
        let column = |v: [u8; 3]| Column::U8(v.to_vec());
        t.set_property(Property::new("return_number", column([1, 2, 15])));
        t.set_property(Property::new("number_of_returns", column([2, 2, 15])));
        t.set_property(Property::new("withheld", column([0, 1, 0])));
        t.set_property(Property::new("scanner_channel", column([3, 0, 1])));
        t.set_property(Property::new("gps_time", Column::F64(vec![1.5, -2.0, 1e9])));
        let extras = [("p_sharp", ScalarType::F32), ("offset", ScalarType::I16)];
        // Format 6 also without return numbers: the header counts them all as return 1.
        for (format, returns) in [(6, true), (6, false), (7, true), (8, true)] {
            let mut t = t.clone();
            if !returns {
                t.properties
                    .retain(|p| !p.name.ends_with("returns") && p.name != "return_number");
            }
            if format == 6 {
                t.properties
                    .retain(|p| !["red", "green", "blue"].contains(&p.name.as_str()));
            }
            if format == 8 {
                t.set_property(Property::new("nir", Column::U16(vec![0, 1, 65535])));
            }
            let las = write_bytes(&t, false);
            let header = |bytes: &[u8]| Reader::new(Cursor::new(bytes.to_vec())).unwrap();
            let (mut fast, mut laz) = (header(&las), header(&write_bytes(&t, true)));
            assert_eq!(fast.header().point_format().to_u8().unwrap(), format);
            assert_eq!(fast.header().number_of_points(), 3);
            let first_returns = fast.header().number_of_points_by_return(1);
            assert_eq!(first_returns, Some(if returns { 1 } else { 3 }));
            for r in 1..=15 {
                let counts = [fast.header(), laz.header()].map(|h| h.number_of_points_by_return(r));
                assert_eq!(counts[0], counts[1], "return {r}");
            }
            let (b, c) = (fast.header().bounds(), laz.header().bounds());
            let step = 1e-3;
            for (u, v) in [(b.min.x, c.min.x), (b.max.y, c.max.y), (b.min.z, c.min.z)] {
                assert!((u - v).abs() <= step, "{b:?} {c:?}");
            }
            let records = |r: &mut Reader| r.read_all().unwrap().raw_bytes().to_vec();
            assert_eq!(records(&mut fast), records(&mut laz));
            let back = assert_agrees_with_las_crate(&las, &extras);
            assert_eq!(back.property("withheld"), t.property("withheld"));
            assert_eq!(back.property("gps_time"), t.property("gps_time"));
        }
    }
}
