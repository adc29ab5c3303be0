//! One query's candidate filter and k-smallest selection, the inner loop of the search.
//!
//! Performance notes (1M-point surface clouds, k = 128: ~450 candidates in the cells
//! a query does not skip, ~144 within the usual limit, see the `grid` module):
//! - one branch-free loop over the structure-of-arrays `f32` coordinates computes each
//!   candidate's distance and keeps its key when within the limit (always write,
//!   advance on keep) in a buffer that is never re-zeroed (a separate, vectorised
//!   distance loop measured 1% slower: cells are small); with AVX-512, eight
//!   candidates at a time (see the `network` module), all the pieces a query does not
//!   skip in one call (one call per piece cost 4.5% more);
//! - a key is `(f32 distance bits << 32 | index) + 1`, and 0 for the query itself, so
//!   integer order is the documented neighbour order (query, distance, index), and
//!   sorting needs no comparator. (A counting sort into distance buckets was tried and
//!   measured slower: its data-dependent branches cost more than the comparisons it
//!   saves.)
//! - for k = 128 and up to 192 kept keys (the usual case) AVX-512 sorting networks
//!   take the 128 smallest in order, when the CPU has AVX-512 (see the `network`
//!   module: half the time of `sort_unstable`); otherwise up to `1.25 k` kept keys are
//!   sorted whole, and beyond that `select_nth_unstable` first cuts them to `k` (at
//!   ~1.5 k the two cost the same; at 1.12 k sorting is cheaper).

use std::ops::Range;

/// A query of the distance filter: the candidates among the structure-of-arrays
/// coordinates `xyz` (original indices `index`) within squared distance `lim` of `p`,
/// whose own index is `q`.
#[derive(Clone, Copy)]
pub(crate) struct Filter<'a> {
    pub(crate) p: [f32; 3],
    pub(crate) q: u32,
    pub(crate) lim: f32,
    pub(crate) xyz: (&'a [f32], &'a [f32], &'a [f32]),
    pub(crate) index: &'a [u32],
}

impl Filter<'_> {
    /// The filter for the candidates `range`, one at a time: their keys written to
    /// `keys` from `kept` on (always written, advanced past when kept); the new count.
    #[inline(always)]
    pub(crate) fn keep_one_by_one(
        &self,
        range: Range<usize>,
        keys: &mut [u64],
        kept: usize,
    ) -> usize {
        let (xs, ys, zs) = self.xyz;
        let mut kept = kept;
        for c in range {
            let d = crate::knn::dist2(self.p, [xs[c], ys[c], zs[c]]);
            let i = self.index[c];
            let key = (u64::from(d.to_bits()) << 32 | u64::from(i)) + 1;
            keys[kept] = if i == self.q { 0 } else { key };
            kept += usize::from(d < self.lim);
        }
        kept
    }
}

/// Reusable buffers of one query's selection.
pub(crate) struct Selection {
    /// Keys of the candidates kept so far (the first `kept`), then the sorted result.
    keys: Vec<u64>,
    kept: usize,
    /// The candidate ranges the next [`keep_ranges`](Self::keep_ranges) filters.
    pub(crate) ranges: Vec<Range<usize>>,
    /// Which pieces of a group a query filters (reused).
    pub(crate) near: Vec<bool>,
    /// AVX-512 sorting networks for the usual case, when the CPU has them.
    #[cfg(target_arch = "x86_64")]
    network: Option<crate::network::Network>,
}

/// Empty buffers, with the sorting networks when the CPU has them.
impl Default for Selection {
    fn default() -> Self {
        Self {
            keys: Vec::new(),
            kept: 0,
            ranges: Vec::new(),
            near: Vec::new(),
            #[cfg(target_arch = "x86_64")]
            network: crate::network::Network::detect(),
        }
    }
}

impl Selection {
    /// Starts a new query.
    pub(crate) fn clear(&mut self) {
        self.kept = 0;
    }

    /// Number of candidates kept so far.
    pub(crate) fn kept(&self) -> usize {
        self.kept
    }

