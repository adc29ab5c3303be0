//! Context features: what a first classifier said about each neighbourhood, for a second
//! one (auto-context).
//!
//! A point's own statistics see its neighbours' positions but not whether those neighbours
//! look like edges. A second classifier that also sees, per scale, how edge-like the
//! first one found the neighbourhood and where its sharp points lie can sharpen a band of
//! probable sharp points towards its middle and drop isolated false alarms. These values per
//! scale are computed from the same sorted neighbour lists as the features.

use bounded_geom::{Sym3, dot};

/// Context values per scale of [`ContextSet::Neighbourhood`].
pub const CONTEXT_PER_SCALE: usize = 4;

/// Names of the context values of one scale of [`ContextSet::Neighbourhood`], in output order.
pub const CONTEXT_NAMES: [&str; CONTEXT_PER_SCALE] = [
    "ctx_sharp_mean",
    "ctx_boundary_mean",
    "ctx_sharp_offset",
    "ctx_sharp_excess",
];

/// Names of the values [`ContextSet::WithLine`] adds after [`CONTEXT_NAMES`], in output order.
const LINE_NAMES: [&str; 3] = ["ctx_line_linearity", "ctx_line_across", "ctx_line_along"];

/// Which context values a second stage reads per scale.
///
/// The means and the sharp centroid's offset say how much sharp probability a neighbourhood
/// holds, not whether it lies along a line nor where the point sits across that line: the
/// points of a band and those a spacing or two beside it see nearly the same means. The line
/// costs a 3x3 eigen problem per point and scale; model files name their context values, so
/// a file says which one it reads.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum ContextSet {
    /// The four values of [`CONTEXT_NAMES`].
    #[default]
    Neighbourhood,
    /// Those four, then where the sharp probability lies as a line: the linearity
    /// `(l1 - l2) / l1` of its weighted covariance, and the point's distance across and along
    /// the principal direction through its weighted centroid, over the neighbourhood's radius.
    WithLine,
}

impl ContextSet {
    /// Every context, [`ContextSet::Neighbourhood`] first.
    pub const ALL: [Self; 2] = [Self::Neighbourhood, Self::WithLine];

    /// Names of the context values of one scale, in output order.
    pub fn names(self) -> Vec<&'static str> {
        let line: &[&str] = match self {
            Self::Neighbourhood => &[],
            Self::WithLine => &LINE_NAMES,
        };
        CONTEXT_NAMES.iter().chain(line).copied().collect()
    }

    /// Number of context values per scale.
    pub fn count(self) -> usize {
        match self {
            Self::Neighbourhood => CONTEXT_PER_SCALE,
            Self::WithLine => CONTEXT_PER_SCALE + LINE_NAMES.len(),
        }
    }
}

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

