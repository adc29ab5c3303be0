//! Exact duplicate positions, collapsed so that a neighbourhood counts each position once.
//!
//! Real scans repeat points (overlapping flight lines, a registration that appends a frame
//! twice, a room scan with every point stored twice). A repeated point carries no geometry,
//! but it takes a place among the `k` nearest neighbours and so shrinks every scale: the
//! same surface would be labelled differently stored once or twice. Features are therefore
//! computed on the distinct positions and shared by the points that repeat them.

use crate::PointCloud;
use rayon::prelude::*;

/// The distinct positions of a cloud, each named by the first point there, and the points
/// that share it. Holds indices only (8 bytes per point and 4 per position): the positions
/// stay in the cloud, which [`KnnIndex::of_subset`](crate::KnnIndex::of_subset) searches.
#[derive(Debug, Clone)]
pub struct Distinct {
    /// The first point at each position, increasing.
    firsts: Vec<u32>,
    /// Points at position `u`: `members[starts[u]..starts[u + 1]]`.
    starts: Vec<u32>,
    members: Vec<u32>,
}

impl Distinct {
    /// The distinct positions of `cloud`, or `None` when no position repeats (then nothing
    /// is allocated beyond the check).
    ///
    /// Positions are equal when the cloud's stored `f32` offsets are (`-0.0` equals `0.0`):
    /// exact repeats always are, and distinct positions are merged only when they are closer
    /// than the cloud's `f32` resolution, about 2^-24 of their distance from its origin
    /// (see [`PointCloud`]: far outliers do not coarsen it for the bulk of the points).
    /// Costs a parallel sort of 16 bytes per point, freed before it returns.
    pub fn of(cloud: &PointCloud) -> Option<Self> {
        let points = cloud.points();
        if u32::try_from(points.len()).is_err() {
            return None; // the neighbour search refuses such clouds with its own error
        }
        let mut keyed: Vec<([u32; 3], u32)> = points
            .par_iter()
            .enumerate()
            // Adding 0.0 turns -0.0 into 0.0, so equal values have equal bits.
            .map(|(i, p)| (p.map(|c| (c + 0.0).to_bits()), i as u32))
            .collect();
        keyed.par_sort_unstable();
        if !keyed.par_windows(2).any(|w| w[0].0 == w[1].0) {
            return None;
        }
        // For each point, the first (smallest) index of its position: groups are sorted by
        // index, so that is the group's first entry.
        let mut of = vec![0u32; points.len()];
        let mut groups = 0;
        for group in keyed.chunk_by(|a, b| a.0 == b.0) {
            for &(_, i) in group {
                of[i as usize] = group[0].1;
            }
            groups += 1;
        }
        drop(keyed);
        // Number the positions in the order of their first points; a repeat takes its
        // first's number, already assigned as the first comes earlier.
        let mut firsts = Vec::with_capacity(groups);
        for i in 0..of.len() {
            let first = of[i] as usize;
            if first == i {
                of[i] = firsts.len() as u32;
                firsts.push(i as u32);
            } else {
                of[i] = of[first];
            }
        }
        let mut starts = vec![0u32; firsts.len() + 1];
        for &u in &of {
            starts[u as usize + 1] += 1;
        }
        for u in 0..firsts.len() {
            starts[u + 1] += starts[u];
        }
        let mut fill = starts.clone();
        let mut members = vec![0u32; of.len()];
        for (i, &u) in of.iter().enumerate() {
            members[fill[u as usize] as usize] = i as u32;
            fill[u as usize] += 1;
        }
        Some(Self {
            firsts,
            starts,
            members,
        })
    }

    /// The first point at each distinct position, increasing.
    pub fn firsts(&self) -> &[u32] {
        &self.firsts
    }

    /// The points at the position of `first` (itself included), increasing; empty when
    /// `first` is not one of [`firsts`](Self::firsts).
    pub fn members(&self, first: u32) -> &[u32] {
        match self.firsts.binary_search(&first) {
            Ok(u) => &self.members[self.starts[u] as usize..self.starts[u + 1] as usize],
            Err(_) => &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeats_are_grouped_under_their_first_point() {
        let cloud = PointCloud::from_local(
            [10.0; 3],
            vec![
                [1.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 0.0, -0.0],
                [0.0, 2.0, 0.0],
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
            ],
        )
        .unwrap();
        let d = Distinct::of(&cloud).unwrap();
        assert_eq!(d.firsts(), [0, 1, 3]);
        assert_eq!(d.members(0), [0, 2, 6]);
        assert_eq!(d.members(1), [1, 4]);
        assert_eq!(d.members(3), [3, 5]);
        assert_eq!(d.members(2), [] as [u32; 0]);
    }

    #[test]
    fn distinct_clouds_are_not_copied() {
        let cloud = PointCloud::from_f64(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
        assert!(Distinct::of(&cloud).is_none());
    }
}
