//! Labelled datasets: which clouds train, validate and evaluate, and the validation sample.
//!
//! A dataset is a directory. Clouds in its `train/`, `validation/` and `evaluation/`
//! subdirectories take that role; a `manifest.txt` (lines `<role> <path>`, paths relative
//! to the directory, `#` comments) lists roles explicitly and takes precedence. A generated
//! set written into `train/` is a dataset like any other.
//!
//! ```
//! use bounded_data::dataset::{Role, validation_sample};
//! use bounded_geom::Class;
//!
//! let labels = [vec![Class::NonEdge; 5000], vec![Class::Sharp; 40], vec![Class::Boundary; 300]].concat();
//! let sample = validation_sample(&labels, 7);
//! assert_eq!(sample.len(), 1000 + 40 + 100);
//! assert_eq!(Role::parse("train"), Some(Role::Train));
//! ```

use crate::labels::{self, Convention};
use crate::synth::SetConfig;
use crate::{DataError, LabelledCloud, abc, format};
use bounded_geom::Class;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

/// Points per class in the validation sample (non-edge, sharp, boundary), as in the paper.
pub const VALIDATION_PER_CLASS: [usize; 3] = [1000, 1000, 100];

/// File extensions of clouds a dataset directory may hold.
const CLOUD_EXTENSIONS: [&str; 7] = ["ply", "pcd", "xyz", "txt", "csv", "las", "laz"];

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
                    &format!("unknown role {role:?} (train, validation or evaluation)"),
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

/// The cloud files directly in `dir`, by extension, sorted.
pub fn cloud_files(dir: &Path) -> Result<Vec<PathBuf>, DataError> {
    let io = |source| DataError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        let known = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| CLOUD_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()));
        if known && path.is_file() {
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

/// Where training clouds come from, parsed from a spec (`bounded train --data`).
#[derive(Debug, Clone, PartialEq)]
pub enum TrainingSource {
    /// A dataset directory: its train and validation clouds (a directory without roles: all).
    Dataset(PathBuf),
    /// `abc:DIR`: ABC models, OBJ meshes beside their features YAML (see [`abc::load_dir`]).
    Abc(PathBuf),
    /// `generated:KIND:SEED[:SHAPES]`: a generated set (see [`SetConfig::from_spec`]).
    Generated(SetConfig),
}

impl TrainingSource {
    /// Parses `spec`: `generated:KIND:SEED[:SHAPES]`, `abc:DIR`, else a dataset directory.
    pub fn parse(spec: &str) -> Result<TrainingSource, DataError> {
        if spec.starts_with("generated:") {
            return Ok(TrainingSource::Generated(SetConfig::from_spec(spec)?));
        }
        Ok(match spec.strip_prefix("abc:") {
            Some(dir) => TrainingSource::Abc(dir.into()),
            None => TrainingSource::Dataset(spec.into()),
        })
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
            TrainingSource::Generated(config) => crate::synth::generate(config),
        }
    }
}

/// The validation sample: [`VALIDATION_PER_CLASS`] random points of each class (all of a
/// class that has fewer), as sorted indices into `labels`; the same seed gives the same sample.
///
/// For a dataset of several clouds, pass their labels concatenated.
pub fn validation_sample(labels: &[Class], seed: u64) -> Vec<usize> {
    validation_sample_with(labels, VALIDATION_PER_CLASS, seed)
}

/// [`validation_sample`] with other per-class counts (indexed by `Class as usize`).
pub fn validation_sample_with(labels: &[Class], per_class: [usize; 3], seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sample = Vec::new();
    for class in Class::ALL {
        let mut members: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == class).collect();
        let take = per_class[class as usize].min(members.len());
        // Partial Fisher-Yates: written out so the sample does not depend on how a rand
        // version implements index sampling.
        for k in 0..take {
            let j = rng.random_range(k..members.len());
            members.swap(k, j);
        }
        sample.extend_from_slice(&members[..take]);
    }
    sample.sort_unstable();
    sample
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{NoiseDirection, SetKind};

    fn labels() -> Vec<Class> {
        // Interleaved classes: 5000 non-edge, 50 sharp, 300 boundary.
        (0..5350)
            .map(|i| match i % 107 {
                0 => Class::Sharp,
                1..=6 => Class::Boundary,
                _ => Class::NonEdge,
            })
            .collect()
    }

    #[test]
    fn validation_sample_takes_the_paper_counts_or_all() {
        let l = labels();
        let counts = |s: &[usize]| {
            let mut c = [0; 3];
            for &i in s {
                c[l[i] as usize] += 1;
            }
            c
        };
        assert_eq!(l.iter().filter(|&&c| c == Class::Sharp).count(), 50);
        assert_eq!(l.iter().filter(|&&c| c == Class::Boundary).count(), 300);
        let s = validation_sample(&l, 1);
        assert_eq!(counts(&s), [1000, 50, 100]);
        assert!(s.windows(2).all(|w| w[0] < w[1]), "sorted and distinct");
        assert_eq!(s, validation_sample(&l, 1));
        assert_ne!(s, validation_sample(&l, 2));
        assert_eq!(
            counts(&validation_sample_with(&l, [3, 0, 300], 5)),
            [3, 0, 300]
        );
    }

    #[test]
    fn directory_roles_and_manifest_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        for (sub, file) in [
            ("train", "b.ply"),
            ("train", "a.xyz"),
            ("train", "notes.md"),
            ("evaluation", "c.LAS"),
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
        assert!(e.contains("line 3: unknown role \"test\""), "{e}");
        std::fs::write(&path, "train\n").unwrap();
        let e = Manifest::read(&path).unwrap_err().to_string();
        assert!(e.contains("line 1: expected `<role> <path>`"), "{e}");
    }

    #[test]
    fn generated_specs_parse_or_say_what_is_wrong() {
        let config = SetConfig::from_spec("generated:boundary:7").unwrap();
        assert_eq!(config, SetConfig::new(SetKind::Boundary, 7, 60));
        assert_eq!(SetConfig::from_spec("generated:cad:1:5").unwrap().shapes, 5);
        for (spec, expected) in [
            ("generated:cad", "expected generated:KIND:SEED[:SHAPES]"),
            (
                "generated:cad:1:2:3",
                "expected generated:KIND:SEED[:SHAPES]",
            ),
            (
                "generated:cube:1",
                "unknown set kind \"cube\" (cad, random, boundary, mixed)",
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
        ] {
            let e = SetConfig::from_spec(spec).unwrap_err();
            assert!(matches!(e, DataError::Generator { .. }), "{spec}: {e}");
            assert!(e.to_string().contains(expected), "{spec}: {e}");
        }
    }

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
        let generated = TrainingSource::Generated(SetConfig::new(SetKind::Cad, 1, 2));
        assert_eq!(parse("generated:cad:1:2"), generated);
        assert!(TrainingSource::parse("generated:cad").is_err());
    }
}
