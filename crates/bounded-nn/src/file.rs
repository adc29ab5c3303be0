//! The self-describing model file.
//!
//! Layout: the 8 magic bytes `BOUNDED\0`, the format version as a little-endian `u32`, then
//! the [`ModelFile`] as MessagePack with field names (rmp-serde). The version sits outside the
//! MessagePack body so that a file of another version is reported as such rather than as a
//! decoding error. Version 2 added the optional second stage, version 3 the sensitivity chosen
//! on validation clouds; a file is written with the oldest version that holds it, so builds
//! that predate a field still read files without it, and refuse files with it rather than
//! run a two-stage model's first stage alone or decide by another rule.

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};

use crate::{
    CLASS_NAMES, LayerWeights, Model, ModelConfig, NnError, Standardisation, TrainedModel,
};

/// First bytes of every model file.
pub const MAGIC: [u8; 8] = *b"BOUNDED\0";

/// The newest format version, which this build writes for models with a recorded
/// sensitivity; it reads every version from 1.
pub const FORMAT_VERSION: u32 = 3;

/// The largest magnitude of a weight, bias, mean or standard deviation a valid file holds.
/// Trained weights are of order 1 (the inputs are standardised) and the features are ratios
/// of order 1: a value beyond a million is a corrupt or crafted file, whose products would
/// overflow to infinities and NaN probabilities.
pub const MAX_VALUE: f32 = 1e6;

/// The smallest standard deviation, exclusive, a valid file holds: what training keeps
/// (smaller ones become 1), as dividing by a tiny one overflows.
pub const MIN_STD: f32 = crate::standardisation::MIN_STD;

/// Where a model came from: enough to reproduce it and to recognise its training data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The command line that trained it (given by the caller).
    pub command: String,
    /// Training seed.
    pub seed: u64,
    /// [`crate::Dataset::fingerprint`] of the training data.
    pub data_hash: u64,
    /// Validation loss of the kept weights.
    pub val_loss: f32,
    /// Iterations per run.
    pub iterations: usize,
    /// Runs, of which the best was kept.
    pub runs: usize,
    /// Batch size.
    pub batch_size: usize,
}

/// A trained network with everything needed to use and to trace it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// Network shape.
    pub model: ModelConfig,
    /// Neighbourhood sizes of the scales, largest first (informational; given by the caller).
    pub scales: Vec<usize>,
    /// Names of the features of one scale, in input order (given by the caller).
    pub feature_names: Vec<String>,
    /// Names of the output classes, in code order.
    pub class_names: Vec<String>,
    /// Input standardisation applied before the first layer.
    pub standardisation: Standardisation,
    /// Training command, seed and data hash.
    pub provenance: Provenance,
    /// Weights of every layer in [`ModelConfig::layer_shapes`] order.
    pub layers: Vec<LayerWeights>,
    /// An optional second network (auto-context), whose probabilities are the model's output.
    /// Its inputs per scale are this network's features followed by the context of this
    /// network's probabilities over the same neighbourhood (one of `bounded-features`'
    /// `ContextSet`s, which its feature names say); its scales are this one's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub second_stage: Option<Box<ModelFile>>,
    /// The decision rule of the model's output, chosen on validation clouds when it was
    /// trained ([`crate::calibration::Calibration::chosen_sensitivity`]): the sensitivity a
    /// [`crate::Detector`] applies unless told otherwise; `None`, the most probable class.
    /// It belongs to the whole model: a first stage run alone decides by the most probable
    /// class.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensitivity: Option<f32>,
}

impl ModelFile {
    /// Packs a trained model. `scales` must have one entry per scale and `feature_names` one
    /// per feature of a scale; `command` is recorded as given.
    pub fn from_trained(
        trained: &TrainedModel,
        scales: Vec<usize>,
        feature_names: Vec<String>,
        command: String,
    ) -> Result<Self, NnError> {
        let config = &trained.config;
        let file = Self {
            model: config.model.clone(),
            scales,
            feature_names,
            class_names: CLASS_NAMES.iter().map(|s| s.to_string()).collect(),
            standardisation: trained.standardisation.clone(),
            provenance: Provenance {
                command,
                seed: config.seed,
                data_hash: trained.data_hash,
                val_loss: trained.val_loss,
                iterations: config.iterations,
                runs: config.runs,
                batch_size: config.batch_size,
            },
            layers: trained.model.export_weights()?,
            second_stage: None,
            sensitivity: None,
        };
        file.validate()?;
        Ok(file)
    }

