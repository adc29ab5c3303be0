//! Where each input's result goes, checked before any work, so that a run which cannot write
//! its results fails at once and leaves nothing behind. The refusals name the options of
//! `bounded detect` (`-o`, `--format`), whose rules these are.

use crate::SurveyError;
use bounded_data::format::Format;
use std::path::{Path, PathBuf};

/// Returns [`SurveyError::Outputs`] with the formatted reason.
macro_rules! refuse {
    ($($reason:tt)*) => {
        return Err(SurveyError::Outputs(format!($($reason)*)))
    };
}

/// Where the result of each of `inputs` goes, and whether into a directory: `output` for one input,
/// unless it is a directory (or ends with a separator); else a file of the input's name in
/// that directory, which is created only when the results are written, so a failed run
/// leaves nothing behind. Checked before any work: known formats, an existing parent (for a
/// directory, its nearest existing ancestor is a directory), no two inputs to one file, no
/// input replaced by another's result.
pub fn output_paths(
    inputs: &[PathBuf],
    output: &Path,
    format: Option<&str>,
) -> Result<Vec<PathBuf>, SurveyError> {
    if output == Path::new("-") {
        if inputs.len() != 1 {
            refuse!(
                "-o - (standard output) takes one input, not {}",
                inputs.len()
            );
        }
        stdout_format(&inputs[0], output, format)?;
        return Ok(vec![output.to_path_buf()]);
    }
    let names_directory =
        output.is_dir() || (output.to_str()).is_some_and(|s| s.ends_with(std::path::is_separator));
    if inputs.len() == 1 && !names_directory {
        if format.is_some() {
            refuse!(
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
            refuse!("{}: output directory does not exist", parent.display());
        }
        refuse_replacing_input(&inputs[0], output)?;
        bounded_geom::atomic::probe(output)?;
        return Ok(vec![output.to_path_buf()]);
    }
    if output.exists() && !output.is_dir() {
        refuse!(
            "{}: several inputs need a directory output, and this is a file",
            output.display()
        );
    }
    let mut outputs: Vec<PathBuf> = Vec::with_capacity(inputs.len());
    for input in inputs {
        let Some(name) = input.file_name().filter(|_| input != Path::new("-")) else {
            refuse!("{}: no file name to write under", input.display())
        };
        let mut path = output.join(name);
        if let Some(ext) = format {
            // `--format .las` means the extension, not `name..las`.
            path.set_extension(ext.trim_start_matches('.'));
        }
        Format::from_path(&path)?;
        if outputs.contains(&path) {
            refuse!(
                "{}: another input is written to {} too; rename one",
                input.display(),
                path.display()
            );
        }
        for input in inputs {
            refuse_replacing_input(input, &path)?;
        }
        outputs.push(path);
    }
    let existing = (output.ancestors()).find(|a| !a.as_os_str().is_empty() && a.exists());
    match existing {
        Some(file) if !file.is_dir() => refuse!(
            "cannot create {}: {} is not a directory",
            output.display(),
            file.display()
        ),
        Some(directory) => writable(directory)?,
        None => writable(Path::new("."))?,
    }
    Ok(outputs)
}

/// The format of `output` when it is `-` (standard output): `format` (an extension), else
/// `input`'s; `None` for a file output.
pub fn stdout_format(
    input: &Path,
    output: &Path,
    format: Option<&str>,
) -> Result<Option<Format>, SurveyError> {
    if output != Path::new("-") {
        return Ok(None);
    }
    let named = match (format, input) {
        (Some(ext), _) => Path::new("-").with_extension(ext.trim_start_matches('.')),
        (None, input) if input != Path::new("-") => input.to_path_buf(),
        _ => refuse!("standard output has no extension: --format names its format (ply, las, ...)"),
    };
    Ok(Some(Format::from_path(&named)?))
}

/// Refuses an `output` that is `input` itself (by file identity, so a hard link or another
/// spelling of the path counts too): the result would replace the data it is computed from.
fn refuse_replacing_input(input: &Path, output: &Path) -> Result<(), SurveyError> {
    if bounded_geom::atomic::same_file(input, output) {
        refuse!(
            "{}: the output {} is this input; its result would replace it (choose another \
             output or --format)",
            input.display(),
            output.display()
        );
    }
    Ok(())
}

/// Fails now, before any work, when no file can be created in `directory`.
fn writable(directory: &Path) -> Result<(), SurveyError> {
    Ok(bounded_geom::atomic::probe(&directory.join("probe"))?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refusal(inputs: &[&str], output: &Path, format: Option<&str>) -> String {
        let inputs: Vec<PathBuf> = inputs.iter().map(PathBuf::from).collect();
        output_paths(&inputs, output, format)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn one_input_to_a_file_several_into_a_directory_created_later() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("out.ply");
        let one = output_paths(&["a.las".into()], &file, None).unwrap();
        assert_eq!(one, [file]);
        let sub = dir.path().join("results");
        let inputs = ["x/a.las".into(), "y/b.ply".into()];
        let many = output_paths(&inputs, &sub, Some(".las")).unwrap();
        assert_eq!(many, [sub.join("a.las"), sub.join("b.las")]);
        assert!(!sub.exists(), "the directory waits for the results");
    }

    #[test]
    fn refusals_name_the_paths_and_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let e = refusal(&["x/a.las", "y/a.las"], dir.path(), None);
        assert!(
            e.contains("another input is written to") && e.contains("a.las"),
            "{e}"
        );
        let e = refusal(&["a.las", "b.las"], Path::new("-"), None);
        assert!(e.contains("takes one input, not 2"), "{e}");
        let e = refusal(&["a.las"], &dir.path().join("out.ply"), Some("las"));
        assert!(e.contains("--format is for a directory output"), "{e}");
        let e = refusal(&["a.las"], &dir.path().join("none/out.ply"), None);
        assert!(e.contains("output directory does not exist"), "{e}");
        let input = dir.path().join("a.ply");
        std::fs::write(&input, "ply").unwrap();
        let e = output_paths(std::slice::from_ref(&input), &input, None).unwrap_err();
        assert!(e.to_string().contains("is this input"), "{e}");
        let e = stdout_format(Path::new("-"), Path::new("-"), None).unwrap_err();
        assert!(e.to_string().contains("--format names its format"), "{e}");
        let f = stdout_format(Path::new("-"), Path::new("-"), Some("ply")).unwrap();
        assert_eq!(f, Some(Format::Ply));
        assert_eq!(stdout_format(&input, &input, None).unwrap(), None);
    }
}
