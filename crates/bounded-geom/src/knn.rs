//! All-points exact k-nearest-neighbour search, traversed in Morton-ordered chunks.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::{GeomError, PointCloud, morton::morton_order};

/// Neighbour lists of a run of query points, as handed out by
/// [`KnnIndex::for_each_chunk`].
///
/// Row `j` holds the `k` neighbours of `queries()[j]`: the query itself first, then the
/// others by increasing distance, ties by increasing index. Row-major, `u32` indices.
#[derive(Debug, Clone, Default)]
pub struct NeighbourChunk {
    k: usize,
    queries: Vec<u32>,
    neighbours: Vec<u32>,
}

impl NeighbourChunk {
    /// Neighbours per row.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Number of query points in the chunk.
    pub fn len(&self) -> usize {
        self.queries.len()
    }

    /// True for a chunk without queries (never handed out).
    pub fn is_empty(&self) -> bool {
        self.queries.is_empty()
    }

    /// The query points' indices in the cloud, in Morton order.
    pub fn queries(&self) -> &[u32] {
        &self.queries
    }

    /// The neighbours of `queries()[row]`.
    pub fn row(&self, row: usize) -> &[u32] {
        &self.neighbours[row * self.k..(row + 1) * self.k]
    }

    /// All rows, row-major (`len() * k()` indices), e.g. for `par_chunks(k())`.
    pub fn rows(&self) -> &[u32] {
        &self.neighbours
    }
}

/// An exact all-points kNN index over a [`PointCloud`].
///
/// Built once; every query asks for the `k0` nearest neighbours of a cloud point, so
/// each smaller `k` is a prefix of the same list. Points are visited in Morton order so
/// consecutive queries hit the same part of the tree.
pub struct KnnIndex<'a> {
    points: &'a [[f32; 3]],
    tree: ImmutableKdTree<f32, 3>,
    order: Vec<u32>,
}

impl<'a> KnnIndex<'a> {
    /// Builds the index (a kiddo k-d tree and the Morton order of the points).
    pub fn new(cloud: &'a PointCloud) -> Result<Self, GeomError> {
        let points = cloud.points();
        if u32::try_from(points.len()).is_err() {
            return Err(GeomError::TooManyPoints {
                points: points.len(),
            });
        }
        let tree =
            ImmutableKdTree::new_from_slice(points).map_err(|_| GeomError::TooManyPoints {
                points: points.len(),
            })?;
        Ok(Self {
            points,
            tree,
            order: morton_order(points),
        })
    }

    /// Number of indexed points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no point is indexed (never, for a constructed cloud).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Point indices in the Morton order used by [`for_each_chunk`](Self::for_each_chunk).
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The `k` nearest neighbours of point `query`, written to `out` (length `k`): the
    /// point itself first, then by increasing distance, ties by increasing index.
    pub fn nearest(&self, query: u32, out: &mut [u32]) -> Result<(), GeomError> {
        self.check_k(out.len())?;
        self.nearest_unchecked(query, out, &mut Vec::new());
        Ok(())
    }

    /// Calls `f` with the neighbour lists (`k` per point) of consecutive runs of at most
    /// `chunk_points` points in Morton order, covering every point once.
    ///
    /// Each chunk is searched in parallel; `f` runs on the calling thread, in order.
    /// Memory is `O(chunk_points * k)` whatever the cloud size.
    pub fn for_each_chunk(
        &self,
        k: usize,
        chunk_points: usize,
        mut f: impl FnMut(&NeighbourChunk),
    ) -> Result<(), GeomError> {
        self.check_k(k)?;
        let mut chunk = NeighbourChunk {
            k,
            ..NeighbourChunk::default()
        };
        for queries in self.order.chunks(chunk_points.max(1)) {
            chunk.queries.clear();
            chunk.queries.extend_from_slice(queries);
            chunk.neighbours.resize(queries.len() * k, 0);
            chunk
                .neighbours
                .par_chunks_mut(k)
                .zip(queries.par_iter())
                .for_each_init(Vec::new, |scratch, (out, &q)| {
                    self.nearest_unchecked(q, out, scratch)
                });
            f(&chunk);
        }
        Ok(())
    }

    fn check_k(&self, k: usize) -> Result<(), GeomError> {
        if k == 0 || k > self.points.len() {
            return Err(GeomError::TooFewPoints {
                points: self.points.len(),
                k,
            });
        }
        Ok(())
    }

