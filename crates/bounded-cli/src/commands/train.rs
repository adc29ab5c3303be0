//! `bounded train`: features of labelled clouds, computed once, then the classifier.

use super::training_clouds;
use crate::cli::{FeatureGroupArg, NoiseAlong, TrainArgs};
use crate::progress::{self, FitBars};
use anyhow::{Context, Result, bail};
use bounded_data::dataset::TrainingSource;
use bounded_features::{ContextSet, FeatureConfig, FeatureGroups};
use bounded_geom::Class;
use bounded_nn::calibration::{describe, with_chosen_sensitivity};
use bounded_nn::{Schedule, Widths, fit_stages};
use std::time::Instant;

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
        h: has(FeatureGroupArg::H),
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
        context: if args.context_line {
            ContextSet::WithLine
        } else {
            ContextSet::Neighbourhood
        },
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
    let (levels, along) = (noise.noise.as_deref(), noise.noise_along.into());
    let with_noise = |spec: &&String| {
        (TrainingSource::parse(spec)?.with_noise(levels, along)).context("--noise")
    };
    let specs: Vec<_> = args.data.iter().chain(&args.calibrate_on).collect();
    let sources = specs.iter().map(with_noise).collect::<Result<Vec<_>>>()?;
    let generated = (sources.iter()).any(|s| matches!(s, TrainingSource::Generated(_)));
    if !generated && (noise.noise.is_some() || noise.noise_along != NoiseAlong::Any) {
        bail!("--noise and --noise-along apply to generated sets, and none is given");
    }
    let mut clouds = Vec::new();
    for (source, spec) in sources.iter().zip(specs) {
        clouds.push(progress::spinning("load", spec, || source.load())?);
    }
    let validation: Vec<_> = (clouds.split_off(args.data.len()).into_iter())
        .flatten()
        .collect();
    let clouds: Vec<_> = clouds.into_iter().flatten().collect();
    let labels: Vec<Class> = clouds.iter().flat_map(|c| c.1.labels.clone()).collect();
    let [_, sharp, boundary] = Class::counts(&labels);
    let schedule = Schedule {
        iterations: args.iterations,
        runs: args.runs,
        seed: args.seed,
    };
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let (file, seconds) = FitBars::around(|progress| {
        let clouds = training_clouds(&clouds);
        fit_stages(
            &clouds,
            &config,
            &schedule,
            &widths,
            args.context,
            command,
            progress,
        )
    })?;
    let validation = training_clouds(&validation);
    let (file, _) = progress::spinning("calibrate", "", || {
        with_chosen_sensitivity(file, &validation)
    })?;
    file.save(&args.output)?;
    eprintln!(
        "{} clouds, {} points ({} sharp, {} boundary): features {:.1} s, \
         total {:.1} s, best validation loss {:.4}, deciding by {}; wrote {}",
        clouds.len(),
        labels.len(),
        sharp,
        boundary,
        seconds.features,
        start.elapsed().as_secs_f64(),
        file.provenance.val_loss,
        describe(file.sensitivity),
        args.output.display()
    );
    Ok(())
}
