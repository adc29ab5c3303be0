use crate::GeomError;
use rayon::prelude::*;

/// A point cloud of positions only.
///
/// Points are stored as `f32` offsets in a [`Frame`]: position = origin + scale x offset,
/// with an `f64` origin and an exact power-of-four scale; 12 bytes per point. The
/// constructors from `f64` positions take the centre of the bounding box as origin, which
/// keeps about a 16-millionth of the cloud's extent for any real-world coordinates, and
/// scale 1; a reader of `f32` coordinates takes the origin 0 and keeps them exactly. Two
/// exceptions keep the offsets usable, each leaving ordinary clouds as just said:
///
/// - **Extent.** Offsets whose largest magnitude lies outside `[2^-30, 2^30]` are divided by
///   the power of four that brings it into `[1, 4)` (the scale). The neighbour search squares
///   `f32` differences, which overflow for clouds of about `1e19` and beyond and lose digits
///   in subnormals for clouds of about `1e-20` and below; the features are scale-invariant,
///   and scaling by a power of four is exact for every operation they use, square roots
///   included, so a cloud scaled by `4^k` gets features bit for bit equal to the cloud's.
/// - **Far outliers.** When a few points lie so far away that the bounding box is more than
///   2^10 times larger than the bulk of the points (their eighth to seventh-eighth ranks per
///   axis, on a fixed sample of at most 4096 points), the origin is the centre of the
///   bounding box of the bulk and its surroundings (those ranks widened by their spread on
///   each side) instead: the bulk keeps the offsets it has without the outliers, which lose
///   at most one bit of the precision they had.
///
/// [`points`](Self::points) are the offsets; [`position_f64`](Self::position_f64) gives
/// back the absolute positions. Positions are told apart by their offsets: points closer
/// than the cloud's `f32` resolution (about 2^-24 of their distance from the origin, in
/// absolute units) are one position to the neighbour search and to [`crate::Distinct`].
/// Two clouds are equal when every point has the same absolute position, whatever their
/// frames.
#[derive(Debug, Clone)]
pub struct PointCloud {
    frame: Frame,
    points: Vec<[f32; 3]>,
}

/// Where the `f32` offsets of a [`PointCloud`] are measured from: position = `origin` +
/// `scale` x offset, `scale` a power of four (1 for ordinary clouds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// The position of offset 0.
    pub origin: [f64; 3],
    /// The length of a unit offset.
    pub scale: f64,
}

/// Largest offset magnitudes in this range are kept as they are (scale 1).
const SAFE: std::ops::RangeInclusive<f64> = (1.0 / (1u64 << 30) as f64)..=(1u64 << 30) as f64;

/// The bounding box is "much larger" than the bulk of the points beyond this ratio.
const FAR: f64 = 1024.0;

/// Points sampled to find the bulk.
const SAMPLE: usize = 4096;

impl Frame {
    /// The frame of the `len` finite positions `position(i)` whose bounding box has the
    /// corners `lo`, `hi` (either way round per axis): the origin and scale the
    /// [`PointCloud`] constructors take (see there).
    pub fn of(
        lo: [f64; 3],
        hi: [f64; 3],
        len: usize,
        position: impl Fn(usize) -> [f64; 3] + Sync,
    ) -> Self {
        let (lo, hi) = (
            std::array::from_fn(|a| lo[a].min(hi[a])),
            std::array::from_fn(|a| lo[a].max(hi[a])),
        );
        let Some((inner_lo, inner_hi)) = bulk(lo, hi, len, &position) else {
            return Self::of_bounds(lo, hi);
        };
        let (bulk_lo, bulk_hi) = (0..len)
            .into_par_iter()
            .map(&position)
            .filter(|p| (0..3).all(|a| (inner_lo[a]..=inner_hi[a]).contains(&p[a])))
            .map(|p| (p, p))
            .reduce(
                || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |(l0, h0), (l1, h1)| {
                    (
                        std::array::from_fn(|a| l0[a].min(l1[a])),
                        std::array::from_fn(|a| h0[a].max(h1[a])),
                    )
                },
            );
        Self::centred(centre(bulk_lo, bulk_hi), lo, hi)
    }

