//! Training on labelled clouds: their features computed once, the network fitted (best of
//! several runs), and for a two-stage model the context of its probabilities and a second
//! network over it, packed as one model file.

use std::time::Instant;

use bounded_features::{
    FeatureConfig, extract, extract_in_context, values_per_point, values_per_scale,
};
use bounded_geom::{Class, PointCloud};

use crate::{
    Classifier, Dataset, ModelConfig, ModelFile, N_CLASSES, NnError, Progress, TrainConfig, train,
};

/// A labelled cloud to train on (or to evaluate, see [`crate::report::evaluate`]).
#[derive(Debug, Clone, Copy)]
pub struct TrainingCloud<'a> {
    /// Its name, for error messages.
    pub name: &'a str,
    /// The points.
    pub cloud: &'a PointCloud,
    /// One class per point.
    pub labels: &'a [Class],
}

impl<'a> TrainingCloud<'a> {
    /// The cloud `name` of points `cloud` labelled `labels` (one class per point).
    pub fn new(name: &'a str, cloud: &'a PointCloud, labels: &'a [Class]) -> Self {
        Self {
            name,
            cloud,
            labels,
        }
    }
}

/// Features and labels of many clouds, concatenated (row-major, `per_point` values a row).
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureSet {
    /// Feature rows.
    pub features: Vec<f32>,
    /// Class code per row.
    pub labels: Vec<u8>,
    /// Values per row.
    pub per_point: usize,
    /// Whether every scale's features are followed by the context of a first stage.
    pub in_context: bool,
}

impl FeatureSet {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// True for no rows.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// The rows restricted to `columns` (indices into a row), in that order.
    pub fn select(&self, columns: &[usize]) -> FeatureSet {
        let mut features = Vec::with_capacity(self.len() * columns.len());
        for row in self.features.chunks_exact(self.per_point) {
            features.extend(columns.iter().map(|&c| row[c]));
        }
        FeatureSet {
            features,
            labels: self.labels.clone(),
            per_point: columns.len(),
            in_context: self.in_context,
        }
    }
}

/// Column indices of `target`'s values within rows computed with `full` (for
/// [`FeatureSet::select`]): the nested neighbourhoods make a smaller configuration's features
/// a subset of a larger one's, so ablations need no second feature pass. An error when
/// `target` asks for a scale or feature that `full` lacks.
pub fn columns(full: &FeatureConfig, target: &FeatureConfig) -> Result<Vec<usize>, NnError> {
    let full_names = full.groups.names();
    let per_scale = full_names.len();
    let mut columns = Vec::new();
    for scale in &target.scales {
        let s = (full.scales.iter().position(|k| k == scale)).ok_or_else(|| {
            NnError::InvalidConfig(format!("scale {scale} is not among {:?}", full.scales))
        })?;
        for name in target.groups.names() {
            let v = (full_names.iter().position(|n| *n == name))
                .ok_or_else(|| NnError::InvalidConfig(format!("feature {name} not computed")))?;
            columns.push(s * per_scale + v);
        }
    }
    Ok(columns)
}

/// How long and how often to train.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// Iterations per run.
    pub iterations: usize,
    /// Runs; the lowest validation loss wins.
    pub runs: usize,
    /// Seed of the first run.
    pub seed: u64,
}

/// Layer widths of the network (see [`ModelConfig`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Widths {
    /// Output width of each fusion level.
    pub fusion: Vec<usize>,
    /// Widths of the hidden layers.
    pub hidden: Vec<usize>,
}

impl Default for Widths {
    /// SPEC.md's network (about 1.6k parameters at 4 scales x 12 features).
    fn default() -> Self {
        let spec = ModelConfig::new(4, 12);
        Self {
            fusion: spec.fusion_widths,
            hidden: spec.hidden_widths,
        }
    }
}

impl Widths {
    /// SPEC.md's network and two wider ones: the bench's width ablation (measured: wider
    /// helps every set a little, the noise gap hardly).
    pub fn ablations() -> [Widths; 3] {
        let widths = |fusion: [usize; 2], hidden: [usize; 2]| Widths {
            fusion: fusion.to_vec(),
            hidden: hidden.to_vec(),
        };
        [
            Widths::default(),
            widths([16, 24], [24, 24]),
            widths([24, 32], [48, 48]),
        ]
    }

    /// The network for `config`'s features, `in_context` of a first stage or not, with these
    /// widths.
    pub fn model(&self, config: &FeatureConfig, in_context: bool) -> ModelConfig {
        ModelConfig::new(config.scales.len(), values_per_scale(config, in_context))
            .with_fusion_widths(self.fusion.clone())
            .with_hidden_widths(self.hidden.clone())
    }
}

/// What a fit is doing, for a progress display.
#[derive(Debug, Clone, Copy)]
pub enum Step<'a> {
    /// Features of the training clouds: points done of all, with a first stage's context or
    /// not.
    Features {
        /// Points done.
        done: usize,
        /// Points in all clouds.
        total: usize,
        /// Whether these are the second stage's features (with context).
        context: bool,
    },
    /// Training, after every iteration.
    Training(&'a Progress),
}

