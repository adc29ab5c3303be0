//! A uniform grid of points for min-distance tests and near-neighbour queries.
//!
//! Cells are cubes of side `cell`; a query visits the 27 cells around the query point, so it
//! sees every stored point within distance `cell`. Cell heads live in a dense array when the
//! bounding box holds few enough cells (the fast case: most looked-up cells are empty, and
//! an array answers that at once), else in a hash map.

use bounded_geom::vec3::{V3, norm, sub};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Multiplicative hash of a packed cell key: the std SipHash costs more than the whole query.
#[derive(Default, Clone, Copy)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

const NONE: u32 = u32::MAX;

/// Largest number of cells held as a dense array (16 MB of heads).
const DENSE_CELLS: f64 = (1 << 22) as f64;

/// Where the first point of each cell is found.
enum Heads {
    /// Cells of the bounding box, x fastest; coordinates outside are clamped onto it.
    Dense {
        lo: [i64; 3],
        dims: [i64; 3],
        heads: Vec<u32>,
    },
    /// Cells by packed key.
    Sparse(HashMap<u64, u32, BuildHasherDefault<CellHasher>>),
}

/// Points bucketed by cell, each cell a linked list threaded through `next`.
pub(crate) struct Grid {
    cell: f64,
    heads: Heads,
    next: Vec<u32>,
    points: Vec<V3>,
}

/// The bounding box `[lo, hi]` of some points.
pub(crate) fn bounds(points: impl IntoIterator<Item = V3>) -> [V3; 2] {
    points.into_iter().fold(
        [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
        |[lo, hi], p| {
            [
                [0, 1, 2].map(|a| lo[a].min(p[a])),
                [0, 1, 2].map(|a| hi[a].max(p[a])),
            ]
        },
    )
}

impl Grid {
    /// An empty grid; `cell` is the largest query radius it will answer exactly, `[lo, hi]`
    /// the box where points and queries are expected (points outside still work, slower).
    pub(crate) fn new(cell: f64, [lo, hi]: [V3; 2]) -> Self {
        let lo_cell = lo.map(|c| (c / cell).floor());
        let dims = [0, 1, 2].map(|a| (hi[a] / cell).floor() - lo_cell[a] + 1.0);
        let count = dims.iter().product::<f64>();
        let heads = if (1.0..=DENSE_CELLS).contains(&count) {
            Heads::Dense {
                lo: lo_cell.map(|c| c as i64),
                dims: dims.map(|d| d as i64),
                heads: vec![NONE; count as usize],
            }
        } else {
            Heads::Sparse(HashMap::default())
        };
        Self {
            cell,
            heads,
            next: Vec::new(),
            points: Vec::new(),
        }
    }

    fn coords(&self, p: V3) -> [i64; 3] {
        let c = p.map(|c| (c / self.cell).floor() as i64);
        match &self.heads {
            Heads::Dense { lo, dims, .. } => {
                [0, 1, 2].map(|a| (c[a] - lo[a]).clamp(0, dims[a] - 1))
            }
            Heads::Sparse(_) => c,
        }
    }

    /// The head of cell `c` (in the coordinates of [`coords`](Self::coords)); `None` outside
    /// a dense grid.
    fn head(&self, c: [i64; 3]) -> Option<u32> {
        match &self.heads {
            Heads::Dense { dims, heads, .. } => {
                let inside = (0..3).all(|a| (0..dims[a]).contains(&c[a]));
                inside.then(|| heads[((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize])
            }
            Heads::Sparse(map) => map.get(&Self::key(c)).copied(),
        }
    }

    /// Packs cell coordinates into one key; far cells may share a key, which only costs a
    /// few extra distance checks, never a wrong answer.
    fn key(c: [i64; 3]) -> u64 {
        const MASK: u64 = (1 << 21) - 1;
        (c[0] as u64 & MASK) | ((c[1] as u64 & MASK) << 21) | ((c[2] as u64 & MASK) << 42)
    }

    /// Stores `p` and returns its index (insertion order).
    pub(crate) fn insert(&mut self, p: V3) -> u32 {
        let index = self.points.len() as u32;
        let c = self.coords(p);
        let head = match &mut self.heads {
            Heads::Dense { dims, heads, .. } => {
                &mut heads[((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize]
            }
            Heads::Sparse(map) => map.entry(Self::key(c)).or_insert(NONE),
        };
        self.next.push(*head);
        *head = index;
        self.points.push(p);
        index
    }

    /// The stored points, in insertion order.
    pub(crate) fn points(&self) -> &[V3] {
        &self.points
    }

    /// Calls `visit(index, distance)` for stored points in the 27 cells around `p`, the
    /// query point's own cell first, until `visit` returns `true`; returns whether it did.
    pub(crate) fn search_near(&self, p: V3, mut visit: impl FnMut(u32, f64) -> bool) -> bool {
        let c = self.coords(p);
        // The own cell first: a rejected dart usually hits there, and stops the search.
        const ORDER: [i64; 3] = [0, -1, 1];
        for dx in ORDER {
            for dy in ORDER {
                for dz in ORDER {
                    let mut i = self.head([c[0] + dx, c[1] + dy, c[2] + dz]).unwrap_or(NONE);
                    while i != NONE {
                        if visit(i, norm(sub(self.points[i as usize], p))) {
                            return true;
                        }
                        i = self.next[i as usize];
                    }
                }
            }
        }
        false
    }

    /// Calls `visit(index, distance)` for every stored point in the 27 cells around `p`.
    pub(crate) fn for_each_near(&self, p: V3, mut visit: impl FnMut(u32, f64)) {
        self.search_near(p, |i, d| {
            visit(i, d);
            false
        });
    }

    /// True when a stored point lies closer than `r` (at most the cell size) to `p`.
    pub(crate) fn any_within(&self, p: V3, r: f64) -> bool {
        self.search_near(p, |_, d| d < r)
    }

    /// Distance to the nearest stored point other than `p` itself, if one lies within the cell size.
    pub(crate) fn nearest_other(&self, p: V3) -> Option<f64> {
        let mut best = f64::INFINITY;
        self.for_each_near(p, |_, d| {
            if d > 0.0 && d < best {
                best = d;
            }
        });
        (best <= self.cell).then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_points_across_cell_borders_and_negative_coordinates() {
        // Dense (small box), dense with points outside the box, and sparse (huge box).
        for box_ in [
            [[-1.0; 3], [4.0; 3]],
            [[0.0; 3], [0.5; 3]],
            [[-1e9; 3], [1e9; 3]],
        ] {
            let mut g = Grid::new(1.0, box_);
            g.insert([-0.05, 0.0, 0.0]);
            g.insert([3.0, 3.0, 3.0]);
            assert!(g.any_within([0.05, 0.0, 0.0], 0.2));
            assert!(!g.any_within([0.5, 0.0, 0.0], 0.2));
            let d = g.nearest_other([0.35, 0.0, 0.0]).unwrap();
            assert!((d - 0.4).abs() < 1e-12);
            assert_eq!(g.nearest_other([10.0, 0.0, 0.0]), None);
            assert!(g.any_within([3.5, 3.0, 3.0], 0.6));
        }
        assert!(matches!(
            Grid::new(1.0, [[-1.0; 3], [4.0; 3]]).heads,
            Heads::Dense { .. }
        ));
        assert!(matches!(
            Grid::new(1.0, [[-1e9; 3], [1e9; 3]]).heads,
            Heads::Sparse(_)
        ));
    }
}
