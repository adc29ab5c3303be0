//! The statistics of one point's nested neighbourhoods (SPEC.md, "Features").
//!
//! Performance notes (k0 = 128, 4 scales; shares of the whole extraction):
//! - the 16 eigen problems of a point are solved in two batches of 8 (each scale's
//!   covariance and half-neighbourhood covariance, then each scale's upper and lower
//!   set), so their long dependency chains overlap: 9% less time for `detect` than
//!   one at a time, with bit-identical results;
//! - the moment sums (~12%) run in small functions that are never inlined: inlined into
//!   `point_features` their accumulators lived on the stack (~6%);
//! - the normal's half-neighbourhood selection works on single `u64` keys (distance
//!   bits with the rank in the low bits) rather than on (distance, rank) pairs (~3%),
//!   with [`SmallestFirst`]: a branch-free quickselect instead of
//!   `select_nth_unstable` (~8%), and AVX-512 sorting networks where the CPU has
//!   them (another ~4%), which mark the half's ranks as bits by comparing every key
//!   with the half's largest (~2% over setting them key by key); the half is then
//!   summed in rank order (from those bits, ~3%), so the features do not depend on
//!   which selection ran; the
//!   keys are computed by code compiled for AVX-512 / AVX2 where the CPU has them
//!   (~2%); the same treatment did not pay for the neighbour gather and the upper-set
//!   compaction, nor did summing moments in vector lanes, side by side, or in two
//!   chains (the sets are short: dispatch and setup cost as much as they save);
//! - the upper set is first compacted without a branch, then summed: on real scans
//!   which side a neighbour lies on is unpredictable (+12% points/s on an airborne
//!   LiDAR tile, +3% on a room scan, -1% on the smooth test cube); summing every point
//!   with a zero weight instead cost 4% on the cube;
//! - tried, did not pay: two accumulator sets per sum, summing all k with lane masks
//!   (eight points at a time, structure-of-arrays: 40% slower even with AVX-512),
//!   sorting instead of selecting small half-neighbourhoods, and (in `bounded-geom`)
//!   rows ordered only by scale bands instead of fully sorted, as the selections that
//!   replace the sort cost as much and the half-neighbourhood selection is slower on
//!   unsorted rows.

use bounded_geom::{Eigen3, SmallestFirst, Sym3, dot, eigenvalues_batch};

use crate::FeatureConfig;

/// Values per scale with every group on (see `config::NAMES`).
pub(crate) const ALL_FEATURES: usize = 15;

/// Per-thread buffers, reused from point to point so the hot loop never allocates.
pub(crate) struct Scratch {
    /// Neighbours relative to the query point, in `f64`.
    local: Vec<[f64; 3]>,
    /// Moments of each scale's neighbourhood, smallest scale first.
    prefix: Vec<Moments>,
    /// The selection of the normal's half neighbourhood.
    near_centroid: NearCentroid,
    /// The eigen problems of a point, solved in batches.
    batch: Batch,
}

impl Scratch {
    pub(crate) fn new(k0: usize) -> Self {
        Self {
            local: Vec::with_capacity(k0),
            prefix: Vec::new(),
            near_centroid: NearCentroid::new(),
            batch: Batch::default(),
        }
    }
}

/// Keys (squared distance to the centroid, rank) of a half neighbourhood's candidates,
/// the selection that finds the smaller half, and the chosen ranks as bits.
struct NearCentroid {
    keys: Vec<u64>,
    select: SmallestFirst,
    chosen: Vec<u64>,
}

impl NearCentroid {
    fn new() -> Self {
        Self {
            keys: Vec::new(),
            select: SmallestFirst::new(),
            chosen: Vec::new(),
        }
    }
}

/// One batch of covariances (two per scale) with their eigenvalues, and what the batches
/// give per scale, largest scale first.
#[derive(Default)]
struct Batch {
    matrices: Vec<Sym3>,
    values: Vec<[f64; 3]>,
    frames: Vec<Frame>,
    /// The upper and lower set of each scale, with their variances.
    sides: Vec<[(Moments, [f64; 3]); 2]>,
    /// The points of the upper set being summed.
    upper: Vec<[f64; 3]>,
}