/// Computes the features of every cloud with `config`; given a first stage's `probabilities`
/// (every cloud's points in turn), each beside their context (for a second stage).
pub fn feature_set(
    clouds: &[TrainingCloud<'_>],
    config: &FeatureConfig,
    probabilities: Option<&[[f32; N_CLASSES]]>,
    progress: &mut dyn FnMut(Step<'_>),
) -> Result<FeatureSet, NnError> {
    let total = clouds.iter().map(|c| c.cloud.len()).sum::<usize>();
    if let Some(p) = probabilities
        && p.len() != total
    {
        return Err(NnError::Shape(format!(
            "{} first-stage probabilities for {total} training points",
            p.len()
        )));
    }
    let mut set = FeatureSet {
        features: Vec::with_capacity(total * values_per_point(config, probabilities.is_some())),
        labels: Vec::with_capacity(total),
        per_point: values_per_point(config, probabilities.is_some()),
        in_context: probabilities.is_some(),
    };
    for c in clouds {
        let features = match probabilities {
            None => extract(c.cloud, config),
            Some(all) => {
                let first = set.labels.len();
                extract_in_context(c.cloud, config, &all[first..first + c.cloud.len()])
            }
        }
        .map_err(|source| NnError::Cloud {
            name: c.name.to_string(),
            source: Box::new(source.into()),
        })?;
        set.features.extend_from_slice(features.as_slice());
        set.labels.extend(c.labels.iter().map(|&l| l as u8));
        progress(Step::Features {
            done: set.labels.len(),
            total,
            context: set.in_context,
        });
    }
    Ok(set)
}

/// Trains a classifier on `set` (computed with `config`) and packs it with its provenance
/// (`command`, the line that trained it).
pub fn fit(
    set: &FeatureSet,
    config: &FeatureConfig,
    schedule: &Schedule,
    widths: &Widths,
    command: String,
    progress: &mut dyn FnMut(Step<'_>),
) -> Result<ModelFile, NnError> {
    let data = Dataset::new(&set.features, &set.labels, set.per_point)?;
    let train_config = TrainConfig::new(widths.model(config, set.in_context))
        .with_iterations(schedule.iterations)
        .with_runs(schedule.runs)
        .with_seed(schedule.seed);
    let trained = train(&data, &train_config, |p| progress(Step::Training(p)))?;
    let context = (set.in_context.then(|| config.context.names()))
        .into_iter()
        .flatten();
    let names = (config.groups.names().into_iter())
        .chain(context)
        .map(str::to_string)
        .collect();
    ModelFile::from_trained(&trained, config.scales.clone(), names, command)
}

/// Seconds spent on the training clouds' features and on training.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seconds {
    /// Feature extraction (both passes for two stages).
    pub features: f64,
    /// Training (both networks for two stages).
    pub training: f64,
}

/// Features of `clouds`, then the network; with `context`, then the context features of its
/// probabilities and the second network, packed as one two-stage model.
pub fn fit_stages(
    clouds: &[TrainingCloud<'_>],
    config: &FeatureConfig,
    schedule: &Schedule,
    widths: &Widths,
    context: bool,
    command: String,
    progress: &mut dyn FnMut(Step<'_>),
) -> Result<(ModelFile, Seconds), NnError> {
    let mut seconds = Seconds {
        features: 0.0,
        training: 0.0,
    };
    // Refused before the features are computed, not after.
    widths.model(config, false).validate()?;
    let t = Instant::now();
    let set = feature_set(clouds, config, None, progress)?;
    seconds.features += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let file = fit(&set, config, schedule, widths, command.clone(), progress)?;
    seconds.training += t.elapsed().as_secs_f64();
    if !context {
        return Ok((file, seconds));
    }
    let t = Instant::now();
    let mut probabilities = vec![[0f32; N_CLASSES]; set.len()];
    Classifier::from_file(file.clone())?.predict(&set.features, &mut probabilities)?;
    drop(set);
    let set = feature_set(clouds, config, Some(&probabilities), progress)?;
    seconds.features += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let second = fit(&set, config, schedule, widths, command, progress)?;
    seconds.training += t.elapsed().as_secs_f64();
    Ok((file.with_second_stage(second)?, seconds))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bounded_features::FeatureGroups;

    #[test]
    fn columns_of_a_smaller_configuration() {
        // Per scale: sigma_1..3, d_perp, d_par.
        let groups = FeatureGroups {
            sigma: true,
            d: true,
            ..FeatureGroups::NONE
        };
        let full = FeatureConfig {
            scales: vec![16, 8],
            groups,
            ..FeatureConfig::default()
        };
        let d_only = FeatureGroups {
            sigma: false,
            ..groups
        };
        let target = |scales: Vec<usize>, groups| FeatureConfig {
            scales,
            groups,
            ..FeatureConfig::default()
        };
        assert_eq!(columns(&full, &target(vec![8], d_only)).unwrap(), [8, 9]);
        assert_eq!(
            columns(&full, &target(vec![16, 8], groups)).unwrap(),
            (0..10).collect::<Vec<_>>()
        );
        let e = columns(&full, &target(vec![4], d_only)).unwrap_err();
        assert!(
            e.to_string().contains("scale 4 is not among [16, 8]"),
            "{e}"
        );
        let e = columns(&full, &target(vec![8], FeatureGroups::BOUNDED)).unwrap_err();
        assert!(
            e.to_string().contains("feature sigma_u1 not computed"),
            "{e}"
        );
    }
}
