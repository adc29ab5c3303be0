//! Labelled datasets: which clouds train, validate and evaluate, how their labels are read,
//! and where training clouds come from.
//!
//! A dataset is a directory. Clouds in its `train/`, `validation/` and `evaluation/`
//! subdirectories take that role; a `manifest.txt` (lines `<role> <path>`, paths relative
//! to the directory, `#` comments) lists roles explicitly and takes precedence. A generated
//! set written into `train/` is a dataset like any other.
//!
//! ```
//! use bounded_data::dataset::{Role, TrainingSource};
//!
//! assert_eq!(Role::parse("train"), Some(Role::Train));
//! assert_eq!(TrainingSource::parse("abc:models")?, TrainingSource::Abc("models".into()));
//! # Ok::<(), bounded_data::DataError>(())
//! ```

use crate::labels::{self, Convention};
#[cfg(feature = "generator")]
use crate::synth::SetConfig;
use crate::{DataError, LabelledCloud, abc, format};
use bounded_geom::Class;
use std::path::{Path, PathBuf};

/// What a cloud is used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Role {
    /// Training data.
    Train,
    /// Held out to pick the best training run.
    Validation,
    /// Only for measuring results; never trained on.
    Evaluation,
}

impl Role {
    /// Every role, in manifest order.
    pub const ALL: [Role; 3] = [Role::Train, Role::Validation, Role::Evaluation];

    /// The name used in manifests and as the subdirectory name.
    pub fn name(self) -> &'static str {
        match self {
            Role::Train => "train",
            Role::Validation => "validation",
            Role::Evaluation => "evaluation",
        }
    }

    /// The role called `name`, if any.
    pub fn parse(name: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// The clouds of a dataset with their roles, sorted by role then path.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Manifest {
    /// `(path, role)` pairs; paths include the dataset directory.
    pub entries: Vec<(PathBuf, Role)>,
}

impl Manifest {
    /// Reads the dataset in `dir`: its `manifest.txt` if present, else its role subdirectories.
    pub fn open(dir: &Path) -> Result<Manifest, DataError> {
        let listed = dir.join("manifest.txt");
        if listed.is_file() {
            return Self::read(&listed);
        }
        let mut entries = Vec::new();
        for role in Role::ALL {
            let sub = dir.join(role.name());
            if sub.is_dir() {
                entries.extend(cloud_files(&sub)?.into_iter().map(|p| (p, role)));
            }
        }
        Ok(Self::sorted(entries))
    }

    /// Reads a manifest file; paths are relative to its directory.
    pub fn read(path: &Path) -> Result<Manifest, DataError> {
        let text = std::fs::read_to_string(path).map_err(|source| DataError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let base = path.parent().unwrap_or(Path::new(""));
        let mut entries = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let (role, file) = line
                .split_once(char::is_whitespace)
                .map(|(r, f)| (r, f.trim()))
                .ok_or_else(|| malformed(path, n + 1, "expected `<role> <path>`"))?;
            let role = Role::parse(role).ok_or_else(|| {
                malformed(
                    path,
                    n + 1,
                    &format!(
                        "unknown role {} (train, validation or evaluation)",
                        crate::error::quoted(role)
                    ),
                )
            })?;
            entries.push((base.join(file), role));
        }
        Ok(Self::sorted(entries))
    }

