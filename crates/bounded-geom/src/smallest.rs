//! The `m`-th smallest of a set of keys: the threshold of the features' half
//! neighbourhoods.

/// The `m`-th smallest of a set of distinct `u64` keys: the threshold at or below which
/// the `m` smallest lie.
///
/// A quickselect with branch-free partitions, on a copy; for the smaller half of 16,
/// 32, 64 or 128 keys of eight lanes side by side
/// ([`nth_smallest_lanes`](Self::nth_smallest_lanes)), AVX-512 sorting networks when the
/// CPU has them (checked once, when the selector is made). The result is the same
/// either way.
///
/// ```
/// use bounded_geom::SmallestFirst;
/// assert_eq!(SmallestFirst::new().nth_smallest(&[9, 3, 7, 1, 8, 2], 3), 3);
/// ```
#[derive(Clone)]
pub struct SmallestFirst {
    #[cfg(target_arch = "x86_64")]
    network: Option<crate::network::Network>,
    /// The selection's copy of the keys, and room for its partitions.
    copy: Vec<u64>,
    spare: Vec<u64>,
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
            spare: Vec::new(),
        }
    }

    /// The `m`-th smallest of `keys` (distinct), counting from 1; the largest when
    /// `m >= keys.len()`. Panics for no keys or `m = 0`.
    pub fn nth_smallest(&mut self, keys: &[u64], m: usize) -> u64 {
        assert!(m > 0 && !keys.is_empty(), "no keys to choose from");
        self.copy.clear();
        self.copy.extend_from_slice(keys);
        self.spare.resize(keys.len(), 0);
        nth_of_copy(&mut self.copy, &mut self.spare, m)
    }

    /// [`nth_smallest`](Self::nth_smallest) of each of the eight columns of `keys` (rows
    /// of eight lanes, e.g. eight points' keys side by side).
    pub fn nth_smallest_lanes(&mut self, keys: &[[u64; 8]], m: usize) -> [u64; 8] {
        assert!(m > 0 && !keys.is_empty(), "no keys to choose from");
        #[cfg(target_arch = "x86_64")]
        if let Some(network) = self.network
            && crate::network::Network::halves(keys.len())
            && m == keys.len() / 2
        {
            return network.half_max_lanes(keys);
        }
        self.spare.resize(keys.len(), 0);
        std::array::from_fn(|l| {
            self.copy.clear();
            self.copy.extend(keys.iter().map(|k| k[l]));
            nth_of_copy(&mut self.copy, &mut self.spare, m)
        })
    }
}

/// The `m`-th smallest of `keys` (not empty, `m > 0`; the largest when `m` exceeds
/// them), selected by [`partition`]s between `keys` and `spare`, which it overwrites.
///
/// The pivot is the key at position `m`, which is nearly right for the features' half
/// neighbourhoods: the neighbours come sorted by distance to the query point, which lies
/// near the centroid. The side a partition keeps is in the order it had (the smaller
/// keys) or reversed (the larger), so the next pivot is taken from the matching end.
fn nth_of_copy(keys: &mut [u64], spare: &mut [u64], m: usize) -> u64 {
    let (mut from, mut to) = (keys, spare);
    let (mut range, mut m, mut reversed) = (0..from.len(), m.min(from.len()), false);
    loop {
        let s = &from[range.clone()];
        let n = s.len();
        if n <= 16 {
            let mut small = [u64::MAX; 16];
            small[..n].copy_from_slice(s);
            small.sort_unstable();
            return small[m - 1];
        }
        let p = s[if reversed {
            (n - 1).saturating_sub(m)
        } else {
            m.min(n - 1)
        }];
        let (below, above) = partition(s, p, &mut to[..n]);
        // `p` and any key equal to it rank from below + 1 to n - above.
        if m <= below {
            range = 0..below;
        } else if m > n - above {
            (m, range, reversed) = (m - (n - above), n - above..n, !reversed);
        } else {
            return p;
        }
        std::mem::swap(&mut from, &mut to);
    }
}

/// Writes the keys of `s` below `p` to the front of `out` in their order and those above
/// it to the back in reverse order, returning how many of each (keys equal to `p`, one
/// of `s`, are in neither).
///
/// Every key is written to both ends, and only the matching end's count moves on: no
/// branch on the unpredictable side a key falls on, and, unlike a swap in place, no load
/// of a slot just stored to (a Lomuto partition's swap stalled on exactly that: 18% of a
/// detection on an AVX2 machine). The write that does not count lands on the slot the
/// next key of that end overwrites, or past the end's last key.
fn partition(s: &[u64], p: u64, out: &mut [u64]) -> (usize, usize) {
    let n = out.len();
    let (mut below, mut above) = (0, 0);
    for &v in s {
        // below + above counts the keys before v not equal to p, fewer than n - 1 but
        // when v is the last key and the only p: the two slots differ or count nowhere.
        out[below] = v;
        out[n - 1 - above] = v;
        below += usize::from(v < p);
        above += usize::from(v > p);
    }
    (below, above)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nth_of_copy_matches_a_sort() {
        // Random, ascending, descending and organ-pipe orders, and five values repeated;
        // every rank.
        let mut random = crate::test_stream(7);
        let random: Vec<u64> = (0..130).map(|i| (random() >> 20) << 8 | i).collect();
        let ascending: Vec<u64> = (0..100).collect();
        let descending: Vec<u64> = (0..100).rev().collect();
        let pipe: Vec<u64> = (0..50).chain((50..100).rev()).collect();
        let repeated: Vec<u64> = (0..90).map(|i| i * 7 % 5).collect();
        for keys in [random, ascending, descending, pipe, repeated] {
            let mut want = keys.clone();
            want.sort_unstable();
            let mut spare = vec![0; keys.len()];
            for m in 1..=keys.len() + 1 {
                let mut copy = keys.clone();
                let got = nth_of_copy(&mut copy, &mut spare, m);
                assert_eq!(got, want[m.min(keys.len()) - 1], "m {m}");
            }
        }
    }

    #[test]
    fn partition_of_a_hand_made_set() {
        // Below 5 in their order to the front, above it reversed to the back; the slot
        // between them holds whatever was written last, and is not read.
        let mut out = [0; 7];
        assert_eq!(partition(&[7, 2, 5, 9, 1, 6, 3], 5, &mut out), (3, 3));
        assert_eq!((&out[..3], &out[4..]), (&[2, 1, 3][..], &[6, 9, 7][..]));
    }

    #[test]
    fn nth_smallest_matches_a_sort_for_halves_and_other_counts() {
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
                        // Nearly sorted (as the features' keys) or random.
                        let high = if round % 2 == 0 {
                            i + (r >> 62)
                        } else {
                            r >> 40
                        };
                        high << 8 | i
                    })
                    .collect();
                let mut sorted = keys.clone();
                sorted.sort_unstable();
                for m in [n / 2, 1, n - 1, n, n + 3] {
                    let want = sorted[m.min(n) - 1];
                    assert_eq!(select.nth_smallest(&keys, m), want, "n {n} m {m}");
                    // The same keys in every lane but one, which holds them reversed.
                    let lanes: Vec<[u64; 8]> = (0..n)
                        .map(|j| std::array::from_fn(|l| keys[if l == 5 { n - 1 - j } else { j }]))
                        .collect();
                    assert_eq!(
                        select.nth_smallest_lanes(&lanes, m),
                        [want; 8],
                        "n {n} m {m}"
                    );
                }
            }
        }
    }
}