    /// Keeps the candidates of `ranges` whose squared distance to the
    /// point of `filter` is below its limit.
    pub(crate) fn keep_ranges(&mut self, filter: Filter<'_>) {
        // Room for a whole register of keys past the last one kept.
        let candidates: usize = self.ranges.iter().map(|r| r.len()).sum();
        let need = self.kept + candidates + 8;
        if self.keys.len() < need {
            self.keys.resize(need, 0);
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(network) = self.network {
            self.kept = network.keep_ranges(filter, &self.ranges, &mut self.keys, self.kept);
            return;
        }
        for r in &self.ranges {
            self.kept = filter.keep_one_by_one(r.clone(), &mut self.keys, self.kept);
        }
    }

    /// Sorts the `k` smallest kept keys (`k <= kept()`) into [`sorted`](Self::sorted).
    pub(crate) fn select(&mut self, k: usize) {
        let keys = &mut self.keys[..self.kept];
        #[cfg(target_arch = "x86_64")]
        if let Some(network) = self.network
            && k == crate::network::K
            && keys.len() <= crate::network::MAX_KEPT
        {
            network.smallest_sorted(keys);
            return;
        }
        if keys.len() > k + k / 4 {
            keys.select_nth_unstable(k - 1);
            keys[..k].sort_unstable();
        } else {
            keys.sort_unstable();
        }
    }

    /// The result of [`select`](Self::select): `k` keys, ascending.
    pub(crate) fn sorted(&self, k: usize) -> &[u64] {
        &self.keys[..k]
    }
}

/// Squared distance stored in a neighbour key.
pub(crate) fn key_distance(key: u64) -> f32 {
    if key == 0 {
        0.0
    } else {
        f32::from_bits(((key - 1) >> 32) as u32)
    }
}

/// The original index stored in a neighbour key; `q` for the query's own key 0.
pub(crate) fn key_index(key: u64, q: u32) -> u32 {
    if key == 0 { q } else { (key - 1) as u32 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: every key, sorted.
    fn reference(p: [f32; 3], q: u32, lim: f32, pts: &[[f32; 3]], k: usize) -> Vec<u64> {
        let mut keys: Vec<u64> = (0u32..)
            .zip(pts)
            .filter(|(_, x)| crate::knn::dist2(p, **x) < lim)
            .map(|(i, x)| {
                let d = crate::knn::dist2(p, *x);
                if i == q {
                    0
                } else {
                    (u64::from(d.to_bits()) << 32 | u64::from(i)) + 1
                }
            })
            .collect();
        keys.sort_unstable();
        keys.truncate(k);
        keys
    }

    fn run(p: [f32; 3], q: u32, lim: f32, pts: &[[f32; 3]], k: usize) -> Option<Vec<u64>> {
        let mut s = Selection::default();
        s.clear();
        // Three ranges ("cells"), to exercise appending and the one-by-one rest.
        let xs: Vec<f32> = pts.iter().map(|x| x[0]).collect();
        let ys: Vec<f32> = pts.iter().map(|x| x[1]).collect();
        let zs: Vec<f32> = pts.iter().map(|x| x[2]).collect();
        let index: Vec<u32> = (0..pts.len() as u32).collect();
        let (m, n) = (pts.len() / 3, pts.len());
        s.ranges = vec![0..m, m..m + 5, m + 5..n];
        s.keep_ranges(Filter {
            p,
            q,
            lim,
            xyz: (&xs, &ys, &zs),
            index: &index,
        });
        (s.kept() >= k).then(|| {
            s.select(k);
            s.sorted(k).to_vec()
        })
    }

    #[test]
    fn matches_a_full_sort_with_ties_duplicates_and_clusters() {
        // Integer grid points (many equal distances), duplicates of the query, and a
        // far cluster that squeezes most keys into the first bucket.
        let mut pts: Vec<[f32; 3]> = (0..300)
            .map(|i| [(i % 7) as f32, (i / 7 % 6) as f32, (i / 42) as f32 * 0.5])
            .collect();
        pts.extend([[3.0, 2.0, 1.0]; 5]);
        pts.extend((0..20).map(|i| [1000.0 + i as f32, 0.0, 0.0]));
        let q = 100;
        let p = pts[q as usize];
        for k in [1, 2, 17, 128, 300] {
            for lim in [0.0, 1.0, 9.5, f32::INFINITY] {
                let want = reference(p, q, lim, &pts, k);
                let got = run(p, q, lim, &pts, k);
                assert_eq!(got, (want.len() >= k).then_some(want), "k {k} lim {lim}");
            }
        }
    }

    #[test]
    fn all_equal_distances_sort_by_index() {
        let pts = vec![[1.0, 0.0, 0.0]; 50];
        let got = run([0.0; 3], 999, f32::INFINITY, &pts, 10).unwrap();
        let idx: Vec<u32> = got.iter().map(|&k| key_index(k, 999)).collect();
        assert_eq!(idx, (0..10).collect::<Vec<u32>>());
    }
}
