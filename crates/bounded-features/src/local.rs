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
//! - the upper sets of eight points are summed side by side, a point per vector lane
//!   (AVX-512: one register per sum for all eight), each lane adding only where its
//!   point is in U: 6% faster on the 1M test cube than compacting each point's set
//!   without a branch and summing it (which had beaten a branch on real scans, where
//!   which side a neighbour lies on is unpredictable, and a zero weight per point);
//! - tried, did not pay: two accumulator sets per sum, summing one point's k
//!   neighbours eight at a time with lane masks (40% slower even with AVX-512),
//!   sorting instead of selecting small half-neighbourhoods, and (in `bounded-geom`)
//!   rows ordered only by scale bands instead of fully sorted, as the selections that
//!   replace the sort cost as much and the half-neighbourhood selection is slower on
//!   unsorted rows.

use bounded_geom::{Eigen3, SmallestFirst, Sym3, dot, eigenvalues_batch};

use crate::FeatureConfig;

/// Values per scale with every group on (see `config::NAMES`).
pub(crate) const ALL_FEATURES: usize = 15;

/// Points processed side by side: their upper sets are summed in one pass, a point per
/// vector lane.
pub(crate) const LANES: usize = 8;

/// Per-thread buffers, reused from group to group so the hot loop never allocates.
pub(crate) struct Scratch {
    /// One point's buffers per lane.
    lanes: Vec<Lane>,
    /// The lanes' neighbours side by side: `[neighbour][axis][lane]`.
    side_by_side: Vec<[[f64; LANES]; 3]>,
}

impl Scratch {
    pub(crate) fn new(k0: usize) -> Self {
        Self {
            lanes: (0..LANES).map(|_| Lane::new(k0)).collect(),
            side_by_side: Vec::with_capacity(k0),
        }
    }
}

/// The buffers of one point.
struct Lane {
    /// Neighbours relative to the query point, in `f64`.
    local: Vec<[f64; 3]>,
    /// Moments of each scale's neighbourhood, smallest scale first.
    prefix: Vec<Moments>,
    /// The selection of the normal's half neighbourhood.
    near_centroid: NearCentroid,
    /// The eigen problems of a point, solved in batches.
    batch: Batch,
}

