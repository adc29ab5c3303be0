//! AVX-512 code for the hot loops of the search and the features, used when the CPU has
//! AVX-512 (detected at run time through `pulp`, so the binary stays portable). Every
//! result is bit for bit that of the portable path.
//!
//! Performance notes (1M-point surface cloud, `detect`, interleaved runs):
//! - sorting the kept neighbour keys: the usual search keeps 128..~170 keys for
//!   k = 128; the first 128 and the rest (padded with `u64::MAX`) are sorted by bitonic
//!   networks in 16 registers and in as few as the rest fills (1, 2, 4 or 8: ~1.5%
//!   faster than always 8), the 128 smallest are taken by one min against the
//!   reversed rest (a bitonic sequence) and merged by seven more stages. Every index and
//!   mask is a constant, the registers never leave the register file and nothing
//!   branches on the data: 12% faster than `sort_unstable`. The first rounds of the 128-
//!   and 64-key sorts (up to sorted runs of 16 or 8, the rounds that permute within
//!   registers) are replaced by Batcher's network on whole registers (every column
//!   sorted at once) and a transpose: 1M cube 1.16 -> 1.10 s;
//! - the smaller half of 16..128 keys of eight points side by side (the normals' half
//!   neighbourhoods; a point per lane, keys down the columns): blocks of 16 rows
//!   sorted by Batcher's network, merged, one half's min against the other reversed,
//!   whose largest is the threshold. The sorts compare whole registers, all eight
//!   points at once: ~3% faster than transposing the keys into rows and sorting each
//!   point's (which had been ~4% faster than the quickselect);
//! - the distance filter, eight candidates per register, keys packed by a compress:
//!   ~4.5% (7% on an airborne scan).
//!
//! The same sort written with `std::arch` behind one `unsafe` entry measured 2.5%
//! slower; enabling pulp's AVX-512 level for the whole build left the models `train`
//! writes unchanged, checked byte for byte. What the networks call must be inlined into
//! the `vectorize` body (`inline(always)`, macros instead of function values), or the
//! intrinsics become calls and the code runs 5x slower.

use std::arch::x86_64::{__m256, __m512i, _CMP_LT_OQ};
use std::ops::Range;

use pulp::x86::V4;

use pulp::{NullaryFnOnce, b8, cast, u64x8};

use crate::select::Filter;

/// Lanes per register.
const L: usize = 8;
/// The neighbour count the networks serve.
pub(crate) const K: usize = 128;
/// The most kept keys they take.
pub(crate) const MAX_KEPT: usize = K + K / 2;

/// The AVX-512 code paths, when this CPU has AVX-512.
#[derive(Clone, Copy)]
pub(crate) struct Network(V4);

impl Network {
    /// The AVX-512 paths, or `None` without AVX-512.
    pub(crate) fn detect() -> Option<Self> {
        V4::try_new().map(Self)
    }

    /// Sorts the `K` smallest of `keys` (`K..=MAX_KEPT` distinct keys) into `keys[..K]`.
    pub(crate) fn smallest_sorted(self, keys: &mut [u64]) {
        assert!((K..=MAX_KEPT).contains(&keys.len()));
        self.0.vectorize(SmallestSorted { simd: self.0, keys });
    }

    /// The distance filter of [`Selection::keep_ranges`](crate::select::Selection) over
    /// the candidates `ranges`, eight at a time and the rest one by one, in one call:
    /// writes the kept keys to `out` from `kept` on (overwriting up to a register
    /// beyond them) and returns the new count. Distances are computed exactly as there.
    pub(crate) fn keep_ranges(
        self,
        filter: Filter<'_>,
        ranges: &[Range<usize>],
        out: &mut [u64],
        kept: usize,
    ) -> usize {
        let simd = self.0;
        self.0.vectorize(KeepRanges {
            simd,
            filter,
            ranges,
            out,
            kept,
        })
    }

    /// Whether [`half_max_lanes`](Self::half_max_lanes) takes `n` keys.
    pub(crate) fn halves(n: usize) -> bool {
        matches!(n, 16 | 32 | 64 | 128)
    }

