//! Polylines cut into short pieces and bucketed, for distance queries near them: which
//! points lie within a band of a crease or border, and how far a point is from a curve.

use super::grid::Grid;
use super::mesh::Polyline;
use super::vec3::{V3, add, dot, lerp, norm, scale, segment_distance, sub};

/// Polylines cut into pieces no longer than the query radius, bucketed by their midpoints.
pub(crate) struct SegmentIndex {
    grid: Grid,
    pieces: Vec<(V3, V3)>,
}

/// The point of a polyline nearest to a query point.
pub(crate) struct Nearest {
    /// Distance from the query point.
    pub(crate) distance: f64,
    /// The nearest point itself.
    pub(crate) point: V3,
    /// The direction of the piece it lies on (not normalised).
    pub(crate) direction: V3,
}

impl SegmentIndex {
    /// An index answering distance queries up to `max_radius` around the box `box_`.
    pub(crate) fn new(lines: &[Polyline], max_radius: f64, box_: [V3; 2]) -> Self {
        // A point within max_radius of a piece is within 1.5 max_radius of its midpoint.
        let mut grid = Grid::new(2.0 * max_radius, box_);
        let mut pieces = Vec::new();
        for (a, b) in lines.iter().flat_map(Polyline::segments) {
            let k = (norm(sub(b, a)) / max_radius).ceil().max(1.0) as usize;
            for j in 0..k {
                let (u, v) = (
                    lerp(a, b, j as f64 / k as f64),
                    lerp(a, b, (j + 1) as f64 / k as f64),
                );
                grid.insert(lerp(u, v, 0.5));
                pieces.push((u, v));
            }
        }
        Self { grid, pieces }
    }

    /// True when a piece passes closer than `r` to `p`.
    pub(crate) fn within(&self, p: V3, r: f64) -> bool {
        self.grid.search_near(p, |i, _| {
            let (a, b) = self.pieces[i as usize];
            segment_distance(p, a, b) < r
        })
    }

    /// The nearest point of the polylines to `p` if one lies within `r` (at most the
    /// index's `max_radius`); of equally near pieces, the first inserted.
    pub(crate) fn nearest(&self, p: V3, r: f64) -> Option<Nearest> {
        let mut best: Option<(f64, u32)> = None;
        self.grid.for_each_near(p, |i, _| {
            let (a, b) = self.pieces[i as usize];
            let d = segment_distance(p, a, b);
            if d <= r && best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                best = Some((d, i));
            }
        });
        best.map(|(distance, i)| {
            let (a, b) = self.pieces[i as usize];
            let ab = sub(b, a);
            let len2 = dot(ab, ab);
            let t = if len2 > 0.0 {
                (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            Nearest {
                distance,
                point: add(a, scale(ab, t)),
                direction: ab,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_finds_the_closest_piece_within_the_radius() {
        let line = Polyline {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            closed: false,
        };
        let index = SegmentIndex::new(&[line], 0.3, [[-1.0; 3], [2.0; 3]]);
        let n = index.nearest([0.5, 0.2, 0.0], 0.3).unwrap();
        assert!((n.distance - 0.2).abs() < 1e-12);
        assert_eq!(n.point, [0.5, 0.0, 0.0]);
        assert!(n.direction[0] > 0.0 && n.direction[1] == 0.0);
        let n = index.nearest([1.1, 0.6, 0.0], 0.3).unwrap();
        assert!((n.distance - 0.1).abs() < 1e-12);
        assert!(index.nearest([0.5, 0.35, 0.0], 0.3).is_none());
        assert!(index.within([0.5, 0.25, 0.0], 0.3));
        assert!(!index.within([0.5, 0.25, 0.0], 0.2));
    }
}
