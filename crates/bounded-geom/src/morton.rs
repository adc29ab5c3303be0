//! Morton (Z-order) codes: spatially coherent ordering and an implicit octree.
//!
//! Sorting points by their 63-bit code on a 2^21 grid sorts them by the cell of every
//! coarser level at once (a level-`L` cell is a run of equal `code >> 3L`).

use rayon::prelude::*;

/// Bits per axis of the Morton code (3 x 21 = 63 bits).
pub(crate) const BITS: u32 = 21;

/// Maps coordinates to integer cells of a 2^21 grid over a bounding cube.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Quantiser {
    /// Lower corner of the bounding box.
    pub(crate) lo: [f64; 3],
    /// Fine cells per unit length (0 when all points coincide).
    pub(crate) inv: f64,
}

impl Quantiser {
    pub(crate) fn new(points: impl IntoIterator<Item = [f32; 3]>) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for a in 0..3 {
                lo[a] = lo[a].min(f64::from(p[a]));
                hi[a] = hi[a].max(f64::from(p[a]));
            }
        }
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        let cells = f64::from((1u32 << BITS) - 1);
        let inv = if extent > 0.0 { cells / extent } else { 0.0 };
        Self { lo, inv }
    }

    /// Fine cell coordinates of `p`.
    pub(crate) fn cell(&self, p: [f32; 3]) -> [u64; 3] {
        [0, 1, 2].map(|a| ((f64::from(p[a]) - self.lo[a]) * self.inv) as u64)
    }

    /// Coordinate of the lower face of fine cell `c` along axis `a`.
    pub(crate) fn face(&self, a: usize, c: u64) -> f64 {
        self.lo[a] + c as f64 / self.inv
    }
}

/// Morton code of fine cell coordinates.
pub(crate) fn code(c: [u64; 3]) -> u64 {
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// Indices of `points` sorted by their Morton code on a 2^21 grid over the bounding
/// box, ties by index. Consecutive indices are spatially close, so neighbouring
/// queries touch the same memory.
pub fn morton_order(points: &[[f32; 3]]) -> Vec<u32> {
    let quant = Quantiser::new(points.iter().copied());
    sorted_codes(points.len(), |i| points[i], &quant)
        .into_iter()
        .map(|(_, i)| i)
        .collect()
}

/// (code, index) pairs of the `len` points `point(i)`, sorted by code, then index. Indices
/// must fit in `u32`.
pub(crate) fn sorted_codes(
    len: usize,
    point: impl Fn(usize) -> [f32; 3] + Sync,
    quant: &Quantiser,
) -> Vec<(u64, u32)> {
    let mut keyed: Vec<(u64, u32)> = (0..len)
        .into_par_iter()
        .map(|i| (code(quant.cell(point(i))), i as u32))
        .collect();
    keyed.par_sort_unstable();
    keyed
}

/// Spreads the low 21 bits of `v` so that bit `b` moves to bit `3b`.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffff;
    x = (x | x << 16) & 0x1f0000ff0000ff;
    x = (x | x << 8) & 0x100f00f00f00f00f;
    x = (x | x << 4) & 0x10c30c30c30c30c3;
    x = (x | x << 2) & 0x1249249249249249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_moves_bits_to_multiples_of_three() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0b101), 0b1_000_001);
        assert_eq!(spread(1 << 20), 1 << 60);
    }

    #[test]
    fn z_order_of_a_2x2x2_cube() {
        // Corners listed in reverse Z order; Morton order is x fastest, then y, then z.
        let pts: Vec<[f32; 3]> = (0..8)
            .rev()
            .map(|c| [(c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2 & 1) as f32])
            .collect();
        assert_eq!(morton_order(&pts), vec![7, 6, 5, 4, 3, 2, 1, 0]);
    }

    #[test]
    fn identical_points_keep_index_order() {
        assert_eq!(morton_order(&[[1.0; 3]; 4]), vec![0, 1, 2, 3]);
    }
}
