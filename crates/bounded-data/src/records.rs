//! Shared codecs: fixed-size binary records decoded and encoded in blocks, text rows
//! parsed and written, header lines read with a length limit.

use crate::DataError;
use crate::table::{Column, Endian, PositionType, Scalar, ScalarType, TableView};
use std::io::{BufRead, Read, Write};
use std::path::Path;

/// Records decoded or encoded per block: 64k records keep the buffer in cache-friendly
/// megabytes while amortising the per-block column dispatch.
pub(crate) const BLOCK: usize = 1 << 16;

/// Records per block for records of `stride` bytes: [`BLOCK`], or fewer so that a block
/// stays within 4 MiB however wide the records (a corrupt header must not exhaust memory).
pub(crate) fn block_len(stride: usize) -> usize {
    ((4 << 20) / stride.max(1)).clamp(1, BLOCK)
}

/// Runs `produce(block, first)` then `consume(block, first)` on the blocks of `block_len`
/// records of `stride` bytes that make up `total` records, in order, with two buffers: block
/// `i` is consumed by a pool task while the calling thread produces block `i + 1`, so the
/// file I/O on one side runs alongside the parallel decoding or encoding on the other
/// instead of leaving the other cores idle. `produce` stays on the calling thread: a LAZ
/// reader cannot move between threads. Stops at the first error (a `consume` error wins
/// over a `produce` error of the same step).
pub(crate) fn pipelined<E: Send>(
    total: usize,
    block_len: usize,
    stride: usize,
    mut produce: impl FnMut(&mut [u8], usize) -> Result<(), E>,
    mut consume: impl FnMut(&[u8], usize) -> Result<(), E> + Send,
) -> Result<(), E> {
    let size = stride * total.min(block_len);
    let (mut ready, mut next) = (vec![0u8; size], vec![0u8; size]);
    // The block waiting in `ready`: its first record and its length in bytes.
    let mut pending: Option<(usize, usize)> = None;
    let mut first = 0;
    while first < total || pending.is_some() {
        let n = (total - first).min(block_len);
        let mut consumed = Ok(());
        let produced = rayon::in_place_scope(|scope| {
            if let Some((at, len)) = pending {
                let (consume, ready, consumed) = (&mut consume, &ready, &mut consumed);
                scope.spawn(move |_| *consumed = consume(&ready[..len], at));
            }
            match n {
                0 => Ok(()),
                _ => produce(&mut next[..n * stride], first),
            }
        });
        consumed?;
        produced?;
        std::mem::swap(&mut ready, &mut next);
        pending = (n > 0).then_some((first, n * stride));
        first += n;
    }
    Ok(())
}

/// Header lines longer than this are rejected (guards against reading a binary blob as
/// one "line").
pub(crate) const MAX_HEADER_LINE: u64 = 64 * 1024;

/// Reads one line of at most [`MAX_HEADER_LINE`] bytes, without its `\n` / `\r\n`; `None`
/// at end of input.
pub(crate) fn read_line(
    input: &mut impl BufRead,
    buf: &mut Vec<u8>,
    path: &Path,
) -> Result<Option<usize>, DataError> {
    buf.clear();
    let n = input
        .by_ref()
        .take(MAX_HEADER_LINE)
        .read_until(b'\n', buf)
        .map_err(|e| DataError::io(path, e))?;
    if n == 0 {
        return Ok(None);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    } else if n as u64 == MAX_HEADER_LINE {
        return Err(DataError::malformed(
            path,
            format!("a line is longer than {MAX_HEADER_LINE} bytes"),
        ));
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(Some(n))
}

/// Parses the `tokens` of one text row into `columns`, one token each.
pub(crate) fn parse_row<'t>(
    mut tokens: impl Iterator<Item = &'t str>,
    columns: &mut [Column],
    line: usize,
    path: &Path,
) -> Result<(), DataError> {
    let expected = columns.len();
    for (k, column) in columns.iter_mut().enumerate() {
        let token = tokens.next().ok_or_else(|| {
            DataError::malformed(
                path,
                format!("line {line}: expected {expected} values, found {k}"),
            )
        })?;
        column.push_token(token).map_err(|e| {
            DataError::malformed(path, format!("line {line}, value {}: {e}", k + 1))
        })?;
    }
    if tokens.next().is_some() {
        return Err(DataError::malformed(
            path,
            format!("line {line}: more than {expected} values"),
        ));
    }
    Ok(())
}

