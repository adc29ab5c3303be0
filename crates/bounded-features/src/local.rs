//! The statistics of a point's nested neighbourhoods (SPEC.md, "Features"), eight
//! points at a time.
//!
//! Performance notes (k0 = 128, 4 scales, 1M-point test cube, `detect`):
//! - every sum over neighbours (each scale's moments, half neighbourhood and upper
//!   set) runs for eight points side by side, a point per vector lane: with AVX-512
//!   one register holds a sum for all eight, and a lane adds only where its point
//!   belongs, so each lane's sums are the one-point sums in the same order, bit for
//!   bit. Against one point at a time (scalar sums of compacted sets, which had beaten
//!   branching on real scans): 1.43 -> 1.25 s. `pulp` compiles the sums for AVX-512,
//!   AVX2 or plain registers; what they call must be inlined (`array::map` with an
//!   intrinsic inside was not, and cost 2x). Measured with the rest on AVX-512 and only
//!   the sums forced down: with AVX2 the 1M cube took what one point at a time took
//!   (1.40 s), with plain registers 1.93 s (every lane adds every neighbour);
//! - the 16 eigen problems of a point are solved in two batches for the whole group
//!   (each scale's covariance and half-neighbourhood covariance, then each scale's
//!   upper and lower set), so their long dependency chains overlap: 9% less time than
//!   one at a time for batches of a point, 1.5% less again for batches of eight points;
//! - the normal's half neighbourhood is found from single `u64` keys (distance bits
//!   with the rank in the low bits): [`SmallestFirst`] gives the threshold key of the
//!   smaller half (AVX-512 sorting networks where the CPU has them, else a branch-free
//!   quickselect), and the sums keep the keys at or below it;
//! - the neighbour gather reads the cloud in its own order: on the randomly ordered
//!   test cube it is ~9% of the time, bound by cache misses; prefetching the next
//!   group's neighbours, and (with the kNN giving positions) reading the index's
//!   Morton-ordered copy instead, measured no faster;
//! - tried, did not pay: two accumulator sets per sum, summing one point's k
//!   neighbours eight at a time with lane masks (40% slower even with AVX-512),
//!   sorting instead of selecting small half neighbourhoods, and (in `bounded-geom`)
//!   rows ordered only by scale bands instead of fully sorted.

use bounded_geom::vec3::{norm, normalize, scale, sub};
use bounded_geom::{Eigen3, SmallestFirst, Sym3, cross, dot, eigenvalues_batch};
use pulp::Simd;

use crate::FeatureConfig;

/// Values per scale with every group on (see `config::NAMES`).
pub(crate) const ALL_FEATURES: usize = 16;

/// Points computed side by side, one per vector lane.
pub(crate) const LANES: usize = 8;

/// One value per lane.
type Lanes = [f64; LANES];

/// Per-thread buffers, reused from group to group so the hot loop never allocates.
pub(crate) struct Scratch {
    /// The group's neighbours relative to their query points, in `f64`, side by side:
    /// `[neighbour][axis][lane]`.
    xyz: Vec<[Lanes; 3]>,
    /// Each scale's moments per lane, largest scale first.
    prefix: Vec<[Moments; LANES]>,
    /// The moments of each scale's half neighbourhood per lane, largest scale first.
    half: Vec<[Moments; LANES]>,
    /// Each lane's keys of a half neighbourhood's candidates.
    keys: Vec<[u64; LANES]>,
    /// The selection of the half neighbourhoods.
    select: SmallestFirst,
    /// A batch of eigen problems, all lanes', and their eigenvalues.
    matrices: Vec<Sym3>,
    values: Vec<[f64; 3]>,
    /// Each lane's frames and sides.
    lanes: Vec<Lane>,
    /// Each scale's `h` per lane before its normalisation (see [`hull_insets`]).
    insets: Vec<Lanes>,
}

impl Scratch {
    pub(crate) fn new(k0: usize) -> Self {
        Self {
            xyz: Vec::with_capacity(k0),
            prefix: Vec::new(),
            half: Vec::new(),
            keys: Vec::with_capacity(k0),
            select: SmallestFirst::new(),
            matrices: Vec::new(),
            values: Vec::new(),
            lanes: (0..LANES).map(|_| Lane::default()).collect(),
            insets: Vec::new(),
        }
    }
}

