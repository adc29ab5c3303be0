//! Context features: what a first classifier said about each neighbourhood, for a second
//! one (auto-context).
//!
//! A point's own statistics see its neighbours' positions but not whether those neighbours
//! look like edges. A second classifier that also sees, per scale, how edge-like the
//! first one found the neighbourhood and where its sharp points lie can sharpen a band of
//! probable sharp points towards its middle and drop isolated false alarms. These four
//! values per scale are computed from the same sorted neighbour lists as the features.

/// Context values per scale.
pub const CONTEXT_PER_SCALE: usize = 4;

/// Names of the context values of one scale, in output order.
pub const CONTEXT_NAMES: [&str; CONTEXT_PER_SCALE] = [
    "ctx_sharp_mean",
    "ctx_boundary_mean",
    "ctx_sharp_offset",
    "ctx_sharp_excess",
];

/// What the context reads of a first classifier's results.
pub(crate) trait FirstResults: Sync {
    /// The position of cloud point `j` and its sharp and boundary probabilities.
    fn read(&self, j: u32) -> ([f32; 3], [f32; 2]);
}

/// A first classifier's probabilities (non-edge, sharp, boundary) per cloud point, as callers
/// give them, read by position in an index's Morton order: `points` and `order` by
/// position (as [`KnnIndex::points`](bounded_geom::KnnIndex::points) and
/// [`KnnIndex::order`](bounded_geom::KnnIndex::order)), `first` by cloud index.
pub(crate) struct Probabilities<'a> {
    pub(crate) points: &'a [[f32; 3]],
    pub(crate) order: &'a [u32],
    pub(crate) first: &'a [[f32; 3]],
}

impl FirstResults for Probabilities<'_> {
    fn read(&self, j: u32) -> ([f32; 3], [f32; 2]) {
        let p = self.first[self.order[j as usize] as usize];
        (self.points[j as usize], [p[1], p[2]])
    }
}

/// The context of a point's neighbourhood at every scale. `row` holds the query point first,
/// then its neighbours by increasing distance (at least `scales[0]` of them); `scales` are
/// neighbour counts, strictly descending, each neighbourhood a prefix of `row`;
/// `first` gives each cloud point's position and first-stage result.
/// Calls `put(scale index, values)` with, per scale:
/// - the mean sharp and the mean boundary probability over the neighbourhood;
/// - the distance from the query point to the sharp-probability-weighted centroid, over the
///   neighbourhood's radius (small in the middle of a band of sharp points, near 1 at its
///   rim; 1 when the neighbourhood holds almost no sharp probability);
/// - the query point's sharp probability minus the neighbourhood's mean.
///
/// One pass over the largest neighbourhood serves every scale: the sums run from the query
/// point outwards and are read off as each smaller prefix ends. Unit-free, so it does not
/// change when the cloud is moved, rotated or scaled.
pub(crate) fn contexts(
    row: &[u32],
    scales: &[usize],
    first: &impl FirstResults,
    mut put: impl FnMut(usize, [f32; CONTEXT_PER_SCALE]),
) {
    let (x, [own, _]) = first.read(row[0]);
    let offset = |y: [f32; 3]| [0, 1, 2].map(|a| f64::from(y[a]) - f64::from(x[a]));
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let own = f64::from(own);
    let (mut sharp, mut boundary) = (0.0f64, 0.0f64);
    let mut centroid = [0.0f64; 3];
    let mut summed = 0;
    // Smallest scale first, so each prefix extends the last.
    for (scale, &k) in scales.iter().enumerate().rev() {
        for &j in &row[summed..k] {
            let (y, sb) = first.read(j);
            let [s, b] = sb.map(f64::from);
            sharp += s;
            boundary += b;
            let d = offset(y);
            for a in 0..3 {
                centroid[a] += s * d[a];
            }
        }
        summed = k;
        let radius = norm(offset(first.read(row[k - 1]).0));
        let centroid_offset = if sharp > 1e-3 && radius > 0.0 {
            norm(centroid) / (sharp * radius)
        } else {
            1.0
        };
        let n = k as f64;
        put(
            scale,
            [sharp / n, boundary / n, centroid_offset, own - sharp / n].map(|v| v as f32),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The context at each of `scales`, in `scales` order.
    fn at_scales(
        points: &[[f32; 3]],
        row: &[u32],
        scales: &[usize],
        probabilities: &[[f32; 3]],
    ) -> Vec<[f32; CONTEXT_PER_SCALE]> {
        let mut out = vec![[f32::NAN; CONTEXT_PER_SCALE]; scales.len()];
        let order: Vec<u32> = (0..points.len() as u32).collect();
        let first = Probabilities {
            points,
            order: &order,
            first: probabilities,
        };
        contexts(row, scales, &first, |s, values| out[s] = values);
        out
    }

    #[test]
    fn hand_computed_neighbourhood() {
        // Query at the origin, neighbours at distances 1, 2 and 4.
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 4.0],
        ];
        let probabilities = [
            [0.7, 0.2, 0.1],
            [0.0, 1.0, 0.0],
            [0.2, 0.5, 0.3],
            [0.4, 0.0, 0.6],
        ];
        let c = at_scales(&points, &[0, 1, 2, 3], &[4, 2], &probabilities);
        let expected = [
            // All four: sharp sum 1.7, boundary sum 1.0; weighted centroid (1, 1, 0), radius 4.
            [0.425, 0.25, 2f32.sqrt() / (1.7 * 4.0), 0.2 - 0.425],
            // The first two (the smaller scale): radius 1, centroid (1, 0, 0).
            [0.6, 0.05, 1.0 / 1.2, 0.2 - 0.6],
        ];
        for (got, want) in c.iter().flatten().zip(expected.iter().flatten()) {
            assert!((got - want).abs() < 1e-6, "{c:?} vs {expected:?}");
        }
    }

    #[test]
    fn centred_in_a_band_and_without_sharp_points() {
        // A row of sharp points through the query: the weighted centroid is the query.
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
        ];
        let band = [
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
        ];
        let row = [0, 1, 2, 3];
        assert_eq!(
            at_scales(&points, &row, &[4], &band),
            [[0.75, 0.0, 0.0, 0.25]]
        );
        // No sharp probability anywhere: offset 1, the rim value.
        let flat = [[1.0, 0.0, 0.0]; 4];
        assert_eq!(
            at_scales(&points, &row, &[4], &flat),
            [[0.0, 0.0, 1.0, 0.0]]
        );
        // A neighbourhood of the query alone stays finite.
        assert_eq!(
            at_scales(&points, &row, &[1], &band),
            [[1.0, 0.0, 1.0, 0.0]]
        );
    }
}
