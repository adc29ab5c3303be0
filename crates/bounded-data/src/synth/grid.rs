//! A spatial hash of points for min-distance tests and near-neighbour queries.
//!
//! Cells are cubes of side `cell`; a query visits the 27 cells around the query point, so it
//! sees every stored point within distance `cell`. Cells live in a hash map (not a dense
//! array) because thin, stretched shapes would make a dense grid huge.

use super::vec3::{V3, norm, sub};
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

/// Points bucketed by cell, each cell a linked list threaded through `next`.
pub(crate) struct Grid {
    cell: f64,
    heads: HashMap<u64, u32, BuildHasherDefault<CellHasher>>,
    next: Vec<u32>,
    points: Vec<V3>,
}

impl Grid {
    /// An empty grid; `cell` is the largest query radius it will answer exactly.
    pub(crate) fn new(cell: f64) -> Self {
        Self {
            cell,
            heads: HashMap::default(),
            next: Vec::new(),
            points: Vec::new(),
        }
    }

    fn coords(&self, p: V3) -> [i64; 3] {
        p.map(|c| (c / self.cell).floor() as i64)
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
        let head = self.heads.entry(Self::key(self.coords(p))).or_insert(NONE);
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
                    let key = Self::key([c[0] + dx, c[1] + dy, c[2] + dz]);
                    let mut i = self.heads.get(&key).copied().unwrap_or(NONE);
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
        let mut g = Grid::new(1.0);
        g.insert([-0.05, 0.0, 0.0]);
        g.insert([3.0, 3.0, 3.0]);
        assert!(g.any_within([0.05, 0.0, 0.0], 0.2));
        assert!(!g.any_within([0.5, 0.0, 0.0], 0.2));
        let d = g.nearest_other([0.35, 0.0, 0.0]).unwrap();
        assert!((d - 0.4).abs() < 1e-12);
        assert_eq!(g.nearest_other([10.0, 0.0, 0.0]), None);
    }
}
