//! Reading: the header through the `las` crate, the records in blocks decoded in parallel.

use super::header::InputHeader;
use super::las_error;
use super::layout::*;
use crate::DataError;
use crate::records::{BLOCK, block_len, pipelined, truncated};
use crate::table::{
    Column, Endian, ExactCloud, ExactPositions, PointTable, PositionType, Property,
};
use las::{Header, LazParallelism, PointDataBuilder, Reader, ReaderOptions, Transform, Vector};
use rayon::prelude::*;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
/// Reads a LAS or LAZ file from `input`; `path` names it in errors.
pub fn read_from<R: Read + Seek + Send + Sync + 'static>(
    input: R,
    path: &Path,
) -> Result<PointTable, DataError> {
    read_in_blocks(input, path, BLOCK)
}

/// [`read_from`] with at most `max_block` records per block (tests set it small to cross
/// block boundaries with a few points).
pub(super) fn read_in_blocks<R: Read + Seek + Send + Sync + 'static>(
    input: R,
    path: &Path,
    max_block: usize,
) -> Result<PointTable, DataError> {
    let mut file = Opened::new(input, path, max_block)?;
    let blocks = file.blocks;
    let compressed = file.header.point_format().is_compressed;
    let capacity = if compressed { 0 } else { blocks.total };
    let decoded = file.decode(0, blocks, capacity)?;
    file.table(decoded, false)
}

/// Reads the LAS or LAZ file at `path` in consecutive tables of at most `chunk` points, each
/// handed to `sink` with the index of its first point: a file too large to hold, read in
/// bounded memory. Every table has the file's header records and properties, the optional
/// flags whether or not its points set them (every table has the same columns, so that their
/// outputs join into one file), and the exact positions of the file
/// (`TableView::position`). Returns the number of points read.
pub fn read_chunks<E: From<DataError>>(
    path: &Path,
    chunk: usize,
    mut sink: impl FnMut(usize, PointTable) -> Result<(), E>,
) -> Result<usize, E> {
    let input = std::fs::File::open(path).map_err(|e| DataError::io(path, e))?;
    let input = std::io::BufReader::with_capacity(1 << 20, input);
    let mut file = Opened::new(input, path, BLOCK)?;
    let total = file.blocks.total;
    let mut first = 0;
    while first < total {
        let n = chunk.max(1).min(total - first);
        let blocks = Blocks {
            total: n,
            ..file.blocks
        };
        let decoded = file.decode(first, blocks, n)?;
        sink(first, file.table(decoded, true)?)?;
        first += n;
    }
    Ok(total)
}

/// A LAS or LAZ file whose header is read and checked, positioned at its first record.
struct Opened<'p, R: Read + Seek + Send + Sync + 'static> {
    path: &'p Path,
    header: Header,
    names: Vec<String>,
    slots: Vec<Slot>,
    blocks: Blocks,
    records: Records<R>,
}

/// Where the records come from.
enum Records<R: Read + Seek + Send + Sync + 'static> {
    /// The bytes of an uncompressed file.
    Las(LegacyCount<R>),
    /// The sequential LAZ decompressor, and its buffer.
    Laz(Box<Reader>, las::PointData),
}

