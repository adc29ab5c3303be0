//! BoundED's point classifier: the pairwise scale-fusion network of the paper, its focal-loss
//! training on the CPU with Burn, a self-describing model file, a fast Burn-free inference
//! path and the evaluation metrics.
//!
//! Inputs are plain `f32` feature rows, `[point][scale (largest first)][feature]`, and `u8`
//! class codes: 0 non-edge, 1 sharp edge, 2 boundary. This crate knows nothing about point
//! clouds.
//!
//! ```
//! use bounded_nn::{argmax, default_model};
//!
//! let classifier = default_model()?;
//! // One point: 4 scales x 12 features.
//! let features = vec![0.5f32; classifier.n_inputs()];
//! let mut probabilities = [[0.0f32; 3]; 1];
//! classifier.predict(&features, &mut probabilities)?;
//! let sum: f32 = probabilities[0].iter().sum();
//! assert!((sum - 1.0).abs() < 1e-5);
//! assert!(argmax(&probabilities[0]) < 3);
//! # Ok::<(), bounded_nn::NnError>(())
//! ```
//!
//! Training: build a [`Dataset`] over the feature rows and labels, a [`TrainConfig`] over a
//! [`ModelConfig`], call [`train`], pack the result with [`ModelFile::from_trained`] and build a
//! [`Classifier`] from the file.
//!
//! A two-stage model ([`ModelFile::second_stage`], [`Classifier::second_stage`]) holds a second
//! network whose inputs are the features beside the context of the first network's
//! probabilities over each point's neighbourhoods (`bounded-features`' `extract_in_context`):
//! [`Classifier::predict`] gives the first network's probabilities, which those context
//! features need, and the second network's prediction over them is the model's.

mod backend;
pub mod data;
mod error;
pub mod file;
pub mod inference;
pub mod loss;
pub mod metrics;
pub mod model;
mod standardisation;
pub mod training;

pub use backend::cpu_device;
pub use data::{Dataset, Sampling};
pub use error::NnError;
pub use file::{FORMAT_VERSION, ModelFile, Provenance};
pub use inference::{Classifier, argmax};
pub use loss::FocalLoss;
pub use metrics::{BinaryConfusion, ConfusionMatrix, Scores, median};
pub use model::{CLASS_NAMES, LayerWeights, Model, ModelConfig, N_CLASSES};
pub use standardisation::Standardisation;
pub use training::{Progress, TrainConfig, TrainedModel, train};

/// The embedded default model (4 scales of 128, 64, 32, 16 neighbours x 12 features, and an
/// auto-context second stage over those features beside 4 context values per scale), trained
/// on generated sets only by the `bounded train` command recorded in the file and in README.md.
const DEFAULT_MODEL: &[u8] = include_bytes!("../models/default.bmodel");

/// The classifier embedded in the library.
pub fn default_model() -> Result<Classifier, NnError> {
    Classifier::from_bytes(DEFAULT_MODEL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_model_loads_with_the_paper_shape() {
        let classifier = default_model().unwrap();
        let file = classifier.file();
        assert_eq!(file.scales, vec![128, 64, 32, 16]);
        assert_eq!(file.feature_names.len(), 12);
        assert_eq!(file.model.n_params(), 1595);
        assert_eq!(file.class_names, CLASS_NAMES);
        let second = classifier
            .second_stage()
            .expect("an auto-context second stage");
        assert_eq!(second.file().feature_names.len(), 12 + 4);
        assert_eq!(second.file().model.n_params(), 1787);
    }
}
