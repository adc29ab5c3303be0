//! A uniform grid over Morton-sorted points, with cell-batched exact kNN queries.
//!
//! Performance on uneven clouds (real scans: dense near the scanner, sparse far away,
//! outliers): the cell size follows the average density, so a dense cell can hold
//! thousands of points; its points are kept in pieces of at most [`PIECE`] with their
//! own boxes, grouped by [`GROUP`], and a query tests groups and pieces before any
//! point. A point in a sparse part, whose neighbours lie beyond the shared box, visits
//! cells best-first through the octree above them (see [`Grid::by_distance`]).
//!
//! Cells are cubes of one level of the implicit Morton octree, so each occupied cell is
//! a contiguous run of the sorted points. All queries of a cell share one candidate set
//! (the cells within `RING` of it); a query is answered from it when its `k` best
//! candidates lie closer than the candidate box's nearest face, which makes the answer
//! exact. Otherwise (points in sparse parts) cells are visited in order of distance,
//! found best-first in the octree above them.
//!
//! Within a cell, each query first filters the shared candidates with a limit taken
//! from the previous query (consecutive queries are Morton neighbours): its `k`-th
//! distance widened by 6%, which keeps ~1.12 k candidates and lets whole cells be
//! skipped; when that keeps fewer than `k` (rare on a surface), the triangle
//! bound `d_k(p) <= d_k(prev) + |p - prev|` (~1.5 k candidates); then the box's own
//! limit. Exactness never depends on these limits: whenever `k` candidates lie below a
//! limit that is inside the box, they are the true `k` nearest.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

use rayon::prelude::*;

use crate::morton::{BITS, Quantiser, code};
use crate::select::{Filter, Selection, key_distance, key_index};

/// Cells on each side of the query cell in the shared candidate box.
const RING: i64 = 2;
/// Relative safety margin on squared distances against rounding of faces and distances.
const MARGIN: f64 = 1e-4;

/// Occupied cells of one level, over points sorted by Morton code.
pub(crate) struct Grid {
    level: u32,
    /// Level codes of the occupied cells, ascending.
    codes: Vec<u64>,
    /// Start of each cell's run of sorted points (one extra entry: the end).
    starts: Vec<u32>,
    /// Largest cell coordinate on any axis.
    max_cell: i64,
}

/// Candidate points in structure-of-arrays form, with original indices, grouped in
/// pieces of consecutive sorted points so that a query can skip whole pieces beyond
/// its distance limit.
#[derive(Default)]
pub(crate) struct Candidates {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    index: Vec<u32>,
    /// Per piece: end of its points in the arrays above, and its bounding box.
    pieces: Vec<usize>,
    /// Per piece, its bounding box by axis: lower corners, then upper corners (so a
    /// query tests many boxes per vector instruction).
    boxes: [Vec<f64>; 6],
    /// Per group of [`GROUP`] consecutive pieces: end of its pieces, and a box around
    /// them, so that a query skips far groups without testing each piece.
    groups: Vec<(usize, Box3)>,
    /// One past the largest sorted position among the candidates.
    end: usize,
}

/// Points per candidate piece at most. Cells hold `k / 6` points on average, but a
/// dense part of an uneven cloud (a scan near its scanner) packs thousands into one
/// cell; split like this, a query computes distances only to the pieces near it.
const PIECE: usize = 32;

/// Pieces per group: a cell holding a dense half of a million-point cloud becomes
/// ~16k pieces, which one query would otherwise test one by one.
const GROUP: usize = 32;

/// Lower and upper corner of an axis-aligned box.
type Box3 = ([f64; 3], [f64; 3]);

/// Per-thread buffers of the search.
#[derive(Default)]
pub(crate) struct Scratch {
    shared: Candidates,
    own: Candidates,
    select: Selection,
    /// Octree nodes to visit, nearest first (see [`Grid::by_distance`]).
    by_distance: BinaryHeap<Reverse<Node>>,
    /// The last query of this thread and its `k`-th squared distance: where the next
    /// query's limits come from, also across cells.
    prev: Option<([f32; 3], f32)>,
}