    /// This network followed by `second`, trained on this one's features and context.
    pub fn with_second_stage(self, second: ModelFile) -> Result<Self, NnError> {
        let file = Self {
            second_stage: Some(Box::new(second)),
            ..self
        };
        file.validate()?;
        Ok(file)
    }

    /// The first network alone (the whole model when it has one stage), deciding by the most
    /// probable class unless it is the whole model.
    pub fn first_stage(&self) -> Self {
        let sensitivity = self.sensitivity.filter(|_| self.second_stage.is_none());
        Self {
            second_stage: None,
            sensitivity,
            ..self.clone()
        }
    }

    /// This model deciding at `sensitivity` (`None`: the most probable class).
    pub fn with_sensitivity(self, sensitivity: Option<f32>) -> Result<Self, NnError> {
        let file = Self {
            sensitivity,
            ..self
        };
        file.validate()?;
        Ok(file)
    }

    /// Whether `other` holds the same model (weights, standardisation, configuration and
    /// provenance of every stage), whatever command line each records: a retraining
    /// reproduces a model when this holds.
    pub fn same_model(&self, other: &ModelFile) -> bool {
        fn without_commands(file: &ModelFile) -> ModelFile {
            let mut file = file.clone();
            file.provenance.command.clear();
            file.second_stage = file.second_stage.map(|s| Box::new(without_commands(&s)));
            file
        }
        without_commands(self) == without_commands(other)
    }

    /// The format version this file is written with: the oldest that holds it.
    pub fn format_version(&self) -> u32 {
        if self.sensitivity.is_some() {
            3
        } else if self.second_stage.is_some() {
            2
        } else {
            1
        }
    }

    /// Checks that every stored size agrees with the configuration and that all numbers are
    /// finite.
    pub fn validate(&self) -> Result<(), NnError> {
        let bad = |msg: String| Err(NnError::InconsistentModel(msg));
        self.model.validate()?;
        self.model.check_weights(&self.layers)?;
        if self.scales.len() != self.model.n_scales {
            return bad(format!(
                "{} scales listed for {} model scales",
                self.scales.len(),
                self.model.n_scales
            ));
        }
        if self.feature_names.len() != self.model.features_per_scale {
            return bad(format!(
                "{} feature names for {} features per scale",
                self.feature_names.len(),
                self.model.features_per_scale
            ));
        }
        if self.class_names.len() != CLASS_NAMES.len() {
            return bad(format!(
                "{} class names, expected {}",
                self.class_names.len(),
                CLASS_NAMES.len()
            ));
        }
        let std = &self.standardisation;
        if std.mean.len() != self.model.n_inputs() || std.std.len() != self.model.n_inputs() {
            return bad(format!(
                "standardisation of {}/{} inputs for {} model inputs",
                std.mean.len(),
                std.std.len(),
                self.model.n_inputs()
            ));
        }
        if let Some(s) = std.std.iter().find(|&&s| s.is_nan() || s <= MIN_STD) {
            return bad(format!(
                "standard deviation {s:e}: each must be above {MIN_STD:e} (training sets 1 for \
                 constant inputs)"
            ));
        }
        if let Some(s) = self.sensitivity.filter(|s| !(*s > 0.0 && *s < 1.0)) {
            return bad(format!("sensitivity {s} is not strictly between 0 and 1"));
        }
        if let Some(second) = &self.second_stage {
            second.validate()?;
            if second.second_stage.is_some() || second.sensitivity.is_some() {
                return bad("a second stage with a stage or a sensitivity of its own".into());
            }
            if second.scales != self.scales || second.class_names != self.class_names {
                return bad("a second stage with other scales or classes".into());
            }
            let own = &second.feature_names;
            if own.len() <= self.feature_names.len() || !own.starts_with(&self.feature_names) {
                return bad(format!(
                    "second stage features [{}] do not extend the first's [{}]",
                    own.join(", "),
                    self.feature_names.join(", ")
                ));
            }
        }
        let numbers = self
            .layers
            .iter()
            .flat_map(|l| l.weight.iter().chain(&l.bias));
        if let Some(v) = numbers
            .chain(&std.mean)
            .chain(&std.std)
            .find(|v| v.is_nan() || v.abs() > MAX_VALUE)
        {
            return bad(format!(
                "weight or standardisation value {v:e}: each must be finite and at most \
                 {MAX_VALUE:e} in magnitude"
            ));
        }
        Ok(())
    }