impl Batch {
    /// Solves the eigenvalues of `matrices` into `values`.
    fn solve(&mut self) {
        self.values.resize(self.matrices.len(), [0.0; 3]);
        eigenvalues_batch(&self.matrices, &mut self.values);
    }
}

/// Count, sum and sum of outer products of points (relative to the query point, so
/// the one-pass covariance loses only ~1e-16 of the neighbourhood's squared radius).
#[derive(Clone, Copy, Default)]
struct Moments {
    n: usize,
    sum: [f64; 3],
    outer: Sym3,
}

impl Moments {
    fn add(&mut self, q: [f64; 3]) {
        self.n += 1;
        for (s, c) in self.sum.iter_mut().zip(q) {
            *s += c;
        }
        self.outer.add_outer(q);
    }

    /// The moments of `pts`.
    ///
    /// Never inlined: inside the large `point_features` the accumulators were kept on
    /// the stack, putting a store-to-load round trip into every addition's chain.
    #[inline(never)]
    fn of(pts: impl Iterator<Item = [f64; 3]>) -> Self {
        let mut m = Self::default();
        pts.for_each(|q| m.add(q));
        m
    }

    /// The moments of the points of `pts` whose bits are set in `chosen`, in order (not
    /// inlined, like [`of`](Self::of)).
    #[inline(never)]
    fn of_chosen(pts: &[[f64; 3]], chosen: &[u64]) -> Self {
        let mut m = Self::default();
        for (w, &word) in chosen.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                m.add(pts[w * 64 + bits.trailing_zeros() as usize]);
                bits &= bits - 1;
            }
        }
        m
    }

    /// Adds `pts`, in order (not inlined, like [`of`](Self::of)).
    #[inline(never)]
    fn extend(&mut self, pts: &[[f64; 3]]) {
        let mut m = *self;
        pts.iter().for_each(|&q| m.add(q));
        *self = m;
    }

    /// The moments of the points in `self` but not in `part`.
    fn minus(&self, part: &Self) -> Self {
        let (a, b) = (&self.outer, &part.outer);
        Self {
            n: self.n - part.n,
            sum: [0, 1, 2].map(|i| self.sum[i] - part.sum[i]),
            outer: Sym3 {
                xx: a.xx - b.xx,
                xy: a.xy - b.xy,
                xz: a.xz - b.xz,
                yy: a.yy - b.yy,
                yz: a.yz - b.yz,
                zz: a.zz - b.zz,
            },
        }
    }

    /// Mean (zero for no points).
    fn mean(&self) -> [f64; 3] {
        self.sum.map(|c| c / self.n.max(1) as f64)
    }

    /// Population covariance (divided by the count).
    fn covariance(&self) -> Sym3 {
        let inv = 1.0 / self.n.max(1) as f64;
        let m = self.mean();
        let o = &self.outer;
        Sym3 {
            xx: o.xx * inv - m[0] * m[0],
            xy: o.xy * inv - m[0] * m[1],
            xz: o.xz * inv - m[0] * m[2],
            yy: o.yy * inv - m[1] * m[1],
            yz: o.yz * inv - m[1] * m[2],
            zz: o.zz * inv - m[2] * m[2],
        }
    }

    /// Eigenvalues of the covariance, descending, clamped at 0, from `eigenvalues` (its
    /// covariance's); zeros below 2 points.
    fn variances(&self, eigenvalues: [f64; 3]) -> [f64; 3] {
        if self.n < 2 {
            return [0.0; 3];
        }
        eigenvalues.map(|v| v.max(0.0))
    }
}