/// The sorted points a grid indexes.
pub(crate) struct Sorted<'a> {
    pub(crate) quant: &'a Quantiser,
    pub(crate) points: &'a [[f32; 3]],
    /// Original index of each sorted point.
    pub(crate) order: &'a [u32],
}

impl Grid {
    /// The finest level whose occupied cells hold on average at least `k / 6` points:
    /// on a surface the k-th neighbour then lies about 1.4 cells away, inside the
    /// shared box of `RING` = 2 cells.
    pub(crate) fn new(s: &Sorted<'_>, k: usize) -> Self {
        let codes: Vec<u64> = s
            .points
            .par_iter()
            .map(|p| code(s.quant.cell(*p)))
            .collect();
        // Consecutive codes first differ at bit b: different cells at levels <= b / 3.
        let mut split_at = [0usize; BITS as usize + 1];
        for w in codes.windows(2) {
            if w[0] != w[1] {
                split_at[((63 - (w[0] ^ w[1]).leading_zeros()) / 3) as usize] += 1;
            }
        }
        let target = (k / 6).max(1);
        let mut level = BITS;
        let mut cells_above = 0;
        for l in (0..=BITS).rev() {
            cells_above += split_at[l as usize];
            if codes.len() / (cells_above + 1) >= target {
                level = l;
            }
        }
        let mut grid = Self {
            level,
            codes: Vec::new(),
            starts: Vec::new(),
            max_cell: i64::from(((1u32 << BITS) - 1) >> level),
        };
        for (i, c) in codes.iter().enumerate() {
            let c = c >> (3 * level);
            if grid.codes.last() != Some(&c) {
                grid.codes.push(c);
                grid.starts.push(i as u32);
            }
        }
        grid.starts.push(codes.len() as u32);
        grid
    }

    /// Index of the cell holding sorted point `pos`.
    pub(crate) fn cell_of(&self, pos: usize) -> usize {
        self.starts.partition_point(|&s| s as usize <= pos) - 1
    }

    /// Sorted positions of cell `cell`'s points.
    pub(crate) fn range(&self, cell: usize) -> Range<usize> {
        self.starts[cell] as usize..self.starts[cell + 1] as usize
    }

    fn coords(&self, s: &Sorted<'_>, cell: usize) -> [i64; 3] {
        s.quant
            .cell(s.points[self.starts[cell] as usize])
            .map(|c| (c >> self.level) as i64)
    }

    fn lookup(&self, c: [i64; 3]) -> Option<Range<usize>> {
        if c.iter().any(|&v| v < 0 || v > self.max_cell) {
            return None;
        }
        let i = self.codes.binary_search(&code(c.map(|v| v as u64))).ok()?;
        Some(self.range(i))
    }

    /// Gathers the points of the cells within `RING` of cell coordinates `c`.
    fn gather(&self, s: &Sorted<'_>, c: [i64; 3], out: &mut Candidates) {
        out.clear();
        for z in c[2] - RING..=c[2] + RING {
            for y in c[1] - RING..=c[1] + RING {
                for x in c[0] - RING..=c[0] + RING {
                    if let Some(range) = self.lookup([x, y, z]) {
                        out.add(s, range, self.block_box(s, [x, y, z], 1));
                    }
                }
            }
        }
    }

    /// Box of the `size`^3 cells from cell coordinates `c` up.
    fn block_box(&self, s: &Sorted<'_>, c: [i64; 3], size: i64) -> Box3 {
        let lo = [0, 1, 2].map(|a| s.quant.face(a, (c[a] as u64) << self.level));
        let hi = [0, 1, 2].map(|a| s.quant.face(a, ((c[a] + size) as u64) << self.level));
        (lo, hi)
    }

