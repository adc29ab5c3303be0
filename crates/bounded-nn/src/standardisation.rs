//! Per-input standardisation.
//!
//! The twelve features of a scale live on very different ranges (eigenvalues of a normalised
//! neighbourhood are around 0.1-1, offsets like `c` are around 0.01, and the constant `c` of the
//! largest scale is exactly 0). A net this small (1.6k weights) trained for a few thousand Adam
//! steps learns much faster and more reliably when every input is centred and scaled to unit
//! variance first. The mean and standard deviation are measured on the training data and stored
//! in the model, so inference applies exactly the transform the network was trained with.

use serde::{Deserialize, Serialize};

use crate::NnError;

/// Standard deviations below this are treated as constant inputs (scaled by 1, only centred).
pub(crate) const MIN_STD: f32 = 1e-6;

/// Mean and standard deviation of every network input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Standardisation {
    /// Mean of every input, in input order.
    pub mean: Vec<f32>,
    /// Standard deviation of every input; inputs that are constant in the training data get 1.
    pub std: Vec<f32>,
}

impl Standardisation {
    /// The identity transform for `n_inputs` inputs (mean 0, std 1).
    pub fn identity(n_inputs: usize) -> Self {
        Self {
            mean: vec![0.0; n_inputs],
            std: vec![1.0; n_inputs],
        }
    }

    /// Measures mean and standard deviation of every column of `features`, a row-major
    /// `[point][input]` array with `n_inputs` columns. Accumulates in f64 so that millions of
    /// points do not lose precision.
    pub fn fit(features: &[f32], n_inputs: usize) -> Result<Self, NnError> {
        if n_inputs == 0 || features.is_empty() || !features.len().is_multiple_of(n_inputs) {
            return Err(NnError::Shape(format!(
                "{} feature values do not form rows of {n_inputs} inputs",
                features.len()
            )));
        }
        let n = (features.len() / n_inputs) as f64;
        let mut sum = vec![0.0f64; n_inputs];
        let mut sum_sq = vec![0.0f64; n_inputs];
        for row in features.chunks_exact(n_inputs) {
            for ((s, q), &v) in sum.iter_mut().zip(&mut sum_sq).zip(row) {
                let v = f64::from(v);
                *s += v;
                *q += v * v;
            }
        }
        let mean: Vec<f32> = sum.iter().map(|s| (s / n) as f32).collect();
        let std = sum
            .iter()
            .zip(&sum_sq)
            .map(|(s, q)| {
                let m = s / n;
                let std = (q / n - m * m).max(0.0).sqrt() as f32;
                if std.is_finite() && std > MIN_STD {
                    std
                } else {
                    1.0
                }
            })
            .collect();
        Ok(Self { mean, std })
    }

    /// Number of inputs this transform applies to.
    pub fn len(&self) -> usize {
        self.mean.len()
    }

    /// True for a transform of zero inputs.
    pub fn is_empty(&self) -> bool {
        self.mean.is_empty()
    }

    /// `1 / std` per input, the factor the forward passes multiply by.
    pub fn inv_std(&self) -> Vec<f32> {
        self.std.iter().map(|s| 1.0 / s).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_measures_mean_and_population_std() {
        // Column 0: 1, 3 -> mean 2, std 1. Column 1: constant 5 -> std replaced by 1.
        let s = Standardisation::fit(&[1.0, 5.0, 3.0, 5.0], 2).unwrap();
        assert_eq!(s.mean, vec![2.0, 5.0]);
        assert_eq!(s.std, vec![1.0, 1.0]);
        let s = Standardisation::fit(&[0.0, 4.0], 1).unwrap();
        assert_eq!((s.mean[0], s.std[0]), (2.0, 2.0));
    }

    #[test]
    fn fit_rejects_ragged_rows() {
        assert!(Standardisation::fit(&[1.0, 2.0, 3.0], 2).is_err());
        assert!(Standardisation::fit(&[], 2).is_err());
    }
}
