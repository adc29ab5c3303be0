//! `bounded train`: features of labelled clouds, computed once, then the classifier.

use super::training_clouds;
use crate::atomic;
use crate::cli::{FeatureGroupArg, NoiseAlong, TrainArgs};
use crate::progress::{self, FitBars};
use anyhow::{Context, Result, bail};
use bounded_data::dataset::TrainingSource;
use bounded_features::{FeatureConfig, FeatureGroups};
use bounded_nn::{ModelFile, N_CLASSES, Schedule, Widths, fit_stages};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

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
    let noise = &args.noise;
    let sources = (args.data.iter())
        .map(|spec| match TrainingSource::parse(spec)? {
            TrainingSource::Generated(config) => Ok(TrainingSource::Generated(
                (config.with_noise(noise.noise.as_deref(), noise.noise_along.into()))
                    .context("--noise")?,
            )),
            other => Ok(other),
        })
        .collect::<Result<Vec<_>>>()?;
    let generated = (sources.iter()).any(|s| matches!(s, TrainingSource::Generated(_)));
    if !generated && (noise.noise.is_some() || noise.noise_along != NoiseAlong::Any) {
        bail!("--noise and --noise-along apply to generated sets, and --data names none");
    }
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
