//! `bounded train`: features of labelled clouds, computed once, then the classifier.

use super::sources::TrainingSource;
use crate::cli::{FeatureGroupArg, TrainArgs};
use crate::progress;
use anyhow::{Result, bail};
use bounded_data::LabelledCloud;
use bounded_features::{FeatureConfig, FeatureGroups};
use bounded_nn::{ModelFile, N_CLASSES, Schedule, Step, TrainingCloud, Widths, fit_stages};
use indicatif::ProgressBar;
use std::path::Path;
use std::time::Instant;

/// A progress display for the library's fit steps: a bar for features, one for training.
pub struct FitBars {
    bar: Option<(bool, ProgressBar)>,
}

impl FitBars {
    /// No bar yet.
    pub fn new() -> Self {
        Self { bar: None }
    }

    /// Shows `step`, starting a new bar when the step changes.
    pub fn show(&mut self, step: Step<'_>) {
        let training = matches!(step, Step::Training(_));
        if self.bar.as_ref().is_some_and(|(t, _)| *t != training) {
            self.finish();
        }
        match step {
            Step::Features {
                done,
                total,
                context,
            } => {
                let (_, bar) = self.bar.get_or_insert_with(|| {
                    let name = if context { "context" } else { "features" };
                    (false, progress::bar(name, total as u64, "points"))
                });
                bar.set_position(done as u64);
            }
            Step::Training(p) => {
                let (_, bar) = self.bar.get_or_insert_with(|| {
                    (true, progress::bar("train", (p.iterations * p.runs) as u64, "its"))
                });
                bar.inc(1);
                if let Some(best) = p.best_val_loss {
                    bar.set_message(format!(
                        "run {}/{} loss {:.4} best val {best:.4}",
                        p.run + 1,
                        p.runs,
                        p.loss
                    ));
                }
            }
        }
    }

    /// Clears the current bar.
    pub fn finish(&mut self) {
        if let Some((_, bar)) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

/// The clouds as the library's training clouds.
pub fn training_clouds(clouds: &[(String, LabelledCloud)]) -> Vec<TrainingCloud<'_>> {
    (clouds.iter())
        .map(|(name, c)| TrainingCloud {
            name,
            cloud: &c.cloud,
            labels: &c.labels,
        })
        .collect()
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
    let mut bars = FitBars::new();
    let (file, seconds) = fit_stages(
        &training_clouds(&clouds),
        &config,
        &schedule,
        &widths,
        args.context,
        command,
        &mut |step| bars.show(step),
    )?;
    bars.finish();
    file.save(&args.output)?;
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
