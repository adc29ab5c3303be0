//! `bounded generate`: noise levels and direction from the command line; bad options refused.

mod common;

use bounded_data::LabelledCloud;
use bounded_data::labels::{Convention, load};
use common::{bounded_paths, stderr};
use std::path::Path;

/// Generates 2 CAD shapes of seed 3 into `dir` with `options`; returns them by file name.
fn generate(dir: &Path, options: &[&str]) -> Vec<(String, LabelledCloud)> {
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![
        &"generate",
        &"--kind",
        &"cad",
        &"--shapes",
        &"2",
        &"--seed",
        &"3",
        &"-o",
        &dir,
    ];
    args.extend(options.iter().map(|o| o as &dyn AsRef<std::ffi::OsStr>));
    let run = bounded_paths(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| {
            let name = f.file_name().unwrap().to_string_lossy().into_owned();
            (name, load(f, Convention::ClassProperty).unwrap())
        })
        .collect()
}

#[test]
fn noise_levels_and_direction_move_the_same_points() {
    let root = tempfile::tempdir().unwrap();
    let clean = generate(&root.path().join("clean"), &["--noise", "0"]);
    let normal = generate(
        &root.path().join("normal"),
        &["--noise", "0.5", "--noise-along", "normal"],
    );
    let any = generate(&root.path().join("any"), &["--noise", "0.5"]);
    assert_eq!(clean.len(), 2);
    for ((c, n), a) in clean.iter().zip(&normal).zip(&any) {
        assert_eq!(c.0, n.0);
        assert_eq!(c.1.labels, n.1.labels, "{}: labels are the clean ones", c.0);
        assert_eq!(c.1.labels, a.1.labels);
        let moved = |other: &LabelledCloud| {
            (0..c.1.cloud.len())
                .filter(|&i| c.1.cloud.position_f64(i) != other.cloud.position_f64(i))
                .count()
        };
        assert!(moved(&n.1) > c.1.cloud.len() * 9 / 10, "{}", c.0);
        assert!(moved(&a.1) > c.1.cloud.len() * 9 / 10, "{}", c.0);
        assert_ne!(n.1.cloud, a.1.cloud, "{}: the direction matters", c.0);
    }
}

#[test]
fn bad_noise_or_no_shapes_is_refused_before_any_file() {
    for (option, named) in [
        ("--noise=-1", "--noise"),
        ("--noise=nan", "--noise"),
        ("--noise=inf", "--noise"),
        ("--shapes=0", "--shapes"),
    ] {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("set");
        let run = bounded_paths(&[&"generate", &"-o", &out, &option]);
        let err = stderr(&run);
        assert!(!run.status.success(), "{option}: accepted");
        assert!(err.contains(named) && !err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{option}: {} created", out.display());
    }
}

#[test]
fn free_form_label_rules_follow_the_kind() {
    let root = tempfile::tempdir().unwrap();
    let set = |name: &str, kind: &str| {
        let out = root.path().join(name);
        let run = bounded_paths(&[
            &"generate",
            &"--kind",
            &kind,
            &"--shapes",
            &"1",
            &"--seed",
            &"5",
            &"-o",
            &out,
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let file = std::fs::read_dir(&out)
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path();
        load(&file, Convention::ClassProperty).unwrap()
    };
    let sharp = |c: &LabelledCloud| -> Vec<bool> {
        (c.labels.iter())
            .map(|&l| l == bounded_geom::Class::Sharp)
            .collect()
    };
    let default = set("default", "freeform");
    let deep = set("deep", "freeform:depth=2");
    assert_eq!(
        default.cloud, deep.cloud,
        "a rule changes labels, not geometry"
    );
    let (all, kept) = (sharp(&default), sharp(&deep));
    let count = |v: &[bool]| v.iter().filter(|&&s| s).count();
    assert!(
        count(&kept) < count(&all),
        "a deeper minimum keeps fewer sharp points"
    );
    assert!(
        kept.iter().zip(&all).all(|(&k, &a)| !k || a),
        "and adds none"
    );
    for bad in ["cad:depth=2", "freeform:depth=-1", "freeform:width=2"] {
        let out = root.path().join("bad");
        let run = bounded_paths(&[&"generate", &"--kind", &bad, &"-o", &out]);
        let err = stderr(&run);
        assert!(!run.status.success(), "{bad}: accepted");
        assert!(
            err.contains("--kind") && !err.contains("panicked"),
            "{bad}: {err}"
        );
        assert!(!out.exists(), "{bad}: {} created", out.display());
    }
}
