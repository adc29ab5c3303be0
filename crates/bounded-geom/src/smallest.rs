//! Moving the `m` smallest of a set of keys to the front, the selection behind the
//! features' half neighbourhoods.

use std::cmp::Ordering;

/// Marks the `m` smallest of a set of distinct `u64` keys, as bits by position.
///
/// The smaller half of 16, 32, 64 or 128 keys is found by AVX-512 code when the CPU has
/// it (checked once, when the selector is made: a bracket from the nearly sorted keys,
/// or sorting networks); anything else by a quickselect with branch-free partitions on
/// a copy. The marked keys are the same either way.
///
/// ```
/// use bounded_geom::SmallestFirst;
/// let mut bits = Vec::new();
/// SmallestFirst::new().mark(&[9, 3, 7, 1, 8, 2], 3, &mut bits);
/// assert_eq!(bits, [0b10_1010]);
/// ```
#[derive(Clone)]
pub struct SmallestFirst {
    #[cfg(target_arch = "x86_64")]
    network: Option<crate::network::Network>,
    /// The quickselect's copy of the keys.
    copy: Vec<u64>,
}

impl Default for SmallestFirst {
    fn default() -> Self {
        Self::new()
    }
}

impl SmallestFirst {
    /// A selector for this CPU.
    pub fn new() -> Self {
        Self {
            #[cfg(target_arch = "x86_64")]
            network: crate::network::Network::detect(),
            copy: Vec::new(),
        }
    }

    /// Sets `bits` to `keys.len().div_ceil(64)` words with bit `j % 64` of word `j / 64`
    /// set when `keys[j]` is one of the `m` smallest of `keys` (distinct); all of them
    /// when `m >= keys.len()`.
    pub fn mark(&mut self, keys: &[u64], m: usize, bits: &mut Vec<u64>) {
        bits.clear();
        bits.resize(keys.len().div_ceil(64), 0);
        #[cfg(target_arch = "x86_64")]
        if let Some(network) = self.network
            && crate::network::Network::halves(keys.len())
            && m == keys.len() / 2
        {
            network.mark_smaller_half(keys, bits);
            return;
        }
        let m = m.min(keys.len());
        if m == 0 {
            return;
        }
        self.copy.clear();
        self.copy.extend_from_slice(keys);
        quickselect(&mut self.copy, m);
        let threshold = self.copy[..m].iter().copied().max().unwrap_or(0);
        for (j, &key) in keys.iter().enumerate() {
            bits[j / 64] |= u64::from(key <= threshold) << (j % 64);
        }
    }
}

/// Moves the `m` smallest of `keys` to the front: [`SmallestFirst::mark`] without AVX-512.
///
/// Quickselect with branch-free Lomuto partitions: which side a key falls on is
/// unpredictable, so an unconditional swap costs less than a branch. The pivot is the
/// key at position `m`, which is nearly right for the features' half neighbourhoods:
/// the neighbours come sorted by distance to the query point, which lies near the
/// centroid. Together ~8% faster `detect` than `select_nth_unstable` (median-of-3
/// pivots: ~5%).
fn quickselect(keys: &mut [u64], m: usize) {
    let (mut lo, mut hi) = (0, keys.len());
    if m >= hi {
        return;
    }
    while hi - lo > 3 {
        let s = &mut keys[lo..hi];
        let n = s.len();
        // lo <= m < hi
        let pivot = s[m - lo];
        // Invariant: s[..store] < pivot <= s[store..i].
        let mut store = 0;
        for i in 0..n {
            let v = s[i];
            s.swap(i, store);
            store += usize::from(v < pivot);
        }
        let cut = lo + store;
        match cut.cmp(&m) {
            Ordering::Equal => return,
            Ordering::Greater => hi = cut,
            Ordering::Less if store > 0 => lo = cut,
            Ordering::Less => {
                // Nothing below the pivot: it is the smallest, so it stays in front.
                let at = s.iter().position(|&v| v == pivot).unwrap_or(0);
                s.swap(0, at);
                lo += 1;
            }
        }
    }
    keys[lo..hi].sort_unstable();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smallest_first_matches_a_sort() {
        // Random, ascending, descending and organ-pipe orders; every prefix length.
        let mut random = crate::test_stream(7);
        let random: Vec<u64> = (0..130).map(|i| (random() >> 20) << 8 | i).collect();
        let ascending: Vec<u64> = (0..100).collect();
        let descending: Vec<u64> = (0..100).rev().collect();
        let pipe: Vec<u64> = (0..50).chain((50..100).rev()).collect();
        for keys in [random, ascending, descending, pipe] {
            let mut want = keys.clone();
            want.sort_unstable();
            for m in 1..=keys.len() {
                let mut got = keys.clone();
                quickselect(&mut got, m);
                got[..m].sort_unstable();
                assert_eq!(got[..m], want[..m], "m {m}");
            }
        }
    }

    #[test]
    fn marks_match_a_sort_for_halves_and_other_counts() {
        let mut select = SmallestFirst::new();
        #[cfg(target_arch = "x86_64")]
        if select.network.is_none() {
            println!("the AVX-512 path is not tested: this CPU has no AVX-512");
        }
        let mut random = crate::test_stream(3);
        for n in [16usize, 32, 45, 64, 128] {
            for round in 0..200 {
                let keys: Vec<u64> = (0..n as u64)
                    .map(|i| {
                        let r = random();
                        // Nearly sorted (as the features' keys, most taking the
                        // bracket), shuffled a little more, or random (the networks).
                        let high = match round % 3 {
                            0 => i + (r >> 62),
                            1 => i + (r >> 59),
                            _ => r >> 40,
                        };
                        high << 8 | i
                    })
                    .collect();
                let mut sorted = keys.clone();
                sorted.sort_unstable();
                for m in [n / 2, 1, n - 1] {
                    let mut want = vec![0u64; n.div_ceil(64)];
                    for (j, key) in keys.iter().enumerate() {
                        if *key <= sorted[m - 1] {
                            want[j / 64] |= 1 << (j % 64);
                        }
                    }
                    let mut got = Vec::new();
                    select.mark(&keys, m, &mut got);
                    assert_eq!(got, want, "n {n} m {m} round {round}");
                }
            }
        }
    }
}