/// The `context` of a point's neighbourhood at every scale. `row` holds the query point
/// first, then its neighbours by increasing distance (at least `scales[0]` of them); `scales`
/// are neighbour counts, strictly descending, each neighbourhood a prefix of `row`;
/// `first` gives each cloud point's position and first-stage result.
/// Calls `put(scale index, values)` with, per scale:
/// - the mean sharp and the mean boundary probability over the neighbourhood;
/// - the distance from the query point to the sharp-probability-weighted centroid, over the
///   neighbourhood's radius (small in the middle of a band of sharp points, near 1 at its
///   rim; 1 when the neighbourhood holds almost no sharp probability);
/// - the query point's sharp probability minus the neighbourhood's mean;
/// - for [`ContextSet::WithLine`], of the sharp-probability-weighted covariance about that
///   centroid: its linearity `(l1 - l2) / l1` (0 when it is zero), and the query point's
///   distance across and (unsigned) along the principal direction through the centroid,
///   over the radius (0, 1 and 0, as far from any sharp point, when the neighbourhood holds
///   almost no sharp probability).
///
/// One pass over the largest neighbourhood serves every scale: the sums run from the query
/// point outwards and are read off as each smaller prefix ends. Unit-free, so it does not
/// change when the cloud is moved, rotated or scaled.
pub(crate) fn contexts(
    row: &[u32],
    scales: &[usize],
    context: ContextSet,
    first: &impl FirstResults,
    mut put: impl FnMut(usize, &[f32]),
) {
    let line = context == ContextSet::WithLine;
    let (x, [own, _]) = first.read(row[0]);
    let offset = |y: [f32; 3]| [0, 1, 2].map(|a| f64::from(y[a]) - f64::from(x[a]));
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let own = f64::from(own);
    let (mut sharp, mut boundary) = (0.0f64, 0.0f64);
    let mut centroid = [0.0f64; 3];
    // The sharp-weighted second moments about the query point, for the line.
    let mut moments = Sym3::default();
    let mut summed = 0;
    let mut values = [0f32; CONTEXT_PER_SCALE + LINE_NAMES.len()];
    // Smallest scale first, so each prefix extends the last.
    for (scale, &k) in scales.iter().enumerate().rev() {
        for &j in &row[summed..k] {
            let (y, sb) = first.read(j);
            let [s, b] = sb.map(f64::from);
            sharp += s;
            boundary += b;
            let d = offset(y);
            let sd = d.map(|v| s * v);
            for a in 0..3 {
                centroid[a] += sd[a];
            }
            if line {
                moments.add_weighted_outer(s, d);
            }
        }
        summed = k;
        let radius = norm(offset(first.read(row[k - 1]).0));
        let weighted = sharp > 1e-3 && radius > 0.0;
        let centroid_offset = if weighted {
            norm(centroid) / (sharp * radius)
        } else {
            1.0
        };
        let n = k as f64;
        let means = [sharp / n, boundary / n, centroid_offset, own - sharp / n];
        values[..CONTEXT_PER_SCALE].copy_from_slice(&means.map(|v| v as f32));
        if line {
            let geometry = if weighted {
                line_geometry(&moments, centroid.map(|v| v / sharp), sharp, radius)
            } else {
                [0.0, 1.0, 0.0]
            };
            values[CONTEXT_PER_SCALE..].copy_from_slice(&geometry.map(|v| v as f32));
        }
        put(scale, &values[..context.count()]);
    }
}

