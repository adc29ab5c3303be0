//! One file too large to hold, labelled in spatial blocks: each block with a halo of the
//! file's other points, proven per point as a tile's is (see [`crate::proof`]), so that the
//! labels are those of the file labelled as one cloud in the plan's frame, bit for bit.
//!
//! Three passes over the file (LAS or LAZ, read in chunks, never whole):
//! 1. *split*: each point's index and offset in the plan's frame go to the spill file of its
//!    block (a cell of a grid over x and y, sized for [`Options::block_points`] points at an
//!    even density), and its block number to a file in point order; the choices of the
//!    annotated output (`bounded_data::annotate::Choices`) are made from every point;
//! 2. *label*: block by block, the block's points and, read-only, the points of the other
//!    blocks' spill files within the halo radius of its box, as one cloud in file order; the
//!    block's probabilities go to its label file; where a proof fails, the halo grows;
//! 3. *write*: the file again in chunks, each point with its probabilities from its block's
//!    label file, into one LAS or LAZ output, atomically.
//!
//! Peak memory is the largest block with its halo, plus a chunk of the file. The spill, block
//! number and label files (34 bytes a point) are written to a scratch directory beside the
//! output (`bounded_geom::atomic::ScratchDir`), removed at the end or on an interruption.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bounded_data::annotate::{Choices, write_annotated_chunks};
use bounded_data::format::Format;
use bounded_data::{DataError, las};
use bounded_geom::atomic::ScratchDir;
use bounded_geom::{Class, PointCloud};
use bounded_nn::{Detector, N_CLASSES};

use crate::detect::{Event, Options, TileReport, first_radius, output_directory};
use crate::halo::{Region, local_box, position_in_bounds};
use crate::{Plan, SurveyError, proof};

/// Points per chunk of the split and write passes.
const CHUNK: usize = 1 << 20;

/// Bytes of a spilled point: its index (`u64`) and its offsets (3 `f32`), little-endian.
const SPILLED: usize = 20;

/// Bytes of a point's probabilities in a label file.
const LABEL: usize = 4 * N_CLASSES;

/// Spilled bytes buffered per block in the split pass before they are appended to its file.
const BUFFER: usize = 1 << 18;

/// Whether tile `tile` of `plan` is labelled in blocks: the plan's one input, a LAS or LAZ
/// file of more than `options.block_points` points.
pub(crate) fn in_blocks(plan: &Plan, tile: usize, options: &Options) -> Result<bool, SurveyError> {
    let input = &plan.inputs()[tile];
    let las = matches!(Format::from_path(&input.path)?, Format::Las { .. });
    Ok(plan.inputs().len() == 1 && las && input.points > options.block_points as u64)
}

/// A grid over x and y of the survey's box; each cell is a block.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: [f64; 2],
    extent: [f64; 2],
    cells: [usize; 2],
}

impl Grid {
    /// A grid of about `points / block_points` cells over `lo`..`hi`, as square as the box.
    fn new(lo: [f64; 3], hi: [f64; 3], points: u64, block_points: usize) -> Self {
        let count = points.div_ceil(block_points.max(1) as u64).max(1) as f64;
        let extent = [hi[0] - lo[0], hi[1] - lo[1]];
        let x = match extent {
            [ex, ey] if ex > 0.0 && ey > 0.0 => (count * ex / ey).sqrt().round().clamp(1.0, count),
            [ex, _] if ex > 0.0 => count,
            _ => 1.0,
        };
        let cells = [x as usize, (count / x).ceil() as usize];
        Grid {
            lo: [lo[0], lo[1]],
            extent,
            cells,
        }
    }

    fn len(&self) -> usize {
        self.cells[0] * self.cells[1]
    }

    /// The cell of the absolute position `p`.
    fn cell(&self, p: [f64; 3]) -> usize {
        let at = |a: usize| {
            let n = self.cells[a];
            match self.extent[a] > 0.0 {
                true => (((p[a] - self.lo[a]) / self.extent[a] * n as f64) as usize).min(n - 1),
                false => 0,
            }
        };
        at(1) * self.cells[0] + at(0)
    }
}

/// A block's points: how many, and the box of their absolute positions.
#[derive(Debug, Clone, Copy)]
struct Block {
    points: usize,
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Default for Block {
    fn default() -> Self {
        Block {
            points: 0,
            lo: [f64::INFINITY; 3],
            hi: [f64::NEG_INFINITY; 3],
        }
    }
}

/// The scratch files of a file labelled in blocks.
struct Scratch {
    dir: ScratchDir,
}

impl Scratch {
    fn spill(&self, block: usize) -> PathBuf {
        self.dir.path().join(format!("{block}.points"))
    }

