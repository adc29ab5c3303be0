//! `bounded generate`: write a synthetic labelled set as binary PLY files.

use crate::cli::GenerateArgs;
use crate::progress;
use anyhow::{Context, Result};
use bounded_data::dataset::write_generated;
use bounded_data::synth::{SetConfig, SetKind};
use std::num::NonZeroUsize;
use std::time::Instant;

pub fn run(args: &GenerateArgs) -> Result<()> {
    let start = Instant::now();
    // `freeform:depth=1:band=1.5` or `cad:faces=3` carries options, as `train --data` does.
    let mut fields = args.kind.split(':');
    let kind = SetKind::from_name(fields.next().unwrap_or_default()).context("--kind")?;
    let options: Vec<&str> = fields.collect();
    let config = SetConfig::new(kind, args.seed, args.shapes.map_or(60, NonZeroUsize::get))
        .with_options(&options)
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