    /// The largest of the smaller half of each column of `keys` (rows of eight lanes,
    /// distinct down each column, a length that [`halves`](Self::halves) takes): the
    /// keys at or below it are that half.
    pub(crate) fn half_max_lanes(self, keys: &[[u64; L]]) -> [u64; L] {
        assert!(Self::halves(keys.len()));
        let simd = self.0;
        self.0.vectorize(HalfMaxLanes { simd, keys })
    }
}

/// The `K` smallest of the sorted registers `$a` and the keys of `$keys` beyond `K`
/// (sorted in `$r` registers by `$sort`), in order, into `$a`: the first `K - 8 $r` of
/// `$a` are among them; with `min(a[K - 8 $r + t], b[8 $r - 1 - t])` after them, `$a`
/// is a bitonic sequence (rising through `a`, falling through `b`), which
/// [`merge128`] sorts. (A macro: a sort passed as a function value is not inlined,
/// and its intrinsics become calls.)
macro_rules! merge_rest {
    ($simd:expr, $keys:expr, $a:expr, $r:literal, $sort:ident) => {{
        let mut b: [u64x8; $r] = load_registers($keys, K);
        $sort($simd, &mut b);
        keep_smaller($simd, &mut $a[K / L - $r..], &b);
        merge128($simd, &mut $a);
    }};
}

/// The body of [`Network::smallest_sorted`], compiled for AVX-512: what it calls must
/// be inlined into it (`inline(always)`), or the intrinsics become function calls.
struct SmallestSorted<'a> {
    simd: V4,
    keys: &'a mut [u64],
}

impl NullaryFnOnce for SmallestSorted<'_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let Self { simd, keys } = self;
        let mut a: [u64x8; K / L] = load_registers(keys, 0);
        sort128(simd, &mut a);
        // The rest, padded with u64::MAX, in as few registers as it needs.
        match keys.len() - K {
            0 => {}
            1..=8 => merge_rest!(simd, keys, a, 1, sort8),
            9..=16 => merge_rest!(simd, keys, a, 2, sort16),
            17..=32 => merge_rest!(simd, keys, a, 4, sort32),
            _ => merge_rest!(simd, keys, a, 8, sort64),
        }
        store_registers(keys, &a);
    }
}

/// `a[i] = min(a[i], b[n - 1 - i])` for sorted `a` and `b` of `n` keys each: the `n`
/// smallest of both, as a bitonic sequence.
#[inline(always)]
fn keep_smaller(simd: V4, a: &mut [u64x8], b: &[u64x8]) {
    for (x, y) in a.iter_mut().zip(b.iter().rev()) {
        *x = simd.min_u64x8(*x, reverse(simd, *y));
    }
}

/// The body of [`Network::half_max_lanes`], compiled for AVX-512 (see
/// [`columns_half_max`]).
struct HalfMaxLanes<'a> {
    simd: V4,
    keys: &'a [[u64; L]],
}

impl NullaryFnOnce for HalfMaxLanes<'_> {
    type Output = [u64; L];

    #[inline(always)]
    fn call(self) -> [u64; L] {
        columns_half_max(self.simd, self.keys)
    }
}