/// What the eigen problems give one point, per scale, largest scale first.
#[derive(Default)]
struct Lane {
    frames: Vec<Frame>,
    /// The upper and lower set of each scale, with their variances.
    sides: Vec<[(Moments, [f64; 3]); 2]>,
    /// Each scale's `h` (see [`hull_insets`]), when that group is selected.
    hulls: Vec<f64>,
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
    gather(points, rows, k0, &mut scratch.xyz);
    let xyz = &scratch.xyz;
    let arch = pulp::Arch::new();
    // Moments of every scale from one pass: scales are prefixes, smallest first.
    scratch.prefix.clear();
    scratch
        .prefix
        .resize(config.scales.len(), [Moments::default(); LANES]);
    arch.dispatch(PrefixSums {
        xyz,
        scales: &config.scales,
        out: &mut scratch.prefix,
    });
    scratch.half.clear();
    for (&k, prefix) in config.scales.iter().zip(&scratch.prefix) {
        let (keys, select) = (&mut scratch.keys, &mut scratch.select);
        let half = half_neighbourhoods(arch, &xyz[..k], prefix, keys, select);
        scratch.half.push(half);
    }
    // Two batches of eigen problems for the whole group (see `eigenvalues_batch`): each
    // scale's covariance and its half neighbourhood's give the frames; then the upper
    // and lower set of every scale, which need the frames' normals.
    let per_lane = 2 * config.scales.len();
    let matrices = &mut scratch.matrices;
    matrices.clear();
    for l in 0..count {
        matrices.extend(scratch.prefix.iter().map(|m| m[l].covariance()));
        matrices.extend(scratch.half.iter().map(|m| m[l].covariance()));
    }
    solve(matrices, &mut scratch.values);
    let problems = matrices
        .chunks_exact(per_lane)
        .zip(scratch.values.chunks_exact(per_lane));
    for (l, (lane, solved)) in scratch.lanes.iter_mut().zip(problems).enumerate() {
        let prefix = scratch.prefix.iter().map(|m| &m[l]);
        frames(&config.scales, prefix, solved, lane);
    }
    if config.groups.h {
        hull_insets(arch, scratch, count, &config.scales);
    }
    upper_sets(arch, scratch, count, config);
    let matrices = &mut scratch.matrices;
    matrices.clear();
    for lane in &scratch.lanes[..count] {
        // All upper sets, then all lower sets.
        for side in 0..2 {
            matrices.extend(lane.sides.iter().map(|s| s[side].0.covariance()));
        }
    }
    solve(matrices, &mut scratch.values);
    let per_point = out.chunks_exact_mut(config.features_per_point());
    let solved = scratch.values.chunks_exact(per_lane);
    for (l, ((lane, out), values)) in scratch
        .lanes
        .iter_mut()
        .zip(per_point)
        .zip(solved)
        .enumerate()
    {
        side_variances(lane, values);
        point_values(config, scratch.prefix.iter().map(|m| &m[l]), lane, out);
    }
}

/// The eigenvalues of `matrices` into `values`.
fn solve(matrices: &[Sym3], values: &mut Vec<[f64; 3]>) {
    values.resize(matrices.len(), [0.0; 3]);
    eigenvalues_batch(matrices, values);
}

/// The neighbours of each row of `rows` (`k0` each, the query point first) relative to
/// their query point, in `f64` (small, well-conditioned coordinates), side by side in
/// `xyz`; lanes without a row hold zeros.
fn gather(points: &[[f32; 3]], rows: &[u32], k0: usize, xyz: &mut Vec<[Lanes; 3]>) {
    xyz.clear();
    xyz.resize(k0, [[0.0; LANES]; 3]);
    for (l, row) in rows.chunks_exact(k0).enumerate() {
        let p = points[row[0] as usize].map(f64::from);
        for (x, &j) in xyz.iter_mut().zip(row) {
            let q = points[j as usize];
            for a in 0..3 {
                x[a][l] = f64::from(q[a]) - p[a];
            }
        }
    }
}

/// The features of one point from its scales' moments (largest scale first) and its
/// lane's frames and sides.
fn point_values<'a>(
    config: &FeatureConfig,
    prefix: impl Iterator<Item = &'a Moments> + Clone,
    lane: &Lane,
    out: &mut [f32],
) {
    let Some(m0) = prefix.clone().next() else {
        return;
    };
    let f0 = &lane.frames[0];
    let per_scale = out.chunks_exact_mut(config.features_per_scale());
    for (i, (moments, out)) in prefix.zip(per_scale).enumerate() {
        let frame = &lane.frames[i];
        let mut all = scale_features(frame, &lane.sides[i]);
        if i > 0 {
            // c: this scale's centroid against the rest of the k0 neighbourhood,
            // in the k0 frame.
            let rest = m0.minus(moments).mean();
            let c = [0, 1, 2].map(|a| (frame.mean[a] - rest[a]) * f0.scale);
            [all[13], all[14]] = split(c, f0.normal);
        }
        if let Some(&h) = lane.hulls.get(i) {
            all[15] = h;
        }
        for (o, i) in out.iter_mut().zip(config.groups.selected()) {
            *o = all[i] as f32;
        }
    }
}