/// Writes the selected features of every scale for the point `neighbours[0]`, whose
/// `k0` sorted neighbours are `neighbours`, into `out` (scales x selected values).
pub(crate) fn point_features(
    points: &[[f32; 3]],
    neighbours: &[u32],
    config: &FeatureConfig,
    scratch: &mut Scratch,
    out: &mut [f32],
) {
    // Centre on the query point in f64: small, well-conditioned coordinates.
    let p = points[neighbours[0] as usize].map(f64::from);
    scratch.local.clear();
    scratch.local.extend(neighbours.iter().map(|&j| {
        let q = points[j as usize];
        [0, 1, 2].map(|a| f64::from(q[a]) - p[a])
    }));
    let local = &scratch.local;
    // Moments of every scale from one pass: scales are prefixes, smallest first.
    scratch.prefix.clear();
    let mut running = Moments::default();
    for &k in config.scales.iter().rev() {
        running.extend(&local[running.n..k]);
        scratch.prefix.push(running);
    }
    // Two batches of eigen problems (see `eigenvalues_batch`): each scale's covariance
    // and its half neighbourhood's give the frames; then the upper and lower set of
    // every scale, which need the frames' normals.
    let batch = &mut scratch.batch;
    let scales = config
        .scales
        .iter()
        .copied()
        .zip(scratch.prefix.iter().rev());
    frames(local, scales.clone(), &mut scratch.near_centroid, batch);
    sides(local, scales.clone(), batch);
    let (m0, f0) = (&scratch.prefix[config.scales.len() - 1], &batch.frames[0]);
    let per_scale = out.chunks_exact_mut(config.features_per_scale());
    for (i, ((_, moments), out)) in scales.zip(per_scale).enumerate() {
        let frame = &batch.frames[i];
        let mut all = scale_features(frame, &batch.sides[i]);
        if i > 0 {
            // c: this scale's centroid against the rest of the k0 neighbourhood,
            // in the k0 frame.
            let rest = m0.minus(moments).mean();
            let c = [0, 1, 2].map(|a| (frame.mean[a] - rest[a]) * f0.scale);
            [all[13], all[14]] = split(c, f0.normal);
        }
        for (o, i) in out.iter_mut().zip(config.groups.selected()) {
            *o = all[i] as f32;
        }
    }
}

/// Each scale's frame into `batch.frames`, from the scales' sizes and moments, largest
/// first.
fn frames<'a>(
    local: &[[f64; 3]],
    scales: impl Iterator<Item = (usize, &'a Moments)> + Clone,
    near_centroid: &mut NearCentroid,
    batch: &mut Batch,
) {
    batch.matrices.clear();
    batch
        .matrices
        .extend(scales.clone().map(|(_, m)| m.covariance()));
    let count = batch.matrices.len();
    for (k, m) in scales.clone() {
        batch.matrices.push(if k / 2 == 0 {
            Sym3::default()
        } else {
            nearest_half(&local[..k], m.mean(), near_centroid).covariance()
        });
    }
    batch.solve();
    batch.frames.clear();
    for (i, (k, m)) in scales.enumerate() {
        let j = count + i;
        let half = (k / 2 > 0).then(|| batch.matrices[j].eigen_from(batch.values[j]));
        let frame = frame(m, m.variances(batch.values[i]), half);
        batch.frames.push(frame);
    }
}

/// Each scale's upper and lower set, with their variances, into `batch.sides`.
fn sides<'a>(
    local: &[[f64; 3]],
    scales: impl Iterator<Item = (usize, &'a Moments)>,
    batch: &mut Batch,
) {
    batch.sides.clear();
    for ((k, m), f) in scales.zip(&batch.frames) {
        let upper = upper_set(&local[..k], f, &mut batch.upper);
        batch
            .sides
            .push([(upper, [0.0; 3]), (m.minus(&upper), [0.0; 3])]);
    }
    // One batch: all upper sets, then all lower sets.
    batch.matrices.clear();
    for side in 0..2 {
        let sets = batch.sides.iter().map(|s| s[side].0.covariance());
        batch.matrices.extend(sets);
    }
    batch.solve();
    let count = batch.sides.len();
    for (i, pair) in batch.sides.iter_mut().enumerate() {
        for (side, (set, variances)) in pair.iter_mut().enumerate() {
            *variances = set.variances(batch.values[side * count + i]);
        }
    }
}

/// A neighbourhood's normalised frame: centroid, scale factor and oriented normal.
struct Frame {
    mean: [f64; 3],
    /// `2 / (sqrt(s1) + sqrt(s2))`, or 1 when that is not finite (all points equal).
    scale: f64,
    /// Unit normal with `<p^_i, n> >= 0`.
    normal: [f64; 3],
    /// Eigenvalues of the covariance, descending, clamped at 0.
    variances: [f64; 3],
}

