//! `bounded train` on a small generated set: the model file records the requested network,
//! `detect` runs with it (a two-stage one's second stage too), and a bad width fails before
//! any work.

mod common;

use bounded_features::{CONTEXT_NAMES, FeatureConfig, FeatureGroups, extract, extract_in_context};
use bounded_nn::{Classifier, ModelFile};
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
fn a_context_model_labels_with_its_second_stage() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("context.bmodel");
    let options = [
        "--iterations",
        "20",
        "--runs",
        "1",
        "--scales",
        "32,16",
        "--context",
    ];
    let run = train(&model, &options);
    assert!(run.status.success(), "{}", stderr(&run));
    let file = ModelFile::load(&model).unwrap();
    let second = file.second_stage.as_deref().expect("a second stage");
    let names: Vec<&str> = second.feature_names.iter().map(String::as_str).collect();
    assert_eq!(names[..12], FeatureGroups::BOUNDED.names());
    assert_eq!(names[12..], CONTEXT_NAMES);

    let cloud_path = dir.path().join("box.ply");
    let table = bounded_data::table::PointTable::new(common::box_cloud(2000, 4).cloud);
    bounded_data::format::write(&cloud_path, &table).unwrap();
    let out = dir.path().join("out.ply");
    let run = bounded_paths(&[&"detect", &cloud_path, &"--model", &model, &"-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    let labelled = bounded_data::format::read(&out).unwrap();
    let p_sharp = labelled.property("p_sharp").expect("p_sharp");

    // The same through the library: first stage, context, second stage.
    let cloud = bounded_data::format::read(&cloud_path).unwrap().cloud;
    let config = FeatureConfig {
        scales: vec![32, 16],
        groups: FeatureGroups::BOUNDED,
    };
    let classifier = Classifier::from_file(file.clone()).unwrap();
    let mut first = vec![[0f32; 3]; cloud.len()];
    let features = extract(&cloud, &config).unwrap();
    classifier.predict(features.as_slice(), &mut first).unwrap();
    let mut expected = vec![[0f32; 3]; cloud.len()];
    let features = extract_in_context(&cloud, &config, &first).unwrap();
    let second = classifier.second_stage().unwrap();
    second.predict(features.as_slice(), &mut expected).unwrap();
    for (i, p) in expected.iter().enumerate() {
        assert!(
            (p_sharp.get_f64(i) - f64::from(p[1])).abs() < 1e-6,
            "point {i}"
        );
    }
    let changed = first.iter().zip(&expected).filter(|(a, b)| a != b).count();
    assert!(changed > 0, "the second stage changed no probability");

    // --fast runs the first stage alone; a one-stage model has nothing to leave out.
    let fast = dir.path().join("fast.ply");
    let run = bounded_paths(&[
        &"detect",
        &cloud_path,
        &"--model",
        &model,
        &"--fast",
        &"-o",
        &fast,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let fast = bounded_data::format::read(&fast).unwrap();
    let fast_sharp = fast.property("p_sharp").expect("p_sharp");
    for (i, p) in first.iter().enumerate() {
        assert!(
            (fast_sharp.get_f64(i) - f64::from(p[1])).abs() < 1e-6,
            "point {i}"
        );
    }
    let one_stage = dir.path().join("one.bmodel");
    file.first_stage().save(&one_stage).unwrap();
    let refused = dir.path().join("refused.ply");
    let run = bounded_paths(&[
        &"detect",
        &cloud_path,
        &"--model",
        &one_stage,
        &"--fast",
        &"-o",
        &refused,
    ]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("one stage"), "{}", stderr(&run));
    assert!(!refused.exists());

    // A second stage reading context this build does not compute is refused.
    let mut renamed = file.clone();
    renamed.second_stage.as_mut().unwrap().feature_names[12] = "ctx_unknown".into();
    let bad = dir.path().join("renamed.bmodel");
    renamed.save(&bad).unwrap();
    let bad_out = dir.path().join("bad.ply");
    let run = bounded_paths(&[&"detect", &cloud_path, &"--model", &bad, &"-o", &bad_out]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("ctx_unknown"), "{}", stderr(&run));
    assert!(!bad_out.exists());
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