    /// Encodes the file (magic, version, MessagePack body).
    pub fn to_bytes(&self) -> Result<Vec<u8>, NnError> {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&self.format_version().to_le_bytes());
        bytes.extend(rmp_serde::to_vec_named(self)?);
        Ok(bytes)
    }

    /// Decodes and validates a file.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, NnError> {
        let body = bytes.strip_prefix(&MAGIC).ok_or(NnError::BadMagic)?;
        let (version, body) = body.split_first_chunk::<4>().ok_or(NnError::BadMagic)?;
        let found = u32::from_le_bytes(*version);
        if !(1..=FORMAT_VERSION).contains(&found) {
            return Err(NnError::UnsupportedVersion {
                found,
                expected: FORMAT_VERSION,
            });
        }
        let file: Self = rmp_serde::from_slice(body)?;
        if file.format_version() > found {
            let what = if found < 2 && file.second_stage.is_some() {
                "a second stage"
            } else {
                "a sensitivity"
            };
            return Err(NnError::InconsistentModel(format!(
                "{what} in a version {found} file"
            )));
        }
        file.validate()?;
        Ok(file)
    }

    /// Writes the file to `path`, atomically ([`bounded_geom::atomic`]: a failed or
    /// interrupted write leaves any previous file in place and no partial one).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), NnError> {
        Ok(bounded_geom::atomic::write(
            path.as_ref(),
            &self.to_bytes()?,
        )?)
    }

    /// Reads and validates the file at `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, NnError> {
        Self::from_bytes(&std::fs::read(path)?)
    }

    /// The Burn model with these weights on `device` (for further training or checks).
    pub fn to_burn(&self, device: &Device) -> Result<Model, NnError> {
        self.model.init(&self.standardisation, &self.layers, device)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// A valid file with random weights for `n_scales` x `fps` inputs.
    pub(crate) fn random_file(n_scales: usize, fps: usize, seed: u64) -> ModelFile {
        let model = ModelConfig::new(n_scales, fps);
        let layers = model.random_weights(&mut StdRng::seed_from_u64(seed));
        let n = model.n_inputs();
        ModelFile {
            scales: (0..n_scales).map(|i| 128 >> i).collect(),
            feature_names: (0..fps).map(|i| format!("f{i}")).collect(),
            class_names: CLASS_NAMES.iter().map(|s| s.to_string()).collect(),
            standardisation: Standardisation {
                mean: (0..n).map(|i| i as f32 * 0.1).collect(),
                std: (0..n).map(|i| 0.5 + i as f32 * 0.05).collect(),
            },
            provenance: Provenance {
                command: "test".into(),
                seed,
                data_hash: 42,
                val_loss: 0.1,
                iterations: 1,
                runs: 1,
                batch_size: 1,
            },
            layers,
            model,
            second_stage: None,
            sensitivity: None,
        }
    }

    /// `random_file(n_scales, fps, seed)` with a random second stage over 4 context values.
    pub(crate) fn two_stage_file(n_scales: usize, fps: usize, seed: u64) -> ModelFile {
        let mut second = random_file(n_scales, fps + 4, seed + 1);
        let first = random_file(n_scales, fps, seed);
        second.feature_names = first.feature_names.clone();
        second
            .feature_names
            .extend((0..4).map(|i| format!("ctx{i}")));
        first.with_second_stage(second).unwrap()
    }

    #[test]
    fn round_trips_through_bytes() {
        let file = random_file(4, 12, 1);
        let bytes = file.to_bytes().unwrap();
        assert_eq!(&bytes[..8], b"BOUNDED\0");
        assert_eq!(ModelFile::from_bytes(&bytes).unwrap(), file);
    }

    #[test]
    fn two_stages_round_trip_as_version_2() {
        let file = two_stage_file(4, 12, 3);
        let bytes = file.to_bytes().unwrap();
        assert_eq!(&bytes[8..12], &2u32.to_le_bytes());
        assert_eq!(ModelFile::from_bytes(&bytes).unwrap(), file);
        // A single stage stays version 1, which older builds read.
        let bytes = random_file(4, 12, 3).to_bytes().unwrap();
        assert_eq!(&bytes[8..12], &1u32.to_le_bytes());
    }

    #[test]
    fn a_sensitivity_round_trips_as_version_3_and_older_labels_are_refused() {
        let file = two_stage_file(2, 6, 3).with_sensitivity(Some(0.6)).unwrap();
        let mut bytes = file.to_bytes().unwrap();
        assert_eq!(&bytes[8..12], &3u32.to_le_bytes());
        assert_eq!(ModelFile::from_bytes(&bytes).unwrap(), file);
        // A version 2 build would decide by the most probable class instead.
        bytes[8..12].copy_from_slice(&2u32.to_le_bytes());
        let e = ModelFile::from_bytes(&bytes).unwrap_err();
        assert!(
            e.to_string().contains("a sensitivity in a version 2 file"),
            "{e}"
        );
        // It is the whole model's: the first stage alone decides by the most probable class,
        // and a one-stage model keeps it.
        assert_eq!(file.first_stage().sensitivity, None);
        let single = random_file(2, 6, 3).with_sensitivity(Some(0.3)).unwrap();
        assert_eq!(single.first_stage().sensitivity, Some(0.3));
        for bad in [0.0, 1.0, -0.5, f32::NAN] {
            let e = file.clone().with_sensitivity(Some(bad)).unwrap_err();
            assert!(e.to_string().contains("strictly between 0 and 1"), "{e}");
        }
        // Nor may the second stage carry one of its own.
        let mut nested = file.clone();
        nested.second_stage.as_mut().unwrap().sensitivity = Some(0.5);
        assert!(nested.validate().is_err());
    }

    #[test]
    fn inconsistent_second_stages_are_rejected() {
        let file = two_stage_file(2, 6, 1);
        // Labelled version 1: a build of that version would have dropped the second stage.
        let mut bytes = file.to_bytes().unwrap();
        bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
        assert!(matches!(
            ModelFile::from_bytes(&bytes),
            Err(NnError::InconsistentModel(m)) if m.contains("version 1")
        ));
        let first = random_file(2, 6, 1);
        let mut second = file.second_stage.clone().unwrap();
        second.scales[0] += 1;
        assert!(first.clone().with_second_stage(*second).is_err());
        // Features that do not extend the first stage's.
        let mut second = random_file(2, 10, 2);
        second.feature_names.reverse();
        let e = first.clone().with_second_stage(second).unwrap_err();
        assert!(e.to_string().contains("do not extend"), "{e}");
        // No third stage.
        let nested = file.clone().with_second_stage(file.clone());
        assert!(nested.is_err());
    }

    #[test]
    fn wrong_magic_and_version_are_clear_errors() {
        let mut bytes = random_file(2, 6, 1).to_bytes().unwrap();
        bytes[8] = 99;
        assert!(matches!(
            ModelFile::from_bytes(&bytes),
            Err(NnError::UnsupportedVersion {
                found: 99,
                expected: FORMAT_VERSION
            })
        ));
        assert!(matches!(
            ModelFile::from_bytes(b"PLY\n..."),
            Err(NnError::BadMagic)
        ));
        assert!(matches!(
            ModelFile::from_bytes(&bytes[..10]),
            Err(NnError::BadMagic)
        ));
    }

    #[test]
    fn inconsistent_shapes_are_rejected() {
        let mut file = random_file(4, 12, 1);
        file.layers[1].bias.pop();
        assert!(matches!(
            ModelFile::from_bytes(&file.to_bytes().unwrap()),
            Err(NnError::InconsistentModel(_))
        ));
        let mut file = random_file(4, 12, 1);
        file.scales.pop();
        assert!(matches!(
            file.validate(),
            Err(NnError::InconsistentModel(_))
        ));
        let mut file = random_file(4, 12, 1);
        file.standardisation.std[3] = f32::NAN;
        assert!(matches!(
            file.validate(),
            Err(NnError::InconsistentModel(_))
        ));
        let mut file = random_file(4, 12, 1);
        file.model.n_scales = 8;
        assert!(file.validate().is_err());
    }

    #[test]
    fn declared_sizes_beyond_the_weights_fail_before_allocating() {
        // Sizes whose layer list would need 2^27 to 2^62 entries, or whose products overflow:
        // each fails on the layer count or the overflow check, allocating nothing for them.
        for (scales, features, width) in [
            (1usize << 63, 12, 12),
            (1 << 32, 12, 12),
            (1 << 28, 12, 12),
            (4, 1 << 63, 12),
            (4, 12, 1 << 63),
            (4, 12, 1 << 32),
        ] {
            let mut file = random_file(4, 12, 1);
            file.model.n_scales = scales;
            file.model.features_per_scale = features;
            file.model.fusion_widths[0] = width;
            let e = ModelFile::from_bytes(&file.to_bytes().unwrap()).unwrap_err();
            assert!(
                matches!(
                    &e,
                    NnError::InconsistentModel(_) | NnError::InvalidConfig(_)
                ),
                "{scales} x {features}, width {width}: {e}"
            );
        }
        let mut file = random_file(4, 12, 1);
        file.model.hidden_widths = vec![1 << 40, 1 << 40];
        let e = ModelFile::from_bytes(&file.to_bytes().unwrap()).unwrap_err();
        assert!(e.to_string().contains("above the largest allowed"), "{e}");
        // Within the width bound, 2^32 scales of 2^32 features still overflow.
        let mut file = random_file(4, 12, 1);
        file.model.n_scales = 1 << 32;
        file.model.features_per_scale = 1 << 32;
        let e = ModelFile::from_bytes(&file.to_bytes().unwrap()).unwrap_err();
        assert!(e.to_string().contains("sizes overflow"), "{e}");
    }

    #[test]
    fn huge_non_finite_values_and_tiny_deviations_are_refused() {
        let set = |f: &mut ModelFile, what: usize, v: f32| match what {
            0 => f.layers[2].weight[5] = v,
            1 => f.layers[0].bias[1] = v,
            2 => f.standardisation.mean[3] = v,
            _ => f.standardisation.std[3] = v,
        };
        for what in 0..4 {
            for v in [f32::NAN, f32::INFINITY, -f32::INFINITY, 1.25e38, -2e6] {
                let mut file = random_file(4, 12, 1);
                set(&mut file, what, v);
                let e = ModelFile::from_bytes(&file.to_bytes().unwrap()).unwrap_err();
                let expected = if what == 3 && (v.is_nan() || v < 0.0) {
                    "standard deviation"
                } else {
                    "each must be finite and at most 1e6 in magnitude"
                };
                assert!(e.to_string().contains(expected), "{what} {v}: {e}");
            }
            // The bound itself is allowed.
            let mut file = random_file(4, 12, 1);
            set(&mut file, what, 1e6);
            assert!(file.validate().is_ok());
        }
        for tiny in [1e-45, 1e-6, 0.0, -1.0] {
            let mut file = random_file(4, 12, 1);
            file.standardisation.std[0] = tiny;
            let e = file.validate().unwrap_err().to_string();
            assert!(e.contains("each must be above 1e-6"), "{tiny}: {e}");
        }
        // The shipped model passes.
        let shipped = ModelFile::from_bytes(include_bytes!("../models/default.bmodel"));
        assert!(shipped.is_ok());
    }

    #[test]
    fn saving_replaces_the_file_and_never_rewrites_it_in_place() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.bmodel");
        let (old, new) = (random_file(2, 6, 1), random_file(2, 6, 2));
        old.save(&path).unwrap();
        // A second name for the old file keeps the old model: the save wrote a new file.
        let link = dir.path().join("old.bmodel");
        std::fs::hard_link(&path, &link).unwrap();
        new.save(&path).unwrap();
        assert_eq!(ModelFile::load(&path).unwrap(), new);
        assert_eq!(ModelFile::load(&link).unwrap(), old);
        let names = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(names, 2, "no temporary file left");
        // A directory at the path is refused, naming it.
        let e = new.save(dir.path()).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn truncated_body_is_a_decode_error() {
        let bytes = random_file(2, 6, 1).to_bytes().unwrap();
        assert!(matches!(
            ModelFile::from_bytes(&bytes[..bytes.len() - 5]),
            Err(NnError::Decode(_))
        ));
    }

    #[test]
    fn the_same_model_whatever_its_command_but_not_with_other_weights() {
        let embedded = crate::default_model().unwrap().file().clone();
        let mut retrained = embedded.clone();
        retrained.provenance.command = "bounded bench".into();
        let second = retrained.second_stage.as_mut().unwrap();
        second.provenance.command = "bounded bench".into();
        assert!(retrained.same_model(&embedded));

        let mut other = retrained.clone();
        other.second_stage.as_mut().unwrap().layers[0].weight[0] += 1e-3;
        assert!(!other.same_model(&embedded));
        let mut other = retrained;
        other.provenance.data_hash ^= 1;
        assert!(!other.same_model(&embedded));
    }
}