/// The columns of the 8 x 8 matrix with rows `r`: three rounds of pairwise
/// interleaving (single keys, pairs, quadruples), 24 permutes. (Loops, not `array::map`:
/// its closures are not always inlined, and their intrinsics become calls.)
#[inline(always)]
fn transpose(simd: V4, r: [u64x8; L]) -> [u64x8; L] {
    let mix = |a: u64x8, b: u64x8, index: [u64; L]| -> u64x8 {
        let (a, index, b): (__m512i, __m512i, __m512i) = (cast(a), cast(index), cast(b));
        cast(simd.avx512f._mm512_permutex2var_epi64(a, index, b))
    };
    let zero = simd.splat_u64x8(0);
    // a[2i], a[2i + 1]: rows 2i and 2i + 1 interleaved, even and odd columns.
    let (even, odd) = ([0, 8, 2, 10, 4, 12, 6, 14], [1, 9, 3, 11, 5, 13, 7, 15]);
    let mut a = [zero; L];
    for i in (0..L).step_by(2) {
        a[i] = mix(r[i], r[i + 1], even);
        a[i + 1] = mix(r[i], r[i + 1], odd);
    }
    // b[c], b[c + 4] (c < 4): columns c and c + 4 of rows 0-3 and of rows 4-7.
    let (low, high) = ([0, 1, 8, 9, 4, 5, 12, 13], [2, 3, 10, 11, 6, 7, 14, 15]);
    let mut b = [zero; L];
    for base in [0, 4] {
        for parity in 0..2 {
            let (x, y) = (a[base + parity], a[base + parity + 2]);
            b[base + parity] = mix(x, y, low);
            b[base + parity + 2] = mix(x, y, high);
        }
    }
    let (lower, upper) = ([0, 1, 2, 3, 8, 9, 10, 11], [4, 5, 6, 7, 12, 13, 14, 15]);
    let mut columns = [zero; L];
    for c in 0..4 {
        columns[c] = mix(b[c], b[c + 4], lower);
        columns[c + 4] = mix(b[c], b[c + 4], upper);
    }
    columns
}

/// The body of [`Network::keep_ranges`], compiled for AVX-512.
struct KeepRanges<'a> {
    simd: V4,
    filter: Filter<'a>,
    ranges: &'a [Range<usize>],
    out: &'a mut [u64],
    kept: usize,
}

impl NullaryFnOnce for KeepRanges<'_> {
    type Output = usize;

    #[inline(always)]
    fn call(self) -> usize {
        let Self {
            simd,
            filter,
            ranges,
            out,
            mut kept,
        } = self;
        let Filter {
            p,
            q,
            lim,
            xyz: (xs, ys, zs),
            index,
        } = filter;
        let (avx, avx512) = (simd.avx, simd.avx512f);
        let (px, py, pz) = (
            avx._mm256_set1_ps(p[0]),
            avx._mm256_set1_ps(p[1]),
            avx._mm256_set1_ps(p[2]),
        );
        let limit = avx._mm256_set1_ps(lim);
        let query = avx512._mm512_set1_epi64(i64::from(q));
        let one = avx512._mm512_set1_epi64(1);
        for r in ranges {
            let (chunks, _) = index[r.clone()].as_chunks::<L>();
            let (cx, cy, cz) = (
                xs[r.clone()].as_chunks::<L>().0,
                ys[r.clone()].as_chunks::<L>().0,
                zs[r.clone()].as_chunks::<L>().0,
            );
            for (b, &i) in chunks.iter().enumerate() {
                // (p - x)^2 + (p - y)^2 + (p - z)^2 in this order, as `knn::dist2`.
                let dx = avx._mm256_sub_ps(px, cast::<[f32; L], __m256>(cx[b]));
                let dy = avx._mm256_sub_ps(py, cast::<[f32; L], __m256>(cy[b]));
                let dz = avx._mm256_sub_ps(pz, cast::<[f32; L], __m256>(cz[b]));
                let d = avx._mm256_add_ps(
                    avx._mm256_add_ps(avx._mm256_mul_ps(dx, dx), avx._mm256_mul_ps(dy, dy)),
                    avx._mm256_mul_ps(dz, dz),
                );
                let within = avx512._mm256_cmp_ps_mask::<_CMP_LT_OQ>(d, limit);
                let i = avx512._mm512_cvtepu32_epi64(cast(i));
                let bits = avx512._mm512_cvtepu32_epi64(cast(d));
                let key = avx512._mm512_add_epi64(
                    avx512._mm512_or_si512(avx512._mm512_slli_epi64::<32>(bits), i),
                    one,
                );
                // The query's own key is 0.
                let own = avx512._mm512_cmpeq_epi64_mask(i, query);
                let key = avx512._mm512_maskz_mov_epi64(!own, key);
                let packed = avx512._mm512_maskz_compress_epi64(within, key);
                out[kept..kept + L].copy_from_slice(&cast::<__m512i, [u64; L]>(packed));
                kept += within.count_ones() as usize;
            }
            let rest = r.start + chunks.len() * L..r.end;
            kept = filter.keep_one_by_one(rest, out, kept);
        }
        kept
    }
}

