//! Detection: a model's stages run over a point cloud, one library call.
//!
//! The features are streamed block by block straight into the classifier, so memory stays
//! `O(points + block)` whatever the cloud's size. A two-stage model needs the first stage's
//! probabilities over every point's neighbourhood; both stages share one neighbour search and
//! one feature pass ([`extract_chunks_staged`]), so the second stage costs its context and its
//! network, not a second pass over the cloud.

use std::path::Path;
use std::str::FromStr;
use std::time::{Duration, Instant};

use bounded_features::{
    ContextSet, DEFAULT_CHUNK_POINTS, FeatureBlock, FeatureConfig, FeatureGroups, extract_chunks,
    extract_chunks_staged,
};
use bounded_geom::{Class, PointCloud};

use crate::{Classifier, EmbeddedModel, N_CLASSES, NnError, argmax, default_model};

/// A model ready to label point clouds: its networks, the feature extraction it was trained
/// with (or scales that replace the model's) and the decision rule.
///
/// ```
/// use bounded_geom::{Class, PointCloud};
/// use bounded_nn::Detector;
///
/// // A folded sheet: two planes meeting at a right angle along the line x = 0.
/// let positions: Vec<[f64; 3]> = (0..40 * 40)
///     .map(|i| {
///         let (u, v) = ((i % 40) as f64 - 20.0, (i / 40) as f64);
///         if u < 0.0 { [u, v, 0.0] } else { [0.0, v, u] }
///     })
///     .collect();
/// let cloud = PointCloud::from_f64(&positions)?;
/// let detector = Detector::embedded()?; // both stages of the embedded model
/// let detection = detector.detect(&cloud)?;
/// assert_eq!(detection.classes.len(), cloud.len());
/// // A point on the fold, midway along it, is a sharp edge; one far from it is not.
/// assert_eq!(detection.classes[20 * 40 + 20], Class::Sharp);
/// assert_eq!(detection.classes[20 * 40 + 10], Class::NonEdge);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct Detector {
    classifier: Classifier,
    config: FeatureConfig,
    /// The decision rule asked for ([`Detector::with_sensitivity`],
    /// [`Detector::most_probable_class`]); without one, the model's.
    decision: Option<Option<f32>>,
}

/// A decision rule as users spell it (`--sensitivity`, Python's `sensitivity=`): a number,
/// or `argmax` for the most probable class. The number's range is checked by
/// [`Detector::with_decision`].
///
/// ```
/// use bounded_nn::Decision;
///
/// assert_eq!("argmax".parse::<Decision>()?, Decision::MostProbableClass);
/// assert_eq!("0.6".parse::<Decision>()?, Decision::Sensitivity(0.6));
/// assert!("most".parse::<Decision>().is_err());
/// # Ok::<(), bounded_nn::NnError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    /// Every point gets its most probable class.
    MostProbableClass,
    /// Sharp where p_sharp reaches 1 - the sensitivity ([`Detector::with_sensitivity`]).
    Sensitivity(f32),
}

impl FromStr for Decision {
    type Err = NnError;

    fn from_str(text: &str) -> Result<Self, NnError> {
        match text {
            "argmax" => Ok(Self::MostProbableClass),
            _ => text.parse().map(Self::Sensitivity).map_err(|_| {
                NnError::InvalidConfig(format!(
                    "sensitivity `{text}` is neither a number nor `argmax`"
                ))
            }),
        }
    }
}

/// Per-point results of [`Detector::detect`].
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// Class probabilities (non-edge, sharp, boundary) per point, in input order.
    pub probabilities: Vec<[f32; N_CLASSES]>,
    /// The class of every point, by the detector's decision rule.
    pub classes: Vec<Class>,
    /// Wall time of the whole run (neighbour search, features and classification).
    pub elapsed: Duration,
    /// Wall time spent in the networks alone.
    pub classification: Duration,
    /// Points whose features were computed twice: the halos of blocks whose second stage
    /// could not wait for the first stage of their neighbours' block (see
    /// `bounded_features::extract_chunks_staged`).
    pub recomputed: usize,
}

/// What [`Detector::detect_blocks`] spent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Work {
    /// Wall time in the networks.
    pub classification: Duration,
    /// Points whose features were computed twice (see [`Detection::recomputed`]).
    pub recomputed: usize,
}

impl Detection {
    /// Points per class (non-edge, sharp, boundary).
    pub fn class_counts(&self) -> [usize; N_CLASSES] {
        Class::counts(&self.classes)
    }

    /// The classes as their integer codes.
    pub fn codes(&self) -> Vec<u8> {
        Class::codes(&self.classes)
    }
}

impl Detector {
    /// The detector of `classifier` (one or two stages) at its own scales.
    pub fn new(classifier: Classifier) -> Result<Self, NnError> {
        let config = trained_config(&classifier)?;
        Ok(Self {
            classifier,
            config,
            decision: None,
        })
    }

    /// The detector of the embedded default model (two stages).
    pub fn embedded() -> Result<Self, NnError> {
        Self::new(default_model()?)
    }