    /// The frame [`Frame::of`] gives positions with the bounding box `lo`..`hi` (either way
    /// round per axis) and no far outliers, from the box alone: the box's centre and the
    /// scale of its extent. Parts of a cloud (the tiles of a survey) built in the frame of
    /// the whole cloud's box get the offsets the whole cloud has.
    pub fn of_bounds(lo: [f64; 3], hi: [f64; 3]) -> Self {
        let (lo, hi) = (
            std::array::from_fn(|a| lo[a].min(hi[a])),
            std::array::from_fn(|a| lo[a].max(hi[a])),
        );
        Self::centred(centre(lo, hi), lo, hi)
    }

    /// The frame at `origin` of positions within `lo`..`hi` (ordered).
    fn centred(origin: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Self {
        // Half the largest distance from the origin along an axis (halves cannot overflow).
        let half_reach = (0..3)
            .map(|a| (0.5 * hi[a] - 0.5 * origin[a]).max(0.5 * origin[a] - 0.5 * lo[a]))
            .fold(0.0, f64::max);
        Self {
            origin,
            scale: scale_for(half_reach),
        }
    }

    /// The offset of the absolute position `p`.
    pub fn local(&self, p: [f64; 3]) -> [f32; 3] {
        // Divided first, so that no difference overflows; exact for scale 1.
        std::array::from_fn(|a| (p[a] / self.scale - self.origin[a] / self.scale) as f32)
    }

    /// The absolute position of the offset `q`.
    pub fn absolute(&self, q: [f32; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.origin[a] + self.scale * f64::from(q[a]))
    }
}

/// The centre of the box `lo`..`hi`, halved first so that it cannot overflow (the same as
/// `0.5 * (lo + hi)` otherwise: halving is exact).
fn centre(lo: [f64; 3], hi: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|a| 0.5 * lo[a] + 0.5 * hi[a])
}

/// The box of the bulk of the positions and its surroundings, when the bounding box `lo`..`hi`
/// is more than [`FAR`] times larger: the eighth and seventh-eighth ranks of a fixed sample
/// per axis, widened on each side by the largest spread between them.
fn bulk(
    lo: [f64; 3],
    hi: [f64; 3],
    len: usize,
    position: &(impl Fn(usize) -> [f64; 3] + Sync),
) -> Option<([f64; 3], [f64; 3])> {
    let m = len.min(SAMPLE);
    if m == 0 {
        return None;
    }
    let sample: Vec<[f64; 3]> = (0..m).map(|j| position(j * len / m)).collect();
    let mut ranks = [[0.0; 2]; 3];
    let mut axis = vec![0.0; m];
    for (a, rank) in ranks.iter_mut().enumerate() {
        for (v, p) in axis.iter_mut().zip(&sample) {
            *v = p[a];
        }
        axis.sort_unstable_by(f64::total_cmp);
        *rank = [axis[m / 8], axis[m - 1 - m / 8]];
    }
    let spread = ranks.iter().map(|[l, h]| h - l).fold(0.0, f64::max);
    let inner_lo = ranks.map(|[l, _]| l - spread);
    let inner_hi = ranks.map(|[_, h]| h + spread);
    let inside = (0..3).all(|a| inner_lo[a] <= lo[a] && hi[a] <= inner_hi[a]);
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    (!inside && extent > FAR * spread).then_some((inner_lo, inner_hi))
}

/// The scale of offsets whose largest magnitude is `2 * half` (halves cannot overflow): 1
/// when that lies in [`SAFE`] (or is 0), else the power of four that brings it into `[1, 4)`.
fn scale_for(half: f64) -> f64 {
    if half == 0.0 || !half.is_finite() || SAFE.contains(&(2.0 * half)) {
        return 1.0;
    }
    let exponent = floor_log2(half) + 1;
    power_of_two(exponent.div_euclid(2) * 2)
}

