//! BoundED's point classifier: the pairwise scale-fusion network of the paper, its focal-loss
//! training on the CPU with Burn, a self-describing model file, a fast Burn-free inference
//! path, the [`Detector`] that runs a model's stages over a point cloud, and the evaluation
//! metrics.
//!
//! Detection is one call: [`Detector::detect`] computes the features of every point
//! (`bounded-features`) and runs the model's networks over them, both stages of a two-stage
//! model over one neighbour search. Two models are embedded ([`EmbeddedModel`]): the default
//! calls one row of points along each crease, the other a band, for ground truth labelled
//! either way.
//!
//! ```
//! use bounded_geom::PointCloud;
//! use bounded_nn::Detector;
//!
//! // A 30 x 30 grid on a plane: no edges inside, a boundary around.
//! let positions: Vec<[f64; 3]> = (0..900).map(|i| [(i % 30) as f64, (i / 30) as f64, 0.0]).collect();
//! let cloud = PointCloud::from_f64(&positions)?;
//! let detection = Detector::embedded()?.detect(&cloud)?;
//! let [non_edge, sharp, boundary] = detection.class_counts();
//! assert_eq!(non_edge + sharp + boundary, 900);
//! assert!(boundary > sharp);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Below the detector, inputs are plain `f32` feature rows, `[point][scale (largest
//! first)][feature]`, and `u8` class codes: 0 non-edge, 1 sharp edge, 2 boundary.
//! [`Classifier::predict`] runs one network over such rows. A two-stage model
//! ([`ModelFile::second_stage`], [`Classifier::second_stage`]) holds a second network whose
//! inputs are the features beside the context of the first network's probabilities over each
//! point's neighbourhoods, so only the [`Detector`] (or a caller that computes that context,
//! `bounded-features`' `extract_in_context`) gives a two-stage model's answer.
//!
//! Training runs on Burn's Flex backend, its pure-Rust CPU backend (NdArray is deprecated in
//! burn 0.22): on the 2-core machine, at batch 16,384 with the default network, 0.034 s per
//! iteration against 0.100 s with NdArray (see `backend.rs`). Only Flex is compiled.
//!
//! Training: build a [`Dataset`] over the feature rows and labels, a [`TrainConfig`] over a
//! [`ModelConfig`], call [`train`], pack the result with [`ModelFile::from_trained`] and build a
//! [`Classifier`] from the file.

mod backend;
pub mod baseline;
pub mod calibration;
pub mod data;
pub mod detector;
mod embedded;
mod error;
pub mod file;
pub mod fit;
pub mod inference;
pub mod loss;
pub mod metrics;
pub mod model;
pub mod report;
mod standardisation;
pub mod training;

pub use backend::cpu_device;
pub use calibration::Reliability;
pub use data::{Dataset, Sampling};
pub use detector::{Decision, Detection, Detector, Work, class_at};
pub use embedded::{EmbeddedModel, default_model};
pub use error::NnError;
pub use file::{FORMAT_VERSION, ModelFile, Provenance};
pub use fit::{FeatureSet, Schedule, Seconds, Step, TrainingCloud, Widths, fit, fit_stages};
pub use inference::{Classifier, argmax};
pub use loss::FocalLoss;
pub use metrics::{BinaryConfusion, ConfusionMatrix, Scores, median};
pub use model::{CLASS_NAMES, LayerWeights, Model, ModelConfig, N_CLASSES};
pub use standardisation::Standardisation;
pub use training::{Progress, TrainConfig, TrainedModel, train};