/// The moments of the `floor(k/2)` of each lane's `k` points `xyz` closest to the lane's
/// centroid (from `prefix`), ties by rank; zeros for `k < 2`.
///
/// A key per point: the squared distance's `f64` bits (non-negative, so they order like
/// the values) with the rank in the lowest bits (a relative 2^-45 at k = 128), so
/// distances equal to that precision tie by rank. The selection gives each lane's
/// threshold key, the half is the keys at or below it, and it is summed in rank
/// order, whichever selection ran, so the sums are the same on every CPU.
fn half_neighbourhoods(
    arch: pulp::Arch,
    xyz: &[[Lanes; 3]],
    prefix: &[Moments; LANES],
    keys: &mut Vec<[u64; LANES]>,
    select: &mut SmallestFirst,
) -> [Moments; LANES] {
    let k = xyz.len();
    if k / 2 == 0 {
        return [Moments::default(); LANES];
    }
    let mut centre = [[0.0; LANES]; 3];
    for (l, m) in prefix.iter().enumerate() {
        for (c, v) in centre.iter_mut().zip(m.mean()) {
            c[l] = v;
        }
    }
    let rank_bits = k.next_power_of_two() as u64 - 1;
    arch.dispatch(Keys {
        xyz,
        centre,
        rank_bits,
        keys,
    });
    let threshold = select.nth_smallest_lanes(keys, k / 2);
    arch.dispatch(NearSums {
        xyz,
        keys,
        threshold,
    })
}

/// Each scale's frame into `lane.frames`, largest first, from the scales' sizes and
/// moments and the solved problems: every scale's covariance, then every scale's half
/// neighbourhood's covariance, with their eigenvalues.
fn frames<'a>(
    scales: &[usize],
    prefix: impl Iterator<Item = &'a Moments>,
    (matrices, values): (&[Sym3], &[[f64; 3]]),
    lane: &mut Lane,
) {
    let count = scales.len();
    lane.frames.clear();
    for (i, (&k, m)) in scales.iter().zip(prefix).enumerate() {
        let j = count + i;
        let half = (k / 2 > 0).then(|| matrices[j].eigen_from(values[j]));
        lane.frames.push(frame(m, m.variances(values[i]), half));
    }
}

/// Each scale's `h` into `lane.hulls` of the first `count` lanes, largest scale first: how
/// far the query point (the origin of `xyz`) lies inside the convex hull of the scale's
/// neighbours projected onto the largest neighbourhood's tangent plane, in the scale's
/// normalised frame, measured as the smallest extent of the neighbours beyond the point
/// over 32 directions ([`Reaches`]). 0 on a border; inside, a good part of the radius.
/// Unlike a mean (`s`, `c`) or an extreme along one estimated direction, it needs no
/// direction to the border: the nearest support line runs through the outermost points,
/// wherever they lie.
///
/// One plane for every scale, so that one running maximum per direction serves all
/// scales: 14 products, 14 sums and 32 extremes per neighbour of the largest scale, side
/// by side over the lanes, where an exact hull per scale sorts each scale's points again
/// (six times the features' time at 16 scales) and a hull grown over the scales more than
/// doubles it. The directions start at the point's offset from the centroid, so the value
/// turns with the cloud.
fn hull_insets(arch: pulp::Arch, scratch: &mut Scratch, count: usize, scales: &[usize]) {
    let lanes = &mut scratch.lanes[..count];
    let mut axes = [[[0.0; LANES]; 3]; 2];
    for (l, lane) in lanes.iter().enumerate() {
        let Some(f0) = lane.frames.first() else {
            continue;
        };
        let n = f0.normal;
        let offset = f0.mean.map(|c| -c);
        let along = sub(offset, scale(n, dot(offset, n)));
        let t1 = if norm(along) * f0.scale > 1e-9 {
            normalize(along)
        } else {
            any_tangent(n)
        };
        for (axis, t) in axes.iter_mut().zip([t1, cross(n, t1)]) {
            for (a, c) in axis.iter_mut().zip(t) {
                a[l] = c;
            }
        }
    }
    let insets = &mut scratch.insets;
    insets.clear();
    insets.resize(scales.len(), [0.0; LANES]);
    arch.dispatch(Reaches {
        xyz: &scratch.xyz[..scales.first().copied().unwrap_or(0)],
        axes,
        scales,
        out: insets,
    });
    for (l, lane) in lanes.iter_mut().enumerate() {
        lane.hulls.clear();
        let per_scale = insets.iter().zip(&lane.frames);
        lane.hulls
            .extend(per_scale.map(|(inset, f)| inset[l] * f.scale));
    }
}

/// Half the directions of [`Reaches`]: `(cos, sin)` of `pi i / 16`.
const DIRECTIONS: [[f64; 2]; 16] = {
    // cos (pi i / 16), i = 0..=8, so that the table is a constant.
    let q = [
        1.0,
        0.980_785_280_403_230_4,
        0.923_879_532_511_286_7,
        0.831_469_612_302_545_2,
        std::f64::consts::FRAC_1_SQRT_2,
        0.555_570_233_019_602_2,
        0.382_683_432_365_089_8,
        0.195_090_322_016_128_3,
        0.0,
    ];
    let mut d = [[0.0; 2]; 16];
    let mut i = 0;
    while i < 16 {
        d[i] = if i <= 8 {
            [q[i], q[8 - i]]
        } else {
            [-q[16 - i], q[i - 8]]
        };
        i += 1;
    }
    d
};