/// `floor(log2(x))` of a positive finite `x`, exactly (from its bits).
fn floor_log2(x: f64) -> i32 {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // Subnormal: x = mantissa * 2^-1074.
        63 - (bits & ((1 << 52) - 1)).leading_zeros() as i32 - 1074
    } else {
        biased - 1023
    }
}

/// `2^e`, exactly, for `e` in `-1074..=1023`.
fn power_of_two(e: i32) -> f64 {
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1 << (e + 1074))
    }
}

impl PointCloud {
    /// Builds a cloud from absolute `f64` positions, in the [`Frame`] of their bounding box.
    ///
    /// Fails on an empty slice or on any NaN / infinite coordinate.
    pub fn from_f64(positions: &[[f64; 3]]) -> Result<Self, GeomError> {
        Self::from_iter_f64(positions.len(), |i| positions[i])
    }

    /// The clouds of `parts` as one, in order (the tiles of a survey labelled together).
    ///
    /// Fails on no points at all.
    pub fn concat(parts: &[&PointCloud]) -> Result<Self, GeomError> {
        let starts: Vec<usize> = (parts.iter())
            .scan(0, |next, c| {
                let first = *next;
                *next += c.len();
                Some(first)
            })
            .collect();
        let n = parts.iter().map(|c| c.len()).sum();
        Self::from_iter_f64(n, |i| {
            let k = starts.partition_point(|&s| s <= i) - 1;
            parts[k].position_f64(i - starts[k])
        })
    }

