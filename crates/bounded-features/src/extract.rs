//! Feature extraction over a whole cloud, streamed in Morton-ordered blocks.

use bounded_geom::{Distinct, GeomError, KnnIndex, NeighbourChunk, PointCloud};
use rayon::prelude::*;

use crate::context::{FirstResults, Probabilities, contexts};
use crate::local::{LANES, Scratch, group_features};
use crate::{FeatureConfig, FeatureError};

/// Points per block of [`extract`]: 16384 x 128 neighbours x 4 B = 8 MiB of
/// neighbour lists at the default scales.
pub const DEFAULT_CHUNK_POINTS: usize = 16_384;

/// Features of a whole cloud, dense `f32`.
///
/// Layout: `[point][scale][feature]`, points in the cloud's original order, scales
/// largest first, features in [`FeatureGroups`](crate::FeatureGroups) order restricted
/// to the selected groups. With the defaults: 4 scales x 12 = 48 values per point.
#[derive(Debug, Clone, PartialEq)]
pub struct Features {
    per_point: usize,
    values: Vec<f32>,
}

impl Features {
    /// Values per point (scales x features per scale).
    pub fn per_point(&self) -> usize {
        self.per_point
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.values.len() / self.per_point
    }

    /// True for no points (never, for a constructed cloud).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The values of point `i` (scales x features).
    pub fn point(&self, i: usize) -> &[f32] {
        &self.values[i * self.per_point..(i + 1) * self.per_point]
    }

    /// All values, row-major.
    pub fn as_slice(&self) -> &[f32] {
        &self.values
    }

    /// All values, row-major, without copying.
    pub fn into_vec(self) -> Vec<f32> {
        self.values
    }
}

/// Features of a run of points, as handed out by [`extract_chunks`].
#[derive(Debug, Clone, Default)]
pub struct FeatureBlock {
    pub(crate) per_point: usize,
    pub(crate) points: Vec<u32>,
    pub(crate) values: Vec<f32>,
    pub(crate) reach: Vec<f32>,
}

impl FeatureBlock {
    /// Cloud indices of the block's points (Morton order).
    pub fn points(&self) -> &[u32] {
        &self.points
    }

    /// Number of points in the block.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True for a block without points (never handed out).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Values per point, as in [`Features`].
    pub fn per_point(&self) -> usize {
        self.per_point
    }

    /// Values of the block's `row`-th point (cloud index `points()[row]`).
    pub fn row(&self, row: usize) -> &[f32] {
        &self.values[row * self.per_point..(row + 1) * self.per_point]
    }

    /// All values, row-major in block order (`len() x per_point()`).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Per point, in block order, how far its values reach: every position they were
    /// computed from lies within this distance of the point (in the cloud's offsets,
    /// rounded to `f32`). For features, with or without a given context, it is the distance
    /// of the point's `k0`-th neighbour; for the second stage of
    /// [`extract_chunks_staged`](crate::extract_chunks_staged), that plus the largest such
    /// distance among its neighbours, whose first-stage results its context reads. A caller
    /// that holds only part of a larger cloud knows a point's values are those of the whole
    /// cloud when every point of the whole cloud within (a little more than) its reach is
    /// held: the neighbour search is exact, ties broken by index.
    pub fn reach(&self) -> &[f32] {
        &self.reach
    }
}

/// Extracts features for every point of `cloud`; see [`Features`] for the layout.
///
/// Built on [`extract_chunks`]; the result does not depend on chunking or thread count.
pub fn extract(cloud: &PointCloud, config: &FeatureConfig) -> Result<Features, FeatureError> {
    dense(cloud, config, None)
}

/// [`extract`] with the [context](crate::ContextSet) (`config.context`) of a first classifier's
/// `probabilities` (non-edge, sharp, boundary per point, in cloud order): per scale, the
/// scale's features followed by its context values.
pub fn extract_in_context(
    cloud: &PointCloud,
    config: &FeatureConfig,
    probabilities: &[[f32; 3]],
) -> Result<Features, FeatureError> {
    dense(cloud, config, Some(probabilities))
}

/// Values per scale of an extraction, with or without context.
pub fn values_per_scale(config: &FeatureConfig, in_context: bool) -> usize {
    let context = if in_context {
        config.context.count()
    } else {
        0
    };
    config.features_per_scale() + context
}

