//! Two classifier stages over one neighbour search and one feature pass.
//!
//! A second (auto-context) stage reads, for every point, the first stage's probabilities over
//! the point's neighbourhood. Running the stages as two passes searches every neighbourhood
//! and computes every feature twice. Here the cloud is walked once in Morton-ordered chunks:
//! each chunk's neighbour lists and features are computed, its first stage runs, and the
//! chunk waits (its lists and features kept) until every point its neighbourhoods hold has a
//! first-stage result; then its context is computed and its second stage runs.
//!
//! Memory stays per chunk, never `n x k` for the cloud: a chunk's neighbours mostly lie in the
//! chunks beside it along the Morton curve, but where the curve jumps (across the planes of the
//! implicit octree) they can lie in a chunk far ahead. At most [`PENDING_CHUNKS`] chunks wait;
//! when one more would, the oldest gets its halo: the neighbours not yet classified are
//! searched, featured and classified on the spot (and again later in their own chunk). Every
//! point's neighbour list, features and probabilities are the same whichever run of points
//! computes them, so the results are those of two passes, bit for bit.
//!
//! The search names neighbours by their Morton position
//! ([`KnnSearch::positions_named`](bounded_geom::KnnSearch::positions_named)), and the
//! features, the first-stage results and the context are read by position from the index's
//! Morton-ordered copy of the points: a neighbourhood then lies in a few runs of memory
//! rather than anywhere in a cloud stored in another order (1M-point random cube,
//! interleaved runs: both stages 9% faster, the first stage alone unchanged, see
//! `docs/performance.md`).

use std::collections::VecDeque;

use bounded_geom::{KnnIndex, NeighbourChunk, PointCloud};
use rayon::prelude::*;

use crate::context::FirstResults;
use crate::extract::{in_context_row, plain_features, radii, values_per_point, with_index};
use crate::{FeatureBlock, FeatureConfig, FeatureError};

/// Chunks that may wait for their second stage at once: each holds its `chunk x k0` neighbour
/// lists and its features (about 11 MiB at the default 16,384 points and scales). On a
/// 1M-point random cube surface the halos then hold 15,041 points (1.5% computed twice);
/// `bounded-nn`'s `detect` example prints the figure for any cloud.
pub const PENDING_CHUNKS: usize = 8;

/// A chunk waiting for its second stage.
struct Pending {
    /// Its neighbour lists, renamed to Morton positions ([`KnnIndex::points`]).
    chunk: NeighbourChunk,
    /// Its points' features, without context (its points by cloud index).
    features: FeatureBlock,
    /// The last chunk whose first stage its neighbourhoods need.
    needs: usize,
}

/// Streams two classifier stages over `cloud` with one neighbour search: `first` gets blocks
/// of plain features (as [`extract_chunks`](crate::extract_chunks) gives them, but each
/// position once, without its repeats) and writes their probabilities (non-edge, sharp,
/// boundary; one per row) into its second argument; `second` gets blocks of the features beside
/// their context of those probabilities (as
/// [`extract_chunks_in_context`](crate::extract_chunks_in_context) lays them out), every point
/// of the cloud exactly once. Returns the number of halo points whose features were computed
/// a second time (see the module notes).
///
/// The blocks `second` gets equal, point for point and bit for bit, those of
/// `extract_chunks_in_context` over the probabilities `first` gave for every point.
pub fn extract_chunks_staged(
    cloud: &PointCloud,
    config: &FeatureConfig,
    chunk_points: usize,
    mut first: impl FnMut(&FeatureBlock, &mut [[f32; 3]]),
    mut second: impl FnMut(&FeatureBlock),
) -> Result<usize, FeatureError> {
    config.validate()?;
    with_index(cloud, &mut second, |index, second| {
        staged(cloud, index, config, chunk_points, &mut first, second)
    })
}