    fn labels(&self, block: usize) -> PathBuf {
        self.dir.path().join(format!("{block}.labels"))
    }

    fn numbers(&self) -> PathBuf {
        self.dir.path().join("blocks")
    }
}

/// The error of I/O on the scratch file `path`.
fn io(path: &Path) -> impl Fn(std::io::Error) -> DataError + '_ {
    move |source| DataError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Labels tile `tile` of `plan` (see [`in_blocks`]) in blocks and writes it to `output`.
pub(crate) fn detect_in_blocks(
    plan: &Plan,
    tile: usize,
    detector: &Detector,
    output: &Path,
    options: &Options,
    progress: &mut dyn FnMut(Event<'_>),
) -> Result<TileReport, SurveyError> {
    let start = Instant::now();
    let input = &plan.inputs()[tile];
    if !matches!(Format::from_path(output)?, Format::Las { .. }) {
        return Err(SurveyError::Invalid(format!(
            "{}: a file of more than {} points is labelled in blocks, which write .las or \
             .laz, not {}",
            input.path.display(),
            options.block_points,
            output.display()
        )));
    }
    let dir = ScratchDir::create(output_directory(output)?).map_err(DataError::from)?;
    let scratch = Scratch { dir };
    let grid = Grid::new(input.lo, input.hi, input.points, options.block_points);
    let (blocks, choices) = split(plan, tile, &grid, &scratch, progress)?;
    let mut report = TileReport {
        output: output.to_path_buf(),
        points: blocks.iter().map(|b| b.points).sum(),
        dropped: 0,
        halo: 0,
        labelled: 0,
        radius: 0.0,
        needed: 0.0,
        attempts: 0,
        class_counts: [0; N_CLASSES],
        detection: Duration::ZERO,
        elapsed: Duration::ZERO,
    };
    let run = Run {
        plan,
        tile,
        detector,
        options,
        blocks,
        scratch,
    };
    let count = run.blocks.iter().filter(|b| b.points > 0).count();
    let with_points = (0..run.blocks.len()).filter(|&b| run.blocks[b].points > 0);
    for (k, b) in with_points.enumerate() {
        run.label(b, (k, count), &mut report, progress)?;
    }
    run.write(output, choices, &mut report, progress)?;
    report.elapsed = start.elapsed();
    progress(Event::Written {
        tile,
        report: &report,
    });
    Ok(report)
}

/// The split pass: every point to its block's spill file, its block number to the numbers
/// file; returns the blocks and the output's choices.
fn split(
    plan: &Plan,
    tile: usize,
    grid: &Grid,
    scratch: &Scratch,
    progress: &mut dyn FnMut(Event<'_>),
) -> Result<(Vec<Block>, Choices), SurveyError> {
    let input = &plan.inputs()[tile];
    let frame = plan.frame();
    if grid.len() > usize::from(u16::MAX) + 1 {
        return Err(SurveyError::Invalid(format!(
            "{}: {} blocks are too many (at most 65,536): raise the block size",
            input.path.display(),
            grid.len()
        )));
    }
    let mut blocks = vec![Block::default(); grid.len()];
    let mut buffers = vec![Vec::new(); grid.len()];
    let numbers_path = scratch.numbers();
    let numbers = File::create(&numbers_path).map_err(io(&numbers_path))?;
    let mut numbers = BufWriter::with_capacity(1 << 20, numbers);
    let mut choices: Option<Choices> = None;
    let total = input.points as usize;
    las::read_chunks(
        &input.path,
        CHUNK,
        |first, table| -> Result<(), SurveyError> {
            let chunk = Choices::of(&table);
            choices = Some(choices.map_or(chunk, |c| c.merge(chunk)));
            let view = table.view();
            for i in 0..table.len() {
                let p = position_in_bounds(input, &view, first, i)?;
                let b = grid.cell(p);
                let block = &mut blocks[b];
                block.points += 1;
                block.lo = std::array::from_fn(|a| block.lo[a].min(p[a]));
                block.hi = std::array::from_fn(|a| block.hi[a].max(p[a]));
                let buffer = &mut buffers[b];
                buffer.extend_from_slice(&((first + i) as u64).to_le_bytes());
                for c in frame.local(p) {
                    buffer.extend_from_slice(&c.to_le_bytes());
                }
                if buffer.len() >= BUFFER {
                    append(&scratch.spill(b), buffer)?;
                }
                numbers
                    .write_all(&(b as u16).to_le_bytes())
                    .map_err(io(&numbers_path))?;
            }
            progress(Event::Streaming {
                tile,
                pass: "split",
                done: first + table.len(),
                total,
            });
            Ok(())
        },
    )?;
    for (b, buffer) in buffers.iter_mut().enumerate() {
        append(&scratch.spill(b), buffer)?;
    }
    numbers.flush().map_err(io(&numbers_path))?;
    let choices = choices.ok_or_else(|| {
        SurveyError::Invalid(format!("{}: no point to label", input.path.display()))
    })?;
    Ok((blocks, choices))
}

/// Appends `buffer` to the file `path` and empties it.
fn append(path: &Path, buffer: &mut Vec<u8>) -> Result<(), DataError> {
    if buffer.is_empty() {
        return Ok(());
    }
    let mut file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(io(path))?;
    file.write_all(buffer).map_err(io(path))?;
    buffer.clear();
    Ok(())
}

/// The points of block `b`'s spill file, in file order: index and offsets.
/// Fails when the file does not hold the block's `points` (the scratch disk was changed
/// behind the run's back).
fn spilled(scratch: &Scratch, b: usize, points: usize) -> Result<Vec<(u64, [f32; 3])>, DataError> {
    let path = scratch.spill(b);
    let bytes = std::fs::read(&path).map_err(io(&path))?;
    if bytes.len() != points * SPILLED {
        let what = format!(
            "holds {} bytes, not the {points} points spilled",
            bytes.len()
        );
        return Err(io(&path)(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            what,
        )));
    }
    Ok(bytes
        .chunks_exact(SPILLED)
        .map(|r| {
            let index = u64::from_le_bytes(bytes_at(r, 0));
            let p = [8, 12, 16].map(|at| f32::from_le_bytes(bytes_at(r, at)));
            (index, p)
        })
        .collect())
}

/// The `N` bytes of `bytes` at `at`.
fn bytes_at<const N: usize>(bytes: &[u8], at: usize) -> [u8; N] {
    std::array::from_fn(|k| bytes[at + k])
}

/// A file labelled in blocks, after the split pass.
struct Run<'a> {
    plan: &'a Plan,
    tile: usize,
    detector: &'a Detector,
    options: &'a Options,
    blocks: Vec<Block>,
    scratch: Scratch,
}

impl Run<'_> {
    /// The label pass for block `b`, the `block.0`-th of `block.1` with points: labels it with
    /// its halo until every point is proven, and writes its probabilities to its label file.
    fn label(
        &self,
        b: usize,
        block: (usize, usize),
        report: &mut TileReport,
        progress: &mut dyn FnMut(Event<'_>),
    ) -> Result<(), SurveyError> {
        let Run {
            plan,
            tile,
            detector,
            options,
            ref blocks,
            ref scratch,
        } = *self;
        let input = &plan.inputs()[tile];
        let frame = plan.frame();
        let frame_error = |what: String| SurveyError::Frame {
            path: input.path.clone(),
            what,
        };
        let own = spilled(scratch, b, blocks[b].points)?;
        let n = own.len();
        let own_points: Vec<[f32; 3]> = own.iter().map(|r| r.1).collect();
        let k0 = detector.feature_config().largest_scale();
        let mut radius = match options.radius {
            Some(r) => r,
            None if n >= k0 => {
                let cloud = PointCloud::from_frame(frame, own_points.clone())
                    .map_err(|e| frame_error(e.to_string()))?;
                first_radius(detector, &cloud)
            }
            None => 0.0,
        };
        let (mut probabilities, mut reach) = (vec![[0f32; N_CLASSES]; n], vec![0f32; n]);
        // The growth of a halo too small to label at all: a quarter of the file's extent.
        let step = (0..3)
            .map(|a| input.hi[a] - input.lo[a])
            .fold(0.0, f64::max)
            / 4.0;
        loop {
            report.attempts += 1;
            let region = Region::around_box(plan, blocks[b].lo, blocks[b].hi, radius);
            // The block's points (marked with their place among them) and the halo's, in file
            // order.
            let mut loaded: Vec<(u64, [f32; 3], u32)> = (own.iter().enumerate())
                .map(|(j, &(i, p))| (i, p, j as u32))
                .collect();
            for (other, o) in blocks.iter().enumerate() {
                let (lo, hi) = local_box(&frame, o.lo, o.hi);
                if other == b || o.points == 0 || !region.meets(lo, hi) {
                    continue;
                }
                let near = spilled(scratch, other, o.points)?
                    .into_iter()
                    .filter(|r| region.contains(r.1));
                loaded.extend(near.map(|(i, p)| (i, p, u32::MAX)));
            }
            loaded.sort_unstable_by_key(|r| r.0);
            let total = loaded.len();
            progress(Event::Loaded {
                tile,
                block: Some(block),
                attempt: report.attempts,
                radius,
                points: n,
                halo: total - n,
            });
            if total < k0 && !region.is_everything() {
                // Too few points to label at all: grow the halo without trying.
                radius = (2.0 * radius).max(step);
                continue;
            }
            let points: Vec<[f32; 3]> = loaded.iter().map(|r| r.1).collect();
            let cloud =
                PointCloud::from_frame(frame, points).map_err(|e| frame_error(e.to_string()))?;
            if cloud.frame() != frame {
                return Err(frame_error(format!(
                    "its offsets were rescaled to {:?}",
                    cloud.frame()
                )));
            }
            let t = Instant::now();
            let mut done = 0;
            detector
                .detect_blocks_with_reach(&cloud, |indices, block, block_reach| {
                    for ((&i, p), &r) in indices.iter().zip(block).zip(block_reach) {
                        let j = loaded[i as usize].2;
                        if j != u32::MAX {
                            probabilities[j as usize] = *p;
                            reach[j as usize] = r;
                        }
                    }
                    done += indices.len();
                    progress(Event::Detecting { tile, done, total });
                })
                .map_err(|source| SurveyError::Detect {
                    path: input.path.clone(),
                    source,
                })?;
            report.detection += t.elapsed();
            report.labelled += total;
            let verdict = proof::check(plan, &region, &own_points, &reach);
            if verdict.unproven == 0 || region.is_everything() {
                report.halo += total - n;
                report.radius = report.radius.max(radius);
                report.needed = report.needed.max(verdict.needed);
                break;
            }
            radius = (2.0 * radius).max(verdict.needed);
            progress(Event::Growing {
                tile,
                unproven: verdict.unproven,
                radius,
            });
        }
        let path = scratch.labels(b);
        let file = File::create(&path).map_err(io(&path))?;
        let mut file = BufWriter::with_capacity(1 << 20, file);
        for p in &probabilities {
            for v in p {
                file.write_all(&v.to_le_bytes()).map_err(io(&path))?;
            }
        }
        file.flush().map_err(io(&path))?;
        Ok(())
    }

    /// The write pass: the file again in chunks, each point with its block's probabilities.
    fn write(
        &self,
        output: &Path,
        choices: Choices,
        report: &mut TileReport,
        progress: &mut dyn FnMut(Event<'_>),
    ) -> Result<(), SurveyError> {
        let Run {
            plan,
            tile,
            detector,
            options,
            ref blocks,
            ref scratch,
        } = *self;
        let input = &plan.inputs()[tile];
        let numbers_path = scratch.numbers();
        let numbers = File::open(&numbers_path).map_err(io(&numbers_path))?;
        let mut numbers = BufReader::with_capacity(1 << 20, numbers);
        // Labels read so far from each block's file.
        let mut read = vec![0usize; blocks.len()];
        let total = input.points as usize;
        write_annotated_chunks(output, &options.annotate, choices, |put| {
            las::read_chunks(
                &input.path,
                CHUNK,
                |first, table| -> Result<(), DataError> {
                    let n = table.len();
                    let mut bytes = vec![0u8; 2 * n];
                    numbers.read_exact(&mut bytes).map_err(io(&numbers_path))?;
                    let of: Vec<usize> = (bytes.chunks_exact(2))
                        .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))
                        .collect();
                    // Each block's labels of this chunk, read at once, and how many are taken.
                    let mut wanted = vec![0usize; blocks.len()];
                    of.iter().for_each(|&b| wanted[b] += 1);
                    let mut labels: Vec<(Vec<u8>, usize)> = vec![(Vec::new(), 0); blocks.len()];
                    for (b, &m) in wanted.iter().enumerate().filter(|(_, m)| **m > 0) {
                        let path = scratch.labels(b);
                        let mut file = File::open(&path).map_err(io(&path))?;
                        file.seek(SeekFrom::Start((read[b] * LABEL) as u64))
                            .map_err(io(&path))?;
                        labels[b].0 = vec![0u8; m * LABEL];
                        file.read_exact(&mut labels[b].0).map_err(io(&path))?;
                        read[b] += m;
                    }
                    let probabilities: Vec<[f32; N_CLASSES]> = (of.iter())
                        .map(|&b| {
                            let (bytes, taken) = &mut labels[b];
                            let at = *taken * LABEL;
                            *taken += 1;
                            std::array::from_fn(|k| f32::from_le_bytes(bytes_at(bytes, at + 4 * k)))
                        })
                        .collect();
                    let classes: Vec<Class> =
                        probabilities.iter().map(|p| detector.decide(p)).collect();
                    let counts = Class::counts(&classes);
                    for (total, c) in report.class_counts.iter_mut().zip(counts) {
                        *total += c;
                    }
                    put(&table, &classes, &probabilities)?;
                    progress(Event::Streaming {
                        tile,
                        pass: "write",
                        done: first + n,
                        total,
                    });
                    Ok(())
                },
            )
            .map(drop)
        })?;
        Ok(())
    }
}
