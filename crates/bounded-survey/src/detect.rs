//! Labelling a survey tile by tile: each tile with its halo, proven per point, written
//! before the next.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bounded_data::annotate::AnnotateOptions;
use bounded_data::format;
use bounded_geom::{Class, Distinct, KnnIndex, NeighbourChunk, PointCloud};
use bounded_nn::{Detection, Detector, N_CLASSES};

use crate::halo::{self, Region};
use crate::{Plan, ReadOptions, SurveyError, proof};

/// How a survey is labelled and written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// How the inputs are read.
    pub read: ReadOptions,
    /// How the outputs are written (the options of `bounded_data::format::write_annotated_with`).
    pub annotate: AnnotateOptions,
    /// The first halo radius of every tile (absolute units); `None`: estimated per tile from
    /// a sample of its points (see [`detect_tile`]). Any radius gives the same labels; a
    /// small one costs more attempts, a large one more halo.
    pub radius: Option<f64>,
    /// A survey of one LAS or LAZ file of more points than this is labelled in spatial
    /// blocks of about this many points (each with its halo, see `crate::blocks`), in memory
    /// bounded by a block's, and written as LAS or LAZ; any other file is held whole.
    pub block_points: usize,
}

/// The default [`Options::block_points`]: about 4 GB of memory while labelling a block.
pub const BLOCK_POINTS: usize = 1 << 25;

impl Default for Options {
    fn default() -> Self {
        Options {
            read: ReadOptions::default(),
            annotate: AnnotateOptions::default(),
            radius: None,
            block_points: BLOCK_POINTS,
        }
    }
}

/// What happens while a tile is labelled, for a progress display.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event<'a> {
    /// The tile and its halo at `radius` are loaded: `points` of the tile, `halo` beyond.
    Loaded {
        /// The tile.
        tile: usize,
        /// For a file labelled in blocks: which block with points, of how many.
        block: Option<(usize, usize)>,
        /// 1 for the first labelling, 2 after its halo grew once, ...
        attempt: usize,
        /// The halo radius (absolute units).
        radius: f64,
        /// The tile's points.
        points: usize,
        /// The halo's points.
        halo: usize,
    },
    /// A pass over a file labelled in blocks (`pass`: `"split"` into blocks, or `"write"`)
    /// has read `done` of its `total` points.
    Streaming {
        /// The tile.
        tile: usize,
        /// The pass.
        pass: &'static str,
        /// Points read so far.
        done: usize,
        /// The file's points.
        total: usize,
    },
    /// Detection has labelled `done` of the `total` points loaded.
    Detecting {
        /// The tile.
        tile: usize,
        /// Points labelled so far.
        done: usize,
        /// Points loaded.
        total: usize,
    },
    /// `unproven` points of the tile reach beyond its halo: it is labelled again at `radius`.
    Growing {
        /// The tile.
        tile: usize,
        /// Points whose proof failed.
        unproven: usize,
        /// The next radius.
        radius: f64,
    },
    /// The tile's output is written.
    Written {
        /// The tile.
        tile: usize,
        /// What it took.
        report: &'a TileReport,
    },
}

/// What labelling one tile took.
#[derive(Debug, Clone, PartialEq)]
pub struct TileReport {
    /// The output written.
    pub output: PathBuf,
    /// The tile's points.
    pub points: usize,
    /// Points of its file left out for a non-finite coordinate (see [`ReadOptions`]).
    pub dropped: usize,
    /// The points of the halo that proved it.
    pub halo: usize,
    /// Points labelled over every attempt (tile and halo, each time).
    pub labelled: usize,
    /// The radius of the halo that proved it (absolute units).
    pub radius: f64,
    /// The smallest radius that would have proved it (see [`proof::Verdict::needed`]).
    pub needed: f64,
    /// Labellings: 1, plus one per growth of the halo.
    pub attempts: usize,
    /// Points per class (non-edge, sharp, boundary).
    pub class_counts: [usize; N_CLASSES],
    /// Wall time in detection, over every attempt.
    pub detection: Duration,
    /// Wall time of the whole tile: reading, halos, detection, proof and writing.
    pub elapsed: Duration,
}