/// `R` registers from `keys[at..]`, `u64::MAX` beyond its end.
#[inline(always)]
fn load_registers<const R: usize>(keys: &[u64], at: usize) -> [u64x8; R] {
    // A loop rather than `array::from_fn`, whose closure is not always inlined; whole
    // registers apart, as a copy of a variable length is a call to `memmove`.
    let mut v = [cast([u64::MAX; L]); R];
    for (r, register) in v.iter_mut().enumerate() {
        let start = at + r * L;
        if let Some(&whole) = keys.get(start..start + L).and_then(|k| k.as_array::<L>()) {
            *register = cast(whole);
        } else if let Some(have) = keys.get(start..) {
            let mut lanes = [u64::MAX; L];
            lanes[..have.len()].copy_from_slice(have);
            *register = cast(lanes);
        }
    }
    v
}

/// Writes `v` to the front of `keys`.
#[inline(always)]
fn store_registers(keys: &mut [u64], v: &[u64x8]) {
    for (out, v) in keys.chunks_exact_mut(L).zip(v) {
        out.copy_from_slice(&cast::<u64x8, [u64; L]>(*v));
    }
}

/// Lane `l ^ j` for every lane `l`.
const fn partner(j: usize) -> [u64; L] {
    let mut p = [0; L];
    let mut l = 0;
    while l < L {
        p[l] = (l ^ j) as u64;
        l += 1;
    }
    p
}

/// The stages of bitonic sorting networks, each `stage::<R, K, J>`: block size `K`,
/// partner distance `J`. Spelled out so that every index and mask is a constant.
macro_rules! stages {
    ($simd:expr, $v:expr, $r:literal; $($k:literal: $($j:literal)*;)*) => {
        $($(stage::<$r, $k, $j>($simd, $v);)*)*
    };
}

/// Bitonic sorts of `8 R` keys in `R` registers, ascending (element `i` is lane
/// `i % 8` of register `i / 8`).
macro_rules! sorter {
    ($name:ident, $r:literal; $($k:literal: $($j:literal)*;)*) => {
        #[inline(always)]
        fn $name(simd: V4, v: &mut [u64x8; $r]) {
            stages!(simd, v, $r; $($k: $($j)*;)*);
        }
    };
}
sorter!(sort8, 1; 2: 1; 4: 2 1; 8: 4 2 1;);
sorter!(sort16, 2; 2: 1; 4: 2 1; 8: 4 2 1; 16: 8 4 2 1;);
sorter!(sort32, 4; 2: 1; 4: 2 1; 8: 4 2 1; 16: 8 4 2 1; 32: 16 8 4 2 1;);

/// [`sorter!`] for 64 keys, its first three rounds (sorted runs of 8) by [`runs8`].
#[inline(always)]
fn sort64(simd: V4, v: &mut [u64x8; 8]) {
    runs8(simd, v);
    stages!(simd, v, 8; 16: 8 4 2 1; 32: 16 8 4 2 1; 64: 32 16 8 4 2 1;);
}

/// [`sorter!`] for 128 keys, its first four rounds (sorted runs of 16) by [`runs16`].
#[inline(always)]
fn sort128(simd: V4, v: &mut [u64x8; 16]) {
    runs16(simd, v);
    stages!(simd, v, 16; 32: 16 8 4 2 1; 64: 32 16 8 4 2 1; 128: 64 32 16 8 4 2 1;);
}

/// Compare-exchanges of whole registers, lane by lane: `(i, j)` leaves the smaller of
/// each lane in `v[i]`. (A macro: every index a constant.)
macro_rules! columns {
    ($simd:expr, $v:expr; $($i:literal $j:literal;)*) => {
        $(
            let (lo, hi) = ($simd.min_u64x8($v[$i], $v[$j]), $simd.max_u64x8($v[$i], $v[$j]));
            ($v[$i], $v[$j]) = (lo, hi);
        )*
    };
}

