//! `bounded demo` runs without files and scores above a floor on its generated scene.

mod common;

use common::{bounded_paths, stderr};

/// The value after `key` on the line starting with `label`.
fn score(stdout: &str, label: &str, key: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("no {label} line in {stdout}"));
    let rest = &line[line
        .find(key)
        .unwrap_or_else(|| panic!("no {key} in {line}"))
        + key.len()..];
    rest.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn demo_writes_its_files_and_scores_above_the_floor() {
    let dir = tempfile::tempdir().unwrap();
    let run = bounded_paths(&[&"demo", &"-o", &dir.path()]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(dir.path().join("demo.ply").is_file());
    assert!(dir.path().join("demo.png").is_file());
    let sharp_mcc = score(&stdout, "sharp:", "MCC ");
    let boundary_f1 = score(&stdout, "boundary:", "F1 ");
    // Floors well below what the embedded model reaches (see README), so that a broken
    // pipeline or model fails, not a small change of the scene.
    assert!(sharp_mcc > 0.5, "sharp MCC {sharp_mcc}\n{stdout}");
    assert!(boundary_f1 > 0.6, "boundary F1 {boundary_f1}\n{stdout}");
}
