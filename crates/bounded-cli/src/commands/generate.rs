//! `bounded generate`: write a synthetic labelled set as binary PLY files.

use crate::cli::GenerateArgs;
use crate::progress;
use anyhow::{Context, Result};
use bounded_data::dataset::write_generated;
use bounded_data::synth::SetConfig;
use std::num::NonZeroUsize;
use std::time::Instant;

pub fn run(args: &GenerateArgs) -> Result<()> {
    let start = Instant::now();
    // `freeform:depth=1:band=1.5` carries label rules, parsed as `train --data` parses them.
    let (kind, rules) = match args.kind.split_once(':') {
        Some((kind, rules)) => (kind, format!(":{rules}")),
        None => (args.kind.as_str(), String::new()),
    };
    let shapes = args.shapes.map_or(60, NonZeroUsize::get);
    let config = SetConfig::from_spec(&format!("generated:{kind}:{}:{shapes}{rules}", args.seed))
        .context("--kind")?
        .with_noise(args.noise.noise.as_deref(), args.noise.noise_along.into())
        .context("--noise")?;
    let bar = progress::bar("generate", config.shapes as u64, "clouds");
    let points = write_generated(&config, &args.output, &|| bar.inc(1));
    bar.finish_and_clear();
    let points = points?;
    eprintln!(
        "{} clouds, {points} points, in {} ({:.1} s)",
        config.shapes,
        args.output.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
