//! The statistics of one point's nested neighbourhoods (SPEC.md, "Features").

use bounded_geom::{Sym3, dot};

use crate::FeatureConfig;

/// Values per scale with every group on (see `config::NAMES`).
pub(crate) const ALL_FEATURES: usize = 15;

/// Per-thread buffers, reused from point to point so the hot loop never allocates.
pub(crate) struct Scratch {
    /// One moment row per neighbour (see [`Row`]).
    rows: Vec<Row>,
    /// Buffers of the normal's half-neighbourhood selection.
    half: HalfScratch,
    /// Moments of each scale's neighbourhood, smallest scale first.
    prefix: Vec<Moments>,
}

impl Scratch {
    pub(crate) fn new(k0: usize) -> Self {
        Self {
            rows: Vec::with_capacity(k0),
            half: HalfScratch::default(),
            prefix: Vec::new(),
        }
    }
}

/// Squared distances to a centroid (as `f64` bits), by rank and as selected.
#[derive(Default)]
struct HalfScratch {
    by_rank: Vec<u64>,
    selected: Vec<u64>,
}

/// Lanes of a moment row: `x, y, z`, then `xx, xy, xz, yy, yz, zz`, then the count.
const LANES: usize = 10;
/// Lane of the first product (`xx`).
const OUTER: usize = 3;
/// Lane of the count.
const COUNT: usize = 9;

/// A neighbour relative to the query point, in `f64`, with its products precomputed:
/// every set's moments are then plain lane-wise sums, which the compiler vectorises,
/// and the products are computed once per neighbour instead of once per set.
#[derive(Clone, Copy)]
struct Row([f64; LANES]);

impl Row {
    fn new(q: [f64; 3]) -> Self {
        let [x, y, z] = q;
        Self([x, y, z, x * x, x * y, x * z, y * y, y * z, z * z, 1.0])
    }

    fn point(&self) -> [f64; 3] {
        [self.0[0], self.0[1], self.0[2]]
    }
}

/// Count, sum and sum of outer products of points (relative to the query point, so
/// the one-pass covariance loses only ~1e-16 of the neighbourhood's squared radius),
/// as a sum of [`Row`]s.
#[derive(Clone, Copy, Default)]
struct Moments([f64; LANES]);

impl Moments {
    fn add(&mut self, row: &Row) {
        for (m, r) in self.0.iter_mut().zip(row.0) {
            *m += r;
        }
    }

    /// Adds `row` when `keep`; otherwise adds +0.0, which leaves every sum unchanged
    /// (sums start at +0.0 and so never become -0.0). Branch-free: the U / L split
    /// is unpredictable.
    fn add_if(&mut self, row: &Row, keep: bool) {
        for (m, r) in self.0.iter_mut().zip(row.0) {
            *m += if keep { r } else { 0.0 };
        }
    }

    fn count(&self) -> f64 {
        self.0[COUNT]
    }

    /// The moments of the points in `self` but not in `part`.
    fn minus(&self, part: &Self) -> Self {
        Self(std::array::from_fn(|i| self.0[i] - part.0[i]))
    }

    /// Mean (zero for no points).
    fn mean(&self) -> [f64; 3] {
        let n = self.count().max(1.0);
        [0, 1, 2].map(|a| self.0[a] / n)
    }

    /// Population covariance (divided by the count).
    fn covariance(&self) -> Sym3 {
        let inv = 1.0 / self.count().max(1.0);
        let m = self.mean();
        let o = &self.0[OUTER..OUTER + 6];
        Sym3 {
            xx: o[0] * inv - m[0] * m[0],
            xy: o[1] * inv - m[0] * m[1],
            xz: o[2] * inv - m[0] * m[2],
            yy: o[3] * inv - m[1] * m[1],
            yz: o[4] * inv - m[1] * m[2],
            zz: o[5] * inv - m[2] * m[2],
        }
    }