    /// Squared distance from `p` below which every point is in the box of the cells
    /// within `RING` of cell `c` (infinite when the box reaches past the grid on every
    /// side it faces).
    fn limit(&self, s: &Sorted<'_>, c: [i64; 3], p: [f32; 3]) -> f32 {
        let r = RING;
        let mut bound = f64::INFINITY;
        for a in 0..3 {
            let x = f64::from(p[a]);
            if c[a] - r > 0 {
                bound = bound.min(x - s.quant.face(a, ((c[a] - r) as u64) << self.level));
            }
            if c[a] + r < self.max_cell {
                bound = bound.min(s.quant.face(a, ((c[a] + r + 1) as u64) << self.level) - x);
            }
        }
        if bound.is_infinite() || s.quant.inv == 0.0 {
            return f32::INFINITY;
        }
        (bound.max(0.0).powi(2) * (1.0 - MARGIN)) as f32
    }

    /// Writes the `out.len()` nearest neighbours of the sorted points `queries` (all in
    /// cell `cell`) to `rows` (row-major), each index `j` as `names[j]` when given.
    /// Returns one past the largest sorted position among the cells searched: no neighbour
    /// lies at or beyond it.
    pub(crate) fn search_cell(
        &self,
        s: &Sorted<'_>,
        cell: usize,
        queries: Range<usize>,
        names: Option<&[u32]>,
        rows: &mut [u32],
        scratch: &mut Scratch,
    ) -> usize {
        let k = rows.len() / queries.len();
        let c = self.coords(s, cell);
        self.gather(s, c, &mut scratch.shared);
        let mut end = scratch.shared.end;
        for (pos, out) in queries.zip(rows.chunks_exact_mut(k)) {
            let p = s.points[pos];
            let q = s.order[pos];
            let exact = self.limit(s, c, p);
            let (guess, bound) = scratch
                .prev
                .map_or((f32::INFINITY, f32::INFINITY), |(x, kth)| {
                    (guess(kth), reach(kth, x, p))
                });
            let sel = &mut scratch.select;
            let shared = &scratch.shared;
            let answered = (guess < exact && shared.best(p, q, guess, sel, out))
                || (guess < bound && bound < exact && shared.best(p, q, bound, sel, out))
                || shared.best(p, q, exact, sel, out);
            if !answered {
                self.by_distance(s, p, q, scratch, out);
                end = end.max(scratch.own.end);
            }
            // Every path leaves this query's neighbours, sorted, in the selection.
            scratch.prev = Some((p, key_distance(scratch.select.sorted(k)[k - 1])));
            // Renamed while the row is in the cache.
            if let Some(names) = names {
                out.iter_mut().for_each(|j| *j = names[*j as usize]);
            }
        }
        end
    }