/// Values per point of an extraction, with or without context.
pub fn values_per_point(config: &FeatureConfig, in_context: bool) -> usize {
    config.scales.len() * values_per_scale(config, in_context)
}

/// [`extract`] or [`extract_in_context`], as `probabilities` are given.
fn dense(
    cloud: &PointCloud,
    config: &FeatureConfig,
    probabilities: Option<&[[f32; 3]]>,
) -> Result<Features, FeatureError> {
    let per_point = values_per_point(config, probabilities.is_some());
    let mut values = vec![0.0; cloud.len() * per_point];
    chunks(
        cloud,
        config,
        probabilities,
        DEFAULT_CHUNK_POINTS,
        |block| {
            for (row, &i) in block.points().iter().enumerate() {
                let i = i as usize;
                values[i * per_point..(i + 1) * per_point].copy_from_slice(block.row(row));
            }
        },
    )?;
    Ok(Features { per_point, values })
}

/// Streams the features of every point of `cloud` to `f`, in blocks of at most
/// `chunk_points` points (Morton order; 0 counts as 1), each point exactly once.
///
/// Points that repeat a position count once in every neighbourhood and share its features
/// (see [`Distinct`]): a cloud gives the same features stored once or with repeats. A block
/// then holds at most `chunk_points` distinct positions, each followed by its repeats.
///
/// Memory is `O(chunk_points x (k0 + values per point))` beyond the cloud and its
/// search index, so huge clouds can be classified block by block. Each block is
/// computed in parallel on the current rayon pool; `f` runs on the calling thread.
pub fn extract_chunks(
    cloud: &PointCloud,
    config: &FeatureConfig,
    chunk_points: usize,
    f: impl FnMut(&FeatureBlock),
) -> Result<(), FeatureError> {
    chunks(cloud, config, None, chunk_points, f)
}

/// [`extract_chunks`] with the context of `probabilities`, laid out as in
/// [`extract_in_context`].
pub fn extract_chunks_in_context(
    cloud: &PointCloud,
    config: &FeatureConfig,
    probabilities: &[[f32; 3]],
    chunk_points: usize,
    f: impl FnMut(&FeatureBlock),
) -> Result<(), FeatureError> {
    chunks(cloud, config, Some(probabilities), chunk_points, f)
}

/// [`extract_chunks`] or [`extract_chunks_in_context`], as `probabilities` are given.
fn chunks(
    cloud: &PointCloud,
    config: &FeatureConfig,
    probabilities: Option<&[[f32; 3]]>,
    chunk_points: usize,
    mut f: impl FnMut(&FeatureBlock),
) -> Result<(), FeatureError> {
    config.validate()?;
    if let Some(p) = probabilities
        && p.len() != cloud.len()
    {
        return Err(FeatureError::ContextLength {
            points: cloud.len(),
            probabilities: p.len(),
        });
    }
    with_index(cloud, &mut f, |index, sink| {
        extract_indexed(cloud, index, config, probabilities, chunk_points, sink)
    })
}

/// Runs `run` over the search index of `cloud`'s distinct positions, with a sink that hands
/// each block of distinct positions on to `f` with every repeat of them (see [`Distinct`]).
pub(crate) fn with_index<R>(
    cloud: &PointCloud,
    f: &mut dyn FnMut(&FeatureBlock),
    run: impl FnOnce(&KnnIndex, &mut dyn FnMut(&FeatureBlock)) -> Result<R, FeatureError>,
) -> Result<R, FeatureError> {
    let Some(distinct) = Distinct::of(cloud) else {
        return run(&KnnIndex::new(cloud)?, f);
    };
    let index = KnnIndex::of_subset(cloud, distinct.firsts())?;
    let mut shared = FeatureBlock::default();
    run(&index, &mut |block| {
        shared.per_point = block.per_point;
        shared.points.clear();
        shared.values.clear();
        shared.reach.clear();
        for (row, &first) in block.points.iter().enumerate() {
            for &i in distinct.members(first) {
                shared.points.push(i);
                shared.values.extend_from_slice(block.row(row));
                shared.reach.push(block.reach[row]);
            }
        }
        f(&shared);
    })
    .map_err(|e| match e {
        FeatureError::Geom(GeomError::TooFewPoints { points, k }) => {
            FeatureError::TooFewDistinctPoints {
                points: cloud.len(),
                distinct: points,
                k,
            }
        }
        e => e,
    })
}

