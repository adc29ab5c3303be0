//! `bounded detect`: label every point of a cloud file, or of several files as one cloud
//! (or each on its own with `--separate`).

use super::{grouped, peak_memory, rate};
use crate::cli::DetectArgs;
use crate::pipeline;
use crate::progress;
use anyhow::{Context, Result, bail};
use bounded_data::DataError;
use bounded_data::annotate::AnnotateOptions;
use bounded_data::format::{self, Format};
use bounded_data::table::PointTable;
use bounded_geom::{GeomError, PointCloud};
use bounded_nn::{Detection, Detector};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub fn run(args: &DetectArgs) -> Result<()> {
    let start = Instant::now();
    // Fail on unknown formats and unusable outputs before any work is done.
    let (outputs, into_directory) = output_paths(args)?;
    let detector = pipeline::detector(&args.model)?;

    // The inputs labelled together: all of them (tiles of one cloud), or each on its own.
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    let written_to: Vec<&Path> = outputs.iter().map(PathBuf::as_path).collect();
    let group = if args.separate { 1 } else { inputs.len() };
    let (mut n, mut counts, mut detecting) = (0, [0; 3], Duration::ZERO);
    for (group_inputs, group_outputs) in inputs.chunks(group).zip(written_to.chunks(group)) {
        let detection = label(
            group_inputs,
            group_outputs,
            into_directory.then_some(&*args.output),
            args,
            &detector,
        )?;
        n += detection.classes.len();
        for (total, count) in counts.iter_mut().zip(detection.class_counts()) {
            *total += count;
        }
        detecting += detection.elapsed;
    }

    // A run killed outright (SIGKILL) leaves its temporary file behind: name those found.
    let files: Vec<&Path> = written_to
        .into_iter()
        .filter(|o| *o != Path::new("-"))
        .collect();
    for stale in bounded_geom::atomic::stale_temporaries_beside(&files) {
        eprintln!(
            "note: {} is the temporary file of an interrupted run; remove it unless another \
             run is writing there now",
            stale.display()
        );
    }
    let [non_edge, sharp, boundary] = counts;
    let seconds = start.elapsed().as_secs_f64();
    let memory = peak_memory().map_or(String::new(), |m| format!(", peak memory {m}"));
    let wrote = match outputs.as_slice() {
        [one] => one.display().to_string(),
        all => format!("{} files to {}", all.len(), args.output.display()),
    };
    eprintln!(
        "{} points: {} sharp edge, {} boundary, {} non-edge; detection {:.2} s ({}), \
         total {seconds:.2} s{memory}; wrote {wrote}",
        grouped(n),
        grouped(sharp),
        grouped(boundary),
        grouped(non_edge),
        detecting.as_secs_f64(),
        rate(n, detecting.as_secs_f64()),
    );
    Ok(())
}

/// Reads `inputs`, labels them as one cloud and writes each one's result to its output
/// (creating `directory` first, if given, so a failed run leaves none behind).
fn label(
    inputs: &[&Path],
    outputs: &[&Path],
    directory: Option<&Path>,
    args: &DetectArgs,
    detector: &Detector,
) -> Result<Detection> {
    let mut tables = Vec::with_capacity(inputs.len());
    for input in inputs {
        let mut table = read(input, args.drop_non_finite)?;
        // The output replaces them: free their memory while the cloud is labelled.
        format::drop_annotated(&mut table);
        tables.push(table);
    }
    let detection = match tables.as_slice() {
        [table] => pipeline::detect(detector, &table.cloud, true),
        _ => {
            let clouds: Vec<&PointCloud> = tables.iter().map(|t| &t.cloud).collect();
            pipeline::detect(detector, &PointCloud::concat(&clouds)?, true)
        }
    }
    .with_context(|| {
        let names: Vec<_> = inputs.iter().map(|p| p.display().to_string()).collect();
        names.join(", ")
    })?;

    if let Some(directory) = directory {
        std::fs::create_dir_all(directory)
            .with_context(|| format!("cannot create {}", directory.display()))?;
    }
    let writing = progress::spinner("write");
    // Each table's results are the next `len` of the joined run. A failure names the outputs
    // already written: they are complete and stay.
    let mut first = 0;
    for (k, (table, output)) in tables.iter().zip(outputs).enumerate() {
        let range = first..first + table.len();
        let classes = &detection.classes[range.clone()];
        let probabilities = &detection.probabilities[range.clone()];
        let options = AnnotateOptions {
            class_to: args.class_to,
            colours: args.colours,
            flavour: args.flavour,
        };
        let written = match stdout_format(args, output)? {
            Some(f) => {
                let stdout = std::io::stdout().lock();
                format::write_annotated_to(
                    stdout,
                    f,
                    output,
                    table,
                    classes,
                    probabilities,
                    &options,
                )
            }
            None => format::write_annotated_with(output, table, classes, probabilities, &options),
        };
        if let Err(e) = written {
            writing.finish_and_clear();
            let done: Vec<_> = outputs[..k]
                .iter()
                .map(|p| p.display().to_string())
                .collect();
            return Err(match done.as_slice() {
                [] => e.into(),
                done => anyhow::Error::from(e).context(format!(
                    "{} of {} outputs were written before this failure and stay complete: {}",
                    done.len(),
                    outputs.len(),
                    done.join(", ")
                )),
            });
        }
        first = range.end;
    }
    writing.finish_and_clear();
    Ok(detection)
}

