//! Writing: LAS 1.4 records encoded in parallel blocks, LAZ through the `las` crate.

use super::header::{InputHeader, finish};
use super::las_error;
use super::layout::*;
use crate::DataError;
use crate::records::{block_len, pipelined};
use crate::table::{Column, Endian, PositionType, ScalarType, TableView};
use las::point::Format as LasFormat;
use las::raw::header::LargeFile;
use las::{
    Builder, Header, LazParallelism, PointDataBuilder, Transform, Vector, Version, Writer,
    WriterOptions,
};
use rayon::prelude::*;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;
/// Records encoded per parallel task when writing: small enough to spread a block over the
/// cores, large enough to amortise the per-field dispatch.
const TASK: usize = 4096;

/// Records per block when writing LAZ, at most 32 MiB: the LAZ compressor works on whole
/// chunks of 50,000 points in parallel, so a block spans ten of them to keep every core busy
/// (blocks of 64k records would hand it one chunk at a time).
fn laz_block_len(stride: usize) -> usize {
    ((32 << 20) / stride.max(1)).clamp(1, 1 << 19)
}

/// Writes `view` as LAS 1.4 (or LAZ when `compressed`) to `out` and returns `out`, flushed;
/// `path` names the file in errors.
pub fn write_to<W: Write + Seek + Send + Sync + 'static>(
    out: W,
    view: &TableView<'_>,
    compressed: bool,
    path: &Path,
) -> Result<W, DataError> {
    let mut writer = ChunkWriter::new(out, compressed, path);
    writer.write(view)?;
    writer.finish()
}

/// Writes one LAS 1.4 or LAZ file from consecutive views, each encoded as [`write_to`]
/// encodes a whole one: the chunks of a file too large to hold (see
/// [`read_chunks`](super::read_chunks)), in bounded memory. Every chunk must give the header
/// of the first (the same properties and position type, and the same input header).
pub struct ChunkWriter<'p, W: Write + Seek + Send + Sync + 'static> {
    path: &'p Path,
    compressed: bool,
    state: State<W>,
}

/// What a [`ChunkWriter`] has written.
enum State<W: Write + Seek + Send + Sync + 'static> {
    /// Nothing yet.
    Empty(W),
    /// The header and the records so far.
    Las {
        out: W,
        header: Header,
        input: Option<InputHeader>,
        stats: Stats,
    },
    /// The las crate's writer, which compresses and counts the records.
    Laz {
        writer: Box<Writer<FailOnce<W>>>,
        header: Header,
        input: Option<InputHeader>,
    },
    /// Taken by an error.
    Failed,
}