/// Each lane's smallest reach of `xyz` at every scale (`scales` largest first, into `out`
/// in that order): how far the points, projected onto the lane's `axes`, reach beyond
/// the origin along each of 32 directions (16 and their opposites, every 11.25 degrees),
/// the least of them. That is the origin's distance to the nearest of 32 support lines,
/// an upper bound of its distance to the points' convex hull that equals it when the
/// nearest edge faces one of the directions. The origin belongs to the set: reaches start
/// at 0.
struct Reaches<'a> {
    xyz: &'a [[Lanes; 3]],
    axes: [[Lanes; 3]; 2],
    scales: &'a [usize],
    out: &'a mut [Lanes],
}

impl pulp::WithSimd for Reaches<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self {
            xyz,
            axes,
            scales,
            out,
        } = self;
        let (mut most, mut least) = ([[0.0; LANES]; 16], [[0.0; LANES]; 16]);
        let mut at = scales.iter().zip(out.iter_mut()).rev().peekable();
        for (j, xyz) in xyz.iter().enumerate() {
            for r in 0..registers::<S>(&xyz[0]).len() {
                // <q, t> as `dot` computes it; axis by axis, no `array::map`, which is not
                // always inlined and then turns the intrinsics into calls.
                let c = |v: &Lanes| registers::<S>(v)[r];
                let along = |t: &[Lanes; 3]| {
                    let xy = simd.add_f64s(
                        simd.mul_f64s(c(&xyz[0]), c(&t[0])),
                        simd.mul_f64s(c(&xyz[1]), c(&t[1])),
                    );
                    simd.add_f64s(xy, simd.mul_f64s(c(&xyz[2]), c(&t[2])))
                };
                let (u, v) = (along(&axes[0]), along(&axes[1]));
                // `max_f64s(w, m)` is `w > m ? w : m` (vmaxpd), as a comparison and a
                // select would be, which the compiler made a masked store whose reload
                // stalled (12% of a detection). The origin's reach of 0 starts both.
                let mut reach = |i: usize, w| {
                    let m = &mut S::as_mut_simd_f64s(&mut most[i]).0[r];
                    *m = simd.max_f64s(w, *m);
                    let m = &mut S::as_mut_simd_f64s(&mut least[i]).0[r];
                    *m = simd.min_f64s(w, *m);
                };
                // Directions 0 and 8 are the axes (1 u + 0 v is u, up to a zero's sign,
                // which a reach starting at 0 ignores). The others come in fours, i, 8 - i,
                // 8 + i and 16 - i, from four products: (-a) + b, as the table's negative
                // cosine gives it, is b - a bit for bit.
                reach(0, u);
                reach(8, v);
                for i in [1, 2, 3, 4] {
                    let [cos, sin] = DIRECTIONS[i];
                    let (cos, sin) = (simd.splat_f64s(cos), simd.splat_f64s(sin));
                    let (a, b) = (simd.mul_f64s(cos, u), simd.mul_f64s(sin, v));
                    reach(i, simd.add_f64s(a, b));
                    reach(16 - i, simd.sub_f64s(b, a));
                    if i < 4 {
                        let (c, d) = (simd.mul_f64s(sin, u), simd.mul_f64s(cos, v));
                        reach(8 - i, simd.add_f64s(c, d));
                        reach(8 + i, simd.sub_f64s(d, c));
                    }
                }
            }
            while let Some((_, out)) = at.next_if(|(k, _)| **k == j + 1) {
                for (r, out) in S::as_mut_simd_f64s(out).0.iter_mut().enumerate() {
                    let min = |a, b| simd.select_f64s(simd.less_than_f64s(b, a), b, a);
                    *out = simd.splat_f64s(f64::INFINITY);
                    for i in 0..16 {
                        let (m, l) = (registers::<S>(&most[i])[r], registers::<S>(&least[i])[r]);
                        *out = min(min(*out, m), simd.sub_f64s(simd.splat_f64s(0.0), l));
                    }
                }
            }
        }
    }
}

/// A unit vector perpendicular to the unit vector `n`: `n` crossed with the axis it is
/// least aligned with.
fn any_tangent(n: [f64; 3]) -> [f64; 3] {
    let least = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(0);
    let mut axis = [0.0; 3];
    axis[least] = 1.0;
    normalize(cross(n, axis))
}

