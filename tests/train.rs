//! `bounded train` on a small generated set: the model file records the requested network,
//! `detect` runs with it, and a bad width fails before any work.

mod common;

use bounded_nn::ModelFile;
use common::{bounded_paths, stderr};
use std::ffi::OsStr;
use std::path::Path;
use std::process::Output;

/// Runs `bounded train` on a 2-cloud generated set with `options`, writing `model`.
fn train(model: &Path, options: &[&str]) -> Output {
    let mut args: Vec<&dyn AsRef<OsStr>> = vec![&"train", &"--data", &"generated:cad:1:2"];
    args.extend(options.iter().map(|o| o as &dyn AsRef<OsStr>));
    args.extend([&"-o" as &dyn AsRef<OsStr>, &model]);
    bounded_paths(&args)
}

#[test]
fn train_with_custom_widths_writes_a_model_that_detect_uses() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("tiny.bmodel");
    let run = train(
        &model,
        &[
            "--iterations",
            "20",
            "--runs",
            "1",
            "--fusion-widths",
            "5",
            "--hidden-widths",
            "7,3",
        ],
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let file = ModelFile::load(&model).unwrap();
    assert_eq!(file.model.fusion_widths, vec![5]);
    assert_eq!(file.model.hidden_widths, vec![7, 3]);
    assert!(file.provenance.command.contains("--hidden-widths 7,3"));

    let cloud = dir.path().join("box.ply");
    let labelled = common::box_cloud(2000, 4);
    let n = labelled.cloud.len();
    bounded_data::format::write(
        &cloud,
        &bounded_data::table::PointTable::new(labelled.cloud),
    )
    .unwrap();
    let out = dir.path().join("out.ply");
    let run = bounded_paths(&[&"detect", &cloud, &"--model", &model, &"-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(bounded_data::format::read(&out).unwrap().len(), n);
}

#[test]
fn a_zero_width_is_refused_before_training() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("bad.bmodel");
    let run = train(&model, &["--hidden-widths", "16,0"]);
    assert!(!run.status.success());
    assert!(
        stderr(&run).contains("hidden widths must be positive"),
        "{}",
        stderr(&run)
    );
    assert!(!model.exists());
}