/// Reads `count` non-blank text rows of whitespace-separated values into `columns`;
/// `line` counts the lines read (for messages), `noun` names the rows ("points").
pub(crate) fn read_text_rows(
    input: &mut impl BufRead,
    count: usize,
    columns: &mut [Column],
    line: &mut usize,
    noun: &str,
    path: &Path,
) -> Result<(), DataError> {
    let mut buf = Vec::new();
    let mut done = 0;
    while done < count {
        *line += 1;
        if read_line(input, &mut buf, path)?.is_none() {
            return Err(DataError::malformed(
                path,
                format!("the file ends at line {line} after {done} of {count} {noun}"),
            ));
        }
        let text = std::str::from_utf8(&buf)
            .map_err(|_| DataError::malformed(path, format!("line {line}: not text")))?;
        if text.trim().is_empty() {
            continue;
        }
        parse_row(text.split_ascii_whitespace(), columns, *line, path)?;
        done += 1;
    }
    Ok(())
}

/// A truncation (unexpected end of input) as a [`DataError::Malformed`] saying `what`,
/// any other I/O error as [`DataError::Io`].
pub(crate) fn truncated(path: &Path, what: String, e: std::io::Error) -> DataError {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        DataError::malformed(path, what)
    } else {
        DataError::io(path, e)
    }
}

/// Reads `count` records of the fixed-size `types` into `columns`, in blocks; `offset` is
/// the byte offset of the first record, for error messages.
pub(crate) fn read_records(
    input: &mut impl Read,
    count: usize,
    types: &[ScalarType],
    columns: &mut [Column],
    endian: Endian,
    offset: u64,
    path: &Path,
) -> Result<(), DataError> {
    let stride: usize = types.iter().map(|t| t.size()).sum();
    let offsets: Vec<usize> = types
        .iter()
        .scan(0, |at, t| {
            let o = *at;
            *at += t.size();
            Some(o)
        })
        .collect();
    let block_len = block_len(stride);
    let mut buf = vec![0u8; stride * count.min(block_len)];
    let mut done = 0;
    while done < count {
        let n = (count - done).min(block_len);
        let block = &mut buf[..n * stride];
        let got = read_full(input, block).map_err(|e| DataError::io(path, e))?;
        if got < block.len() {
            return Err(DataError::malformed(
                path,
                format!(
                    "the point data ends within point {} of {count} (at byte offset {})",
                    done + got / stride,
                    offset + (done * stride + got) as u64
                ),
            ));
        }
        for (column, &at) in columns.iter_mut().zip(&offsets) {
            column.decode_strided(block, stride, at, endian);
        }
        done += n;
    }
    Ok(())
}

/// Fills `buf` from `input` until it is full or the input ends; the number of bytes read.
fn read_full(input: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match input.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Writes one text row per point: positions then properties, separated by `separator`.
pub(crate) fn write_text_rows(
    out: &mut impl Write,
    view: &TableView<'_>,
    separator: char,
) -> std::io::Result<()> {
    let f32_positions = view.position_type == PositionType::F32;
    for i in 0..view.len() {
        let p = view.position(i);
        if f32_positions {
            write!(
                out,
                "{}{separator}{}{separator}{}",
                p[0] as f32, p[1] as f32, p[2] as f32
            )?;
        } else {
            write!(out, "{}{separator}{}{separator}{}", p[0], p[1], p[2])?;
        }
        for property in &view.properties {
            write!(out, "{separator}")?;
            property.values.write_text(i, out)?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// Writes fixed-size records (x, y, z as `position`, a float type, then each property) in
/// blocks.
pub(crate) fn write_records(
    out: &mut impl Write,
    view: &TableView<'_>,
    position: ScalarType,
    endian: Endian,
) -> std::io::Result<()> {
    let p_size = position.size();
    let stride = 3 * p_size
        + view
            .properties
            .iter()
            .map(|p| p.values.scalar_type().size())
            .sum::<usize>();
    let block_len = block_len(stride);
    let mut buf = vec![0u8; stride * view.len().min(block_len)];
    let mut first = 0;
    while first < view.len() {
        let n = (view.len() - first).min(block_len);
        let block = &mut buf[..n * stride];
        match position {
            ScalarType::F32 => encode_positions::<f32>(view, first, block, stride, endian),
            _ => encode_positions::<f64>(view, first, block, stride, endian),
        }
        let mut at = 3 * p_size;
        for p in &view.properties {
            p.values.encode_strided(first, block, stride, at, endian);
            at += p.values.scalar_type().size();
        }
        out.write_all(block)?;
        first += n;
    }
    Ok(())
}

/// Encodes the positions of points `first..` as `T` at the start of each record.
fn encode_positions<T: Scalar>(
    view: &TableView<'_>,
    first: usize,
    block: &mut [u8],
    stride: usize,
    endian: Endian,
) {
    for (k, record) in block.chunks_exact_mut(stride).enumerate() {
        let p = view.position(first + k);
        for (a, c) in p.into_iter().enumerate() {
            T::from_f64(c).encode(&mut record[a * T::SIZE..], endian);
        }
    }
}