    /// Search for `out.len()` (checked: 1..=n) neighbours. Asks the tree for one more
    /// candidate than needed and widens the request while the last candidate ties with
    /// the k-th, so ties at the cut are decided by index, not by the tree's layout.
    fn nearest_unchecked(&self, query: u32, out: &mut [u32], cand: &mut Vec<(bool, f32, u32)>) {
        let k = out.len();
        let n = self.points.len();
        let p = self.points[query as usize];
        let mut want = (k + 1).min(n);
        loop {
            let found = self
                .tree
                .query(&p)
                .nearest_n::<SquaredEuclidean<f32>>(
                    NonZero::new(want).unwrap_or(NonZero::<usize>::MIN),
                )
                .execute();
            cand.clear();
            cand.extend(found.iter().map(|r| {
                (
                    r.item != query,
                    dist2(p, self.points[r.item as usize]),
                    r.item,
                )
            }));
            // kiddo sorts by distance already: only ties and the query's own place
            // move, so an insertion sort is linear here.
            insertion_sort(cand);
            if want == n || cand[k - 1].1 < cand[want - 1].1 {
                break;
            }
            want = (want * 2).min(n);
        }
        for (o, c) in out.iter_mut().zip(cand.iter()) {
            *o = c.2;
        }
    }
}

/// Sorts by [`neighbour_order`]; fast on nearly sorted input.
fn insertion_sort(v: &mut [(bool, f32, u32)]) {
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 && neighbour_order(v[j - 1], v[j]).is_gt() {
            v.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// Squared Euclidean distance in `f32`, the one metric every search path uses so that
/// ties are decided identically.
pub(crate) fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// Neighbour ordering: the query itself (`false` sorts first), then distance, then index.
pub(crate) fn neighbour_order(a: (bool, f32, u32), b: (bool, f32, u32)) -> std::cmp::Ordering {
    a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(points: Vec<[f32; 3]>) -> PointCloud {
        PointCloud::from_local([0.0; 3], points).unwrap()
    }

    /// Brute force: sort all points by the documented key.
    fn brute(points: &[[f32; 3]], q: u32, k: usize) -> Vec<u32> {
        let p = points[q as usize];
        let mut all: Vec<_> = (0..points.len() as u32)
            .map(|i| (i != q, dist2(p, points[i as usize]), i))
            .collect();
        all.sort_by(|a, b| neighbour_order(*a, *b));
        all[..k].iter().map(|c| c.2).collect()
    }

    fn grid(n: usize) -> Vec<[f32; 3]> {
        (0..n * n)
            .map(|i| [(i % n) as f32, (i / n) as f32, 0.0])
            .collect()
    }

    #[test]
    fn grid_ties_broken_by_index() {
        // 5x5 grid, centre point 12 at (2,2): 4 neighbours at distance 1 (7, 11, 13, 17),
        // then 4 at sqrt2 (6, 8, 16, 18), then 4 at 2 (2, 10, 14, 22).
        let c = cloud(grid(5));
        let idx = KnnIndex::new(&c).unwrap();
        let mut out = [0u32; 13];
        idx.nearest(12, &mut out).unwrap();
        assert_eq!(out, [12, 7, 11, 13, 17, 6, 8, 16, 18, 2, 10, 14, 22]);
        // A cut inside a tie (k = 3) keeps the lowest indices.
        let mut out3 = [0u32; 3];
        idx.nearest(12, &mut out3).unwrap();
        assert_eq!(out3, [12, 7, 11]);
    }

    #[test]
    fn duplicates_put_the_query_first() {
        let c = cloud(vec![[0.0; 3], [0.0; 3], [0.0; 3], [1.0, 0.0, 0.0]]);
        let idx = KnnIndex::new(&c).unwrap();
        let mut out = [0u32; 3];
        idx.nearest(2, &mut out).unwrap();
        assert_eq!(out, [2, 0, 1]);
    }

    #[test]
    fn chunks_cover_every_point_once_with_prefix_property() {
        let pts = grid(9);
        let c = cloud(pts.clone());
        let idx = KnnIndex::new(&c).unwrap();
        let mut seen = vec![0; pts.len()];
        let mut chunks = 0;
        idx.for_each_chunk(20, 7, |ch| {
            chunks += 1;
            assert!(ch.len() <= 7 && ch.k() == 20);
            for (j, &q) in ch.queries().iter().enumerate() {
                seen[q as usize] += 1;
                assert_eq!(ch.row(j), brute(&pts, q, 20).as_slice());
                // Smaller k is a prefix of the k0 list.
                let mut small = [0u32; 9];
                idx.nearest(q, &mut small).unwrap();
                assert_eq!(&ch.row(j)[..9], &small);
            }
        })
        .unwrap();
        assert_eq!(chunks, 81usize.div_ceil(7));
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn whole_cloud_as_neighbourhood() {
        let pts = grid(3);
        let c = cloud(pts.clone());
        let idx = KnnIndex::new(&c).unwrap();
        let mut out = [0u32; 9];
        idx.nearest(0, &mut out).unwrap();
        assert_eq!(out.to_vec(), brute(&pts, 0, 9));
    }

    #[test]
    fn too_few_points_is_an_error() {
        let c = cloud(grid(2));
        let idx = KnnIndex::new(&c).unwrap();
        let e = idx.for_each_chunk(5, 10, |_| {}).unwrap_err();
        assert_eq!(e, GeomError::TooFewPoints { points: 4, k: 5 });
        assert!(e.to_string().contains("4 points"));
    }
}