impl<'p, R: Read + Seek + Send + Sync + 'static> Opened<'p, R> {
    fn new(mut input: R, path: &'p Path, max_block: usize) -> Result<Self, DataError> {
        let raw = check_declared_sizes(&mut input, path)?;
        // LAS 1.4: the 64-bit count, also where the legacy one differs (see the module docs).
        let zero_legacy = raw.large_file.is_some_and(|l| {
            l.number_of_point_records != 0
                && l.number_of_point_records != u64::from(raw.number_of_point_records)
        });
        let mut input = LegacyCount {
            inner: input,
            at: 0,
            zero: zero_legacy,
        };
        let header = Header::new(&mut input).map_err(|e| las_error(path, e))?;
        let compressed = header.point_format().is_compressed;
        if compressed {
            check_chunk_table(&mut input, &header, &raw, path)?;
            check_layer_sizes(&mut input, &header, &raw, path)?;
        }
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
        let records = if compressed {
            laz_records(input, path)?
        } else {
            las_records(input, blocks, path)?
        };
        Ok(Self {
            path,
            header,
            names,
            slots,
            blocks,
            records,
        })
    }

    /// Decodes the next `blocks.total` records, the file's from `first` on, with room for
    /// `capacity` in each column.
    fn decode(
        &mut self,
        first: usize,
        blocks: Blocks,
        capacity: usize,
    ) -> Result<Decoded, DataError> {
        let (path, total) = (self.path, self.blocks.total);
        let record_len = blocks.record_len;
        let records = &mut self.records;
        decode_blocks(blocks, capacity, &self.slots, |block, at| {
            records.fill(block, first + at, total, record_len, path)
        })
    }

    /// The table of `decoded`: with `every_column`, the optional flags too where no point
    /// sets them.
    fn table(&self, mut decoded: Decoded, every_column: bool) -> Result<PointTable, DataError> {
        if every_column {
            let n = decoded.xyz.len();
            for column in &mut decoded.columns {
                if let Column::U8(v) = column {
                    v.resize(n, 0);
                }
            }
        }
        let transforms = self.header.transforms();
        let names = self.names.clone();
        let mut table = into_table(transforms, names, &self.slots, decoded, self.path)?;
        let input = InputHeader::of(&self.header).map_err(|e| las_error(self.path, e))?;
        apply_scaling(&mut table.properties, &input.descriptors);
        table.las_header = Some(input);
        Ok(table)
    }
}

impl<R: Read + Seek + Send + Sync + 'static> Records<R> {
    /// Fills `block` with the records from `first` on (of `total`, for errors).
    fn fill(
        &mut self,
        block: &mut [u8],
        first: usize,
        total: usize,
        record_len: usize,
        path: &Path,
    ) -> Result<(), DataError> {
        match self {
            Records::Las(input) => input.read_exact(block).map_err(|e| {
                let what = format!("LAS: point data ends within point {first} of {total}");
                truncated(path, what, e)
            }),
            Records::Laz(reader, data) => {
                let ends = |what: String| {
                    let what =
                        format!("LAS: point data ends within point {first} of {total}{what}");
                    DataError::malformed(path, what)
                };
                // The crate's arithmetic decoder indexes its tables with values from the
                // stream and panics on some corrupt streams (found by the `laz` fuzz target):
                // a panic of this call, and only of this call, becomes an error naming the
                // file.
                let records = (block.len() / record_len) as u64;
                let filled = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    reader.fill_points(records, data)
                }));
                match filled {
                    Ok(filled) => filled.map_err(|e| ends(format!(": {e}")))?,
                    Err(panic) => {
                        let why = (panic.downcast_ref::<String>().map(String::as_str))
                            .or_else(|| panic.downcast_ref::<&str>().copied())
                            .unwrap_or("no message");
                        let what = format!(
                            "LAZ: the compressed point data is corrupt (the laz decoder failed: {why})"
                        );
                        return Err(DataError::malformed(path, what));
                    }
                };
                let bytes = data.raw_bytes();
                if bytes.len() != block.len() {
                    return Err(ends(String::new()));
                }
                block.copy_from_slice(bytes);
                Ok(())
            }
        }
    }
}

/// A LAS file read with its legacy point count (the `u32` at byte 107) as 0 when `zero`, so
/// that the las crate takes the LAS 1.4 64-bit count instead.
struct LegacyCount<R> {
    inner: R,
    /// The position in `inner`.
    at: u64,
    zero: bool,
}

impl<R: Read> Read for LegacyCount<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if self.zero && self.at < 111 && self.at + n as u64 > 107 {
            for (k, b) in buf[..n].iter_mut().enumerate() {
                if (107..111).contains(&(self.at + k as u64)) {
                    *b = 0;
                }
            }
        }
        self.at += n as u64;
        Ok(n)
    }
}

