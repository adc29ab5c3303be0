//! The embedded model on the published evaluation clouds in `../shared/datasets`; skipped,
//! with the reason printed, when they are not beside the checkout.

mod common;

use common::{bounded_paths, stderr};
use std::path::PathBuf;

fn dataset(name: &str) -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/datasets/pcednet")
        .join(name);
    if dir.is_dir() {
        Some(dir)
    } else {
        println!(
            "SKIPPED: {} is missing (the shared datasets are not beside the checkout)",
            dir.display()
        );
        None
    }
}

/// The median MCC of our model, from the last line of the per-model table.
fn median_mcc(stdout: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("| **median**"))
        .expect("median row");
    line.split('|').nth(4).unwrap().trim().parse().unwrap()
}

#[test]
fn embedded_model_beats_the_published_pcednet_on_the_default_set() {
    let Some(dir) = dataset("default") else {
        return;
    };
    let run = bounded_paths(&[&"eval", &"--data", &dir]);
    assert!(run.status.success(), "{}", stderr(&run));
    let mcc = median_mcc(&String::from_utf8_lossy(&run.stdout));
    // PCEDNet-2c's published median on these models is 0.402.
    assert!(mcc > 0.402, "median MCC {mcc}");
}