/// Which side a neighbour exactly on the split plane takes (see [`upper_sets`]): the top bit of
/// its rank times 2^64 / golden ratio, a fixed pattern that splits any run of ranks
/// about evenly and irregularly, as rounding splits a rotated plane.
#[inline(always)]
fn on_plane_goes_up(rank: usize) -> bool {
    (rank as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 63 == 0
}

/// Every scale's upper and lower set of the first `count` lanes into their
/// `lane.sides`: U holds the points with `<q - m, n> >= 0` in the scale's frame (the
/// sign of `<q^, n>`, as the scale factor is positive), L the rest, so its moments are
/// the whole set's minus U's.
///
/// Not in the paper: a neighbour exactly on the split plane (`<q, n> = <m, n>`) joins U
/// or L by its rank ([`on_plane_goes_up`]). On a rotated plane the offsets' rounding
/// splits its points about in halves, and the classifier learns from such clouds; on a
/// plane along the axes (a CAD part, a wall) every offset is exactly 0, and `>= 0` alone
/// would put all of them in U and leave L empty, features no rotated copy has (an
/// axis-aligned open box's rim: 39% found as boundary against 98% rotated). Only exact
/// ties change sides: any tolerance also moved some of the rounding-split neighbours of
/// the generated training clouds (1e-14 of the neighbourhood's size did), and so the
/// features the embedded model was trained on.
fn upper_sets(arch: pulp::Arch, scratch: &mut Scratch, count: usize, config: &FeatureConfig) {
    let lanes = &mut scratch.lanes[..count];
    for lane in lanes.iter_mut() {
        lane.sides.clear();
    }
    for (i, (&k, prefix)) in config.scales.iter().zip(&scratch.prefix).enumerate() {
        let mut normal = [[0.0; LANES]; 3];
        let mut threshold = [0.0; LANES];
        for (l, lane) in lanes.iter().enumerate() {
            let f = &lane.frames[i];
            for (n, c) in normal.iter_mut().zip(f.normal) {
                n[l] = c;
            }
            // <q - m, n> >= 0  <=>  <q, n> >= <m, n>
            threshold[l] = dot(f.mean, f.normal);
        }
        let upper = arch.dispatch(UpperSums {
            xyz: &scratch.xyz[..k],
            normal,
            threshold,
        });
        for ((lane, upper), m) in lanes.iter_mut().zip(upper).zip(prefix) {
            lane.sides
                .push([(upper, [0.0; 3]), (m.minus(&upper), [0.0; 3])]);
        }
    }
}

/// Each lane's moments of `xyz` at every scale (`scales` largest first, into `out` in
/// that order): the points added one at a time, in order, the scales' moments taken on
/// the way.
struct PrefixSums<'a> {
    xyz: &'a [[Lanes; 3]],
    scales: &'a [usize],
    out: &'a mut [[Moments; LANES]],
}

impl pulp::WithSimd for PrefixSums<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self { xyz, scales, out } = self;
        let mut acc = [[0.0; LANES]; 10];
        let mut at = scales.iter().zip(out.iter_mut()).rev().peekable();
        for (j, xyz) in xyz.iter().enumerate() {
            let [x, y, z] = [&xyz[0], &xyz[1], &xyz[2]].map(registers::<S>);
            for r in 0..x.len() {
                add_lanes(simd, &mut acc, r, [x[r], y[r], z[r]], None);
            }
            while let Some((_, out)) = at.next_if(|(k, _)| **k == j + 1) {
                *out = moments(&acc);
            }
        }
    }
}

/// The keys of [`half_neighbourhoods`] into `keys`: each lane's squared distances of
/// `xyz` to its `centre`, the rank in the `rank_bits`, side by side, as the selection
/// takes them (down the columns; written into a row per lane instead, the scattered
/// stores cost 4%).
struct Keys<'a> {
    xyz: &'a [[Lanes; 3]],
    centre: [Lanes; 3],
    rank_bits: u64,
    keys: &'a mut Vec<[u64; LANES]>,
}

impl pulp::WithSimd for Keys<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self {
            xyz,
            centre,
            rank_bits,
            keys,
        } = self;
        keys.clear();
        keys.resize(xyz.len(), [0; LANES]);
        for (j, (xyz, keys)) in xyz.iter().zip(keys.iter_mut()).enumerate() {
            let registers = S::as_mut_simd_u64s(keys).0;
            for (r, out) in registers.iter_mut().enumerate() {
                *out = near_key(simd, xyz, &centre, rank_bits, j, r);
            }
        }
    }
}

/// Each lane's moments of the points of `xyz` whose `keys` (from [`Keys`], reused rather
/// than recomputed: 2% of `detect`) are at or below its `threshold`, in rank order.
struct NearSums<'a> {
    xyz: &'a [[Lanes; 3]],
    keys: &'a [[u64; LANES]],
    threshold: [u64; LANES],
}

impl pulp::WithSimd for NearSums<'_> {
    type Output = [Moments; LANES];

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> [Moments; LANES] {
        let Self {
            xyz,
            keys,
            threshold,
        } = self;
        let threshold = S::as_simd_u64s(&threshold).0;
        let mut acc = [[0.0; LANES]; 10];
        for (xyz, keys) in xyz.iter().zip(keys) {
            let [x, y, z] = [&xyz[0], &xyz[1], &xyz[2]].map(registers::<S>);
            let keys = S::as_simd_u64s(keys).0;
            for r in 0..x.len() {
                let near = simd.less_than_or_equal_u64s(keys[r], threshold[r]);
                add_lanes(simd, &mut acc, r, [x[r], y[r], z[r]], Some(near));
            }
        }
        moments(&acc)
    }
}