impl<R: Seek> Seek for LegacyCount<R> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.at = self.inner.seek(to)?;
        Ok(self.at)
    }
}

/// Checks that every extended VLR fits in the file and that the point count times the record
/// length is a file size at all, then rewinds `input` and returns the raw
/// header: the las crate allocates an EVLR's stated length (up to 2^64 bytes) before reading
/// it, so a corrupt length must fail here, not exhaust memory (found by fuzzing).
fn check_declared_sizes(
    mut input: impl Read + Seek,
    path: &Path,
) -> Result<las::raw::Header, DataError> {
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
    // The las crate computes where the points end without overflow checks.
    let count = raw
        .large_file
        .map_or(0, |l| l.number_of_point_records)
        .max(u64::from(raw.number_of_point_records));
    let points_end = count
        .checked_mul(u64::from(raw.point_data_record_length))
        .and_then(|b| b.checked_add(u64::from(raw.offset_to_point_data)));
    if points_end.is_none() {
        return Err(DataError::malformed(
            path,
            format!(
                "LAS: {count} points of {} bytes each are more than any file holds",
                raw.point_data_record_length
            ),
        ));
    }
    input.rewind().map_err(io)?;
    Ok(raw)
}

/// Checks the chunk count of a chunked LAZ file's chunk table against the file, then rewinds
/// `input`: the laz crate reserves 16 bytes per declared chunk before reading them (2^32
/// chunks: 68 GB). Every chunk starts with its first point stored whole, so the point data
/// between its start (after the table's 8-byte offset) and the table holds at most its
/// length over the record length chunks. Where the table is, is found as the crate finds it:
/// the first 8 bytes of the point data, or the file's last 8 when those were never updated.
fn check_chunk_table(
    mut input: impl Read + Seek,
    header: &Header,
    raw: &las::raw::Header,
    path: &Path,
) -> Result<(), DataError> {
    let io = |e| DataError::io(path, e);
    // The LASzip VLR's compressor: 2 (point-wise) and 3 (layered) are chunked.
    let chunked = laszip_vlr(header)
        .and_then(|data| data.first_chunk::<2>().copied())
        .is_some_and(|c| u16::from_le_bytes(c) >= 2);
    if !chunked {
        return Ok(());
    }
    let data = u64::from(raw.offset_to_point_data);
    // Too short to hold an offset: the crate's own reading fails on it.
    let mut table = word_at(&mut input, SeekFrom::Start(data)).map_or(0, i64::from_le_bytes);
    if table <= data as i64 {
        table = word_at(&mut input, SeekFrom::End(-8)).map_or(0, i64::from_le_bytes);
    }
    // A table the crate cannot read, it does without (or names it).
    if let Some(word) = (table > data as i64)
        .then(|| word_at(&mut input, SeekFrom::Start(table as u64)))
        .flatten()
    {
        let chunks = u64::from(u32::from_le_bytes([word[4], word[5], word[6], word[7]]));
        let room = (table as u64).saturating_sub(data + 8);
        let record_len = u64::from(raw.point_data_record_length).max(1);
        if chunks > room / record_len {
            return Err(DataError::malformed(
                path,
                format!(
                    "LAZ: the chunk table declares {chunks} chunks, but the {room} bytes of point \
                     data before it hold at most {} (each starts with a whole {record_len}-byte \
                     point)",
                    room / record_len
                ),
            ));
        }
    }
    input.rewind().map_err(io)
}