    /// Exact fallback for isolated points: visit cells by increasing distance until
    /// `k` candidates are in and every cell within the `k`-th of them is visited.
    ///
    /// The cells are found best-first in the implicit octree above them (a node at
    /// `depth` d is a run of cells sharing `code >> 3d`), so a query costs about
    /// `log(cells)` node visits plus the cells near it, never a pass over all cells:
    /// that pass made scattered outliers cost O(points x cells).
    fn by_distance(&self, s: &Sorted<'_>, p: [f32; 3], q: u32, sc: &mut Scratch, out: &mut [u32]) {
        let k = out.len();
        let heap = &mut sc.by_distance;
        heap.clear();
        let root = Node {
            distance: 0,
            depth: BITS - self.level,
            cells: (0, self.codes.len() as u32),
        };
        heap.push(Reverse(root));
        let own = &mut sc.own;
        own.clear();
        let mut reach = f64::INFINITY;
        while let Some(Reverse(node)) = heap.pop() {
            if f64::from_bits(node.distance) > reach {
                break;
            }
            let (lo, hi) = (node.cells.0 as usize, node.cells.1 as usize);
            if node.depth == 0 {
                own.add(s, self.range(lo), self.block_box(s, self.coords(s, lo), 1));
                if reach.is_infinite() && own.index.len() >= k {
                    own.best(p, q, f32::INFINITY, &mut sc.select, out);
                    let kth = key_distance(sc.select.sorted(k)[k - 1]);
                    reach = f64::from(kth) * (1.0 + MARGIN);
                }
                continue;
            }
            // Children: the runs of equal `code >> 3 (depth - 1)` among the node's cells.
            let shift = 3 * (node.depth - 1);
            let size = 1i64 << (node.depth - 1);
            let mut start = lo;
            while start < hi {
                let child = self.codes[start] >> shift;
                let end = start + self.codes[start..hi].partition_point(|&c| c >> shift == child);
                let corner = self.coords(s, start).map(|v| v & !(size - 1));
                let d2 = box_distance2(p, &self.block_box(s, corner, size));
                heap.push(Reverse(Node {
                    distance: d2.to_bits(),
                    depth: node.depth - 1,
                    cells: (start as u32, end as u32),
                }));
                start = end;
            }
        }
        own.best(p, q, f32::INFINITY, &mut sc.select, out);
    }
}

/// A node of the implicit octree over the grid's cells, for [`Grid::by_distance`].
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Node {
    /// Bits of the squared distance from the query to the node's box (non-negative
    /// `f64` bits order like the values), so nodes order nearest first.
    distance: u64,
    /// Levels above the grid's cells (0: one cell).
    depth: u32,
    /// The node's cells: a range of indices into `Grid::codes`.
    cells: (u32, u32),
}

impl Candidates {
    fn clear(&mut self) {
        self.end = 0;
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.index.clear();
        self.pieces.clear();
        self.boxes.iter_mut().for_each(Vec::clear);
        self.groups.clear();
    }

    /// Appends a piece ending at point `end`, with box `b`, to the last group or a new one.
    fn push_piece(&mut self, end: usize, b: Box3) {
        if self.pieces.len().is_multiple_of(GROUP) {
            self.groups.push((self.pieces.len() + 1, b));
        } else if let Some((last, g)) = self.groups.last_mut() {
            *last += 1;
            for a in 0..3 {
                g.0[a] = g.0[a].min(b.0[a]);
                g.1[a] = g.1[a].max(b.1[a]);
            }
        }
        self.pieces.push(end);
        for a in 0..3 {
            self.boxes[a].push(b.0[a]);
            self.boxes[a + 3].push(b.1[a]);
        }
    }

    /// Appends the sorted points `range`, which fill the box `cell`: as one piece, or
    /// when they are more than two pieces' worth, in pieces of [`PIECE`] points, each
    /// with its bounding box.
    fn add(&mut self, s: &Sorted<'_>, range: Range<usize>, cell: Box3) {
        self.end = self.end.max(range.end);
        let pts = &s.points[range.clone()];
        self.xs.extend(pts.iter().map(|p| p[0]));
        self.ys.extend(pts.iter().map(|p| p[1]));
        self.zs.extend(pts.iter().map(|p| p[2]));
        let start = self.index.len();
        self.index.extend_from_slice(&s.order[range]);
        if pts.len() <= 2 * PIECE {
            self.push_piece(self.index.len(), cell);
            return;
        }
        for (i, piece) in pts.chunks(PIECE).enumerate() {
            let mut bounds = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for p in piece {
                for (a, &x) in p.iter().enumerate() {
                    bounds.0[a] = bounds.0[a].min(f64::from(x));
                    bounds.1[a] = bounds.1[a].max(f64::from(x));
                }
            }
            self.push_piece(start + i * PIECE + piece.len(), bounds);
        }
    }

