//! Training data: a borrowed feature matrix with labels, the validation split and the seeded
//! batch sampler.

use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::{N_CLASSES, NnError};

/// Features `[point][input]` (row-major, `n_inputs` per point) and class codes (0 non-edge,
/// 1 sharp, 2 boundary) of a set of points.
#[derive(Debug, Clone, Copy)]
pub struct Dataset<'a> {
    features: &'a [f32],
    labels: &'a [u8],
    n_inputs: usize,
}

impl<'a> Dataset<'a> {
    /// Wraps features and labels after checking that they describe the same points and that
    /// every label is a class code below 3.
    pub fn new(features: &'a [f32], labels: &'a [u8], n_inputs: usize) -> Result<Self, NnError> {
        if n_inputs == 0 || features.len() != labels.len() * n_inputs {
            return Err(NnError::Shape(format!(
                "{} feature values for {} labels of {n_inputs} inputs",
                features.len(),
                labels.len()
            )));
        }
        if let Some(bad) = labels.iter().find(|&&l| usize::from(l) >= N_CLASSES) {
            return Err(NnError::Data(format!(
                "label {bad} is not a class code (0, 1, 2)"
            )));
        }
        Ok(Self {
            features,
            labels,
            n_inputs,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// Inputs per point.
    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }

    /// All features, row-major.
    pub fn features(&self) -> &'a [f32] {
        self.features
    }

    /// All labels.
    pub fn labels(&self) -> &'a [u8] {
        self.labels
    }

    /// Features of point `i`.
    fn row(&self, i: usize) -> &'a [f32] {
        &self.features[i * self.n_inputs..(i + 1) * self.n_inputs]
    }

    /// Number of points per class.
    pub fn class_counts(&self) -> [usize; N_CLASSES] {
        let mut counts = [0; N_CLASSES];
        for &l in self.labels {
            counts[usize::from(l)] += 1;
        }
        counts
    }

    /// 64-bit FNV-1a hash of the input count, the feature bytes (little endian) and the
    /// labels: identifies the training data a model file was made from.
    pub fn fingerprint(&self) -> u64 {
        const PRIME: u64 = 0x0000_0100_0000_01b3;
        let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |byte: u8| hash = (hash ^ u64::from(byte)).wrapping_mul(PRIME);
        (self.n_inputs as u64)
            .to_le_bytes()
            .into_iter()
            .for_each(&mut eat);
        self.features
            .iter()
            .flat_map(|f| f.to_le_bytes())
            .for_each(&mut eat);
        self.labels.iter().copied().for_each(&mut eat);
        hash
    }

    /// Copies the features and labels of `indices` into `features` and `labels` (cleared first;
    /// labels as i64, the type Burn's integer tensors are built from).
    pub(crate) fn gather(&self, indices: &[u32], features: &mut Vec<f32>, labels: &mut Vec<i64>) {
        features.clear();
        labels.clear();
        for &i in indices {
            features.extend_from_slice(self.row(i as usize));
            labels.push(i64::from(self.labels[i as usize]));
        }
    }
}

/// How training batches are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sampling {
    /// Every training point equally likely: batches keep the data's class imbalance, which
    /// the focal loss is there to handle (the paper's setting, and the default).
    Uniform,
    /// First a class uniformly among the classes present, then a point of that class.
    ClassBalanced,
}

/// Splits the point indices into training and validation indices. Validation takes
/// `min(per_class[c], n_c / 2)` random points of each class `c`, so that a rare class is never
/// removed from training entirely.
pub(crate) fn split_validation(
    labels: &[u8],
    per_class: [usize; N_CLASSES],
    rng: &mut StdRng,
) -> (Vec<u32>, Vec<u32>) {
    let mut by_class: [Vec<u32>; N_CLASSES] = Default::default();
    for (i, &l) in labels.iter().enumerate() {
        by_class[usize::from(l)].push(i as u32);
    }
    let (mut train, mut val) = (Vec::with_capacity(labels.len()), Vec::new());
    for (class, mut indices) in by_class.into_iter().enumerate() {
        let take = per_class[class].min(indices.len() / 2);
        let (chosen, rest) = indices.partial_shuffle(rng, take);
        val.extend_from_slice(chosen);
        train.extend_from_slice(rest);
    }
    train.sort_unstable();
    val.sort_unstable();
    (train, val)
}