/// Checks the layer sizes of every chunk of a layered LAZ file (LAS 1.4 point formats 6-10,
/// compressor 3) against the file, then rewinds `input`: at the start of each chunk the laz
/// crate reads the chunk's first point whole, its point count and one `u32` size per layer,
/// and resizes a buffer to every size before reading the layer (4 GB a layer from a 100-byte
/// file, found by the `laz` fuzz target). The chunks are walked as the crate's sequential
/// reader walks them, each right after the last one's layers; a chunk whose layers would
/// end past the end of the file is refused. Where the walk leaves the file, the crate's own
/// reading fails on it.
fn check_layer_sizes(
    mut input: impl Read + Seek,
    header: &Header,
    raw: &las::raw::Header,
    path: &Path,
) -> Result<(), DataError> {
    let io = |e| DataError::io(path, e);
    let Some(vlr) = laszip_vlr(header) else {
        return Ok(());
    };
    let u16_at = |at: usize| {
        vlr.get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let u32_at = |at: usize| {
        vlr.get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if u16_at(0) != Some(3) {
        return Ok(());
    }
    // Items from byte 34, six bytes each (type, size, version): the layers of each.
    let items = u16_at(32).unwrap_or(0) as usize;
    let mut layers = 0u64;
    for k in 0..items {
        let (Some(kind), Some(size)) = (u16_at(34 + 6 * k), u16_at(36 + 6 * k)) else {
            return Ok(());
        };
        layers += match kind {
            10 => 9,               // Point14: xy and channel, z, classification, ..., GPS time
            11 | 13 => 1,          // RGB14, Wavepacket14
            12 => 2,               // RGBNIR14: colour, near infrared
            14 => u64::from(size), // Byte14: one layer per byte
            _ => return Ok(()),    // not a layered item: the crate refuses the file
        };
    }
    let chunk_size = u64::from(u32_at(12).unwrap_or(u32::MAX));
    let file_len = input.seek(SeekFrom::End(0)).map_err(io)?;
    let record_len = u64::from(raw.point_data_record_length);
    // After the chunk table's offset.
    let mut at = u64::from(raw.offset_to_point_data) + 8;
    let mut left = header.number_of_points();
    let mut word = [0u8; 4];
    while left > 0 && at + record_len + 4 * (layers + 1) <= file_len {
        input.seek(SeekFrom::Start(at + record_len)).map_err(io)?;
        input.read_exact(&mut word).map_err(io)?;
        let count = u64::from(u32::from_le_bytes(word));
        let mut bytes = 0u64;
        for _ in 0..layers {
            input.read_exact(&mut word).map_err(io)?;
            bytes += u64::from(u32::from_le_bytes(word));
        }
        at += record_len + 4 * (layers + 1);
        if bytes > file_len - at {
            return Err(DataError::malformed(
                path,
                format!(
                    "LAZ: a chunk at byte {at} declares {bytes} bytes of layers, but the file \
                     ends {} bytes later",
                    file_len - at
                ),
            ));
        }
        at += bytes;
        // Fixed-size chunks hold `chunk_size` points; variable ones say how many.
        left = left.saturating_sub(if chunk_size == u64::from(u32::MAX) {
            count.max(1)
        } else {
            chunk_size.max(1)
        });
    }
    input.rewind().map_err(io)
}

/// The data of the LASzip VLR (compressor, coder, version, chunk size, items), if any.
fn laszip_vlr(header: &Header) -> Option<&[u8]> {
    (header.all_vlrs())
        .find(|v| v.user_id == "laszip encoded" && v.record_id == 22204)
        .map(|v| v.data.as_slice())
}

/// The 8 bytes at `at`, if the file holds them.
fn word_at(input: &mut (impl Read + Seek), at: SeekFrom) -> Option<[u8; 8]> {
    let mut word = [0u8; 8];
    input
        .seek(at)
        .and_then(|_| input.read_exact(&mut word))
        .ok()?;
    Some(word)
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
    let (names, slots): (Vec<String>, _) = standard
        .into_iter()
        .map(|(n, s)| (n.to_string(), s))
        .chain(extra_fields(header, base_len, extra_len))
        .unzip();
    crate::table::check_names(names.iter().map(String::as_str), path)?;
    Ok((names, slots, record_len))
}

/// The `total` uncompressed records that start at the position of `input`, after checking
/// that the file holds them: a corrupt count fails before anything is allocated.
fn las_records<R: Read + Seek + Send + Sync + 'static>(
    mut input: LegacyCount<R>,
    blocks: Blocks,
    path: &Path,
) -> Result<Records<R>, DataError> {
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
    Ok(Records::Las(input))
}

/// The records of the LAZ file `input`, decompressed as they are read. The columns grow with
/// the records actually decoded (the compressed size does not bound the count), so a corrupt
/// count ends in an error where the compressed data ends, not in a huge allocation.
fn laz_records<R: Read + Seek + Send + Sync + 'static>(
    mut input: LegacyCount<R>,
    path: &Path,
) -> Result<Records<R>, DataError> {
    input.rewind().map_err(|e| DataError::io(path, e))?;
    // The sequential decompressor: the parallel one cannot read files without a chunk table
    // and sizes its buffers from the table's counts before checking them against the file,
    // and here it would only compete with the column decoding for the same cores.
    let options = ReaderOptions::default().with_laz_parallelism(LazParallelism::No);
    let reader = Reader::with_options(input, options).map_err(|e| las_error(path, e))?;
    let data = PointDataBuilder::new().for_header(reader.header()).build();
    Ok(Records::Laz(Box::new(reader), data))
}

