//! Where clouds, labels and models come from: files, dataset directories, generated sets and
//! the embedded default model.

use crate::cli::{NoiseAlong, NoiseArgs};
use anyhow::{Context, Result, bail};
use bounded_data::dataset::{Manifest, Role, cloud_files};
use bounded_data::labels::{self, Convention};
use bounded_data::synth::{self, NoiseDirection, SetConfig, SetKind};
use bounded_data::{LabelledCloud, format};
use bounded_geom::Class;
use bounded_nn::Classifier;
use std::path::{Path, PathBuf};

/// The classifier in `path`, or the embedded default model.
pub fn model(path: Option<&Path>) -> Result<Classifier> {
    match path {
        Some(p) => {
            Classifier::load(p).with_context(|| format!("cannot load model {}", p.display()))
        }
        None => bounded_nn::default_model().context("cannot load the embedded model"),
    }
}

/// The clouds of dataset `dir` that have `role`; a directory without roles (no
/// `manifest.txt`, no `train/`, `validation/`, `evaluation/`) holds only clouds of that role.
pub fn dataset_files(dir: &Path, roles: &[Role]) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("{}: not a directory", dir.display());
    }
    let manifest = Manifest::open(dir)?;
    let files = if manifest.entries.is_empty() {
        cloud_files(dir)?
    } else {
        roles
            .iter()
            .flat_map(|&r| manifest.with_role(r).map(Path::to_path_buf))
            .collect()
    };
    if files.is_empty() {
        bail!("{}: no point-cloud files found", dir.display());
    }
    Ok(files)
}

/// Reads a labelled cloud, detecting its label convention: a `class` or `label` property
/// if present; otherwise the PCEDNet colours (smooth edges as `smooth_edge`), and the
/// Bazazian colours when a colour outside PCEDNet's palette appears.
pub fn labelled(path: &Path, smooth_edge: Class) -> Result<LabelledCloud> {
    let table = format::read(path)?;
    if labels::class_column(&table).is_some() {
        return Ok(labels::from_table(table, Convention::ClassProperty, path)?);
    }
    if table.property("red").is_none() {
        bail!(
            "{}: no labels: neither a 'class' or 'label' property nor label colours \
             (red, green, blue as in the PCEDNet or Bazazian clouds)",
            path.display()
        );
    }
    let pcednet = Convention::Pcednet { smooth_edge };
    match labels::from_table(table.clone(), pcednet, path) {
        Ok(labelled) => Ok(labelled),
        Err(pcednet_error) => {
            labels::from_table(table, Convention::Bazazian, path).map_err(|_| pcednet_error.into())
        }
    }
}

/// The stem of `path`, naming a cloud in tables.
pub fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Parses a set kind name.
pub fn set_kind(name: &str) -> Result<SetKind> {
    [
        SetKind::Cad,
        SetKind::Random,
        SetKind::Boundary,
        SetKind::Mixed,
        SetKind::Freeform,
    ]
    .into_iter()
    .find(|k| k.name() == name)
    .with_context(|| {
        format!("unknown set kind {name:?} (cad, random, boundary, mixed or freeform)")
    })
}

/// The set described by `generated:KIND:SEED[:SHAPES]` (default 60 shapes).
pub fn generated_config(spec: &str) -> Result<SetConfig> {
    let fields: Vec<&str> = spec.split(':').collect();
    let (kind, seed, shapes) = match fields.as_slice() {
        ["generated", kind, seed] => (kind, seed, "60"),
        ["generated", kind, seed, shapes] => (kind, seed, *shapes),
        _ => bail!("{spec:?}: expected generated:KIND:SEED[:SHAPES]"),
    };
    let seed = seed
        .parse()
        .with_context(|| format!("{spec:?}: bad seed"))?;
    let shapes = shapes
        .parse()
        .ok()
        .filter(|&n: &usize| n > 0)
        .with_context(|| format!("{spec:?}: the shape count must be a whole number above 0"))?;
    Ok(SetConfig::new(set_kind(kind)?, seed, shapes))
}

/// Sets the noise of generated clouds from the command line's options (checked).
pub fn set_noise(config: &mut SetConfig, noise: &NoiseArgs) -> Result<()> {
    if let Some(levels) = &noise.noise {
        config.noise_levels.clone_from(levels);
    }
    config.noise_direction = match noise.noise_along {
        NoiseAlong::Any => NoiseDirection::Isotropic,
        NoiseAlong::Normal => NoiseDirection::Normal,
    };
    config.validate().context("--noise")
}

/// One source of training clouds, parsed and checked before any work.
pub enum TrainingSource {
    /// A generated set, with its noise.
    Generated(SetConfig),
    /// A dataset directory (its train and validation roles).
    Dataset(PathBuf),
}

impl TrainingSource {
    /// Parses every `--data` spec with the noise options; noise options without a
    /// generated set are refused, as they would do nothing.
    pub fn parse_all(specs: &[String], noise: &NoiseArgs) -> Result<Vec<TrainingSource>> {
        let sources = specs
            .iter()
            .map(|spec| {
                if !spec.starts_with("generated:") {
                    return Ok(TrainingSource::Dataset(PathBuf::from(spec)));
                }
                let mut config = generated_config(spec)?;
                set_noise(&mut config, noise)?;
                Ok(TrainingSource::Generated(config))
            })
            .collect::<Result<Vec<_>>>()?;
        let generated = sources
            .iter()
            .any(|s| matches!(s, TrainingSource::Generated(_)));
        if !generated && (noise.noise.is_some() || noise.noise_along != NoiseAlong::Any) {
            bail!("--noise and --noise-along apply to generated sets, and --data names none");
        }
        Ok(sources)
    }

    /// The named clouds of this source.
    pub fn load(&self) -> Result<Vec<(String, LabelledCloud)>> {
        match self {
            TrainingSource::Generated(config) => Ok(synth::generate(config)?),
            TrainingSource::Dataset(dir) => dataset_files(dir, &[Role::Train, Role::Validation])?
                .into_iter()
                .map(|path| Ok((stem(&path), labelled(&path, Class::NonEdge)?)))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_specs_parse_or_say_what_is_wrong() {
        let config = generated_config("generated:boundary:7").unwrap();
        assert_eq!(
            (config.kind, config.seed, config.shapes),
            (SetKind::Boundary, 7, 60)
        );
        assert_eq!(generated_config("generated:cad:1:5").unwrap().shapes, 5);
        for (spec, expected) in [
            ("generated:cad", "expected generated:KIND:SEED[:SHAPES]"),
            ("generated:cube:1", "unknown set kind \"cube\""),
            ("generated:cad:x", "bad seed"),
            (
                "generated:cad:1:0",
                "shape count must be a whole number above 0",
            ),
            (
                "generated:cad:1:-3",
                "shape count must be a whole number above 0",
            ),
        ] {
            let e = generated_config(spec).unwrap_err().to_string();
            assert!(e.contains(expected), "{spec}: {e}");
        }
    }
}