    /// Builds a cloud from `len` absolute positions produced by `position(i)`.
    ///
    /// Lets readers hand over positions without building an intermediate `Vec`.
    pub fn from_iter_f64(
        len: usize,
        position: impl Fn(usize) -> [f64; 3] + Sync,
    ) -> Result<Self, GeomError> {
        if len == 0 {
            return Err(GeomError::Empty);
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for i in 0..len {
            let p = position(i);
            if !p.iter().all(|c| c.is_finite()) {
                return Err(GeomError::NonFinite { index: i, value: p });
            }
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let frame = Frame::of(lo, hi, len, &position);
        let points = (0..len).map(|i| frame.local(position(i))).collect();
        Self::from_frame(frame, points)
    }

    /// Builds a cloud from positions already relative to `origin` (scale 1).
    ///
    /// Fails on an empty slice or on any NaN / infinite coordinate.
    pub fn from_local(origin: [f64; 3], points: Vec<[f32; 3]>) -> Result<Self, GeomError> {
        Self::from_frame(Frame { origin, scale: 1.0 }, points)
    }

    /// Builds a cloud from offsets in `frame`, whose scale must be a power of two; the
    /// offsets are rescaled (exactly, by a power of four) if their magnitude calls for it
    /// (see the type's documentation).
    ///
    /// Fails on an empty slice or on any NaN / infinite coordinate.
    pub fn from_frame(frame: Frame, mut points: Vec<[f32; 3]>) -> Result<Self, GeomError> {
        if points.is_empty() {
            return Err(GeomError::Empty);
        }
        if let Some((index, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(GeomError::NonFinite {
                index,
                value: frame.absolute(*p),
            });
        }
        let magnitude = points
            .par_iter()
            .map(|p| p.map(f32::abs).into_iter().fold(0f32, f32::max))
            .reduce(|| 0f32, f32::max);
        let rescale = scale_for(0.5 * f64::from(magnitude));
        let mut frame = frame;
        if rescale != 1.0 {
            let inverse = 1.0 / rescale;
            points
                .par_iter_mut()
                .for_each(|p| *p = p.map(|c| (f64::from(c) * inverse) as f32));
            frame.scale *= rescale;
        }
        Ok(Self { frame, points })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud holds no points (never, for a constructed cloud).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The origin that [`points`](Self::points) are relative to.
    pub fn origin(&self) -> [f64; 3] {
        self.frame.origin
    }

    /// The length of a unit offset in [`points`](Self::points): 1 for ordinary clouds, a
    /// power of four for clouds of extreme extents (see the type's documentation).
    pub fn scale(&self) -> f64 {
        self.frame.scale
    }

    /// The origin and scale of the offsets.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// The offsets of the points from [`origin`](Self::origin), in units of
    /// [`scale`](Self::scale).
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// Absolute position of point `i`.
    pub fn position_f64(&self, i: usize) -> [f64; 3] {
        self.frame.absolute(self.points[i])
    }
}

impl PartialEq for PointCloud {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len()
            && (0..self.len()).all(|i| self.position_f64(i) == other.position_f64(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recentres_utm_coordinates_with_millimetre_precision() {
        let c =
            PointCloud::from_f64(&[[5_403_150.0, 0.0, 0.0], [5_403_150.001, 0.0, 0.0]]).unwrap();
        let d = c.points()[1][0] - c.points()[0][0];
        assert!((d - 0.001).abs() < 1e-6, "{d}");
        assert!((c.position_f64(1)[0] - 5_403_150.001).abs() < 1e-6);
    }

    #[test]
    fn concat_keeps_every_position_in_order() {
        let a = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
        let b = [[10.25, 0.5, -1.0]];
        let (ca, cb) = (
            PointCloud::from_f64(&a).unwrap(),
            PointCloud::from_f64(&b).unwrap(),
        );
        let joined = PointCloud::concat(&[&ca, &cb, &ca]).unwrap();
        let back: Vec<[f64; 3]> = (0..joined.len()).map(|i| joined.position_f64(i)).collect();
        let expected: Vec<[f64; 3]> = a.iter().chain(&b).chain(&a).copied().collect();
        for (p, q) in back.iter().zip(&expected) {
            assert!((0..3).all(|k| (p[k] - q[k]).abs() < 1e-6), "{p:?} {q:?}");
        }
        assert_eq!(back.len(), 5);
        assert!(matches!(PointCloud::concat(&[]), Err(GeomError::Empty)));
    }

    /// `n` points of the unit cube, pseudo-random.
    fn unit_cube(n: usize) -> Vec<[f64; 3]> {
        let mut next = crate::test_stream(7);
        (0..n)
            .map(|_| [0; 3].map(|_| (next() >> 11) as f64 / (1u64 << 53) as f64))
            .collect()
    }

    #[test]
    fn ordinary_clouds_keep_the_bounding_box_centre_and_scale_1() {
        let points = unit_cube(1000);
        let cloud = PointCloud::from_f64(&points).unwrap();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &points {
            for a in 0..3 {
                (lo[a], hi[a]) = (lo[a].min(p[a]), hi[a].max(p[a]));
            }
        }
        assert_eq!(cloud.origin(), [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])));
        assert_eq!(cloud.scale(), 1.0);
        for (i, p) in points.iter().enumerate() {
            assert_eq!(
                cloud.points()[i],
                [0, 1, 2].map(|a| (p[a] - cloud.origin()[a]) as f32)
            );
        }
        // The frame of the box alone is the same.
        assert_eq!(Frame::of_bounds(hi, lo), cloud.frame());
        // Clouds near the edges of the safe range of the largest offset too (about half
        // the extent here).
        for s in [2f64.powi(-28), 2f64.powi(30)] {
            let scaled: Vec<_> = points.iter().map(|p| p.map(|c| c * s)).collect();
            assert_eq!(PointCloud::from_f64(&scaled).unwrap().scale(), 1.0);
        }
    }

    #[test]
    fn extreme_extents_get_a_power_of_four_scale() {
        let points = unit_cube(100);
        // The largest offset is about half the extent: 5e38 = 1.47 x 4^64, 5e-31 = 2.5 x 4^-51.
        for (s, expected) in [(1e39, 2f64.powi(128)), (1e-30, 2f64.powi(-102))] {
            let scaled: Vec<_> = points.iter().map(|p| p.map(|c| c * s)).collect();
            let cloud = PointCloud::from_f64(&scaled).unwrap();
            assert_eq!(cloud.scale(), expected, "{s}");
            let corner = |f: fn(f64, f64) -> f64| {
                std::array::from_fn(|a| scaled.iter().map(|p| p[a]).fold(scaled[0][a], f))
            };
            assert_eq!(
                Frame::of_bounds(corner(f64::min), corner(f64::max)),
                cloud.frame()
            );
            let magnitude = (cloud.points().iter().flatten()).fold(0f32, |m, c| m.max(c.abs()));
            assert!((1.0..4.0).contains(&magnitude), "{s}: {magnitude}");
            for (i, p) in scaled.iter().enumerate() {
                let back = cloud.position_f64(i);
                assert!((0..3).all(|a| (back[a] - p[a]).abs() <= 1e-7 * s), "{s}");
            }
        }
        // f32 coordinates beyond the safe range are scaled exactly.
        let big = vec![[3e38f32, -3e38, 1e30], [1e38, 0.0, -1e38]];
        let cloud = PointCloud::from_local([0.0; 3], big.clone()).unwrap();
        assert!(cloud.scale() > 1.0);
        for (i, p) in big.iter().enumerate() {
            assert_eq!(cloud.position_f64(i), p.map(f64::from));
        }
    }

    #[test]
    fn far_outliers_leave_the_bulk_its_offsets() {
        let cube = unit_cube(5000);
        let alone = PointCloud::from_f64(&cube).unwrap();
        for outlier in [[1e7, 0.0, 0.0], [-3e9, 2e9, 1e9], [0.0, 0.0, 1e4]] {
            let mut with = cube.clone();
            with.insert(17, outlier);
            let cloud = PointCloud::from_f64(&with).unwrap();
            assert_eq!(cloud.origin(), alone.origin(), "{outlier:?}");
            // The same offsets, but for the power of four of an extent beyond 2^30 (3e9).
            let bulk: Vec<_> = (alone.points().iter())
                .map(|p| p.map(|c| (f64::from(c) / cloud.scale()) as f32))
                .collect();
            assert_eq!(&cloud.points()[..17], &bulk[..17]);
            assert_eq!(&cloud.points()[18..], &bulk[17..]);
            assert!(crate::Distinct::of(&cloud).is_none(), "no position merged");
        }
        // An outlier within 2^10 times the bulk's spread moves nothing.
        let mut near = cube.clone();
        near.push([300.0, 0.0, 0.0]);
        let lo = cube.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
        assert_eq!(
            PointCloud::from_f64(&near).unwrap().origin()[0],
            0.5 * (lo + 300.0)
        );
    }

    #[test]
    fn rejects_empty_and_non_finite() {
        assert_eq!(PointCloud::from_f64(&[]), Err(GeomError::Empty));
        let e = PointCloud::from_f64(&[[0.0; 3], [f64::NAN, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, GeomError::NonFinite { index: 1, .. }));
    }

    #[test]
    fn equal_means_the_same_absolute_positions() {
        let centred = PointCloud::from_f64(&[[0.5, 1.0, 2.0], [1.5, 3.0, 4.0]]).unwrap();
        let at_zero = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0], [1.5, 3.0, 4.0]]);
        assert_ne!(centred.origin(), at_zero.as_ref().unwrap().origin());
        assert_eq!(Ok(centred.clone()), at_zero);
        let moved = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0], [1.5, 3.0, 4.5]]);
        assert_ne!(Ok(centred.clone()), moved);
        let shorter = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0]]);
        assert_ne!(Ok(centred), shorter);
    }
}
