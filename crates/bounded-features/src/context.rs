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

/// The context of one neighbourhood. `row` holds the query point first, then its neighbours
/// by increasing distance; `probabilities` are a first classifier's (non-edge, sharp,
/// boundary) per cloud point. Returns:
/// - the mean sharp and the mean boundary probability over the neighbourhood;
/// - the distance from the query point to the sharp-probability-weighted centroid, over the
///   neighbourhood's radius (small in the middle of a band of sharp points, near 1 at its
///   rim; 1 when the neighbourhood holds almost no sharp probability);
/// - the query point's sharp probability minus the neighbourhood's mean.
///
/// Unit-free, so it does not change when the cloud is moved, rotated or scaled.
pub(crate) fn context(
    points: &[[f32; 3]],
    row: &[u32],
    probabilities: &[[f32; 3]],
) -> [f32; CONTEXT_PER_SCALE] {
    let x = points[row[0] as usize];
    let offset = |j: u32| {
        let y = points[j as usize];
        [0, 1, 2].map(|a| f64::from(y[a]) - f64::from(x[a]))
    };
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let radius = norm(offset(row[row.len() - 1]));
    let (mut sharp, mut boundary) = (0.0f64, 0.0f64);
    let mut centroid = [0.0f64; 3];
    for &j in row {
        let p = probabilities[j as usize];
        sharp += f64::from(p[1]);
        boundary += f64::from(p[2]);
        let d = offset(j);
        for a in 0..3 {
            centroid[a] += f64::from(p[1]) * d[a];
        }
    }
    let k = row.len() as f64;
    let centroid_offset = if sharp > 1e-3 && radius > 0.0 {
        norm(centroid) / (sharp * radius)
    } else {
        1.0
    };
    let own = f64::from(probabilities[row[0] as usize][1]);
    [sharp / k, boundary / k, centroid_offset, own - sharp / k].map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let c = context(&points, &[0, 1, 2, 3], &probabilities);
        // Sharp sum 1.7, boundary sum 1.0 over 4 points; weighted centroid (1, 1, 0), radius 4.
        let expected = [0.425, 0.25, 2f32.sqrt() / (1.7 * 4.0), 0.2 - 0.425];
        for (got, want) in c.iter().zip(expected) {
            assert!((got - want).abs() < 1e-6, "{c:?} vs {expected:?}");
        }
        // Only the first two neighbours (a smaller scale): radius 1, centroid (1, 0, 0).
        let c = context(&points, &[0, 1], &probabilities);
        let expected = [0.6, 0.05, 1.0 / 1.2, 0.2 - 0.6];
        for (got, want) in c.iter().zip(expected) {
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
        let c = context(&points, &[0, 1, 2, 3], &band);
        assert_eq!(c, [0.75, 0.0, 0.0, 0.25]);
        // No sharp probability anywhere: offset 1, the rim value.
        let flat = [[1.0, 0.0, 0.0]; 4];
        assert_eq!(context(&points, &[0, 1, 2, 3], &flat), [0.0, 0.0, 1.0, 0.0]);
        // A neighbourhood of the query alone stays finite.
        assert_eq!(context(&points, &[0], &band), [1.0, 0.0, 1.0, 0.0]);
    }
}