/// Centroid, normalisation and oriented normal of the neighbourhood (relative to the
/// query point, which is therefore the origin) with moments `moments` and covariance
/// eigenvalues `variances`; `half` is the eigen decomposition of the covariance of its
/// `floor(k/2)` points closest to the centroid (none for `k = 1`).
fn frame(moments: &Moments, variances: [f64; 3], half: Option<Eigen3>) -> Frame {
    let m = moments.mean();
    let scale = 2.0 / (variances[0].sqrt() + variances[1].sqrt());
    let scale = if scale.is_finite() { scale } else { 1.0 };
    // Normal from the half neighbourhood closest to the centroid: robust to outliers.
    let raw = half.map_or([0.0, 0.0, 1.0], |e| e.smallest_vector);
    Frame {
        mean: m,
        scale,
        normal: orient(raw, m.map(|c| -c)),
        variances,
    }
}

/// Moments of the `floor(k/2)` of the `k` points `pts` closest to `m`, ties by rank.
///
/// Non-negative f64 bits order like the values; the rank replaces the lowest mantissa
/// bits (a relative 2^-45 at k = 128), so one u64 is the whole key and distances
/// equal to that precision tie by rank. The half is summed in rank order, whatever
/// order the selection leaves it in, so the sums are the same on every CPU.
fn nearest_half(pts: &[[f64; 3]], m: [f64; 3], near: &mut NearCentroid) -> Moments {
    let keys = &mut near.keys;
    let rank_bits = pts.len().next_power_of_two() as u64 - 1;
    keys.clear();
    keys.resize(pts.len(), 0);
    pulp::Arch::new().dispatch(Keys {
        pts,
        m,
        rank_bits,
        keys,
    });
    near.select.mark(keys, pts.len() / 2, &mut near.chosen);
    Moments::of_chosen(pts, &near.chosen)
}

/// The keys of [`nearest_half`]: each point's squared distance to `m`, its rank in the
/// low bits. `pulp` compiles this for AVX-512 and AVX2 registers and runs it at the best
/// level the CPU has (the same operations, so the same keys): ~2% of `detect` on the 1M
/// test cube with AVX-512.
struct Keys<'a> {
    pts: &'a [[f64; 3]],
    m: [f64; 3],
    rank_bits: u64,
    keys: &'a mut [u64],
}

impl pulp::NullaryFnOnce for Keys<'_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        for ((k, q), j) in self.keys.iter_mut().zip(self.pts).zip(0u64..) {
            *k = dist2(*q, self.m).to_bits() & !self.rank_bits | j;
        }
    }
}

/// Orients the unit normal `n` so that `<s, n> >= 0`, where `s = p_i - m` (the query
/// point's offset from the centroid, same direction as `p^_i`).
///
/// When `<s, n>` is exactly 0 the first non-zero component of `n` is made positive,
/// so the result never depends on the eigen solver's sign.
pub(crate) fn orient(n: [f64; 3], s: [f64; 3]) -> [f64; 3] {
    let t = dot(s, n);
    let tie = n.iter().copied().find(|&c| c != 0.0).unwrap_or(0.0);
    if t < 0.0 || (t == 0.0 && tie < 0.0) {
        n.map(|c| -c)
    } else {
        n
    }
}

/// The points of `pts` in the upper set U of frame `f`: `<p - m, n> >= 0` (the sign of
/// `<p^, n>`, as the scale factor is positive). L holds the rest, so its moments are
/// the whole set's minus U's.
fn upper_set(pts: &[[f64; 3]], f: &Frame, kept: &mut Vec<[f64; 3]>) -> Moments {
    // <q - m, n> >= 0  <=>  <q, n> >= <m, n>
    let threshold = dot(f.mean, f.normal);
    // Compacted without a branch (always write, advance on keep): on real clouds the
    // side of a point is unpredictable.
    kept.resize(pts.len(), [0.0; 3]);
    let mut n = 0;
    for &q in pts {
        kept[n] = q;
        n += usize::from(dot(q, f.normal) >= threshold);
    }
    Moments::of(kept[..n].iter().copied())
}