/// [`chunks`] for the points `index` holds, whose positions are all distinct.
fn extract_indexed(
    cloud: &PointCloud,
    index: &KnnIndex,
    config: &FeatureConfig,
    probabilities: Option<&[[f32; 3]]>,
    chunk_points: usize,
    f: &mut dyn FnMut(&FeatureBlock),
) -> Result<(), FeatureError> {
    let mut block = FeatureBlock {
        per_point: values_per_point(config, probabilities.is_some()),
        ..FeatureBlock::default()
    };
    // The features and the context read the index's Morton-ordered copy of the points by
    // position, where neighbours near in space are near in memory.
    let position = index.positions_by_index(cloud.len());
    // With context, the features go to a buffer of their own first, then beside the context.
    let mut plain = Vec::new();
    index.for_each_chunk_named(config.largest_scale(), chunk_points, &position, |chunk| {
        block.points.clear();
        block.points.extend_from_slice(chunk.queries());
        let rows = chunk.rows();
        radii(index.points(), rows, chunk.k(), &mut block.reach);
        match probabilities {
            Some(first) => {
                plain_features(index.points(), rows, config, &mut plain);
                let first = Probabilities {
                    points: index.points(),
                    order: index.order(),
                    first,
                };
                in_context(chunk, config, &plain, &first, &mut block.values);
            }
            None => plain_features(index.points(), rows, config, &mut block.values),
        }
        f(&block);
    })?;
    Ok(())
}

/// The distance of every row's last neighbour from its query (its first entry) into `out`
/// (resized): the [reach](FeatureBlock::reach) of features of `rows` (row-major, `k` per
/// row, naming `points`).
pub(crate) fn radii(points: &[[f32; 3]], rows: &[u32], k: usize, out: &mut Vec<f32>) {
    out.resize(rows.len() / k, 0.0);
    (out.par_iter_mut())
        .zip(rows.par_chunks(k))
        .for_each(|(out, row)| {
            let (p, last) = (points[row[0] as usize], points[row[k - 1] as usize]);
            let d2: f64 = (0..3)
                .map(|a| (f64::from(p[a]) - f64::from(last[a])).powi(2))
                .sum();
            *out = d2.sqrt() as f32;
        });
}

/// The features of every row of `rows` (row-major, `k0` per row, naming `points`) into
/// `out` (resized), in parallel.
pub(crate) fn plain_features(
    points: &[[f32; 3]],
    rows: &[u32],
    config: &FeatureConfig,
    out: &mut Vec<f32>,
) {
    let k0 = config.largest_scale();
    let features = config.features_per_point();
    out.resize(rows.len() / k0 * features, 0.0);
    out.par_chunks_mut(features * LANES)
        .zip(rows.par_chunks(k0 * LANES))
        .for_each_init(
            || Scratch::new(k0),
            |scratch, (out, rows)| group_features(points, rows, config, scratch, out),
        );
}

/// The rows of `chunk` with their `plain` features (as [`plain_features`] gives them), each
/// scale's beside its context of the `first` results, into `out` (resized), in parallel.
fn in_context(
    chunk: &NeighbourChunk,
    config: &FeatureConfig,
    plain: &[f32],
    first: &impl FirstResults,
    out: &mut Vec<f32>,
) {
    let per_point = values_per_point(config, true);
    out.resize(chunk.len() * per_point, 0.0);
    out.par_chunks_mut(per_point)
        .zip(plain.par_chunks(config.features_per_point()))
        .zip(chunk.rows().par_chunks(chunk.k()))
        .for_each(|((out, features), row)| in_context_row(row, config, features, first, out));
}

/// One row of [`in_context`]: the `features` of the point whose neighbour list is `row`, each
/// scale's beside its context, into `out`.
pub(crate) fn in_context_row(
    row: &[u32],
    config: &FeatureConfig,
    features: &[f32],
    first: &impl FirstResults,
    out: &mut [f32],
) {
    let per_scale = config.features_per_scale();
    let stride = values_per_scale(config, true);
    for (out, features) in (out.chunks_exact_mut(stride)).zip(features.chunks_exact(per_scale)) {
        out[..per_scale].copy_from_slice(features);
    }
    contexts(
        row,
        &config.scales,
        config.context,
        first,
        |scale, values| {
            let at = scale * stride + per_scale;
            out[at..at + values.len()].copy_from_slice(values);
        },
    );
}
