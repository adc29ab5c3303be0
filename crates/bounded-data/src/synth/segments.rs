//! Polylines cut into short pieces and bucketed, for distance queries near them: which
//! points lie within a band of a crease or border, and how far a point is from a curve.

use super::grid::{Grid, bounds};
use super::mesh::Polyline;
use bounded_geom::vec3::{V3, lerp, norm, segment_distance, segment_parameter, sub};

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
}

/// A polyline's segments in a tree of bounding boxes over runs of consecutive segments:
/// the nearest point within any radius in about logarithmic time (a grid would visit every
/// piece within a wide radius).
pub(crate) struct CurveTree {
    points: Vec<V3>,
    nodes: Vec<Node>,
}

/// Segments `lo..hi` (segment `i` joins points `i` and `i + 1`, wrapping on a loop), their
/// box, and the node's children unless it is a leaf.
struct Node {
    box_: [V3; 2],
    lo: u32,
    hi: u32,
    children: Option<[u32; 2]>,
}

/// Leaves hold at most this many segments.
const LEAF: usize = 8;

impl CurveTree {
    pub(crate) fn new(line: &Polyline) -> Self {
        let mut tree = Self {
            points: line.points.clone(),
            nodes: Vec::new(),
        };
        let count = line.segments().count();
        if count > 0 {
            tree.build(0, count);
        }
        tree
    }

    fn segment(&self, i: usize) -> (V3, V3) {
        (self.points[i], self.points[(i + 1) % self.points.len()])
    }

    /// Adds the node of segments `lo..hi` (and its subtree), returning its index.
    fn build(&mut self, lo: usize, hi: usize) -> u32 {
        let box_ = bounds((lo..hi).flat_map(|i| {
            let (a, b) = self.segment(i);
            [a, b]
        }));
        let index = self.nodes.len() as u32;
        self.nodes.push(Node {
            box_,
            lo: lo as u32,
            hi: hi as u32,
            children: None,
        });
        if hi - lo > LEAF {
            let mid = (lo + hi) / 2;
            let left = self.build(lo, mid);
            let right = self.build(mid, hi);
            self.nodes[index as usize].children = Some([left, right]);
        }
        index
    }

    /// The nearest point of the polyline to `p` if one lies within `r`.
    pub(crate) fn nearest(&self, p: V3, r: f64) -> Option<Nearest> {
        let mut best: Option<(f64, usize)> = None;
        let mut reach = r;
        // Depth-first: a balanced tree of u32-indexed segments is at most 32 deep, and
        // each level leaves at most one node waiting.
        let mut stack = [0u32; 64];
        let mut len = usize::from(!self.nodes.is_empty());
        while len > 0 {
            len -= 1;
            let node = &self.nodes[stack[len] as usize];
            if box_distance(p, node.box_) > reach {
                continue;
            }
            match node.children {
                Some([left, right]) => {
                    // The nearer child on top: its segments tighten the reach sooner.
                    let (l, r) = (&self.nodes[left as usize], &self.nodes[right as usize]);
                    let (near, far) = if box_distance(p, l.box_) <= box_distance(p, r.box_) {
                        (left, right)
                    } else {
                        (right, left)
                    };
                    stack[len] = far;
                    stack[len + 1] = near;
                    len += 2;
                }
                None => {
                    for i in node.lo as usize..node.hi as usize {
                        let (a, b) = self.segment(i);
                        let d = segment_distance(p, a, b);
                        if d <= reach && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, i));
                            reach = d;
                        }
                    }
                }
            }
        }
        best.map(|(distance, i)| {
            let (a, b) = self.segment(i);
            Nearest {
                distance,
                point: lerp(a, b, segment_parameter(p, a, b)),
                direction: sub(b, a),
            }
        })
    }
}

/// Distance from `p` to the box `[lo, hi]` (0 inside).
fn box_distance(p: V3, [lo, hi]: [V3; 2]) -> f64 {
    let d: V3 = [0, 1, 2].map(|a| (lo[a] - p[a]).max(p[a] - hi[a]).max(0.0));
    norm(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_finds_the_closest_segment_within_the_radius() {
        let line = Polyline {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            closed: false,
        };
        let tree = CurveTree::new(&line);
        let n = tree.nearest([0.5, 0.2, 0.0], 0.3).unwrap();
        assert!((n.distance - 0.2).abs() < 1e-12);
        assert_eq!(n.point, [0.5, 0.0, 0.0]);
        assert!(n.direction[0] > 0.0 && n.direction[1] == 0.0);
        let n = tree.nearest([1.1, 0.6, 0.0], 0.3).unwrap();
        assert!((n.distance - 0.1).abs() < 1e-12);
        assert!(tree.nearest([0.5, 0.35, 0.0], 0.3).is_none());
        let index = SegmentIndex::new(&[line], 0.3, [[-1.0; 3], [2.0; 3]]);
        assert!(index.within([0.5, 0.25, 0.0], 0.3));
        assert!(!index.within([0.5, 0.25, 0.0], 0.2));
    }

    #[test]
    fn the_tree_agrees_with_a_scan_of_every_segment_of_a_loop() {
        // A closed helix-like loop of 500 segments, queried near and far.
        let points: Vec<V3> = (0..500)
            .map(|k| {
                let t = std::f64::consts::TAU * f64::from(k) / 500.0;
                [t.cos(), t.sin(), 0.2 * (3.0 * t).sin()]
            })
            .collect();
        let line = Polyline {
            points,
            closed: true,
        };
        let tree = CurveTree::new(&line);
        for k in 0..200 {
            let t = f64::from(k) * 0.37;
            let p = [
                1.3 * t.cos() * (t * 0.1).sin(),
                1.1 * t.sin(),
                0.3 * t.cos(),
            ];
            let scan = line
                .segments()
                .map(|(a, b)| segment_distance(p, a, b))
                .fold(f64::INFINITY, f64::min);
            for r in [0.1, 0.5, 3.0] {
                let got = tree.nearest(p, r).map(|n| n.distance);
                assert_eq!(got, (scan <= r).then_some(scan), "{p:?} {r}");
            }
        }
    }
}