/// The 15 values of one scale (all groups, `c` left at 0) in the normalised frame `f`,
/// from the upper and lower sets with their variances.
fn scale_features(f: &Frame, [upper, lower]: &[(Moments, [f64; 3]); 2]) -> [f64; ALL_FEATURES] {
    let mut all = [0.0; ALL_FEATURES];
    let s2 = f.scale * f.scale;
    all[..3].copy_from_slice(&f.variances.map(|v| v * s2));
    all[3..6].copy_from_slice(&upper.1.map(|v| v * s2));
    all[6..9].copy_from_slice(&lower.1.map(|v| v * s2));
    let (upper, lower) = (&upper.0, &lower.0);
    if upper.n > 0 && lower.n > 0 {
        let (mu, ml) = (upper.mean(), lower.mean());
        [all[9], all[10]] = split([0, 1, 2].map(|a| (mu[a] - ml[a]) * f.scale), f.normal);
    }
    // The query point is the origin of the points.
    [all[11], all[12]] = split(f.mean.map(|c| -c * f.scale), f.normal);
    all
}

/// Components of `v` along the unit vector `n` and the length of the rest.
fn split(v: [f64; 3], n: [f64; 3]) -> [f64; 2] {
    let along = dot(v, n);
    let rest = [0, 1, 2].map(|a| v[a] - along * n[a]);
    [along, dot(rest, rest).sqrt()]
}

#[inline(always)]
fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    dot(d, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_half_breaks_ties_by_rank() {
        // A 7 x 7 integer grid (many exactly equal distances to the centre), in a
        // scrambled order, and an odd count: brute force on (distance, rank) pairs.
        let pts: Vec<[f64; 3]> = (0..49)
            .map(|i| (i * 19) % 49)
            .map(|i| [(i % 7) as f64, (i / 7) as f64, 0.5 * (i % 3) as f64])
            .collect();
        for (len, m) in [(49, [3.0, 3.0, 0.5]), (48, [0.0; 3]), (3, [1.0, 0.0, 0.0])] {
            let pts = &pts[..len];
            let mut want: Vec<(f64, usize)> = (0..len).map(|j| (dist2(pts[j], m), j)).collect();
            want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let want = Moments::of(want[..len / 2].iter().map(|&(_, j)| pts[j]));
            let got = nearest_half(pts, m, &mut NearCentroid::new());
            assert_eq!((got.n, got.sum, got.outer), (want.n, want.sum, want.outer));
        }
    }

    #[test]
    fn nearest_half_sums_in_rank_order() {
        // Irregular coordinates: only the rank order gives these exact sums, whichever
        // way (AVX-512 networks or quickselect) the half was found.
        for k in [16, 45, 128] {
            let pts: Vec<[f64; 3]> = (0..k)
                .map(|i| {
                    let t = i as f64 * 0.7318;
                    [
                        t.sin() * 1.37,
                        (t * 1.91).cos() * 0.83,
                        (t * 0.37).sin() * 0.11,
                    ]
                })
                .collect();
            let m = [0.1, -0.2, 0.05];
            let mut ranked: Vec<(f64, usize)> = (0..k).map(|j| (dist2(pts[j], m), j)).collect();
            ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut half: Vec<usize> = ranked[..k / 2].iter().map(|&(_, j)| j).collect();
            half.sort_unstable();
            let want = Moments::of(half.iter().map(|&j| pts[j]));
            let got = nearest_half(&pts, m, &mut NearCentroid::new());
            assert_eq!(
                (got.n, got.sum, got.outer),
                (want.n, want.sum, want.outer),
                "k {k}"
            );
        }
    }

    #[test]
    fn orientation_ignores_the_solvers_sign() {
        let n = [0.6, 0.0, -0.8];
        for s in [[1.0, 2.0, 3.0], [-1.0, 0.5, 0.2], [0.8, 7.0, 0.6], [0.0; 3]] {
            let a = orient(n, s);
            assert_eq!(a, orient(n.map(|c| -c), s), "s = {s:?}");
            assert!(dot(a, s) >= 0.0);
        }
        // In-plane query point: the first non-zero component decides.
        assert_eq!(orient([0.0, -1.0, 0.0], [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
    }
}