impl<'p, W: Write + Seek + Send + Sync + 'static> ChunkWriter<'p, W> {
    /// A writer of LAS (LAZ when `compressed`) to `out`; `path` names it in errors.
    pub fn new(out: W, compressed: bool, path: &'p Path) -> Self {
        Self {
            path,
            compressed,
            state: State::Empty(out),
        }
    }

    /// Appends the points of `view`.
    pub fn write(&mut self, view: &TableView<'_>) -> Result<(), DataError> {
        let path = self.path;
        let las = |e| las_error(path, e);
        view.check(path)?;
        let plan = Plan::new(view, self.compressed, path)?;
        self.state = match std::mem::replace(&mut self.state, State::Failed) {
            State::Empty(mut out) if !self.compressed => {
                plan.header.write_to(&mut out).map_err(las)?;
                State::Las {
                    out,
                    header: plan.header.clone(),
                    input: plan.input.cloned(),
                    stats: Stats::default(),
                }
            }
            State::Empty(out) => {
                let options = WriterOptions::default().with_laz_parallelism(LazParallelism::Yes);
                let out = FailOnce {
                    inner: out,
                    failed: false,
                };
                let writer =
                    Writer::with_options(out, plan.header.clone(), options).map_err(las)?;
                State::Laz {
                    writer: Box::new(writer),
                    header: plan.header.clone(),
                    input: plan.input.cloned(),
                }
            }
            State::Failed => return Err(invalid(path, "a previous chunk failed".into())),
            state => state,
        };
        let io = |e| DataError::io(path, e);
        match &mut self.state {
            State::Las {
                out, header, stats, ..
            } => {
                same_header(header, &plan.header, path)?;
                let block_len = block_len(plan.record_len);
                let chunk = encode_blocks(view, &plan, path, block_len, |block| {
                    out.write_all(block).map_err(io)
                })?;
                *stats = stats.merge(chunk);
            }
            State::Laz { writer, header, .. } => {
                same_header(header, &plan.header, path)?;
                encode_blocks(view, &plan, path, laz_block_len(plan.record_len), |block| {
                    let data = PointDataBuilder::new()
                        .for_header(writer.header())
                        .build_from_bytes(block.to_vec())
                        .map_err(las)?;
                    writer.write_points(&data).map_err(las)
                })?;
            }
            State::Empty(_) | State::Failed => unreachable!("set above"),
        }
        Ok(())
    }

    /// Finishes the file (for LAS: the EVLRs, then the header again with the counts and
    /// bounds of the records, the same size, so it overwrites the first one exactly) and
    /// returns `out`, flushed.
    pub fn finish(self) -> Result<W, DataError> {
        let path = self.path;
        let io = |e| DataError::io(path, e);
        let las = |e| las_error(path, e);
        fn vlrs(header: &Header) -> Vec<&las::Vlr> {
            header.all_vlrs().collect()
        }
        let mut out = match self.state {
            State::Las {
                mut out,
                header,
                input,
                stats,
            } => {
                let start_of_evlrs = out.stream_position().map_err(io)?;
                for evlr in header.evlrs() {
                    let raw = evlr.clone().into_raw(true).map_err(las)?;
                    raw.write_to(&mut out).map_err(las)?;
                }
                let mut raw = stats.raw_header(&header).map_err(las)?;
                if let Some(evlr) = raw.evlr.as_mut() {
                    evlr.start_of_first_evlr = start_of_evlrs;
                }
                finish(&mut raw, input.as_ref(), &vlrs(&header));
                out.rewind().map_err(io)?;
                raw.write_to(&mut out).map_err(las)?;
                out
            }
            State::Laz {
                mut writer,
                header,
                input,
            } => {
                writer.close().map_err(las)?;
                let mut raw = writer.header().clone().into_raw().map_err(las)?;
                finish(&mut raw, input.as_ref(), &vlrs(&header));
                let mut out = writer.into_inner().map_err(las)?.inner;
                out.rewind().map_err(io)?;
                raw.write_to(&mut out).map_err(las)?;
                out
            }
            State::Empty(_) => return Err(invalid(path, "no points were written".into())),
            State::Failed => return Err(invalid(path, "a chunk failed".into())),
        };
        out.seek(SeekFrom::End(0)).map_err(io)?;
        out.flush().map_err(io)?;
        Ok(out)
    }
}

/// Fails when a chunk's `header` differs from the first chunk's, `first`.
fn same_header(first: &Header, header: &Header, path: &Path) -> Result<(), DataError> {
    if first == header {
        return Ok(());
    }
    Err(invalid(
        path,
        "a chunk has other properties or positions than the first: its records would not \
         fit the header"
            .into(),
    ))
}

fn invalid(path: &Path, what: String) -> DataError {
    DataError::InvalidOutput {
        path: path.to_path_buf(),
        what,
    }
}