    /// The detector of one of the embedded models (two stages each).
    pub fn embedded_model(which: EmbeddedModel) -> Result<Self, NnError> {
        Self::new(which.classifier()?)
    }

    /// The detector of the model file at `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, NnError> {
        Self::new(Classifier::load(path)?)
    }

    /// Replaces the model's neighbourhood sizes by `scales` (as many, largest first): larger
    /// ones see through more noise but blur small parts and thin walls.
    pub fn with_scales(mut self, scales: &[usize]) -> Result<Self, NnError> {
        let trained = &self.classifier.file().scales;
        if scales.len() != trained.len() {
            return Err(NnError::InvalidConfig(format!(
                "{} scales {scales:?} given, but the model was trained on {} ({trained:?})",
                scales.len(),
                trained.len()
            )));
        }
        let config = FeatureConfig {
            scales: scales.to_vec(),
            groups: self.config.groups,
            context: self.config.context,
        };
        config.validate()?;
        self.config = config;
        Ok(self)
    }

    /// Runs the first network of a two-stage model alone: about half the time, at the first
    /// stage's quality. An error for a one-stage model, where it would silently change nothing.
    pub fn first_stage_only(mut self) -> Result<Self, NnError> {
        if self.classifier.second_stage().is_none() {
            return Err(NnError::InvalidConfig(
                "the first stage alone was asked for, but this model has one stage".into(),
            ));
        }
        self.classifier = Classifier::from_file(self.classifier.file().first_stage())?;
        Ok(self)
    }

    /// Labels a point sharp when its sharp probability reaches `1 - sensitivity` (and is at
    /// least its boundary probability); others get the more probable of non-edge and
    /// boundary. Higher sensitivity, more sharp points. `sensitivity` must lie strictly
    /// between 0 and 1. Without it (or [`most_probable_class`](Self::most_probable_class)),
    /// the detector decides by the rule the model file records (`ModelFile::sensitivity`,
    /// chosen on validation clouds when it was trained).
    pub fn with_sensitivity(mut self, sensitivity: f32) -> Result<Self, NnError> {
        if !(sensitivity > 0.0 && sensitivity < 1.0) {
            return Err(NnError::InvalidConfig(format!(
                "sensitivity {sensitivity} is not strictly between 0 and 1"
            )));
        }
        self.decision = Some(Some(sensitivity));
        Ok(self)
    }

    /// Labels every point with its most probable class, whatever the model file records.
    pub fn most_probable_class(mut self) -> Self {
        self.decision = Some(None);
        self
    }

    /// [`with_sensitivity`](Self::with_sensitivity) or
    /// [`most_probable_class`](Self::most_probable_class), as `decision` names.
    pub fn with_decision(self, decision: Decision) -> Result<Self, NnError> {
        match decision {
            Decision::MostProbableClass => Ok(self.most_probable_class()),
            Decision::Sensitivity(s) => self.with_sensitivity(s),
        }
    }

    /// The sensitivity this detector decides at (`None`: the most probable class).
    pub fn sensitivity(&self) -> Option<f32> {
        (self.decision).unwrap_or(self.classifier.file().sensitivity)
    }

    /// The networks this detector runs.
    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    /// The feature extraction this detector runs (the model's, or the scales given).
    pub fn feature_config(&self) -> &FeatureConfig {
        &self.config
    }

    /// The class of a point with `probabilities`, by this detector's decision rule.
    pub fn decide(&self, probabilities: &[f32; N_CLASSES]) -> Class {
        class_at(probabilities, self.sensitivity())
    }

    /// Classifies every point of `cloud`.
    pub fn detect(&self, cloud: &PointCloud) -> Result<Detection, NnError> {
        self.detect_with_progress(cloud, &mut |_, _| {})
    }

    /// [`detect`](Self::detect), calling `progress(points done, points)` after every block.
    pub fn detect_with_progress(
        &self,
        cloud: &PointCloud,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Detection, NnError> {
        let start = Instant::now();
        let n = cloud.len();
        let mut probabilities = vec![[0f32; N_CLASSES]; n];
        let mut done = 0;
        let work = self.detect_blocks(cloud, |points, block| {
            for (&i, p) in points.iter().zip(block) {
                probabilities[i as usize] = *p;
            }
            done += points.len();
            progress(done, n);
        })?;
        let classes = probabilities.iter().map(|p| self.decide(p)).collect();
        Ok(Detection {
            probabilities,
            classes,
            elapsed: start.elapsed(),
            classification: work.classification,
            recomputed: work.recomputed,
        })
    }

    /// The streaming form of [`detect`](Self::detect): calls `f(points, probabilities)` with
    /// the cloud indices and the final probabilities of one block of points at a time
    /// (spatially coherent, in Morton order), every point exactly once. Returns what the
    /// work took. A block's probabilities are final when it is handed out: a
    /// caller that writes results as they come needs no array for the whole cloud.
    pub fn detect_blocks(
        &self,
        cloud: &PointCloud,
        mut f: impl FnMut(&[u32], &[[f32; N_CLASSES]]),
    ) -> Result<Work, NnError> {
        self.detect_blocks_with_reach(cloud, |points, probabilities, _| f(points, probabilities))
    }

    /// [`detect_blocks`](Self::detect_blocks), handing `f` each point's reach too: every
    /// position its result was computed from lies within that distance of it, in the
    /// cloud's offsets (see `bounded_features::FeatureBlock::reach`; for a two-stage model,
    /// the second stage's). A point of a part of a larger cloud has the result it has in the
    /// whole cloud when the part holds every point of the whole within its reach (and the
    /// part keeps the whole's positions and point order).
    pub fn detect_blocks_with_reach(
        &self,
        cloud: &PointCloud,
        mut f: impl FnMut(&[u32], &[[f32; N_CLASSES]], &[f32]),
    ) -> Result<Work, NnError> {
        let k0 = self.config.largest_scale();
        if cloud.len() < k0 {
            return Err(NnError::TooFewPoints {
                points: cloud.len(),
                scale: k0,
            });
        }
        let mut classification = Duration::ZERO;
        let mut failure = None;
        let mut out = Vec::new();
        let mut classify = |classifier: &Classifier, block: &FeatureBlock, out: &mut [[f32; 3]]| {
            if failure.is_some() {
                return;
            }
            let t = Instant::now();
            match classifier.predict(block.values(), out) {
                Ok(()) if out.iter().flatten().all(|p| p.is_finite()) => {}
                Ok(()) => failure = Some(NnError::NonFinite),
                Err(e) => failure = Some(e),
            }
            classification += t.elapsed();
        };
        let recomputed = match self.classifier.second_stage() {
            None => extract_chunks(cloud, &self.config, DEFAULT_CHUNK_POINTS, |block| {
                out.resize(block.len(), [0.0; N_CLASSES]);
                classify(&self.classifier, block, &mut out);
                f(block.points(), &out, block.reach());
            })
            .map(|()| 0)?,
            Some(second) => {
                // Both stages' blocks go through `classify`; the two closures take turns.
                let classify = std::cell::RefCell::new(classify);
                extract_chunks_staged(
                    cloud,
                    &self.config,
                    DEFAULT_CHUNK_POINTS,
                    |block, probabilities| {
                        (classify.borrow_mut())(&self.classifier, block, probabilities)
                    },
                    |block| {
                        out.resize(block.len(), [0.0; N_CLASSES]);
                        (classify.borrow_mut())(second, block, &mut out);
                        f(block.points(), &out, block.reach());
                    },
                )?
            }
        };
        match failure {
            Some(e) => Err(e),
            None => Ok(Work {
                classification,
                recomputed,
            }),
        }
    }
}