    /// Writes the manifest to `path` (paths relative to its directory where possible).
    pub fn write(&self, path: &Path) -> Result<(), DataError> {
        let base = path.parent().unwrap_or(Path::new(""));
        let text: String = self
            .entries
            .iter()
            .map(|(p, role)| {
                let rel = p.strip_prefix(base).unwrap_or(p);
                format!("{} {}\n", role.name(), rel.display())
            })
            .collect();
        std::fs::write(path, text).map_err(|source| DataError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// The paths with role `role`.
    pub fn with_role(&self, role: Role) -> impl Iterator<Item = &Path> {
        self.entries
            .iter()
            .filter(move |(_, r)| *r == role)
            .map(|(p, _)| p.as_path())
    }

    fn sorted(mut entries: Vec<(PathBuf, Role)>) -> Manifest {
        entries.sort_by(|a, b| (a.1, &a.0).cmp(&(b.1, &b.0)));
        Manifest { entries }
    }
}

fn malformed(path: &Path, line: usize, what: &str) -> DataError {
    DataError::Malformed {
        path: path.to_path_buf(),
        what: format!("line {line}: {what}"),
    }
}

/// The cloud files directly in `dir` (every extension [`format::Format`] reads), sorted.
pub fn cloud_files(dir: &Path) -> Result<Vec<PathBuf>, DataError> {
    let io = |source| DataError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if format::Format::from_path(&path).is_ok() && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// The clouds of dataset `dir` that have one of `roles`; a directory without roles (no
/// `manifest.txt`, no `train/`, `validation/`, `evaluation/`) holds only clouds of those roles.
pub fn files(dir: &Path, roles: &[Role]) -> Result<Vec<PathBuf>, DataError> {
    if !dir.is_dir() {
        return Err(DataError::Dataset {
            path: dir.to_path_buf(),
            what: "not a directory".into(),
        });
    }
    let manifest = Manifest::open(dir)?;
    let files = if manifest.entries.is_empty() {
        cloud_files(dir)?
    } else {
        (roles.iter())
            .flat_map(|&r| manifest.with_role(r).map(Path::to_path_buf))
            .collect()
    };
    if files.is_empty() {
        return Err(DataError::Dataset {
            path: dir.to_path_buf(),
            what: "no point-cloud files found".into(),
        });
    }
    Ok(files)
}

/// Reads a labelled cloud, detecting its label convention: a `class` or `label` property
/// if present; otherwise the PCEDNet colours (smooth edges as `smooth_edge`), and the
/// Bazazian colours when a colour outside PCEDNet's palette appears.
pub fn read_labelled(path: &Path, smooth_edge: Class) -> Result<LabelledCloud, DataError> {
    let table = format::read(path)?;
    if labels::class_column(&table).is_some() {
        return labels::from_table(table, Convention::ClassProperty, path);
    }
    if table.property("red").is_none() {
        return Err(DataError::malformed(
            path,
            "no labels: neither a 'class' or 'label' property nor label colours \
             (red, green, blue as in the PCEDNet or Bazazian clouds)",
        ));
    }
    let pcednet = Convention::Pcednet { smooth_edge };
    labels::from_table(table.clone(), pcednet, path).or_else(|pcednet_error| {
        labels::from_table(table, Convention::Bazazian, path).map_err(|_| pcednet_error)
    })
}

/// The labelled clouds of dataset `dir` that have one of `roles` (see [`files`]), named by
/// their file stems; calls `progress(clouds read, clouds)` after each.
pub fn load(
    dir: &Path,
    roles: &[Role],
    smooth_edge: Class,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<(String, LabelledCloud)>, DataError> {
    let files = files(dir, roles)?;
    let mut clouds = Vec::with_capacity(files.len());
    for path in &files {
        clouds.push((stem(path), read_labelled(path, smooth_edge)?));
        progress(clouds.len(), files.len());
    }
    Ok(clouds)
}

/// The stem of `path`, naming a cloud in tables.
pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Writes the generated set `config` into `dir` (created if missing), one binary PLY file
/// with a `class` property per cloud, named after it, in parallel; calls `progress()` after
/// each file. Returns the number of points written.
#[cfg(feature = "generator")]
pub fn write_generated(
    config: &SetConfig,
    dir: &Path,
    progress: &(dyn Fn() + Sync),
) -> Result<usize, DataError> {
    use rayon::prelude::*;
    config.validate()?;
    std::fs::create_dir_all(dir).map_err(|e| DataError::io(dir, e))?;
    let points = (0..config.shapes).into_par_iter().map(|i| {
        let (name, cloud) = crate::synth::generate_one(config, i)?;
        format::write_labelled(&dir.join(format!("{name}.ply")), &cloud)?;
        progress();
        Ok(cloud.cloud.len())
    });
    points.sum()
}

/// Where training clouds come from, parsed from a spec (`bounded train --data`).
#[derive(Debug, Clone, PartialEq)]
pub enum TrainingSource {
    /// A dataset directory: its train and validation clouds (a directory without roles: all).
    Dataset(PathBuf),
    /// `abc:DIR`: ABC models, OBJ meshes beside their features YAML (see [`abc::load_dir`]).
    Abc(PathBuf),
    /// `generated:KIND:SEED[:SHAPES]`: a generated set (see [`SetConfig::from_spec`]).
    #[cfg(feature = "generator")]
    Generated(SetConfig),
}

impl TrainingSource {
    /// Parses `spec`: `generated:KIND:SEED[:SHAPES]`, `abc:DIR`, else a dataset directory.
    pub fn parse(spec: &str) -> Result<TrainingSource, DataError> {
        if spec.starts_with("generated:") {
            #[cfg(feature = "generator")]
            return Ok(TrainingSource::Generated(SetConfig::from_spec(spec)?));
            #[cfg(not(feature = "generator"))]
            return Err(DataError::Generator {
                what: format!("{spec:?}: built without the generator (feature `generator`)"),
            });
        }
        Ok(match spec.strip_prefix("abc:") {
            Some(dir) => TrainingSource::Abc(dir.into()),
            None => TrainingSource::Dataset(spec.into()),
        })
    }

    /// This source with the noise `levels` (when given) along `direction` if it is a
    /// generated set (see [`SetConfig::with_noise`]); other sources are used as they are.
    #[cfg(feature = "generator")]
    pub fn with_noise(
        self,
        levels: Option<&[f64]>,
        direction: crate::synth::NoiseDirection,
    ) -> Result<TrainingSource, DataError> {
        match self {
            TrainingSource::Generated(config) => Ok(TrainingSource::Generated(
                config.with_noise(levels, direction)?,
            )),
            other => Ok(other),
        }
    }

    /// The named labelled clouds of this source.
    pub fn load(&self) -> Result<Vec<(String, LabelledCloud)>, DataError> {
        match self {
            TrainingSource::Dataset(dir) => load(
                dir,
                &[Role::Train, Role::Validation],
                Class::NonEdge,
                &mut |_, _| {},
            ),
            TrainingSource::Abc(dir) => abc::load_dir(dir),
            #[cfg(feature = "generator")]
            TrainingSource::Generated(config) => crate::synth::generate(config),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(feature = "generator")]
    use crate::synth::{LabelRule, NoiseDirection, SetKind};

    #[test]
    fn directory_roles_and_manifest_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        for (sub, file) in [
            ("train", "b.ply"),
            ("train", "a.xyz"),
            ("train", "notes.md"),
            ("evaluation", "c.LAS"),
            ("evaluation", "d.e57"),
            ("validation", "scan.pcd.bak"),
        ] {
            std::fs::create_dir_all(dir.path().join(sub)).unwrap();
            std::fs::write(dir.path().join(sub).join(file), "").unwrap();
        }
        let m = Manifest::open(dir.path()).unwrap();
        let rel: Vec<(String, Role)> = m
            .entries
            .iter()
            .map(|(p, r)| {
                (
                    p.strip_prefix(dir.path()).unwrap().display().to_string(),
                    *r,
                )
            })
            .collect();
        assert_eq!(
            rel,
            [
                ("train/a.xyz".to_string(), Role::Train),
                ("train/b.ply".to_string(), Role::Train),
                ("evaluation/c.LAS".to_string(), Role::Evaluation),
                ("evaluation/d.e57".to_string(), Role::Evaluation),
            ]
        );
        assert_eq!(m.with_role(Role::Validation).count(), 0);
        // Written, the manifest takes precedence over the directories.
        let mut moved = m.clone();
        moved.entries[0].1 = Role::Validation;
        moved.write(&dir.path().join("manifest.txt")).unwrap();
        let back = Manifest::open(dir.path()).unwrap();
        assert_eq!(back, Manifest::sorted(moved.entries));
    }

    #[test]
    fn bad_manifest_lines_are_reported_with_their_number() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("manifest.txt");
        std::fs::write(&path, "# roles\ntrain a.ply\ntest b.ply\n").unwrap();
        let e = Manifest::read(&path).unwrap_err().to_string();
        assert!(e.contains("line 3: unknown role 'test'"), "{e}");
        std::fs::write(&path, "train\n").unwrap();
        let e = Manifest::read(&path).unwrap_err().to_string();
        assert!(e.contains("line 1: expected `<role> <path>`"), "{e}");
    }

    #[cfg(feature = "generator")]
    #[test]
    fn generated_specs_parse_or_say_what_is_wrong() {
        let config = SetConfig::from_spec("generated:boundary:7").unwrap();
        assert_eq!(config, SetConfig::new(SetKind::Boundary, 7, 60));
        assert_eq!(SetConfig::from_spec("generated:cad:1:5").unwrap().shapes, 5);
        // Label rules of the free-form kind, in any order; unnamed fields keep the default.
        let config = SetConfig::from_spec("generated:freeform:4:8:band=0.5:depth=1").unwrap();
        let rule = LabelRule {
            min_depth: 1.0,
            band: 0.5,
            ..LabelRule::default()
        };
        assert_eq!(config.label_rule, rule);
        let config = SetConfig::from_spec("generated:freeform:4:8:angle=20:noise=3").unwrap();
        assert_eq!(config.label_rule.min_angle, 20.0);
        assert_eq!(config.label_rule.min_depth_per_noise, 3.0);
        let config = SetConfig::from_spec("generated:freeform:4:8:size=3").unwrap();
        assert_eq!(
            (config.feature_size, config.label_rule),
            (3.0, LabelRule::default())
        );
        // The mesh kinds' sparse planes.
        let config = SetConfig::from_spec("generated:cad:5:8:faces=3").unwrap();
        assert_eq!(config.face_spacing, 3.0);
        for (spec, expected) in [
            (
                "generated:cad",
                "expected generated:KIND:SEED[:SHAPES[:OPTION...]]",
            ),
            (
                "generated:cad:1:2:depth=1",
                "depth= is an option of the freeform kind",
            ),
            (
                "generated:freeform:1:2:faces=2",
                "faces= is for the mesh kinds, not freeform",
            ),
            ("generated:cad:1:2:faces=0.5", "face spacing 0.5"),
            (
                "generated:freeform:1:2:3",
                "\"3\" is not depth=, angle=, band=, noise=, size=, faces=, rows=, shallow=, sparse= or dense= a number",
            ),
            (
                "generated:freeform:1:2:depth=x",
                "\"depth=x\" is not depth=, angle=, band=, noise=, size=, faces=, rows=, shallow=, sparse= or dense= a number",
            ),
            ("generated:freeform:1:2:band=0", "label band 0"),
            ("generated:freeform:1:2:size=9", "feature size 9"),
            (
                "generated:cad:1:2:size=2",
                "size= is an option of the freeform kind",
            ),
            (
                "generated:freeform:1:2:noise=-1",
                "label min_depth_per_noise -1",
            ),
            (
                "generated:cube:1",
                "unknown set kind \"cube\" (cad, random, boundary, mixed, freeform)",
            ),
            ("generated:cad:x", "bad seed"),
            (
                "generated:cad:1:0",
                "shape count must be a whole number above 0",
            ),
            (
                "generated:cad:1:-3",
                "shape count must be a whole number above 0",
            ),
            (
                "generated:mixed:1:99999999999",
                "more than the 10000 a set may have",
            ),
        ] {
            let e = SetConfig::from_spec(spec).unwrap_err();
            assert!(matches!(e, DataError::Generator { .. }), "{spec}: {e}");
            assert!(e.to_string().contains(expected), "{spec}: {e}");
        }
    }

    #[cfg(feature = "generator")]
    #[test]
    fn noise_options_replace_the_levels_or_keep_them_and_are_checked() {
        let config = SetConfig::new(SetKind::Cad, 1, 2);
        let normal = (config.clone())
            .with_noise(None, NoiseDirection::Normal)
            .unwrap();
        assert_eq!(normal.noise_levels, config.noise_levels);
        assert_eq!(normal.noise_direction, NoiseDirection::Normal);
        let levels = [0.0, 1.5];
        let set = (config.clone())
            .with_noise(Some(&levels), NoiseDirection::Isotropic)
            .unwrap();
        assert_eq!(set.noise_levels, levels);
        let e = config
            .with_noise(Some(&[0.1, -1.0]), NoiseDirection::Isotropic)
            .unwrap_err();
        assert!(e.to_string().contains("noise level -1"), "{e}");
    }

    #[test]
    fn files_of_a_plain_directory_or_what_is_missing() {
        let dir = tempfile::tempdir().unwrap();
        let e = files(&dir.path().join("none"), &Role::ALL).unwrap_err();
        assert!(e.to_string().ends_with("none: not a directory"), "{e}");
        let e = files(dir.path(), &Role::ALL).unwrap_err();
        assert!(e.to_string().ends_with("no point-cloud files found"), "{e}");
        for name in ["b.ply", "a.xyz", "notes.md"] {
            std::fs::write(dir.path().join(name), "").unwrap();
        }
        let found = files(dir.path(), &[Role::Evaluation]).unwrap();
        assert_eq!(found, [dir.path().join("a.xyz"), dir.path().join("b.ply")]);
    }

    #[test]
    fn labelled_clouds_by_class_property_or_refused_without_labels() {
        let dir = tempfile::tempdir().unwrap();
        let cloud = bounded_geom::PointCloud::from_f64(&[[0.0; 3], [1.0, 0.0, 0.0]]).unwrap();
        let labels = vec![Class::Boundary, Class::Sharp];
        let labelled = LabelledCloud { cloud, labels };
        format::write_labelled(&dir.path().join("a.ply"), &labelled).unwrap();
        std::fs::write(dir.path().join("plain.xyz"), "0 0 0\n1 0 0\n").unwrap();
        let e = read_labelled(&dir.path().join("plain.xyz"), Class::NonEdge).unwrap_err();
        assert!(e.to_string().contains("plain.xyz: no labels"), "{e}");
        std::fs::remove_file(dir.path().join("plain.xyz")).unwrap();
        let loaded = load(dir.path(), &[Role::Train], Class::NonEdge, &mut |_, _| {}).unwrap();
        assert_eq!(loaded, [("a".to_string(), labelled)]);
    }

    #[test]
    fn training_sources_by_prefix() {
        let parse = |spec| TrainingSource::parse(spec).unwrap();
        assert_eq!(parse("abc:models"), TrainingSource::Abc("models".into()));
        assert_eq!(
            parse("data/set"),
            TrainingSource::Dataset("data/set".into())
        );
        #[cfg(feature = "generator")]
        {
            let generated = TrainingSource::Generated(SetConfig::new(SetKind::Cad, 1, 2));
            assert_eq!(parse("generated:cad:1:2"), generated);
            assert!(TrainingSource::parse("generated:cad").is_err());
            let normal = NoiseDirection::Normal;
            let noisy = parse("generated:cad:1:2").with_noise(Some(&[0.5]), normal);
            let mut config = SetConfig::new(SetKind::Cad, 1, 2);
            config.noise_levels = vec![0.5];
            config.noise_direction = normal;
            assert_eq!(noisy.unwrap(), TrainingSource::Generated(config));
            let dir = parse("data/set");
            assert_eq!(dir.clone().with_noise(Some(&[0.5]), normal).unwrap(), dir);
            let bad = parse("generated:cad:1:2").with_noise(Some(&[-1.0]), normal);
            assert!(bad.unwrap_err().to_string().contains("noise level -1"));
        }
        #[cfg(not(feature = "generator"))]
        {
            let e = TrainingSource::parse("generated:cad:1:2").unwrap_err();
            assert!(e.to_string().contains("without the generator"), "{e}");
        }
    }

    #[cfg(feature = "generator")]
    #[test]
    fn a_generated_set_written_as_a_dataset() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("set");
        let mut config = SetConfig::new(SetKind::Cad, 3, 2);
        config.points = 1000..=1200;
        let files = std::sync::atomic::AtomicUsize::new(0);
        let progress = || {
            files.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        let points = write_generated(&config, &out, &progress).unwrap();
        let set = crate::synth::generate(&config).unwrap();
        assert_eq!(files.load(std::sync::atomic::Ordering::Relaxed), 2);
        assert_eq!(points, set.iter().map(|c| c.1.cloud.len()).sum::<usize>());
        let read = load(&out, &[Role::Train], Class::NonEdge, &mut |_, _| {}).unwrap();
        let names: Vec<&String> = read.iter().map(|c| &c.0).collect();
        assert_eq!(names, set.iter().map(|c| &c.0).collect::<Vec<_>>());
        assert_eq!(read[1].1.labels, set[1].1.labels);

        config.noise_levels = vec![-1.0];
        let refused = dir.path().join("refused");
        assert!(write_generated(&config, &refused, &progress).is_err());
        assert!(!refused.exists());
    }
}
