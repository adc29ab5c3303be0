//! The models embedded in the library, one for each way of labelling sharp features.
//!
//! Ground truth comes in two conventions, and a model trained for one is scored poorly against
//! the other: the PCEDNet and ABC clouds label one row of points along each crease, hand- or
//! mesh-labelled scans often a band a few spacings wide. Measured against the other convention,
//! the row model misses most of a band and the band model calls about three rows where one is
//! labelled (docs/model.md, candidate B). Both models are trained on generated clouds only, by
//! the `bounded train` commands recorded in their files and in docs/model.md.

use crate::{Classifier, NnError};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// One of the embedded models; [`EmbeddedModel::Row`] is the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EmbeddedModel {
    /// Trained to call one row of points along each crease, as the PCEDNet and ABC clouds are
    /// labelled.
    #[default]
    Row,
    /// Trained to call bands: every point within 1.5 spacings of a crease or of a feature curve
    /// on a free-form surface (grooves, ridges, steps), as feature curves are often labelled.
    Band,
}

impl EmbeddedModel {
    /// Every embedded model, the default first.
    pub const ALL: [Self; 2] = [Self::Row, Self::Band];

    /// The model's name, as [`FromStr`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Row => "row",
            Self::Band => "band",
        }
    }

    /// The embedded model that `path` names when no file is there (`band` where `--embedded
    /// band` was meant): for a hint beside the error of loading it as a model file.
    pub fn named_by(path: &Path) -> Option<Self> {
        if path.exists() {
            return None;
        }
        path.to_str()?.parse().ok()
    }

    /// The model's classifier (two stages, 16 scales from 128 down to 10 neighbours).
    pub fn classifier(self) -> Result<Classifier, NnError> {
        Classifier::from_bytes(match self {
            Self::Row => include_bytes!("../models/default.bmodel"),
            Self::Band => include_bytes!("../models/band.bmodel"),
        })
    }
}

impl fmt::Display for EmbeddedModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for EmbeddedModel {
    type Err = NnError;

    fn from_str(text: &str) -> Result<Self, NnError> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == text)
            .ok_or_else(|| {
                NnError::InvalidConfig(format!(
                    "no embedded model is called `{text}` (there are `row` and `band`)"
                ))
            })
    }
}

/// The classifier embedded in the library by default ([`EmbeddedModel::Row`]).
pub fn default_model() -> Result<Classifier, NnError> {
    EmbeddedModel::default().classifier()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CLASS_NAMES;

    const SCALES: [usize; 16] = [
        128, 108, 91, 76, 64, 54, 45, 38, 32, 27, 23, 19, 16, 13, 11, 10,
    ];

    #[test]
    fn both_models_load_with_the_paper_network_at_16_scales_and_two_stages() {
        for which in EmbeddedModel::ALL {
            let classifier = which.classifier().unwrap();
            let file = classifier.file();
            assert_eq!(file.scales, SCALES, "{which}");
            // The default model adds the hull inset `h` to SPEC.md's 12 features per scale.
            let (features, first, second) = match which {
                EmbeddedModel::Row => (13, 6371, 7715),
                EmbeddedModel::Band => (12, 6179, 7523),
            };
            assert_eq!(file.feature_names.len(), features, "{which}");
            // SPEC.md's fusion tree over 16 scales (15 fusion layers) and its classifier: the
            // first fusion layers read two scales' features (8 pairs of 2 x features x 12).
            assert_eq!(file.model.n_params(), first, "{which}");
            assert_eq!(file.class_names, CLASS_NAMES);
            let context = classifier
                .second_stage()
                .expect("an auto-context second stage");
            assert_eq!(context.file().feature_names.len(), features + 7);
            assert_eq!(context.file().model.n_params(), second, "{which}");
        }
    }

    #[test]
    fn each_model_was_trained_for_its_convention() {
        let command = |which: EmbeddedModel| {
            which
                .classifier()
                .unwrap()
                .file()
                .provenance
                .command
                .clone()
        };
        let (row, band) = (command(EmbeddedModel::Row), command(EmbeddedModel::Band));
        assert!(!row.contains("band="), "{row}");
        // Every generated set of the band model, and its validation sets, label bands of 1.5.
        let sets = band.split("generated:").skip(1).collect::<Vec<_>>();
        assert_eq!(sets.len(), 8, "{band}");
        for set in sets {
            assert!(
                set.split_whitespace().next().unwrap().ends_with("band=1.5"),
                "{set}"
            );
        }
        assert_ne!(
            default_model().unwrap().file(),
            EmbeddedModel::Band.classifier().unwrap().file()
        );
    }

    #[test]
    fn names_round_trip_and_an_unknown_name_lists_the_known_ones() {
        for which in EmbeddedModel::ALL {
            assert_eq!(which.name().parse::<EmbeddedModel>().unwrap(), which);
        }
        assert_eq!(EmbeddedModel::default(), EmbeddedModel::Row);
        assert_eq!(
            EmbeddedModel::named_by(Path::new("band")),
            Some(EmbeddedModel::Band)
        );
        assert_eq!(EmbeddedModel::named_by(Path::new("bands")), None);
        // An existing file of that name is a model file, not a mistake.
        assert_eq!(
            EmbeddedModel::named_by(Path::new(env!("CARGO_MANIFEST_DIR"))),
            None
        );
        let e = "bands".parse::<EmbeddedModel>().unwrap_err().to_string();
        assert!(
            e.contains("`bands`") && e.contains("`row` and `band`"),
            "{e}"
        );
    }
}