impl TileReport {
    /// The report of a cloud of `points` labelled whole, without a halo (standard input, say).
    pub fn whole(
        output: &Path,
        points: usize,
        dropped: usize,
        detection: &Detection,
        elapsed: Duration,
    ) -> Self {
        TileReport {
            output: output.to_path_buf(),
            points,
            dropped,
            halo: 0,
            labelled: points,
            radius: 0.0,
            needed: 0.0,
            attempts: 1,
            class_counts: detection.class_counts(),
            detection: detection.elapsed,
            elapsed,
        }
    }
}

/// Labels every tile of `plan` in order, writing tile `t`'s result to `outputs[t]` before
/// the next tile is read. Peak memory is that of the largest tile with its halo. A failure
/// stops the run; the outputs written before it stay, complete.
pub fn detect_survey(
    plan: &Plan,
    detector: &Detector,
    outputs: &[PathBuf],
    options: &Options,
    progress: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<TileReport>, SurveyError> {
    if outputs.len() != plan.inputs().len() {
        return Err(SurveyError::Invalid(format!(
            "{} outputs for {} inputs",
            outputs.len(),
            plan.inputs().len()
        )));
    }
    let mut reports = Vec::with_capacity(outputs.len());
    for (tile, output) in outputs.iter().enumerate() {
        match detect_tile(plan, tile, detector, output, options, progress) {
            Ok(report) => reports.push(report),
            Err(e) if tile == 0 => return Err(e),
            Err(e) => {
                return Err(SurveyError::Stopped {
                    written: outputs[..tile].to_vec(),
                    total: outputs.len(),
                    source: Box::new(e),
                });
            }
        }
    }
    Ok(reports)
}

/// Labels tile `tile` of `plan` and writes its points, with every property they were read
/// with and the results (as `bounded_data::format::write_annotated_with` writes them,
/// atomically: a retried tile rewrites the same bytes), to `output`, creating its directory
/// if missing.
///
/// The tile is labelled with its halo at the first radius ([`Options::radius`], or a guess
/// from the reach of a sample of its points) and every point's result proven to be the
/// survey's (see [`crate::proof`]); where a proof fails, the radius at least doubles and the
/// tile is labelled again. The labels are those of the whole survey labelled as one cloud in
/// the plan's frame, bit for bit, whatever the radius.
pub fn detect_tile(
    plan: &Plan,
    tile: usize,
    detector: &Detector,
    output: &Path,
    options: &Options,
    progress: &mut dyn FnMut(Event<'_>),
) -> Result<TileReport, SurveyError> {
    let start = Instant::now();
    let input = plan.inputs().get(tile).ok_or_else(|| {
        SurveyError::Invalid(format!(
            "no tile {tile} in a plan of {}",
            plan.inputs().len()
        ))
    })?;
    if crate::blocks::in_blocks(plan, tile, options)? {
        return crate::blocks::detect_in_blocks(plan, tile, detector, output, options, progress);
    }
    let detect_error = |source| SurveyError::Detect {
        path: input.path.clone(),
        source,
    };
    let (mut table, dropped) = options.read.read(&input.path)?;
    // The output replaces a previous run's results: free their memory while labelling.
    format::drop_annotated(&mut table);
    let n = table.len();
    // A survey of one file is labelled in the file's own frame, as the file alone: no other
    // tile has to agree with it, and there is no halo to prove.
    let alone = plan.inputs().len() == 1;
    let points = if alone {
        Vec::new()
    } else {
        halo::offsets(plan, tile, &table)?
    };
    let mut radius = match options.radius {
        Some(r) => r,
        None if alone => 0.0,
        None => first_radius(detector, &table.cloud),
    };
    let (mut probabilities, mut reach) = (vec![[0f32; N_CLASSES]; n], vec![0f32; n]);
    let (mut attempts, mut labelled, mut detection) = (0, 0, Duration::ZERO);
    let (halo, verdict) = loop {
        attempts += 1;
        let region = Region::around(plan, tile, radius);
        let loaded = if alone {
            None
        } else {
            Some(halo::load(plan, tile, &points, &region, options.read)?)
        };
        let (cloud, first) = loaded
            .as_ref()
            .map_or((&table.cloud, 0), |l| (&l.cloud, l.tile.start));
        let total = cloud.len();
        progress(Event::Loaded {
            tile,
            block: None,
            attempt: attempts,
            radius,
            points: n,
            halo: total - n,
        });
        let t = Instant::now();
        let mut done = 0;
        detector
            .detect_blocks_with_reach(cloud, |indices, block, block_reach| {
                for ((&i, p), &r) in indices.iter().zip(block).zip(block_reach) {
                    if let Some(j) = (i as usize).checked_sub(first).filter(|&j| j < n) {
                        probabilities[j] = *p;
                        reach[j] = r;
                    }
                }
                done += indices.len();
                progress(Event::Detecting { tile, done, total });
            })
            .map_err(detect_error)?;
        detection += t.elapsed();
        labelled += total;
        if alone {
            break (
                0,
                proof::Verdict {
                    unproven: 0,
                    needed: 0.0,
                },
            );
        }
        let verdict = proof::check(plan, &region, &points, &reach);
        if verdict.unproven == 0 || region.is_everything() {
            break (total - n, verdict);
        }
        radius = (2.0 * radius).max(verdict.needed);
        progress(Event::Growing {
            tile,
            unproven: verdict.unproven,
            radius,
        });
    };
    output_directory(output)?;
    let classes: Vec<Class> = probabilities.iter().map(|p| detector.decide(p)).collect();
    format::write_annotated_with(output, &table, &classes, &probabilities, &options.annotate)?;
    let report = TileReport {
        output: output.to_path_buf(),
        points: n,
        dropped,
        halo,
        labelled,
        radius,
        needed: verdict.needed,
        attempts,
        class_counts: Class::counts(&classes),
        detection,
        elapsed: start.elapsed(),
    };
    progress(Event::Written {
        tile,
        report: &report,
    });
    Ok(report)
}

/// The directory of `output` (`.` for a bare file name), created if missing.
pub(crate) fn output_directory(output: &Path) -> Result<&Path, SurveyError> {
    let parent = output.parent().filter(|p| !p.as_os_str().is_empty());
    let parent = parent.unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|source| bounded_data::DataError::Io {
        path: parent.to_path_buf(),
        source,
    })?;
    Ok(parent)
}

/// Points sampled for the first radius.
const SAMPLE: usize = 1024;

/// A first halo radius for `cloud` (absolute units): 1.5 times the largest reach (see
/// [`crate::proof`]) of a sample of its distinct positions (spread along the Morton order),
/// computed within the tile: the `k0`-th neighbour distance, plus for a two-stage model the
/// largest such distance among the neighbours. A retry labels the whole tile again, costing
/// far more than a wider halo: the sample's largest reach, not a typical one.
pub(crate) fn first_radius(detector: &Detector, cloud: &PointCloud) -> f64 {
    let k0 = detector.feature_config().largest_scale();
    let index = match Distinct::of(cloud) {
        Some(distinct) => KnnIndex::of_subset(cloud, distinct.firsts()),
        None => KnnIndex::new(cloud),
    };
    // Too few positions: detection gives the error that says so.
    let Ok(index) = index else { return 0.0 };
    let Ok(search) = index.search(k0) else {
        return 0.0;
    };
    let points = cloud.points();
    // The k0-th neighbour distance of the index's points at Morton `positions`, by cloud index.
    let mut chunk = NeighbourChunk::default();
    let mut radii = |positions: &mut dyn Iterator<Item = usize>| {
        search.positions(positions, &mut chunk);
        (0..chunk.len())
            .map(|row| {
                let (i, last) = (chunk.queries()[row], chunk.row(row)[k0 - 1]);
                let (p, q) = (points[i as usize], points[last as usize]);
                let d2: f64 = (0..3)
                    .map(|a| (f64::from(p[a]) - f64::from(q[a])).powi(2))
                    .sum();
                (i, d2.sqrt(), chunk.row(row).to_vec())
            })
            .collect::<Vec<_>>()
    };
    let len = index.len();
    let sample = radii(&mut (0..len).step_by(len.div_ceil(SAMPLE).max(1)));
    let largest = if detector.classifier().second_stage().is_none() {
        sample.iter().map(|s| s.1).fold(0.0, f64::max)
    } else {
        let position = index.positions_by_index(points.len());
        let mut neighbours: Vec<usize> = (sample.iter())
            .flat_map(|s| s.2.iter().map(|&q| position[q as usize] as usize))
            .collect();
        neighbours.sort_unstable();
        neighbours.dedup();
        let mut own = vec![0.0; points.len()];
        for (i, d, _) in radii(&mut neighbours.into_iter()) {
            own[i as usize] = d;
        }
        (sample.iter())
            .map(|(_, d, row)| d + row.iter().map(|&q| own[q as usize]).fold(0.0, f64::max))
            .fold(0.0, f64::max)
    };
    1.5 * largest * cloud.scale()
}
