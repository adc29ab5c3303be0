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

/// `eval` scores what `detect` would label with the same options: `--fast` (the first network
/// alone) scores Default lower than both networks, and `--scales` equal to the model's own
/// changes nothing while other scales change the result.
#[test]
fn eval_scores_the_first_stage_alone_and_other_scales() {
    let Some(dir) = dataset("default") else {
        return;
    };
    let eval = |extra: &[&str]| {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"eval", &"--data", &dir];
        args.extend(extra.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let run = bounded_paths(&args);
        assert!(run.status.success(), "{extra:?}: {}", stderr(&run));
        String::from_utf8_lossy(&run.stdout).into_owned()
    };
    let both = eval(&[]);
    let fast = eval(&["--fast"]);
    // `bounded eval` gives the embedded model 0.708 with both networks, 0.564 with the first.
    assert!(
        median_mcc(&both) > median_mcc(&fast) + 0.05,
        "two stages {} vs first stage {}",
        median_mcc(&both),
        median_mcc(&fast)
    );
    let own = "128,108,91,76,64,54,45,38,32,27,23,19,16,13,11,10";
    assert_eq!(eval(&["--scales", own]), both);
    let smaller = "96,81,68,57,48,40,34,28,24,20,17,14,12,10,8,7";
    assert_ne!(eval(&["--scales", smaller]), both);
}