/// Reads `input` with every property; with `drop_non_finite`, leaves out (and reports) the
/// points with a non-finite coordinate.
fn read(input: &Path, drop_non_finite: bool) -> Result<PointTable> {
    let reading = progress::spinner("read");
    let read = if input == Path::new("-") {
        let stdin = std::io::stdin().lock();
        format::read_stream(stdin, None, drop_non_finite, input).map(|(t, _, n)| (t, n))
    } else if drop_non_finite {
        format::read_finite(input)
    } else {
        format::read(input).map(|table| (table, 0))
    };
    reading.finish_and_clear();
    let (table, dropped) = read.map_err(|e| match e {
        DataError::Geom {
            source: GeomError::NonFinite { .. },
            ..
        } => anyhow::anyhow!("{e} (--drop-non-finite leaves such points out)"),
        e => e.into(),
    })?;
    if dropped > 0 {
        let points = if dropped == 1 { "point" } else { "points" };
        eprintln!(
            "{}: left out {dropped} {points} with a NaN or infinite coordinate",
            input.display()
        );
    }
    Ok(table)
}

/// Where each input's result goes, and whether into a directory: `--output` for one input,
/// unless it is a directory (or ends with a separator); else a file of the input's name in
/// that directory, which is created only when the results are written, so a failed run
/// leaves nothing behind. Checked before any work: known formats, an existing parent (for a
/// directory, its nearest existing ancestor is a directory), no two inputs to one file, no
/// input replaced by another's result.
fn output_paths(args: &DetectArgs) -> Result<(Vec<PathBuf>, bool)> {
    let output = &args.output;
    if output == Path::new("-") {
        if args.inputs.len() != 1 {
            bail!(
                "-o - (standard output) takes one input, not {}",
                args.inputs.len()
            );
        }
        stdout_format(args, output)?;
        return Ok((vec![output.clone()], false));
    }
    let names_directory =
        output.is_dir() || (output.to_str()).is_some_and(|s| s.ends_with(std::path::is_separator));
    if args.inputs.len() == 1 && !names_directory {
        if args.format.is_some() {
            bail!(
                "--format is for a directory output; {} names a file, whose extension gives the format",
                output.display()
            );
        }
        Format::from_path(output)?;
        let parent = match output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !parent.is_dir() {
            bail!("{}: output directory does not exist", parent.display());
        }
        refuse_replacing_input(&args.inputs[0], output)?;
        bounded_geom::atomic::probe(output)?;
        return Ok((vec![output.clone()], false));
    }
    if output.exists() && !output.is_dir() {
        bail!(
            "{}: several inputs need a directory output, and this is a file",
            output.display()
        );
    }
    let mut outputs: Vec<PathBuf> = Vec::with_capacity(args.inputs.len());
    for input in &args.inputs {
        let name =
            (input.file_name()).with_context(|| format!("{}: no file name", input.display()))?;
        let mut path = output.join(name);
        if let Some(ext) = &args.format {
            // `--format .las` means the extension, not `name..las`.
            path.set_extension(ext.trim_start_matches('.'));
        }
        Format::from_path(&path)?;
        if outputs.contains(&path) {
            bail!(
                "{}: another input is written to {} too; rename one",
                input.display(),
                path.display()
            );
        }
        for input in &args.inputs {
            refuse_replacing_input(input, &path)?;
        }
        outputs.push(path);
    }
    let existing = (output.ancestors()).find(|a| !a.as_os_str().is_empty() && a.exists());
    match existing {
        Some(file) if !file.is_dir() => bail!(
            "cannot create {}: {} is not a directory",
            output.display(),
            file.display()
        ),
        Some(directory) => writable(directory)?,
        None => writable(Path::new("."))?,
    }
    Ok((outputs, true))
}

/// The format of `output` when it is `-` (standard output): `--format`, else the input's.
fn stdout_format(args: &DetectArgs, output: &Path) -> Result<Option<Format>> {
    if output != Path::new("-") {
        return Ok(None);
    }
    let named = match (&args.format, args.inputs[0].as_path()) {
        (Some(ext), _) => Path::new("-").with_extension(ext.trim_start_matches('.')),
        (None, input) if input != Path::new("-") => input.to_path_buf(),
        _ => bail!("standard output has no extension: --format names its format (ply, las, ...)"),
    };
    Ok(Some(Format::from_path(&named)?))
}

/// Refuses an `output` that is `input` itself (by file identity, so a hard link or another
/// spelling of the path counts too): the result would replace the data it is computed from.
fn refuse_replacing_input(input: &Path, output: &Path) -> Result<()> {
    if bounded_geom::atomic::same_file(input, output) {
        bail!(
            "{}: the output {} is this input; its result would replace it (choose another \
             output or --format)",
            input.display(),
            output.display()
        );
    }
    Ok(())
}

/// Fails now, before any work, when no file can be created in `directory`.
fn writable(directory: &Path) -> Result<()> {
    Ok(bounded_geom::atomic::probe(&directory.join("probe"))?)
}
