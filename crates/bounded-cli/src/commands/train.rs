//! `bounded train`: features of labelled clouds, computed once, then the classifier.

use super::sources::TrainingSource;
use crate::cli::{FeatureGroupArg, TrainArgs};
use crate::{atomic, progress};
use anyhow::{Context, Result, bail};
use bounded_data::LabelledCloud;
use bounded_features::{
    CONTEXT_NAMES, FeatureConfig, FeatureGroups, extract, extract_in_context, values_per_point,
    values_per_scale,
};
use bounded_nn::{Classifier, Dataset, ModelConfig, ModelFile, N_CLASSES, TrainConfig, train};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Features and labels of many clouds, concatenated (row-major, `per_point` values a row).
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
}

/// How long and how often to train.
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
    /// The network for `config`'s features, `in_context` of a first stage or not, with these
    /// widths.
    pub fn model(&self, config: &FeatureConfig, in_context: bool) -> ModelConfig {
        ModelConfig::new(config.scales.len(), values_per_scale(config, in_context))
            .with_fusion_widths(self.fusion.clone())
            .with_hidden_widths(self.hidden.clone())
    }
}

/// Computes the features of every cloud with `config`; given a first stage's `probabilities`
/// (every cloud's points in turn), each beside their context (for a second stage).
pub fn feature_set(
    clouds: &[(String, LabelledCloud)],
    config: &FeatureConfig,
    probabilities: Option<&[[f32; N_CLASSES]]>,
    step: &str,
) -> Result<FeatureSet> {
    let total = clouds.iter().map(|(_, c)| c.cloud.len()).sum::<usize>();
    let bar = progress::bar(step, total as u64, "points");
    if let Some(p) = probabilities
        && p.len() != total
    {
        bail!(
            "{} first-stage probabilities for {total} training points",
            p.len()
        );
    }
    let per_point = values_per_point(config, probabilities.is_some());
    let mut set = FeatureSet {
        features: Vec::with_capacity(total * per_point),
        labels: Vec::with_capacity(total),
        per_point,
        in_context: probabilities.is_some(),
    };
    for (name, labelled) in clouds {
        let cloud = &labelled.cloud;
        let features = match probabilities {
            None => extract(cloud, config),
            Some(all) => {
                let first = set.labels.len();
                extract_in_context(cloud, config, &all[first..first + cloud.len()])
            }
        }
        .with_context(|| name.clone())?;
        set.features.extend_from_slice(features.as_slice());
        set.labels.extend(labelled.labels.iter().map(|&c| c as u8));
        bar.inc(cloud.len() as u64);
    }
    bar.finish_and_clear();
    Ok(set)
}

/// Trains a classifier on `set` (computed with `config`) and packs it with its provenance.
pub fn fit(
    set: &FeatureSet,
    config: &FeatureConfig,
    schedule: &Schedule,
    widths: &Widths,
    command: String,
) -> Result<ModelFile> {
    let data = Dataset::new(&set.features, &set.labels, set.per_point)?;
    let train_config = TrainConfig::new(widths.model(config, set.in_context))
        .with_iterations(schedule.iterations)
        .with_runs(schedule.runs)
        .with_seed(schedule.seed);
    let bar = progress::bar("train", (schedule.iterations * schedule.runs) as u64, "its");
    let trained = train(&data, &train_config, |p| {
        bar.inc(1);
        if let Some(best) = p.best_val_loss {
            bar.set_message(format!(
                "run {}/{} loss {:.4} best val {best:.4}",
                p.run + 1,
                p.runs,
                p.loss
            ));
        }
    })?;
    bar.finish_and_clear();
    let context = set
        .in_context
        .then_some(CONTEXT_NAMES)
        .into_iter()
        .flatten();
    let names = config
        .groups
        .names()
        .into_iter()
        .chain(context)
        .map(str::to_string)
        .collect();
    Ok(ModelFile::from_trained(
        &trained,
        config.scales.clone(),
        names,
        command,
    )?)
}

