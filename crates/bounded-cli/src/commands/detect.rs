//! `bounded detect`: label every point of a cloud file.

use super::{peak_memory, rate, sources};
use crate::cli::DetectArgs;
use crate::{pipeline, progress};
use anyhow::{Context, Result, bail};
use bounded_data::DataError;
use bounded_data::format::{self, Format};
use bounded_geom::GeomError;
use std::time::Instant;

pub fn run(args: &DetectArgs) -> Result<()> {
    let start = Instant::now();
    // Fail on an unknown output format before any work is done.
    Format::from_path(&args.output)?;
    let parent = match args.output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if !parent.is_dir() {
        bail!("{}: output directory does not exist", parent.display());
    }
    let classifier = sources::model(args.model.as_deref())?;
    let config = pipeline::feature_config(&classifier, args.scales.as_deref())?;

    let reading = progress::spinner("read");
    let read = if args.drop_non_finite {
        format::read_finite(&args.input)
    } else {
        format::read(&args.input).map(|table| (table, 0))
    };
    reading.finish_and_clear();
    let (mut table, dropped) = read.map_err(|e| match e {
        DataError::Geom {
            source: GeomError::NonFinite { .. },
            ..
        } => anyhow::anyhow!("{e} (--drop-non-finite leaves such points out)"),
        e => e.into(),
    })?;
    if dropped > 0 {
        let points = if dropped == 1 { "point" } else { "points" };
        eprintln!("left out {dropped} {points} with a NaN or infinite coordinate");
    }
    // The output replaces them: free their memory while the cloud is labelled.
    format::drop_annotated(&mut table);
    let n = table.len();
    let detection = pipeline::detect(&table.cloud, &classifier, &config, true)
        .with_context(|| args.input.display().to_string())?;

    let writing = progress::spinner("write");
    let written = format::write_annotated(
        &args.output,
        &table,
        &detection.classes,
        &detection.probabilities,
    );
    writing.finish_and_clear();
    written?;

    let [non_edge, sharp, boundary] = detection.class_counts();
    let seconds = start.elapsed().as_secs_f64();
    let memory = peak_memory().map_or(String::new(), |m| format!(", peak memory {m}"));
    eprintln!(
        "{n} points: {sharp} sharp edge, {boundary} boundary, {non_edge} non-edge; \
         detection {:.2} s ({}), total {seconds:.2} s{memory}; wrote {}",
        detection.elapsed.as_secs_f64(),
        rate(n, detection.elapsed.as_secs_f64()),
        args.output.display()
    );
    Ok(())
}