    /// The `out.len()` best candidates for point `p` (original index `q`) among those
    /// with squared distance below `lim`; false when there are too few.
    ///
    /// Order: the query itself first, then by distance, then by index.
    fn best(&self, p: [f32; 3], q: u32, lim: f32, sel: &mut Selection, out: &mut [u32]) -> bool {
        let k = out.len();
        sel.clear();
        let ranges = &mut sel.ranges;
        ranges.clear();
        let mut first_piece = 0;
        for (last_piece, group) in &self.groups {
            let pieces = std::mem::replace(&mut first_piece, *last_piece)..*last_piece;
            // Skips groups, then pieces, whose every point is beyond the limit.
            if beyond(p, group, lim) {
                continue;
            }
            let near = &mut sel.near;
            near.clear();
            near.resize(pieces.len(), false);
            let boxes = self.boxes.each_ref().map(|b| &b[pieces.clone()]);
            near_boxes(p, lim, boxes, near);
            let mut begin = pieces.start.checked_sub(1).map_or(0, |i| self.pieces[i]);
            for (&end, &near) in self.pieces[pieces].iter().zip(near.iter()) {
                let r = std::mem::replace(&mut begin, end)..end;
                if near {
                    ranges.push(r);
                }
            }
        }
        sel.keep_ranges(Filter {
            p,
            q,
            lim,
            xyz: (&self.xs, &self.ys, &self.zs),
            index: &self.index,
        });
        if sel.kept() < k {
            return false;
        }
        sel.select(k);
        for (o, &key) in out.iter_mut().zip(sel.sorted(k)) {
            *o = key_index(key, q);
        }
        true
    }
}

/// Whether each of the boxes `[lower x, y, z, upper x, y, z]` may hold points within
/// squared distance `lim` of `p` (not [`beyond`]), into `near`, for all boxes in one
/// loop that vectorises (a test and a branch per box cost ~4% of `detect`).
fn near_boxes(p: [f32; 3], lim: f32, boxes: [&[f64]; 6], near: &mut [bool]) {
    let n = near.len();
    let [lx, ly, lz, hx, hy, hz] = boxes.map(|b| &b[..n]);
    for (i, near) in near.iter_mut().enumerate() {
        let b = ([lx[i], ly[i], lz[i]], [hx[i], hy[i], hz[i]]);
        *near = !beyond(p, &b, lim);
    }
}

/// Whether every point of box `b` is beyond squared distance `lim` of `p`, with a
/// rounding margin.
#[inline(always)]
fn beyond(p: [f32; 3], b: &Box3, lim: f32) -> bool {
    box_distance2(p, b) * (1.0 - MARGIN) >= f64::from(lim)
}

/// Squared distance from `p` to the nearest point of box `b` (0 inside).
fn box_distance2(p: [f32; 3], b: &Box3) -> f64 {
    (0..3)
        .map(|a| {
            let x = f64::from(p[a]);
            let d = (b.0[a] - x).max(x - b.1[a]).max(0.0);
            d * d
        })
        .sum()
}

/// First limit tried for a query: the previous query's `k`-th squared distance `kth`,
/// widened by 6% in distance. Consecutive queries are about a point spacing apart, so
/// the `k`-th distance barely changes; measured on a 1M-point surface cloud, 97% of the
/// queries keep `k` or more (1.12 k on average, vs 1.5 k for [`reach`]'s bound).
fn guess(kth: f32) -> f32 {
    (f64::from(kth) * 1.06 * 1.06) as f32
}

/// Squared distance within which the `k` neighbours of a point at `prev`, the
/// farthest at squared distance `kth`, all lie from `p`: an upper bound on `p`'s own
/// `k`-th squared distance (triangle inequality, with a margin for `f32` rounding).
fn reach(kth: f32, prev: [f32; 3], p: [f32; 3]) -> f32 {
    let step = f64::from(crate::knn::dist2(prev, p)).sqrt();
    let r = f64::from(kth).sqrt() + step;
    (r * r * (1.0 + MARGIN)) as f32
}