/// The property `name` of `view`.
pub(super) fn property<'a>(view: &TableView<'a>, name: &str) -> Option<&'a Column> {
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
    /// The LAS input's header records, carried over.
    input: Option<&'a InputHeader>,
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
        let extra_properties = extra_properties(view, &standard, path)?;
        let mut fields: Vec<(Slot, Source<'a>)> = standard
            .iter()
            .filter_map(|&(name, slot)| Some((slot, Source::of(view, name)?)))
            .collect();
        let input_descriptors = view.las_header.map_or(&[][..], |h| &h.descriptors);
        let extras: Vec<Extra> = (extra_properties.iter())
            .map(|(name, column)| extra_field(name, column, input_descriptors))
            .collect();
        let mut at = base_len;
        for (extra, &(_, column)) in extras.iter().zip(&extra_properties) {
            let conversion = match extra.scaling {
                Some((scale, offset)) => Conversion::Scaled { scale, offset },
                None => Conversion::None,
            };
            let ty = extra.ty;
            fields.push((Slot::Plain { ty, at }, Source { column, conversion }));
            at += ty.size();
        }
        format.extra_bytes = u16::try_from(at - base_len)
            .map_err(|_| invalid(path, format!("{} extra bytes per point", at - base_len)))?;
        format.is_compressed = compressed;
        let mut builder = Builder::default();
        builder.version = Version::new(1, 4);
        builder.point_format = format;
        builder.transforms = transforms(view);
        builder.generating_software = concat!("BoundED-rs ", env!("CARGO_PKG_VERSION")).into();
        let input = view.las_header;
        builder.vlrs = input.map_or_else(Vec::new, |h| h.vlrs.clone());
        builder.evlrs = input.map_or_else(Vec::new, |h| h.evlrs.clone());
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
            input,
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
    let mut extras = Vec::new();
    for p in &view.properties {
        let standard_name =
            standard.iter().any(|(n, _)| *n == p.name) || p.name == "scan_angle_rank";
        if !standard_name {
            if p.name.len() > 32 {
                return Err(invalid(
                    path,
                    format!(
                        "property name {} is longer than the 32 bytes of a LAS Extra Bytes name",
                        crate::error::quoted(&p.name)
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
    /// 8-bit colour to LAS's 16 bits.
    Colour,
    /// Legacy scan angle rank (degrees) to LAS 1.4 units of 0.006 degrees.
    ScanAngle,
    /// A value to the integer it is stored as in a scaled Extra Bytes field.
    Scaled { scale: f64, offset: f64 },
}

impl Conversion {
    fn apply(self, value: f64) -> f64 {
        match self {
            Conversion::None => value,
            Conversion::Colour => value * 257.0,
            Conversion::ScanAngle => (value / 0.006).round(),
            Conversion::Scaled { scale, offset } => ((value - offset) / scale).round(),
        }
    }
}

impl<'a> Source<'a> {
    /// The property of `view` that fills the standard field `name`, if any.
    fn of(view: &TableView<'a>, name: &str) -> Option<Self> {
        let with = |column, conversion| Some(Source { column, conversion });
        let own = property(view, name);
        match (name, own) {
            ("scan_angle", None) => with(property(view, "scan_angle_rank")?, Conversion::ScanAngle),
            ("red" | "green" | "blue", Some(c)) if c.scalar_type() == ScalarType::U8 => {
                with(c, Conversion::Colour)
            }
            (_, Some(c)) => with(c, Conversion::None),
            (_, None) => None,
        }
    }

    /// Writes the values of points `first..` into the field `slot` of `records`: 8-bit
    /// colours through a typed loop, any other
    /// conversion through `f64`.
    fn encode(self, slot: Slot, first: usize, records: &mut [u8], stride: usize) {
        let n = records.len() / stride;
        match (slot, self.conversion, self.column) {
            (Slot::Plain { ty, at }, Conversion::None, column) if ty == column.scalar_type() => {
                column.encode_strided(first, records, stride, at, Endian::Little);
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

    /// The raw form of `header` with these counts and bounds (64-bit counts: see [`finish`]
    /// for the legacy ones; return number 0 is not counted).
    fn raw_header(&self, header: &Header) -> las::Result<las::raw::Header> {
        let mut raw = header.clone().into_raw()?;
        let by_return: [u64; 15] = std::array::from_fn(|k| self.by_return[k + 1]);
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

/// The las writer's output: after its first I/O error (a full disk), every later operation
/// does nothing and succeeds. The first error reaches the caller through the writer as
/// usual; without this, dropping the writer after it (it finishes the file when dropped)
/// failed again and panicked.
struct FailOnce<W> {
    inner: W,
    failed: bool,
}

impl<W> FailOnce<W> {
    fn watch<T>(
        &mut self,
        done: T,
        op: impl FnOnce(&mut W) -> std::io::Result<T>,
    ) -> std::io::Result<T> {
        if self.failed {
            return Ok(done);
        }
        op(&mut self.inner).inspect_err(|_| self.failed = true)
    }
}

impl<W: Write> Write for FailOnce<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.watch(buf.len(), |w| w.write(buf))
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.watch((), |w| w.flush())
    }
}

impl<W: Seek> Seek for FailOnce<W> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.watch(0, |w| w.seek(to))
    }
}

/// The input's scale and offset; for single-float clouds [`binary_grid`]; for other clouds
/// the bounding-box centre as offset and the smallest power-of-ten scale not finer than a
/// thousandth of the `f32` resolution.
pub(super) fn transforms(view: &TableView<'_>) -> Vector<Transform> {
    let t: [Transform; 3] = match view.position_type {
        PositionType::Scaled { scale, offset } => std::array::from_fn(|a| Transform {
            scale: scale[a],
            offset: offset[a],
        }),
        PositionType::F32 => binary_grid(view),
        PositionType::F64 => {
            let extent = view
                .cloud
                .points()
                .par_iter()
                .map(|p| p.map(f32::abs).into_iter().fold(0f32, f32::max))
                .reduce(|| 0f32, f32::max);
            let extent = f64::from(extent) * view.cloud.scale();
            // i32 covers +-2.1e9 steps: keep the largest offset below 1e9 steps.
            let exponent = (extent.max(1e-3) / 1e9).log10().ceil();
            let s = 10f64.powf(exponent.max(-9.0));
            let origin = view.cloud.origin();
            std::array::from_fn(|a| Transform {
                scale: s,
                offset: origin[a],
            })
        }
    };
    let [x, y, z] = t;
    Vector { x, y, z }
}

/// Steps per axis that a LAS integer holds with room to spare: the offset sits mid-range.
const MAX_STEPS: f64 = 2_147_483_000.0;

/// Per axis, a power-of-two scale `2^k` and an offset that is a multiple of it: the coarsest
/// `k` on whose grid every coordinate lies (so every coordinate is written exactly) when
/// the axis then spans at most about 2^32 steps, else the finest `k` for which it does. On
/// that finer grid a coordinate is still exact when it is a multiple of `2^k`, which every
/// single float at least `2^(k + 23)` from zero is; the others move by at most half a step.
fn binary_grid(view: &TableView<'_>) -> [Transform; 3] {
    // Per axis: smallest, largest, and the exponent of the lowest set bit over the
    // non-zero coordinates.
    type Axis = (f64, f64, i32);
    let empty: [Axis; 3] = [(f64::INFINITY, f64::NEG_INFINITY, i32::MAX); 3];
    let merge = |a: [Axis; 3], b: [Axis; 3]| {
        std::array::from_fn(|k| (a[k].0.min(b[k].0), a[k].1.max(b[k].1), a[k].2.min(b[k].2)))
    };
    let axes = (0..view.len())
        .into_par_iter()
        .map(|i| {
            let p = view.position(i);
            std::array::from_fn(|a| (p[a], p[a], lowest_bit(p[a])))
        })
        .reduce(|| empty, merge);
    axes.map(|(lo, hi, lowest)| {
        if lo > hi {
            return Transform {
                scale: 1.0,
                offset: 0.0,
            }; // no points
        }
        let mut k = if lowest == i32::MAX { 0 } else { lowest };
        // The range alone bounds `k` from below; start there rather than at a tiny `k`.
        let needed = ((hi - lo) / 2.0 / MAX_STEPS).log2().ceil();
        if needed.is_finite() && f64::from(k) < needed {
            k = needed as i32;
        }
        loop {
            let scale = 2f64.powi(k);
            let offset = ((lo + hi) / 2.0 / scale).round() * scale;
            if (hi - offset).max(offset - lo) / scale <= MAX_STEPS {
                return Transform { scale, offset };
            }
            k += 1;
        }
    })
}

/// The exponent of the lowest set bit of `x` (`x` is an odd multiple of `2^e`); `i32::MAX`
/// for zero and non-finite values, which constrain no grid.
fn lowest_bit(x: f64) -> i32 {
    if x == 0.0 || !x.is_finite() {
        return i32::MAX;
    }
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let mantissa = bits & ((1 << 52) - 1);
    match exponent {
        0 => mantissa.trailing_zeros() as i32 - 1074,
        _ => (mantissa | 1 << 52).trailing_zeros() as i32 + exponent - 1075,
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
    let (origin, unit) = (view.cloud.origin(), view.cloud.scale());
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
                        *s = (o + unit * f64::from(p[a]) - offset) / scale;
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
pub(super) fn round_i32(x: f64) -> Option<i32> {
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