/// The moments of the upper sets U (see [`upper_sets`]) of the lanes' points `xyz`, in
/// rank order, whose split plane lies at `threshold` along `normal`.
struct UpperSums<'a> {
    xyz: &'a [[Lanes; 3]],
    normal: [Lanes; 3],
    threshold: Lanes,
}

impl pulp::WithSimd for UpperSums<'_> {
    type Output = [Moments; LANES];

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> [Moments; LANES] {
        let Self {
            xyz,
            normal,
            threshold,
        } = self;
        let [nx, ny, nz] = [&normal[0], &normal[1], &normal[2]].map(registers::<S>);
        let t = registers::<S>(&threshold);
        let mut acc = [[0.0; LANES]; 10];
        for (rank, xyz) in xyz.iter().enumerate() {
            let [x, y, z] = [&xyz[0], &xyz[1], &xyz[2]].map(registers::<S>);
            let goes_up = on_plane_goes_up(rank);
            for r in 0..x.len() {
                // <q, n> as `dot` computes it.
                let along = simd.add_f64s(
                    simd.add_f64s(simd.mul_f64s(x[r], nx[r]), simd.mul_f64s(y[r], ny[r])),
                    simd.mul_f64s(z[r], nz[r]),
                );
                let up = if goes_up {
                    simd.greater_than_or_equal_f64s(along, t[r])
                } else {
                    simd.greater_than_f64s(along, t[r])
                };
                add_lanes(simd, &mut acc, r, [x[r], y[r], z[r]], Some(up));
            }
        }
        moments(&acc)
    }
}

/// The lanes of `v` as registers of `S`.
#[inline(always)]
fn registers<S: Simd>(v: &Lanes) -> &[S::f64s] {
    S::as_simd_f64s(v).0
}

/// Register `r` of the keys of [`Keys`] for the points `xyz` (the `j`-th of each lane):
/// `dist2(q, centre)`'s bits, `rank_bits` replaced by `j`.
#[inline(always)]
fn near_key<S: Simd>(
    simd: S,
    xyz: &[Lanes; 3],
    centre: &[Lanes; 3],
    rank_bits: u64,
    j: usize,
    r: usize,
) -> S::u64s {
    // Axis by axis: `array::map` is not always inlined, and its intrinsics become calls.
    let d = |a: usize| simd.sub_f64s(registers::<S>(&xyz[a])[r], registers::<S>(&centre[a])[r]);
    let d = [d(0), d(1), d(2)];
    let dist2 = simd.add_f64s(
        simd.add_f64s(simd.mul_f64s(d[0], d[0]), simd.mul_f64s(d[1], d[1])),
        simd.mul_f64s(d[2], d[2]),
    );
    let bits = simd.and_u64s(simd.transmute_u64s_f64s(dist2), simd.splat_u64s(!rank_bits));
    simd.or_u64s(bits, simd.splat_u64s(j as u64))
}

/// Adds each lane's point `[x, y, z]` (register `r`) to its moments in `acc` (count,
/// sums, outer products) where `keep` is set (everywhere for `None`): one point at a time,
/// lane by lane, so the same bits.
#[inline(always)]
fn add_lanes<S: Simd>(
    simd: S,
    acc: &mut [Lanes; 10],
    r: usize,
    [x, y, z]: [S::f64s; 3],
    keep: Option<S::m64s>,
) {
    let mul = |a, b| simd.mul_f64s(a, b);
    let values = [
        simd.splat_f64s(1.0),
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
        let sum = simd.add_f64s(*acc, v);
        *acc = keep.map_or(sum, |keep| simd.select_f64s(keep, sum, *acc));
    }
}