/// Installs a panic hook that stays quiet about the laz crate's decoder panics, which
/// [`read_from`] turns into errors naming the file, and hands every other panic to the hook
/// installed before it. For binaries: Rust's default hook prints a panic even when it is
/// caught, so a corrupt LAZ file would show a panic line above its clean error.
pub fn quiet_decoder_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            // The crate from the registry (`laz-0.13.0/src`) or its patched copy (`laz/src`).
            let in_laz = |file: &str| file.contains("/laz-") || file.contains("/laz/src/");
            if !info.location().is_some_and(|l| in_laz(l.file())) {
                previous(info)
            }
        }));
    });
}

/// How the point records of a file are split into blocks.
#[derive(Debug, Clone, Copy)]
pub(super) struct Blocks {
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
pub(super) fn coordinates(record: &[u8]) -> [i32; 3] {
    std::array::from_fn(|a| {
        let mut v = [0u8; 4];
        v.copy_from_slice(&record[4 * a..4 * a + 4]);
        i32::from_le_bytes(v)
    })
}

/// Appends the field `slot` of the records `bytes` (from record `first` on) to `column`; an
/// optional flag stays empty while no point sets it, as in most files.
pub(super) fn decode(column: &mut Column, slot: Slot, bytes: &[u8], stride: usize, first: usize) {
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
        las_header: None,
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
pub(super) fn cloud_of(
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
    if xyz.is_empty() {
        return Err(bounded_geom::GeomError::Empty);
    }
    let (lo, hi) = (absolute(lo), absolute(hi));
    if !lo.iter().chain(&hi).all(|c| c.is_finite()) {
        // Let the general constructor name the first non-finite point.
        let cloud = bounded_geom::PointCloud::from_iter_f64(xyz.len(), |i| absolute(xyz[i]))?;
        return Ok((cloud, None));
    }
    let frame = bounded_geom::Frame::of(lo, hi, xyz.len(), |i| absolute(xyz[i]));
    let local = move |p: [i32; 3]| frame.local(absolute(p));
    // What the writer makes of the offset on the same scale and offset.
    let returns = |p: [i32; 3]| {
        let q = frame.absolute(local(p));
        (0..3).all(|a| {
            let steps = (q[a] - axes[a].offset) / axes[a].scale;
            steps.round() == f64::from(p[a])
        })
    };
    let exact = (!xyz.par_iter().all(|&p| returns(p))).then(|| ExactPositions::Scaled {
        scale: axes.map(|t| t.scale),
        offset: axes.map(|t| t.offset),
        steps: xyz.clone(),
    });
    let points = xyz.into_iter().map(local).collect();
    Ok((bounded_geom::PointCloud::from_frame(frame, points)?, exact))
}