/// Linearity, distance across and distance along of [`ContextSet::WithLine`], from the
/// sharp-weighted second `moments` about the query point, the weighted `centroid` relative
/// to it, the weights' sum and the neighbourhood's radius (both positive).
fn line_geometry(moments: &Sym3, centroid: [f64; 3], weight: f64, radius: f64) -> [f64; 3] {
    let c = centroid;
    let covariance = Sym3 {
        xx: moments.xx / weight - c[0] * c[0],
        xy: moments.xy / weight - c[0] * c[1],
        xz: moments.xz / weight - c[0] * c[2],
        yy: moments.yy / weight - c[1] * c[1],
        yz: moments.yz / weight - c[1] * c[2],
        zz: moments.zz / weight - c[2] * c[2],
    };
    let values = covariance.eigenvalues();
    let linearity = if values[0] > 0.0 {
        ((values[0] - values[1]) / values[0]).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let direction = covariance.largest_vector(values);
    // The query point is the origin: its offset from the centroid is -c.
    let along = -dot(c, direction);
    let across = [0, 1, 2].map(|a| -c[a] - along * direction[a]);
    [
        linearity,
        dot(across, across).sqrt() / radius,
        along.abs() / radius,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `context` at each of `scales`, in `scales` order.
    fn context_at(
        context: ContextSet,
        points: &[[f32; 3]],
        row: &[u32],
        scales: &[usize],
        probabilities: &[[f32; 3]],
    ) -> Vec<Vec<f32>> {
        let mut out = vec![Vec::new(); scales.len()];
        let order: Vec<u32> = (0..points.len() as u32).collect();
        let first = Probabilities {
            points,
            order: &order,
            first: probabilities,
        };
        contexts(row, scales, context, &first, |s, values| {
            out[s] = values.to_vec()
        });
        out
    }

    /// The [`ContextSet::Neighbourhood`] at each of `scales`, in `scales` order.
    fn at_scales(
        points: &[[f32; 3]],
        row: &[u32],
        scales: &[usize],
        probabilities: &[[f32; 3]],
    ) -> Vec<[f32; CONTEXT_PER_SCALE]> {
        let all = context_at(
            ContextSet::Neighbourhood,
            points,
            row,
            scales,
            probabilities,
        );
        all.into_iter().map(|v| v.try_into().unwrap()).collect()
    }

    /// The line values of [`ContextSet::WithLine`] of the whole `row` as one scale.
    fn line(points: &[[f32; 3]], probabilities: &[[f32; 3]]) -> Vec<f32> {
        let row: Vec<u32> = (0..points.len() as u32).collect();
        let all = context_at(
            ContextSet::WithLine,
            points,
            &row,
            &[row.len()],
            probabilities,
        );
        // The first four are those of the neighbourhood context, unchanged.
        let plain = at_scales(points, &row, &[row.len()], probabilities);
        assert_eq!(all[0][..CONTEXT_PER_SCALE], plain[0]);
        all[0][CONTEXT_PER_SCALE..].to_vec()
    }

    const SHARP: [f32; 3] = [0.0, 1.0, 0.0];
    const FLAT: [f32; 3] = [1.0, 0.0, 0.0];

    #[test]
    fn line_beside_along_and_without_a_band() {
        // A point one unit beside a straight band x = -2..2 (weights 1), the radius 2 (the
        // last neighbour, not sharp): centroid (0, -1, 0) from it, covariance diag(2, 0, 0),
        // linearity 1, across 1 / 2, along 0.
        let beside = [
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [-2.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
        ];
        let p = [FLAT, SHARP, SHARP, SHARP, SHARP, SHARP, FLAT];
        assert_eq!(line(&beside, &p), [1.0, 0.5, 0.0]);
        // At the band's end: offsets 0, -1, .., -4 along x, centroid (-2, 0, 0), variance
        // 6 - 4 = 2 along x, the radius 4: linearity 1, across 0, along 2 / 4.
        let end: Vec<[f32; 3]> = (0..5).map(|i| [2.0 - i as f32, 0.0, 0.0]).collect();
        assert_eq!(line(&end, &[SHARP; 5]), [1.0, 0.0, 0.5]);
        // Sharp points around the query as a cross: covariance diag(1/2, 1/2, 0), the
        // centroid at the query: linearity 0, across and along 0.
        let cross = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
        ];
        assert_eq!(line(&cross, &[FLAT, SHARP, SHARP, SHARP, SHARP]), [0.0; 3]);
        // No sharp probability: as far from any line.
        assert_eq!(line(&cross, &[FLAT; 5]), [0.0, 1.0, 0.0]);
        // A neighbourhood of the query alone stays finite.
        assert_eq!(line(&cross[..1], &[SHARP]), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn line_is_invariant_under_motion_and_scale() {
        let mut stream = bounded_geom::uniform_stream(5);
        let mut r = move || stream() as f32;
        let points: Vec<[f32; 3]> = (0..40).map(|_| [r(), r(), 0.2 * r()]).collect();
        let probabilities: Vec<[f32; 3]> = (0..40)
            .map(|_| {
                let s = r();
                [1.0 - s, s, 0.0]
            })
            .collect();
        // Rotated about z by 30 degrees, about x by 90, scaled by 7 and moved.
        let (sin, cos) = (0.5f32, 0.75f32.sqrt());
        let moved: Vec<[f32; 3]> = (points.iter())
            .map(|&[x, y, z]| {
                let (x, y) = (cos * x - sin * y, sin * x + cos * y);
                let (y, z) = (-z, y);
                [7.0 * x + 100.0, 7.0 * y - 30.0, 7.0 * z + 5.0]
            })
            .collect();
        let row: Vec<u32> = (0..40).collect();
        let scales = [40, 20, 10];
        let a = context_at(ContextSet::WithLine, &points, &row, &scales, &probabilities);
        let b = context_at(ContextSet::WithLine, &moved, &row, &scales, &probabilities);
        for (a, b) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!(a.is_finite() && (a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }

    #[test]
    fn names_match_counts() {
        for c in ContextSet::ALL {
            assert_eq!(c.names().len(), c.count());
        }
        assert_eq!(ContextSet::default().names(), CONTEXT_NAMES);
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