    /// Eigenvalues of the covariance, descending, clamped at 0; zeros below 2 points.
    fn variances(&self) -> [f64; 3] {
        if self.count() < 2.0 {
            return [0.0; 3];
        }
        self.covariance().eigenvalues().map(|v| v.max(0.0))
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
    scratch.rows.clear();
    scratch.rows.extend(neighbours.iter().map(|&j| {
        let q = points[j as usize];
        Row::new([0, 1, 2].map(|a| f64::from(q[a]) - p[a]))
    }));
    let rows = &scratch.rows;
    // Moments of every scale from one pass: scales are prefixes, smallest first.
    scratch.prefix.clear();
    let mut running = Moments::default();
    let mut done = 0;
    for &k in config.scales.iter().rev() {
        rows[done..k].iter().for_each(|r| running.add(r));
        done = k;
        scratch.prefix.push(running);
    }
    let mut largest: Option<(Moments, Frame)> = None;
    let per_scale = config.features_per_scale();
    let scales = config.scales.iter().zip(scratch.prefix.iter().rev());
    for ((&k, &moments), out) in scales.zip(out.chunks_exact_mut(per_scale)) {
        let frame = frame(&rows[..k], &moments, &mut scratch.half);
        let mut all = scale_features(&rows[..k], &moments, &frame);
        if let Some((m0, f0)) = &largest {
            // c: this scale's centroid against the rest of the k0 neighbourhood,
            // in the k0 frame.
            let rest = m0.minus(&moments).mean();
            let c = [0, 1, 2].map(|a| (frame.mean[a] - rest[a]) * f0.scale);
            [all[13], all[14]] = split(c, f0.normal);
        }
        for (o, i) in out.iter_mut().zip(config.groups.selected()) {
            *o = all[i] as f32;
        }
        largest.get_or_insert((moments, frame));
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

/// Centroid, normalisation and oriented normal of `pts` (relative to the query point,
/// which is therefore the origin), whose moments are `moments`.
fn frame(rows: &[Row], moments: &Moments, scratch: &mut HalfScratch) -> Frame {
    let m = moments.mean();
    let variances = moments.variances();
    let scale = 2.0 / (variances[0].sqrt() + variances[1].sqrt());
    let scale = if scale.is_finite() { scale } else { 1.0 };
    // Normal from the floor(k/2) points closest to the centroid: robust to outliers.
    let half = rows.len() / 2;
    let raw = if half == 0 {
        [0.0, 0.0, 1.0]
    } else {
        closest(rows, m, half, scratch)
            .covariance()
            .eigen()
            .smallest_vector
    };
    Frame {
        mean: m,
        scale,
        normal: orient(raw, m.map(|c| -c)),
        variances,
    }
}

/// Moments of the `half` rows closest to `m`, ties by rank, summed in rank order.
///
/// Selecting plain `u64` keys (non-negative `f64` bits order like the values) only
/// to find the `half`-th distance, then one branch-free pass in rank order, beats
/// selecting (distance, rank) pairs and gathering the winners.
fn closest(rows: &[Row], m: [f64; 3], half: usize, scratch: &mut HalfScratch) -> Moments {
    let dists = &mut scratch.by_rank;
    dists.clear();
    dists.extend(rows.iter().map(|r| dist2(r.point(), m).to_bits()));
    let keys = &mut scratch.selected;
    keys.clone_from(dists);
    let cut = *keys.select_nth_unstable(half - 1).1;
    // Rows closer than `cut` are in; rows at `cut` fill the remaining places.
    let mut ties = half - dists.iter().filter(|&&d| d < cut).count();
    let mut moments = Moments::default();
    for (r, &d) in rows.iter().zip(dists.iter()) {
        let tie = d == cut && ties > 0;
        ties -= usize::from(tie);
        moments.add_if(r, d < cut || tie);
    }
    moments
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

/// The 15 values of one scale (all groups, `c` left at 0) in the normalised frame.
///
/// U holds the points with `<p - m, n> >= 0` (the sign of `<p^, n>`, as the scale
/// factor is positive); L the rest, whose moments are the whole set's minus U's.
fn scale_features(rows: &[Row], moments: &Moments, f: &Frame) -> [f64; ALL_FEATURES] {
    let mut all = [0.0; ALL_FEATURES];
    let s2 = f.scale * f.scale;
    all[..3].copy_from_slice(&f.variances.map(|v| v * s2));
    // <q - m, n> >= 0  <=>  <q, n> >= <m, n>
    let threshold = dot(f.mean, f.normal);
    let mut upper = Moments::default();
    for r in rows {
        upper.add_if(r, dot(r.point(), f.normal) >= threshold);
    }
    let lower = moments.minus(&upper);
    all[3..6].copy_from_slice(&upper.variances().map(|v| v * s2));
    all[6..9].copy_from_slice(&lower.variances().map(|v| v * s2));
    if upper.count() > 0.0 && lower.count() > 0.0 {
        let (mu, ml) = (upper.mean(), lower.mean());
        [all[9], all[10]] = split([0, 1, 2].map(|a| (mu[a] - ml[a]) * f.scale), f.normal);
    }
    // The query point is the origin of `rows`.
    [all[11], all[12]] = split(f.mean.map(|c| -c * f.scale), f.normal);
    all
}

/// Components of `v` along the unit vector `n` and the length of the rest.
fn split(v: [f64; 3], n: [f64; 3]) -> [f64; 2] {
    let along = dot(v, n);
    let rest = [0, 1, 2].map(|a| v[a] - along * n[a]);
    [along, dot(rest, rest).sqrt()]
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    dot(d, d)
}

#[cfg(test)]
mod tests {
    use super::*;

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