/// The lanes' moments from the accumulators of [`add_lanes`].
#[inline(always)]
fn moments(acc: &[Lanes; 10]) -> [Moments; LANES] {
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

/// The variances of every scale's upper and lower set in `lane.sides`, from their
/// covariances' eigenvalues `values` (all upper sets, then all lower sets).
fn side_variances(lane: &mut Lane, values: &[[f64; 3]]) {
    let count = lane.sides.len();
    for (i, pair) in lane.sides.iter_mut().enumerate() {
        for (side, (set, variances)) in pair.iter_mut().enumerate() {
            *variances = set.variances(values[side * count + i]);
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

#[cfg(test)]
mod tests {
    use super::*;

    impl Moments {
        fn add(&mut self, q: [f64; 3]) {
            self.n += 1;
            for (s, c) in self.sum.iter_mut().zip(q) {
                *s += c;
            }
            self.outer.add_outer(q);
        }

        /// The moments of `pts`, one point at a time.
        fn of(pts: impl Iterator<Item = [f64; 3]>) -> Self {
            let mut m = Self::default();
            pts.for_each(|q| m.add(q));
            m
        }
    }

    fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
        let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        dot(d, d)
    }

    fn same(a: &Moments, b: &Moments) -> bool {
        (a.n, a.sum, a.outer) == (b.n, b.sum, b.outer)
    }

    /// Lanes of `k` irregular points each, lane `l` its own cloud.
    fn lanes(k: usize) -> Vec<[Lanes; 3]> {
        (0..k)
            .map(|j| {
                let t = |l: usize, a: usize| ((j * 7 + l * 13 + a * 5) as f64 * 0.731).sin();
                [0, 1, 2].map(|a| std::array::from_fn(|l| t(l, a)))
            })
            .collect()
    }

    fn lane(xyz: &[[Lanes; 3]], l: usize) -> Vec<[f64; 3]> {
        xyz.iter().map(|q| q.map(|c| c[l])).collect()
    }

    #[test]
    fn upper_sums_side_by_side_match_one_point_at_a_time() {
        // Lane 0's points lie exactly on its split plane (so join U by rank), lane 1's
        // within 1e-12 of it (so by side), and lanes 6 and 7 have frames that keep no
        // point or every point.
        let k = 45;
        let mut xyz = lanes(k);
        for (j, q) in xyz.iter_mut().enumerate() {
            q[2][0] = 0.25;
            q[2][1] = ((j % 5) as f64 - 2.0) * 1e-12;
        }
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
        (normal[0][1], normal[1][1], normal[2][1], threshold[1]) = (0.0, 0.0, 1.0, 0.0);
        threshold[6] = 10.0;
        threshold[7] = -10.0;
        let got = pulp::Arch::new().dispatch(UpperSums {
            xyz: &xyz,
            normal,
            threshold,
        });
        for (l, got) in got.iter().enumerate() {
            let n = normal.map(|c| c[l]);
            let points = lane(&xyz, l).into_iter().enumerate();
            let want = Moments::of(
                points
                    .filter(|&(j, q)| {
                        let along = dot(q, n);
                        along > threshold[l] || (along == threshold[l] && on_plane_goes_up(j))
                    })
                    .map(|(_, q)| q),
            );
            assert!(same(got, &want), "lane {l}");
        }
        let by_rank = (0..k).filter(|&j| on_plane_goes_up(j)).count();
        assert!(by_rank > k / 3 && by_rank < 2 * k / 3, "{by_rank} of {k}");
        // Lane 1: offsets -2, -1, 0, 1, 2 (x 1e-12) by rank mod 5.
        let side = (0..k).filter(|&j| j % 5 > 2 || (j % 5 == 2 && on_plane_goes_up(j)));
        assert_eq!((got[0].n, got[1].n), (by_rank, side.count()));
        assert_eq!((got[6].n, got[7].n), (0, k));
    }

    #[test]
    fn prefix_sums_match_one_point_at_a_time() {
        let xyz = lanes(40);
        let scales = [40, 23, 16, 1];
        let mut out = vec![[Moments::default(); LANES]; scales.len()];
        pulp::Arch::new().dispatch(PrefixSums {
            xyz: &xyz,
            scales: &scales,
            out: &mut out,
        });
        for l in 0..LANES {
            for (&k, got) in scales.iter().zip(&out) {
                let want = Moments::of(lane(&xyz, l)[..k].iter().copied());
                assert!(same(&got[l], &want), "lane {l} k {k}");
            }
        }
    }

    #[test]
    fn half_neighbourhoods_break_ties_by_rank_and_sum_in_rank_order() {
        // Lane 0: a 7 x 7 integer grid in scrambled order (many exactly equal distances
        // to the centre); the other lanes irregular. Brute force on (distance, rank).
        for k in [16, 45, 48, 128] {
            let mut xyz = lanes(k);
            for (j, q) in xyz.iter_mut().enumerate() {
                let i = (j * 19) % 49;
                let (x, y) = ((i % 7) as f64, (i / 7 % 7) as f64);
                [q[0][0], q[1][0], q[2][0]] = [x, y, 0.5 * (i % 3) as f64];
            }
            let mut prefix = [Moments::default(); LANES];
            for (l, m) in prefix.iter_mut().enumerate() {
                *m = Moments::of(lane(&xyz, l).into_iter());
            }
            let mut select = SmallestFirst::new();
            let arch = pulp::Arch::new();
            let got = half_neighbourhoods(arch, &xyz, &prefix, &mut Vec::new(), &mut select);
            for l in 0..LANES {
                let pts = lane(&xyz, l);
                let m = prefix[l].mean();
                let mut ranked: Vec<(f64, usize)> = (0..k).map(|j| (dist2(pts[j], m), j)).collect();
                ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let mut half: Vec<usize> = ranked[..k / 2].iter().map(|&(_, j)| j).collect();
                half.sort_unstable();
                let want = Moments::of(half.iter().map(|&j| pts[j]));
                assert!(same(&got[l], &want), "k {k} lane {l}");
            }
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

    #[test]
    fn directions_are_every_eleven_and_a_quarter_degrees() {
        for (i, d) in DIRECTIONS.iter().enumerate() {
            let a = std::f64::consts::PI * i as f64 / 16.0;
            assert!(
                (d[0] - a.cos()).abs() < 1e-15 && (d[1] - a.sin()).abs() < 1e-15,
                "{i}"
            );
        }
    }

    #[test]
    fn inset_of_hand_made_sets() {
        // The origin and `points` in the plane z = 0 in every lane, the axes x and y.
        let of = |points: &[[f64; 2]]| {
            let xyz: Vec<[Lanes; 3]> = std::iter::once([0.0, 0.0])
                .chain(points.iter().copied())
                .map(|p| [[p[0]; LANES], [p[1]; LANES], [0.0; LANES]])
                .collect();
            let axes = [
                [[1.0; LANES], [0.0; LANES], [0.0; LANES]],
                [[0.0; LANES], [1.0; LANES], [0.0; LANES]],
            ];
            let mut out = [[f64::NAN; LANES]];
            pulp::Arch::new().dispatch(Reaches {
                xyz: &xyz,
                axes,
                scales: &[xyz.len()],
                out: &mut out,
            });
            assert!(out[0].iter().all(|&v| v == out[0][0]), "{:?}", out[0]);
            out[0][0]
        };
        // The rectangle [-1, 3] x [-2, 1.5] (corners and a point inside): its nearest edge
        // faces a direction, so the hull's distance 1.
        let rect = [
            [-1.0, -2.0],
            [3.0, -2.0],
            [3.0, 1.5],
            [-1.0, 1.5],
            [1.0, 0.5],
        ];
        assert!((of(&rect) - 1.0).abs() < 1e-15, "{}", of(&rect));
        // The triangle (-3, -1), (3, -1), (0, 0.5): the hull's distance is 1 / sqrt 5 =
        // 0.447 (edges x + 2y = 1 and -x + 2y = 1, facing 63.4 and 116.6 degrees); the
        // nearest directions, 67.5 and 112.5 degrees, reach the apex, 0.5 sin 67.5 = 0.462.
        let tri = [[-3.0, -1.0], [3.0, -1.0], [0.0, 0.5], [0.5, 0.0]];
        let want = 0.5 * (3.0 * std::f64::consts::PI / 8.0).sin();
        assert!((of(&tri) - want).abs() < 1e-15, "{}", of(&tri));
        // The origin as a vertex, points on a line facing a direction, the origin alone: 0.
        assert_eq!(of(&[[1.0, 0.0], [0.0, 1.0]]), 0.0);
        assert_eq!(of(&[[-1.0, -1.0], [2.0, 2.0]]), 0.0);
        assert_eq!(of(&[]), 0.0);
        // A line facing no direction (y = 2x, its normal at 116.57 degrees): at 112.5
        // degrees, the nearest, (-1, -2) reaches sqrt 5 sin(26.57 - 22.5 degrees) = 0.159
        // beyond the origin, where the hull has no area.
        let line = of(&[[-1.0, -2.0], [2.0, 4.0]]);
        let want = 5f64.sqrt() * (0.5f64.atan() - std::f64::consts::PI / 8.0).sin();
        assert!((line - want).abs() < 1e-15, "{line} {want}");
    }

    #[test]
    fn reaches_side_by_side_are_the_simple_ones() {
        // Random points about the origin, other in every lane, other axes too; three
        // scales: the same bits as the plain loop over directions and points per lane.
        let mut uniform = bounded_geom::uniform_stream(3);
        let mut next = move || uniform() * 2.0 - 1.0;
        for _ in 0..50 {
            let mut xyz = vec![[[0.0; LANES]; 3]; 40];
            for row in &mut xyz[1..] {
                for c in row.iter_mut() {
                    c.iter_mut().for_each(|v| *v = next());
                }
            }
            let mut axes = [[[0.0; LANES]; 3]; 2];
            for l in 0..LANES {
                let n = normalize([next(), next(), next()]);
                let t1 = any_tangent(n);
                for (axis, t) in axes.iter_mut().zip([t1, cross(n, t1)]) {
                    (0..3).for_each(|a| axis[a][l] = t[a]);
                }
            }
            let scales = [40, 17, 5];
            let mut out = [[0.0; LANES]; 3];
            pulp::Arch::new().dispatch(Reaches {
                xyz: &xyz,
                axes,
                scales: &scales,
                out: &mut out,
            });
            for l in 0..LANES {
                let axis = |t: &[Lanes; 3]| [t[0][l], t[1][l], t[2][l]];
                let (t1, t2) = (axis(&axes[0]), axis(&axes[1]));
                for (&k, got) in scales.iter().zip(&out) {
                    let flat: Vec<[f64; 2]> = xyz[..k]
                        .iter()
                        .map(|q| [dot(axis(q), t1), dot(axis(q), t2)])
                        .collect();
                    let reach = |d: [f64; 2]| {
                        flat.iter()
                            .map(|p| d[0] * p[0] + d[1] * p[1])
                            .fold(0.0f64, f64::max)
                    };
                    let want = DIRECTIONS
                        .iter()
                        .map(|d| reach(*d).min(reach([-d[0], -d[1]])))
                        .fold(f64::INFINITY, f64::min);
                    assert_eq!(got[l], want, "lane {l}, scale {k}");
                }
            }
        }
    }
}