/// [`extract_chunks_staged`] for the points `index` holds, whose positions are all distinct.
fn staged(
    cloud: &PointCloud,
    index: &KnnIndex,
    config: &FeatureConfig,
    chunk_points: usize,
    first: &mut dyn FnMut(&FeatureBlock, &mut [[f32; 3]]),
    second: &mut dyn FnMut(&FeatureBlock),
) -> Result<usize, FeatureError> {
    // Everything below reads the index's Morton-ordered copy of the points, by position:
    // neighbours near in space are near in memory there, whatever the cloud's own order.
    let points = index.points();
    let step = chunk_points.max(1);
    let search = index.search(config.largest_scale())?;
    // Each indexed point's Morton position, by cloud index (the chunk is position / step).
    let position = index.positions_by_index(cloud.len());
    let mut stage = FirstStage {
        results: vec![Classified::NOT_YET; index.len()],
        order: index.order(),
        block: Vec::new(),
        first,
    };
    let mut output = FeatureBlock {
        per_point: values_per_point(config, true),
        ..FeatureBlock::default()
    };
    let mut emit = |p: Pending, stage: &FirstStage<'_>| {
        output.points.clear();
        output.points.extend_from_slice(&p.features.points);
        let results = &stage.results;
        output
            .values
            .resize(p.features.len() * output.per_point, 0.0);
        output.reach.resize(p.features.len(), 0.0);
        (output.values.par_chunks_mut(output.per_point))
            .zip(output.reach.par_iter_mut())
            .zip(p.features.values.par_chunks(p.features.per_point))
            .zip(p.features.reach.par_iter())
            .zip(p.chunk.rows().par_chunks(p.chunk.k()))
            .for_each(|((((out, reach), features), &own), row)| {
                in_context_row(row, config, features, &Table { points, results }, out);
                // The context reads the first stage of every neighbour, which read its own
                // neighbours: the point's reach plus the largest of theirs (entries the
                // context has just read).
                *reach = own + widest(row, results);
            });
        second(&output);
        p
    };
    let mut pending: VecDeque<Pending> = VecDeque::new();
    // Buffers of emitted chunks, reused.
    let mut spare: Vec<Pending> = Vec::new();
    let mut halo = Pending {
        chunk: NeighbourChunk::default(),
        features: FeatureBlock::default(),
        needs: 0,
    };
    let mut halo_points = 0;
    let mut halo_positions = Vec::new();
    for (c, start) in (0..index.len()).step_by(step).enumerate() {
        let mut p = spare.pop().unwrap_or_else(|| Pending {
            chunk: NeighbourChunk::default(),
            features: FeatureBlock::default(),
            needs: 0,
        });
        search.positions_named(
            start..(start + step).min(index.len()),
            &position,
            &mut p.chunk,
        );
        stage.run(points, config, p.chunk.rows(), &mut p.features);
        // The chunk of the furthest neighbour, or one after it: the search's bound costs
        // nothing, where the furthest itself took a lookup of every neighbour (~4% of
        // detection, see docs/performance.md). Waiting longer changes no result.
        p.needs = (p.chunk.positions_below().saturating_sub(1) / step).max(c);
        pending.push_back(p);
        // Second stages whose neighbourhoods are all classified now.
        let mut i = 0;
        while i < pending.len() {
            match pending.get(i) {
                Some(p) if p.needs <= c => {
                    if let Some(p) = pending.remove(i) {
                        spare.push(emit(p, &stage));
                    }
                }
                _ => i += 1,
            }
        }
        // Too many waiting: the oldest gets its halo.
        while pending.len() > PENDING_CHUNKS
            && let Some(p) = pending.pop_front()
        {
            halo_positions.clear();
            halo_positions.extend(
                (p.chunk.rows().iter())
                    .filter(|&&j| !stage.results[j as usize].is_done())
                    .map(|&j| j as usize),
            );
            halo_positions.sort_unstable();
            halo_positions.dedup();
            halo_points += halo_positions.len();
            search.positions_named(halo_positions.iter().copied(), &position, &mut halo.chunk);
            stage.run(points, config, halo.chunk.rows(), &mut halo.features);
            spare.push(emit(p, &stage));
        }
    }
    // Every point is classified: the rest can run.
    while let Some(p) = pending.pop_front() {
        emit(p, &stage);
    }
    Ok(halo_points)
}

/// A point's first-stage result, as the second stage reads it: one 16-byte entry holds all
/// that the context and the reach read of a neighbour but its position (read beside it, at
/// the same Morton position of the index's points). The non-edge probability is not kept:
/// the context does not read it.
#[derive(Debug, Clone, Copy)]
#[repr(align(16))]
struct Classified {
    sharp: f32,
    boundary: f32,
    /// The reach of its features; negative until it is classified.
    radius: f32,
}

impl Classified {
    const NOT_YET: Self = Self {
        sharp: 0.0,
        boundary: 0.0,
        radius: -1.0,
    };

    fn is_done(self) -> bool {
        self.radius >= 0.0
    }
}

/// The largest radius of the `results` that `row` names (all classified, so none negative).
/// Eight running maxima instead of one: a single one waits on the last comparison at every
/// neighbour, and the fold took ~3.5% of two-stage detection (1M cube, perf). The maximum
/// is exact, so the order of the comparisons does not change it.
fn widest(row: &[u32], results: &[Classified]) -> f32 {
    let mut lanes = [0.0f32; 8];
    let mut rows = row.chunks_exact(8);
    for eight in &mut rows {
        for (lane, &q) in lanes.iter_mut().zip(eight) {
            *lane = lane.max(results[q as usize].radius);
        }
    }
    let rest = (rows.remainder().iter()).fold(0.0f32, |w, &q| w.max(results[q as usize].radius));
    lanes.into_iter().fold(rest, f32::max)
}

/// The first-stage results beside the points, both by Morton position.
struct Table<'a> {
    points: &'a [[f32; 3]],
    results: &'a [Classified],
}

impl FirstResults for Table<'_> {
    fn read(&self, j: u32) -> ([f32; 3], [f32; 2]) {
        let c = self.results[j as usize];
        (self.points[j as usize], [c.sharp, c.boundary])
    }
}

/// The first stage's results so far.
struct FirstStage<'a> {
    /// Per Morton position.
    results: Vec<Classified>,
    /// The cloud index at each Morton position.
    order: &'a [u32],
    /// One block's probabilities.
    block: Vec<[f32; 3]>,
    first: &'a mut dyn FnMut(&FeatureBlock, &mut [[f32; 3]]),
}

impl FirstStage<'_> {
    /// Computes the features of the neighbour lists `rows` (by Morton position, the query
    /// first) into `features` and classifies them.
    fn run(
        &mut self,
        points: &[[f32; 3]],
        config: &FeatureConfig,
        rows: &[u32],
        features: &mut FeatureBlock,
    ) {
        let k0 = config.largest_scale();
        features.per_point = config.features_per_point();
        features.points.clear();
        (features.points).extend(rows.iter().step_by(k0).map(|&p| self.order[p as usize]));
        plain_features(points, rows, config, &mut features.values);
        radii(points, rows, k0, &mut features.reach);
        self.block.clear();
        self.block.resize(features.points.len(), [0.0; 3]);
        (self.first)(features, &mut self.block);
        let queries = rows.iter().step_by(k0);
        for ((&i, p), &radius) in queries.zip(&self.block).zip(&features.reach) {
            self.results[i as usize] = Classified {
                sharp: p[1],
                boundary: p[2],
                radius,
            };
        }
    }
}