/// The state of the bitonic sort of 64 keys after its blocks of 8: each register
/// sorted, ascending for even registers, descending for odd ones. The eight columns
/// are sorted by Batcher's odd-even merge network (19 compare-exchanges of whole
/// registers, no permutes), then transposed into rows: a third of the work of the
/// sort's first three rounds (six rounds of permutes within registers).
#[inline(always)]
fn runs8(simd: V4, v: &mut [u64x8; 8]) {
    columns!(simd, v; 0 1; 2 3; 4 5; 6 7; 0 2; 1 3; 4 6; 5 7; 1 2; 5 6; 0 4; 1 5; 2 6; 3 7;
        2 4; 3 5; 1 2; 3 4; 5 6;);
    *v = transpose(simd, *v);
    for r in (1..L).step_by(2) {
        v[r] = reverse(simd, v[r]);
    }
}

/// The state of the bitonic sort of 128 keys after its blocks of 16: each pair of
/// registers sorted, ascending for even pairs, descending for odd ones; as [`runs8`],
/// with Batcher's network for 16 ([`sort_columns16`]).
#[inline(always)]
fn runs16(simd: V4, v: &mut [u64x8; 16]) {
    sort_columns16(simd, v);
    let mut upper = [v[0]; L];
    let mut lower = [v[0]; L];
    upper.copy_from_slice(&v[..L]);
    lower.copy_from_slice(&v[L..]);
    // Column c: its first 8 keys in upper[c], the rest in lower[c].
    let (upper, lower) = (transpose(simd, upper), transpose(simd, lower));
    for c in 0..L {
        if c % 2 == 0 {
            (v[2 * c], v[2 * c + 1]) = (upper[c], lower[c]);
        } else {
            (v[2 * c], v[2 * c + 1]) = (reverse(simd, lower[c]), reverse(simd, upper[c]));
        }
    }
}

/// [`HalfMaxLanes`] column by column, without transposing: blocks of 16 rows sorted
/// down their columns ([`sort_columns16`]), merged pairwise ([`merge_columns`]) into
/// two sorted halves, whose smaller half of the whole is one min against the other
/// reversed, and its largest a max. Every step compares whole registers, all eight
/// points at once.
#[inline(always)]
fn columns_half_max(simd: V4, keys: &[[u64; L]]) -> [u64; L] {
    let n = keys.len();
    let mut all = [simd.splat_u64x8(u64::MAX); K];
    let v = &mut all[..n];
    for (v, row) in v.iter_mut().zip(keys) {
        *v = cast(*row);
    }
    for block in v.as_chunks_mut::<16>().0 {
        sort_columns16(simd, block);
    }
    let mut size = 16;
    while 2 * size < n {
        for pair in v.chunks_exact_mut(2 * size) {
            merge_columns(simd, pair);
        }
        size *= 2;
    }
    let mut top = simd.min_u64x8(v[0], v[n - 1]);
    for i in 1..n / 2 {
        top = simd.max_u64x8(top, simd.min_u64x8(v[i], v[n - 1 - i]));
    }
    cast(top)
}

/// Merges the two halves of `v`, each sorted down every column, into one sorted
/// sequence: the halves compared head against tail, then a bitonic half-cleaner cascade
/// within each half.
#[inline(always)]
fn merge_columns(simd: V4, v: &mut [u64x8]) {
    let n = v.len();
    for i in 0..n / 2 {
        let (a, b) = (v[i], v[n - 1 - i]);
        (v[i], v[n - 1 - i]) = (simd.min_u64x8(a, b), simd.max_u64x8(a, b));
    }
    let mut d = n / 4;
    while d >= 1 {
        for block in v.chunks_exact_mut(2 * d) {
            for i in 0..d {
                let (a, b) = (block[i], block[i + d]);
                (block[i], block[i + d]) = (simd.min_u64x8(a, b), simd.max_u64x8(a, b));
            }
        }
        d /= 2;
    }
}

