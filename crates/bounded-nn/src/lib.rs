//! BoundED's classifier (placeholder docs, completed below).

mod backend;
pub mod data;
mod error;
pub mod loss;
pub mod model;
mod standardisation;
pub mod training;

pub use backend::cpu_device;
pub use data::{Dataset, Sampling};
pub use error::NnError;
pub use loss::FocalLoss;
pub use model::{CLASS_NAMES, LayerWeights, Model, ModelConfig, N_CLASSES};
pub use standardisation::Standardisation;
pub use training::{Progress, TrainConfig, TrainedModel, train};
