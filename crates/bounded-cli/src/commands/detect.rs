//! `bounded detect`: label every point of a cloud file, or of several files as one survey
//! (tile by tile, each with the halo that makes its labels the whole survey's; or each on its
//! own with `--separate`).

use super::{peak_memory, rate};
use crate::cli::DetectArgs;
use crate::pipeline;
use crate::progress;
use anyhow::{Context, Result};
use bounded_data::DataError;
use bounded_data::annotate::AnnotateOptions;
use bounded_data::format;
use bounded_geom::GeomError;
use bounded_nn::Detector;
use bounded_nn::calibration::describe;
use bounded_nn::report::grouped;
use bounded_survey::{
    Event, Options, Plan, ReadOptions, SurveyError, TileReport, output_paths, stdout_format,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub fn run(args: &DetectArgs) -> Result<()> {
    let start = Instant::now();
    // Fail on unknown formats and unusable outputs before any work is done.
    let outputs = output_paths(&args.inputs, &args.output, args.format.as_deref())?;
    let detector = pipeline::detector(&args.model)?;
    let read = ReadOptions {
        drop_non_finite: args.drop_non_finite,
    };
    let options = Options {
        read,
        annotate: AnnotateOptions {
            class_to: args.class_to,
            colours: args.colours,
            flavour: args.flavour,
        },
        block_points: args.block_points,
        radius: None,
    };
    // The inputs labelled together: all of them (the tiles of a survey), or each on its own.
    let group = if args.separate { 1 } else { args.inputs.len() };
    let mut reports = Vec::new();
    if [&args.inputs[0], &outputs[0]].contains(&&PathBuf::from("-")) {
        reports.push(label_stream(args, &outputs[0], &detector, &options)?);
    } else {
        for (inputs, outputs) in args.inputs.chunks(group).zip(outputs.chunks(group)) {
            let plan = Plan::of(inputs, read).map_err(hint)?;
            reports.extend(label(&plan, &detector, outputs, &options)?);
        }
    }
    // A run killed outright (SIGKILL) leaves its temporary file behind: name those found.
    let files: Vec<&Path> = (outputs.iter().map(PathBuf::as_path))
        .filter(|o| *o != Path::new("-"))
        .collect();
    for stale in bounded_geom::atomic::stale_temporaries_beside(&files) {
        eprintln!(
            "note: {} is the temporary file of an interrupted run; remove it unless another \
             run is writing there now",
            stale.display()
        );
    }

    let n: usize = reports.iter().map(|r| r.points).sum();
    let count = |c: usize| grouped(reports.iter().map(|r| r.class_counts[c]).sum());
    let detecting: f64 = reports.iter().map(|r| r.detection.as_secs_f64()).sum();
    let labelled: usize = reports.iter().map(|r| r.labelled).sum();
    let halo = match labelled > n {
        true => format!(" (with halos: {} points labelled)", grouped(labelled)),
        false => String::new(),
    };
    let seconds = start.elapsed().as_secs_f64();
    let memory = peak_memory().map_or(String::new(), |m| format!(", peak memory {m}"));
    let wrote = match outputs.as_slice() {
        [one] => one.display().to_string(),
        all => format!("{} files to {}", all.len(), args.output.display()),
    };
    eprintln!(
        "{} points: {} sharp edge, {} boundary, {} non-edge (by {}); detection {detecting:.2} s \
         ({}){halo}, total {seconds:.2} s{memory}; wrote {wrote}",
        grouped(n),
        count(1),
        count(2),
        count(0),
        describe(detector.sensitivity()),
        rate(labelled, detecting),
    );
    Ok(())
}

/// Labels one cloud read from standard input or written to standard output (`-`), whole.
fn label_stream(
    args: &DetectArgs,
    output: &Path,
    detector: &Detector,
    options: &Options,
) -> Result<TileReport> {
    let input = &args.inputs[0];
    let start = Instant::now();
    let (mut table, dropped) = match input == Path::new("-") {
        true => format::read_stream(std::io::stdin().lock(), None, args.drop_non_finite, input)
            .map(|(t, _, n)| (t, n))
            .map_err(SurveyError::from),
        false => options.read.read(input),
    }
    .map_err(hint)?;
    format::drop_annotated(&mut table);
    let d = pipeline::detect(detector, &table.cloud, true).context(input.display().to_string())?;
    let (classes, probabilities) = (&d.classes, &d.probabilities);
    match stdout_format(input, output, args.format.as_deref())? {
        Some(f) => {
            let stdout = std::io::stdout().lock();
            format::write_annotated_to(
                stdout,
                f,
                output,
                &table,
                classes,
                probabilities,
                &options.annotate,
            )
        }
        None => {
            format::write_annotated_with(output, &table, classes, probabilities, &options.annotate)
        }
    }?;
    let elapsed = start.elapsed();
    Ok(TileReport::whole(output, table.len(), dropped, &d, elapsed))
}

/// Labels the tiles of `plan` into `outputs`, with a progress bar per tile.
fn label(
    plan: &Plan,
    detector: &Detector,
    outputs: &[PathBuf],
    options: &Options,
) -> Result<Vec<TileReport>> {
    let tiles = plan.inputs().len();
    let mut bar = None;
    let reports =
        bounded_survey::detect_survey(plan, detector, outputs, options, &mut |event| match event {
            Event::Loaded {
                tile,
                block,
                points,
                halo,
                ..
            } => {
                let step = match (block, tiles) {
                    (Some((b, n)), _) => format!("block {}/{n}", b + 1),
                    (None, 1) => "detect".to_string(),
                    _ => format!("tile {}/{tiles}", tile + 1),
                };
                bar = Some(progress::bar(&step, (points + halo) as u64, "points"));
            }
            Event::Streaming {
                pass, done, total, ..
            } => {
                let b = bar.get_or_insert_with(|| progress::bar(pass, total as u64, "points"));
                b.set_position(done as u64);
                if done == total {
                    bar.take().iter().for_each(|b| b.finish_and_clear());
                }
            }
            Event::Detecting { done, .. } => bar.iter().for_each(|b| b.set_position(done as u64)),
            Event::Growing { .. } | Event::Written { .. } => {
                bar.take().iter().for_each(|b| b.finish_and_clear())
            }
        });
    bar.iter().for_each(|b| b.finish_and_clear());
    let reports = reports.map_err(hint)?;
    for (input, r) in plan
        .inputs()
        .iter()
        .zip(&reports)
        .filter(|(_, r)| r.dropped > 0)
    {
        let points = if r.dropped == 1 { "point" } else { "points" };
        eprintln!(
            "{}: left out {} {points} with a NaN or infinite coordinate",
            input.path.display(),
            r.dropped
        );
    }
    Ok(reports)
}

/// `e`, with the option that avoids it where there is one.
fn hint(e: SurveyError) -> anyhow::Error {
    let non_finite = |e: &SurveyError| {
        matches!(
            e,
            SurveyError::Data(DataError::Geom {
                source: GeomError::NonFinite { .. },
                ..
            })
        )
    };
    match &e {
        SurveyError::Stopped { source, .. } if non_finite(source) => {}
        e if non_finite(e) => {}
        _ => return e.into(),
    }
    anyhow::anyhow!("{e} (--drop-non-finite leaves such points out)")
}