/// The class of a point with `probabilities` at `sensitivity` (see
/// [`Detector::with_sensitivity`]; `None`: the most probable class), so that one detection can
/// be scored at many sensitivities.
pub fn class_at(probabilities: &[f32; N_CLASSES], sensitivity: Option<f32>) -> Class {
    let [non_edge, sharp, boundary] = *probabilities;
    let code = match sensitivity {
        None => argmax(probabilities),
        Some(s) if sharp >= 1.0 - s && sharp >= boundary => Class::Sharp as u8,
        Some(_) if boundary > non_edge => Class::Boundary as u8,
        Some(_) => Class::NonEdge as u8,
    };
    Class::from_code(code).unwrap_or(Class::NonEdge)
}

/// The feature extraction `classifier` was trained with, checked against what this build
/// computes (the feature names of both stages).
fn trained_config(classifier: &Classifier) -> Result<FeatureConfig, NnError> {
    let file = classifier.file();
    let groups = groups_named(&file.feature_names).ok_or_else(|| {
        NnError::InvalidConfig(format!(
            "the model's features [{}] are not a feature set this build computes",
            file.feature_names.join(", ")
        ))
    })?;
    // The context the second stage reads, by its names after the first stage's features.
    let context = match &file.second_stage {
        None => ContextSet::default(),
        Some(second) => {
            let reads = |c: &ContextSet| {
                (file.feature_names.iter().map(String::as_str))
                    .chain(c.names())
                    .eq(second.feature_names.iter().map(String::as_str))
            };
            *ContextSet::ALL.iter().find(|c| reads(c)).ok_or_else(|| {
                NnError::InvalidConfig(format!(
                    "the model's second stage reads [{}], not the first stage's features and a \
                     context this build computes",
                    second.feature_names.join(", ")
                ))
            })?
        }
    };
    let config = FeatureConfig {
        scales: file.scales.clone(),
        groups,
        context,
    };
    config.validate()?;
    Ok(config)
}

/// The feature groups whose value names are exactly `names`.
fn groups_named(names: &[String]) -> Option<FeatureGroups> {
    (0u8..128)
        .map(|bits| FeatureGroups {
            sigma: bits & 1 != 0,
            sigma_u: bits & 2 != 0,
            sigma_l: bits & 4 != 0,
            d: bits & 8 != 0,
            s: bits & 16 != 0,
            c: bits & 32 != 0,
            h: bits & 64 != 0,
        })
        .find(|g| (g.names().iter().copied()).eq(names.iter().map(String::as_str)))
}
