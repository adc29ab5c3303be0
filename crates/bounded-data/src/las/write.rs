//! Writing: LAS 1.4 records encoded in parallel blocks, LAZ through the `las` crate.

use super::layout::*;
use super::{CODE_BOUNDARY, CODE_NON_EDGE, CODE_SHARP, las_error};
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
    let out = FailOnce {
        inner: out,
        failed: false,
    };
    let mut writer = Writer::with_options(out, plan.header.clone(), options).map_err(las)?;
    encode_blocks(view, plan, path, laz_block_len(plan.record_len), |block| {
        let data = PointDataBuilder::new()
            .for_header(writer.header())
            .build_from_bytes(block.to_vec())
            .map_err(las)?;
        writer.write_points(&data).map_err(las)
    })?;
    writer.close().map_err(las)?;
    Ok(writer.into_inner().map_err(las)?.inner)
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

/// The input's scale and offset, or for other clouds the bounding-box centre as offset and
/// the smallest power-of-ten scale not finer than a thousandth of the `f32` resolution.
pub(super) fn transforms(view: &TableView<'_>) -> Vector<Transform> {
    let (scale, offset) = match view.position_type {
        PositionType::Scaled { scale, offset } => (scale, offset),
        _ => {
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
