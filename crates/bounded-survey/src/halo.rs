//! A tile's points and its halo: the points of the other inputs near it, read-only.
//!
//! The halo of tile `T` at radius `r` is every point of the other inputs inside `T`'s box
//! grown by `r` on each side (the tile's *region*). Each other input whose box meets the
//! region is read once, its points inside kept: a LAS or LAZ neighbour in chunks, so that
//! only a chunk of it is held, any other format whole while it is read. A side of the region
//! at or beyond the survey's bounds is taken as infinitely far: no point of the survey lies
//! past it.
//!
//! The tile and its halo form one cloud in the survey's frame ([`Plan::frame`]), in the
//! survey's point order (inputs in plan order, each file's points in file order): an
//! order-preserving part of the survey as one cloud. The neighbour search breaks distance
//! ties by index, so two points tie the same way in both, and so do repeated positions
//! (their first point is the same one): a point whose neighbourhood lies in the region gets
//! the neighbours, in the same order, that it has in the whole survey.

use std::ops::Range;

use bounded_data::format::Format;
use bounded_data::las;
use bounded_data::table::{PointTable, TableView};
use bounded_geom::{Frame, PointCloud};

use crate::{Input, Plan, ReadOptions, SurveyError};

/// A tile's box grown by a radius, in the offsets of the survey's frame; sides beyond the
/// survey's bounds are infinitely far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    lo: [f64; 3],
    hi: [f64; 3],
    /// The tile's box.
    tile: ([f64; 3], [f64; 3]),
    /// The survey's box.
    survey: ([f64; 3], [f64; 3]),
}

impl Region {
    /// The region of tile `tile` of `plan` at `radius` (absolute units).
    pub fn around(plan: &Plan, tile: usize, radius: f64) -> Self {
        let input = &plan.inputs()[tile];
        Self::around_box(plan, input.lo, input.hi, radius)
    }

    /// The region of the box `lo`..`hi` (absolute coordinates: a tile's, or a block's of a
    /// file labelled in blocks) in `plan` at `radius` (absolute units).
    pub fn around_box(plan: &Plan, lo: [f64; 3], hi: [f64; 3], radius: f64) -> Self {
        let frame = plan.frame();
        let (tile_lo, tile_hi) = local_box(&frame, lo, hi);
        let (survey_lo, survey_hi) = local_box(&frame, plan.bounds().0, plan.bounds().1);
        let r = radius / frame.scale;
        Self {
            lo: std::array::from_fn(|a| {
                let lo = tile_lo[a] - r;
                if lo <= survey_lo[a] {
                    f64::NEG_INFINITY
                } else {
                    lo
                }
            }),
            hi: std::array::from_fn(|a| {
                let hi = tile_hi[a] + r;
                if hi >= survey_hi[a] {
                    f64::INFINITY
                } else {
                    hi
                }
            }),
            tile: (tile_lo, tile_hi),
            survey: (survey_lo, survey_hi),
        }
    }

    /// Whether the offset `p` lies in the region (its sides included).
    pub fn contains(&self, p: [f32; 3]) -> bool {
        (0..3).all(|a| (self.lo[a]..=self.hi[a]).contains(&f64::from(p[a])))
    }

    /// The distance from the offset `p` (inside) to the nearest finite side: how far a
    /// neighbourhood around `p` may reach and still lie in the region.
    pub fn room(&self, p: [f32; 3]) -> f64 {
        (0..3)
            .map(|a| (f64::from(p[a]) - self.lo[a]).min(self.hi[a] - f64::from(p[a])))
            .fold(f64::INFINITY, f64::min)
    }

    /// The smallest radius (in offsets) whose region, around the same tile, has `room` for
    /// `reach` at the tile point `p`: per side, the reach beyond the tile's side, or the gap
    /// between that side and the survey's, where the side becomes infinitely far.
    pub fn radius_for(&self, p: [f32; 3], reach: f64) -> f64 {
        let ((tile_lo, tile_hi), (survey_lo, survey_hi)) = (self.tile, self.survey);
        (0..3)
            .map(|a| {
                let p = f64::from(p[a]);
                let below = (reach - (p - tile_lo[a])).min(tile_lo[a] - survey_lo[a]);
                let above = (reach - (tile_hi[a] - p)).min(survey_hi[a] - tile_hi[a]);
                below.max(above)
            })
            .fold(0.0, f64::max)
    }

    /// Whether the box of offsets `lo`..`hi` meets the region.
    pub(crate) fn meets(&self, lo: [f64; 3], hi: [f64; 3]) -> bool {
        (0..3).all(|a| lo[a] <= self.hi[a] && hi[a] >= self.lo[a])
    }