/// Seconds spent on the training clouds' features and on training.
pub struct Seconds {
    /// Feature extraction (both passes for two stages).
    pub features: f64,
    /// Training (both networks for two stages).
    pub training: f64,
}

/// Features of `clouds`, then the network; with `context`, then the context features of its
/// probabilities and the second network, packed as one two-stage model.
pub fn fit_stages(
    clouds: &[(String, LabelledCloud)],
    config: &FeatureConfig,
    schedule: &Schedule,
    widths: &Widths,
    context: bool,
    command: String,
) -> Result<(ModelFile, Seconds)> {
    let mut seconds = Seconds {
        features: 0.0,
        training: 0.0,
    };
    let t = Instant::now();
    let set = feature_set(clouds, config, None, "features")?;
    seconds.features += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let file = fit(&set, config, schedule, widths, command.clone())?;
    seconds.training += t.elapsed().as_secs_f64();
    if !context {
        return Ok((file, seconds));
    }
    let t = Instant::now();
    let mut probabilities = vec![[0f32; N_CLASSES]; set.len()];
    Classifier::from_file(file.clone())?.predict(&set.features, &mut probabilities)?;
    drop(set);
    let set = feature_set(clouds, config, Some(&probabilities), "context")?;
    seconds.features += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let second = fit(&set, config, schedule, widths, command)?;
    seconds.training += t.elapsed().as_secs_f64();
    Ok((file.with_second_stage(second)?, seconds))
}

/// Writes a model file atomically.
pub fn save(file: &ModelFile, path: &Path) -> Result<()> {
    let bytes = file.to_bytes()?;
    atomic::write_with(path, |out| Ok(out.write_all(&bytes)?))
}

/// The feature groups selected on the command line.
pub fn groups(selected: &[FeatureGroupArg]) -> Result<FeatureGroups> {
    let has = |g| selected.contains(&g);
    let groups = FeatureGroups {
        sigma: false,
        sigma_u: has(FeatureGroupArg::SigmaU),
        sigma_l: has(FeatureGroupArg::SigmaL),
        d: has(FeatureGroupArg::D),
        s: has(FeatureGroupArg::S),
        c: has(FeatureGroupArg::C),
    };
    if groups.count() == 0 {
        bail!("--features selects no feature group");
    }
    Ok(groups)
}

pub fn run(args: &TrainArgs) -> Result<()> {
    let start = Instant::now();
    let config = FeatureConfig {
        scales: args.scales.clone(),
        groups: groups(&args.features)?,
    };
    config.validate()?;
    let defaults = Widths::default();
    let widths = Widths {
        fusion: args.fusion_widths.clone().unwrap_or(defaults.fusion),
        hidden: args.hidden_widths.clone().unwrap_or(defaults.hidden),
    };
    // A bad width fails now, not after the features.
    widths.model(&config, args.context).validate()?;
    // A bad generated set or noise option fails now too.
    let sources = TrainingSource::parse_all(&args.data, &args.noise)?;
    let mut clouds = Vec::new();
    for (source, spec) in sources.iter().zip(&args.data) {
        let loading = progress::spinner("load");
        loading.set_message(spec.clone());
        let loaded = source.load();
        loading.finish_and_clear();
        clouds.extend(loaded?);
    }
    let mut counts = [0usize; N_CLASSES];
    for (_, labelled) in &clouds {
        for &l in &labelled.labels {
            counts[l as usize] += 1;
        }
    }
    let schedule = Schedule {
        iterations: args.iterations,
        runs: args.runs,
        seed: args.seed,
    };
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let (file, seconds) = fit_stages(&clouds, &config, &schedule, &widths, args.context, command)?;
    save(&file, &args.output)?;
    let points: usize = counts.iter().sum();
    eprintln!(
        "{} clouds, {} points ({} sharp, {} boundary): features {:.1} s, \
         total {:.1} s, best validation loss {:.4}; wrote {}",
        clouds.len(),
        points,
        counts[1],
        counts[2],
        seconds.features,
        start.elapsed().as_secs_f64(),
        file.provenance.val_loss,
        args.output.display()
    );
    Ok(())
}