/// Seeded sampler of training batches (with replacement) from a pool of point indices.
pub(crate) struct BatchSampler {
    /// Pool indices per class, for class-balanced sampling.
    by_class: Vec<Vec<u32>>,
    pool: Vec<u32>,
    sampling: Sampling,
    rng: StdRng,
}

impl BatchSampler {
    /// A sampler over `pool` (indices into a dataset with `labels`).
    pub(crate) fn new(pool: Vec<u32>, labels: &[u8], sampling: Sampling, seed: u64) -> Self {
        let mut by_class = vec![Vec::new(); N_CLASSES];
        for &i in &pool {
            by_class[usize::from(labels[i as usize])].push(i);
        }
        by_class.retain(|c| !c.is_empty());
        Self {
            by_class,
            pool,
            sampling,
            rng: StdRng::seed_from_u64(seed),
        }
    }

    /// Fills `batch` with `size` sampled indices.
    pub(crate) fn sample(&mut self, size: usize, batch: &mut Vec<u32>) {
        batch.clear();
        match self.sampling {
            Sampling::Uniform => {
                batch.extend(
                    (0..size).map(|_| self.pool[self.rng.random_range(0..self.pool.len())]),
                );
            }
            Sampling::ClassBalanced => {
                for _ in 0..size {
                    let class = &self.by_class[self.rng.random_range(0..self.by_class.len())];
                    batch.push(class[self.rng.random_range(0..class.len())]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_checks_shapes_and_labels() {
        assert!(Dataset::new(&[0.0; 6], &[0, 1, 2], 2).is_ok());
        assert!(Dataset::new(&[0.0; 5], &[0, 1, 2], 2).is_err());
        assert!(Dataset::new(&[0.0; 6], &[0, 1, 3], 2).is_err());
        let d = Dataset::new(&[0.0; 8], &[0, 2, 2, 0], 2).unwrap();
        assert_eq!(d.class_counts(), [2, 0, 2]);
    }

    #[test]
    fn fingerprint_is_fnv1a_and_sees_every_byte() {
        // FNV-1a of zero-length data is the offset basis; here the 8 bytes of n_inputs = 1
        // come first, so compare two datasets that differ in one label instead.
        let a = Dataset::new(&[1.0, 2.0], &[0, 1], 1).unwrap();
        let b = Dataset::new(&[1.0, 2.0], &[0, 2], 1).unwrap();
        let c = Dataset::new(&[1.0, 2.5], &[0, 1], 1).unwrap();
        assert_ne!(a.fingerprint(), b.fingerprint());
        assert_ne!(a.fingerprint(), c.fingerprint());
        assert_eq!(
            a.fingerprint(),
            Dataset::new(&[1.0, 2.0], &[0, 1], 1).unwrap().fingerprint()
        );
    }

    #[test]
    fn validation_split_is_disjoint_and_capped_per_class() {
        let labels = [0u8, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2];
        let mut rng = StdRng::seed_from_u64(7);
        let (train, val) = split_validation(&labels, [2, 10, 10], &mut rng);
        let count = |idx: &[u32], c: u8| idx.iter().filter(|&&i| labels[i as usize] == c).count();
        // Class 0: min(2, 6/2) = 2; class 1: min(10, 4/2) = 2; class 2: min(10, 1/2) = 0.
        assert_eq!([count(&val, 0), count(&val, 1), count(&val, 2)], [2, 2, 0]);
        assert_eq!(train.len() + val.len(), labels.len());
        assert!(train.iter().all(|i| !val.contains(i)));
    }

    #[test]
    fn class_balanced_batches_are_balanced_and_seeded() {
        let labels: Vec<u8> = (0..1000).map(|i| u8::from(i % 100 == 0)).collect();
        let pool: Vec<u32> = (0..1000).collect();
        let mut batch = Vec::new();
        let mut s = BatchSampler::new(pool.clone(), &labels, Sampling::ClassBalanced, 3);
        s.sample(4000, &mut batch);
        let ones = batch.iter().filter(|&&i| labels[i as usize] == 1).count();
        assert!((1800..2200).contains(&ones), "{ones}");
        let mut again = Vec::new();
        BatchSampler::new(pool.clone(), &labels, Sampling::ClassBalanced, 3)
            .sample(4000, &mut again);
        assert_eq!(batch, again);
        BatchSampler::new(pool, &labels, Sampling::Uniform, 3).sample(4000, &mut batch);
        let ones = batch.iter().filter(|&&i| labels[i as usize] == 1).count();
        assert!(ones < 100, "{ones}");
    }
}