    /// Whether no side is finite: the region holds the whole survey.
    pub fn is_everything(&self) -> bool {
        (0..3).all(|a| self.lo[a] == f64::NEG_INFINITY && self.hi[a] == f64::INFINITY)
    }
}

/// The box `lo`..`hi` in the offsets of `frame` (the offsets of points inside it lie
/// inside it: rounding to `f32` keeps order).
pub(crate) fn local_box(frame: &Frame, lo: [f64; 3], hi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    (
        frame.local(lo).map(f64::from),
        frame.local(hi).map(f64::from),
    )
}

/// The offsets of `table`'s points, the input `index` of `plan`, in the survey's frame;
/// fails for a point outside the input's declared box.
pub fn offsets(
    plan: &Plan,
    index: usize,
    table: &PointTable,
) -> Result<Vec<[f32; 3]>, SurveyError> {
    let mut all = Vec::with_capacity(table.len());
    each_offset(plan, index, 0, table, &mut |p| all.push(p))?;
    Ok(all)
}

/// Points per chunk when a LAS or LAZ neighbour is read for its halo.
const CHUNK: usize = 1 << 20;

/// Calls `f` with the offset of every point of the input `index` of `plan`, read as `read`
/// says: a LAS or LAZ file in chunks, so that only a chunk of it is held, any other whole.
fn each_offset_of_file(
    plan: &Plan,
    index: usize,
    read: ReadOptions,
    f: &mut dyn FnMut([f32; 3]),
) -> Result<(), SurveyError> {
    let path = &plan.inputs()[index].path;
    if let Format::Las { .. } = Format::from_path(path)? {
        las::read_chunks(path, CHUNK, |first, table| {
            each_offset(plan, index, first, &table, f)
        })?;
        return Ok(());
    }
    let (table, _) = read.read(path)?;
    each_offset(plan, index, 0, &table, f)
}

/// Calls `f` with the offset of every point of `table`, the points of input `index` of
/// `plan` from its point `first` on (as [`offsets`] gives them).
fn each_offset(
    plan: &Plan,
    index: usize,
    first: usize,
    table: &PointTable,
    f: &mut dyn FnMut([f32; 3]),
) -> Result<(), SurveyError> {
    let input = &plan.inputs()[index];
    let frame = plan.frame();
    let view = table.view();
    for i in 0..table.len() {
        f(frame.local(position_in_bounds(input, &view, first, i)?));
    }
    Ok(())
}

/// The absolute position of point `i` of `view`, point `first + i` of `input`; fails when it
/// lies outside the input's declared box.
pub(crate) fn position_in_bounds(
    input: &Input,
    view: &TableView<'_>,
    first: usize,
    i: usize,
) -> Result<[f64; 3], SurveyError> {
    let p = view.position(i);
    if !(0..3).all(|a| (input.lo[a]..=input.hi[a]).contains(&p[a])) {
        return Err(SurveyError::OutsideBounds {
            path: input.path.clone(),
            index: first + i,
            position: p,
            lo: input.lo,
            hi: input.hi,
        });
    }
    Ok(p)
}

/// A tile with its halo, as one cloud.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The tile's points and its halo's, in the survey's frame and order.
    pub cloud: PointCloud,
    /// Where the tile's points are in `cloud` (in file order).
    pub tile: Range<usize>,
}

/// Loads the halo of tile `tile` in `region` around `tile_points` (the tile's offsets, from
/// [`offsets`]): reads every other input whose box meets the region, one at a time.
pub fn load(
    plan: &Plan,
    tile: usize,
    tile_points: &[[f32; 3]],
    region: &Region,
    read: ReadOptions,
) -> Result<Loaded, SurveyError> {
    let frame = plan.frame();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    for (j, input) in plan.inputs().iter().enumerate() {
        let (lo, hi) = local_box(&frame, input.lo, input.hi);
        if j == tile || !region.meets(lo, hi) {
            continue;
        }
        let near = if j < tile { &mut before } else { &mut after };
        each_offset_of_file(plan, j, read, &mut |p| {
            if region.contains(p) {
                near.push(p);
            }
        })?;
    }
    let tile_range = before.len()..before.len() + tile_points.len();
    let mut points = before;
    points.extend_from_slice(tile_points);
    points.append(&mut after);
    let path = &plan.inputs()[tile].path;
    let frame_error = |what: String| SurveyError::Frame {
        path: path.clone(),
        what,
    };
    let cloud = PointCloud::from_frame(frame, points).map_err(|e| frame_error(e.to_string()))?;
    if cloud.frame() != frame {
        return Err(frame_error(format!(
            "its offsets were rescaled to {:?}",
            cloud.frame()
        )));
    }
    Ok(Loaded {
        cloud,
        tile: tile_range,
    })
}