impl Lane {
    fn new(k0: usize) -> Self {
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

    /// The moments of the points of `pts` whose bits are set in `chosen`, in order.
    ///
    /// Never inlined: inside the large per-point code the accumulators were kept on
    /// the stack, putting a store-to-load round trip into every addition's chain.
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

    /// Adds `pts`, in order (not inlined, like [`of_chosen`](Self::of_chosen)).
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

/// Writes the selected features of every scale of up to [`LANES`] points into `out`
/// (points x scales x selected values): each row of `k0` in `rows` holds one point's
/// sorted neighbours, the point itself first.
pub(crate) fn group_features(
    points: &[[f32; 3]],
    rows: &[u32],
    config: &FeatureConfig,
    scratch: &mut Scratch,
    out: &mut [f32],
) {
    let k0 = config.largest_scale();
    let count = rows.len() / k0;
    debug_assert!((1..=LANES).contains(&count));
    for (lane, neighbours) in scratch.lanes.iter_mut().zip(rows.chunks_exact(k0)) {
        lane.frames(points, neighbours, config);
    }
    upper_sets(scratch, count, config);
    let per_point = out.chunks_exact_mut(config.features_per_point());
    for (lane, out) in scratch.lanes.iter_mut().zip(per_point) {
        lane.finish(config, out);
    }
}

impl Lane {
    /// The point's neighbours, their prefix moments and every scale's frame.
    fn frames(&mut self, points: &[[f32; 3]], neighbours: &[u32], config: &FeatureConfig) {
        // Centre on the query point in f64: small, well-conditioned coordinates.
        let p = points[neighbours[0] as usize].map(f64::from);
        self.local.clear();
        self.local.extend(neighbours.iter().map(|&j| {
            let q = points[j as usize];
            [0, 1, 2].map(|a| f64::from(q[a]) - p[a])
        }));
        // Moments of every scale from one pass: scales are prefixes, smallest first.
        self.prefix.clear();
        let mut running = Moments::default();
        for &k in config.scales.iter().rev() {
            running.extend(&self.local[running.n..k]);
            self.prefix.push(running);
        }
        // Two batches of eigen problems (see `eigenvalues_batch`): each scale's
        // covariance and its half neighbourhood's give the frames; then (`finish`) the
        // upper and lower set of every scale, which need the frames' normals.
        let scales = config.scales.iter().copied().zip(self.prefix.iter().rev());
        frames(
            &self.local,
            scales,
            &mut self.near_centroid,
            &mut self.batch,
        );
    }

    /// The features, once `batch.sides` holds every scale's upper and lower set.
    fn finish(&mut self, config: &FeatureConfig, out: &mut [f32]) {
        let batch = &mut self.batch;
        side_variances(batch);
        let scales = config.scales.iter().zip(self.prefix.iter().rev());
        let (m0, f0) = (&self.prefix[config.scales.len() - 1], &batch.frames[0]);
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
}

/// Every scale's upper and lower set of the first `count` lanes into their
/// `batch.sides`, the lanes side by side: U holds the points with `<q - m, n> >= 0`
/// in the scale's frame (the sign of `<q^, n>`, as the scale factor is positive), L
/// the rest, so its moments are the whole set's minus U's.
fn upper_sets(scratch: &mut Scratch, count: usize, config: &FeatureConfig) {
    let lanes = &mut scratch.lanes[..count];
    let k0 = config.largest_scale();
    let xyz = &mut scratch.side_by_side;
    xyz.clear();
    xyz.resize(k0, [[0.0; LANES]; 3]);
    for (l, lane) in lanes.iter().enumerate() {
        for (x, q) in xyz.iter_mut().zip(&lane.local) {
            for (x, c) in x.iter_mut().zip(q) {
                x[l] = *c;
            }
        }
    }
    for lane in lanes.iter_mut() {
        lane.batch.sides.clear();
    }
    for (i, &k) in config.scales.iter().enumerate() {
        let mut normal = [[0.0; LANES]; 3];
        let mut threshold = [0.0; LANES];
        for (l, lane) in lanes.iter().enumerate() {
            let f = &lane.batch.frames[i];
            for (n, c) in normal.iter_mut().zip(f.normal) {
                n[l] = c;
            }
            // <q - m, n> >= 0  <=>  <q, n> >= <m, n>
            threshold[l] = dot(f.mean, f.normal);
        }
        let upper = pulp::Arch::new().dispatch(UpperSums {
            xyz: &xyz[..k],
            normal,
            threshold,
        });
        for (lane, upper) in lanes.iter_mut().zip(upper) {
            let m = &lane.prefix[config.scales.len() - 1 - i];
            let pair = [(upper, [0.0; 3]), (m.minus(&upper), [0.0; 3])];
            lane.batch.sides.push(pair);
        }
    }
}

/// The moments of the upper sets U (see [`upper_sets`]) of [`LANES`] points side by
/// side, a point per lane: each lane gets the sums of [`Moments::add`] over its U in
/// order, so the same bits as one point at a time. `pulp` compiles it for AVX-512 /
/// AVX2 registers (a lane per `f64`: one register for the eight points with AVX-512).
struct UpperSums<'a> {
    xyz: &'a [[[f64; LANES]; 3]],
    normal: [[f64; LANES]; 3],
    threshold: [f64; LANES],
}

impl pulp::WithSimd for UpperSums<'_> {
    type Output = [Moments; LANES];

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> [Moments; LANES] {
        let Self {
            xyz,
            normal: [nx, ny, nz],
            threshold,
        } = self;
        fn registers<S: pulp::Simd>(v: &[f64; LANES]) -> &[S::f64s] {
            S::as_simd_f64s(v).0
        }
        let registers = registers::<S>;
        let (nx, ny, nz, t) = (
            registers(&nx),
            registers(&ny),
            registers(&nz),
            registers(&threshold),
        );
        let one = simd.splat_f64s(1.0);
        // Count, sum and outer products, lane by lane: `Moments::add`'s sums in order,
        // each addition kept only where the point is in U, so the same bits.
        let mut acc = [[0.0; LANES]; 10];
        for xyz in xyz {
            let [x, y, z] = [0, 1, 2].map(|a| registers(&xyz[a]));
            for r in 0..x.len() {
                let (x, y, z) = (x[r], y[r], z[r]);
                let along = simd.add_f64s(
                    simd.add_f64s(simd.mul_f64s(x, nx[r]), simd.mul_f64s(y, ny[r])),
                    simd.mul_f64s(z, nz[r]),
                );
                let up = simd.greater_than_or_equal_f64s(along, t[r]);
                let mul = |a, b| simd.mul_f64s(a, b);
                let values = [
                    one,
                    x,
                    y,
                    z,
                    mul(x, x),
                    mul(x, y),
                    mul(x, z),
                    mul(y, y),
                    mul(y, z),
                    mul(z, z),
                ];
                for (acc, v) in acc.iter_mut().zip(values) {
                    let acc = &mut S::as_mut_simd_f64s(acc).0[r];
                    *acc = simd.select_f64s(up, simd.add_f64s(*acc, v), *acc);
                }
            }
        }
        std::array::from_fn(|l| Moments {
            n: acc[0][l] as usize,
            sum: [acc[1][l], acc[2][l], acc[3][l]],
            outer: Sym3 {
                xx: acc[4][l],
                xy: acc[5][l],
                xz: acc[6][l],
                yy: acc[7][l],
                yz: acc[8][l],
                zz: acc[9][l],
            },
        })
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

/// The variances of every scale's upper and lower set in `batch.sides`, one batch.
fn side_variances(batch: &mut Batch) {
    // All upper sets, then all lower sets.
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

    impl Moments {
        /// The moments of `pts`, one point at a time.
        fn of(pts: impl Iterator<Item = [f64; 3]>) -> Self {
            let mut m = Self::default();
            pts.for_each(|q| m.add(q));
            m
        }
    }

    #[test]
    fn upper_sums_side_by_side_match_one_point_at_a_time() {
        // Irregular points and frames per lane, including points exactly on a plane
        // (the ">=" side) and lanes whose frame keeps every point or none.
        let k = 45;
        let xyz: Vec<[[f64; LANES]; 3]> = (0..k)
            .map(|j| {
                let t = |l: usize, a: usize| ((j * 7 + l * 13 + a * 5) as f64 * 0.731).sin();
                let mut q = [0, 1, 2].map(|a| std::array::from_fn(|l| t(l, a)));
                q[2][0] = 0.25;
                q
            })
            .collect();
        let mut normal = [[0.0; LANES]; 3];
        let mut threshold = [0.0; LANES];
        for l in 0..LANES {
            let n = [0.3 + l as f64, -0.2, 1.0 - 0.1 * l as f64];
            let len = dot(n, n).sqrt();
            for a in 0..3 {
                normal[a][l] = n[a] / len;
            }
            threshold[l] = 0.05 * l as f64 - 0.1;
        }
        (normal[0][0], normal[1][0], normal[2][0], threshold[0]) = (0.0, 0.0, 1.0, 0.25);
        threshold[6] = 10.0;
        threshold[7] = -10.0;
        let got = pulp::Arch::new().dispatch(UpperSums {
            xyz: &xyz,
            normal,
            threshold,
        });
        for (l, got) in got.iter().enumerate() {
            let n = normal.map(|c| c[l]);
            let points = xyz.iter().map(|q| q.map(|c| c[l]));
            let want = Moments::of(points.filter(|&q| dot(q, n) >= threshold[l]));
            assert_eq!(
                (got.n, got.sum, got.outer),
                (want.n, want.sum, want.outer),
                "lane {l}"
            );
        }
        assert_eq!((got[6].n, got[7].n), (0, k));
    }

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