/// Sorts each column (lane) of the 16 registers `v` by Batcher's odd-even merge
/// network: 63 compare-exchanges of whole registers.
#[inline(always)]
fn sort_columns16(simd: V4, v: &mut [u64x8; 16]) {
    columns!(simd, v; 0 1; 2 3; 4 5; 6 7; 8 9; 10 11; 12 13; 14 15; 0 2; 1 3; 4 6; 5 7;
        8 10; 9 11; 12 14; 13 15; 1 2; 5 6; 9 10; 13 14; 0 4; 1 5; 2 6; 3 7; 8 12; 9 13;
        10 14; 11 15; 2 4; 3 5; 10 12; 11 13; 1 2; 3 4; 5 6; 9 10; 11 12; 13 14; 0 8; 1 9;
        2 10; 3 11; 4 12; 5 13; 6 14; 7 15; 4 8; 5 9; 6 10; 7 11; 2 4; 3 5; 6 8; 7 9;
        10 12; 11 13; 1 2; 3 4; 5 6; 7 8; 9 10; 11 12; 13 14;);
}

/// The lanes of `x` in reverse order.
#[inline(always)]
fn reverse(simd: V4, x: u64x8) -> u64x8 {
    let reverse: __m512i = cast([7u64, 6, 5, 4, 3, 2, 1, 0]);
    cast(simd.avx512f._mm512_permutexvar_epi64(reverse, cast(x)))
}

/// Sorts the bitonic sequence of 128 keys in `v`, ascending.
#[inline(always)]
fn merge128(simd: V4, v: &mut [u64x8; 16]) {
    stages!(simd, v, 16; 128: 64 32 16 8 4 2 1;);
}

/// One stage of a bitonic sort with block size `K`: elements `i` and `i ^ J`, the
/// smaller first when `i & K == 0`.
#[inline(always)]
fn stage<const R: usize, const K: usize, const J: usize>(simd: V4, v: &mut [u64x8; R]) {
    if J >= L {
        for r in 0..R {
            let p = r ^ (J / L);
            if p > r {
                let (lo, hi) = (simd.min_u64x8(v[r], v[p]), simd.max_u64x8(v[r], v[p]));
                (v[r], v[p]) = if (r * L) & K == 0 { (lo, hi) } else { (hi, lo) };
            }
        }
    } else {
        let partner: __m512i = cast(const { partner(J) });
        for (r, x) in v.iter_mut().enumerate() {
            let w = cast(simd.avx512f._mm512_permutexvar_epi64(partner, cast(*x)));
            let (lo, hi) = (simd.min_u64x8(*x, w), simd.max_u64x8(*x, w));
            let mut take_lo = 0u8;
            for l in 0..L {
                let ascending = (r * L + l) & K == 0;
                if (l & J == 0) == ascending {
                    take_lo |= 1 << l;
                }
            }
            *x = simd.select_u64x8(b8(take_lo), lo, hi);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_max_lanes_matches_each_column_sorted() {
        let Some(network) = Network::detect() else {
            println!("skipped: this CPU has no AVX-512");
            return;
        };
        let mut random = crate::test_stream(5);
        for n in [16, 32, 64, 128] {
            let keys: Vec<[u64; L]> = (0..n as u64)
                .map(|j| std::array::from_fn(|l| (random() >> 40) << 8 | j << 3 | l as u64))
                .collect();
            let got = network.half_max_lanes(&keys);
            for (l, got) in got.into_iter().enumerate() {
                let mut column: Vec<u64> = keys.iter().map(|k| k[l]).collect();
                column.sort_unstable();
                assert_eq!(got, column[n / 2 - 1], "n {n} lane {l}");
            }
        }
    }

    #[test]
    fn matches_a_sort_for_every_kept_count() {
        let Some(network) = Network::detect() else {
            println!("skipped: this CPU has no AVX-512");
            return;
        };
        let mut random = crate::test_stream(11);
        for n in K..=MAX_KEPT {
            for round in 0..20 {
                // Few distinct high parts (ties on distance), unique by index.
                let mut keys: Vec<u64> = (0..n as u64)
                    .map(|i| ((random() >> 60) + round) << 32 | i)
                    .collect();
                let mut want = keys.clone();
                want.sort_unstable();
                network.smallest_sorted(&mut keys);
                assert_eq!(keys[..K], want[..K], "n {n}");
            }
        }
    }
}
