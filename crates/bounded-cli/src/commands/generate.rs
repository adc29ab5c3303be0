//! `bounded generate`: write a synthetic labelled set as binary PLY files.

use crate::cli::GenerateArgs;
use crate::progress;
use anyhow::{Context, Result};
use bounded_data::format;
use bounded_data::synth::{SetConfig, SetKind, generate_one};
use rayon::prelude::*;
use std::num::NonZeroUsize;
use std::time::Instant;

pub fn run(args: &GenerateArgs) -> Result<()> {
    let start = Instant::now();
    let kind = SetKind::from_name(&args.kind)?;
    let config = SetConfig::new(kind, args.seed, args.shapes.map_or(60, NonZeroUsize::get))
        .with_noise(args.noise.noise.as_deref(), args.noise.noise_along.into())
        .context("--noise")?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    let bar = progress::bar("generate", config.shapes as u64, "clouds");
    let points: Vec<usize> = (0..config.shapes)
        .into_par_iter()
        .map(|i| {
            let (name, cloud) = generate_one(&config, i)?;
            format::write_labelled(&args.output.join(format!("{name}.ply")), &cloud)?;
            bar.inc(1);
            Ok(cloud.cloud.len())
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    eprintln!(
        "{} clouds, {} points, in {} ({:.1} s)",
        points.len(),
        points.iter().sum::<usize>(),
        args.output.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
