//! `bounded train` on a small generated set: the model file records the requested network,
//! `detect` runs with it (a two-stage one's second stage too), the noise options reach the
//! generated sets, ABC models are read, and a bad width or noise level fails before any work.

mod common;

use bounded_data::dataset::TrainingSource;
use bounded_features::{
    CONTEXT_NAMES, ContextSet, FeatureConfig, FeatureGroups, extract, extract_in_context,
};
use bounded_nn::calibration::{Calibration, describe};
use bounded_nn::{Classifier, Detector, ModelFile, TrainingCloud, class_at};
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
    // No --calibrate-on: the most probable class.
    assert_eq!(file.sensitivity, None);
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

/// Runs `bounded detect cloud --model model [extra] -o out`.
fn detect(cloud: &Path, model: &Path, extra: &[&str], out: &Path) -> Output {
    let mut args: Vec<&dyn AsRef<OsStr>> = vec![&"detect", &cloud, &"--model", &model];
    args.extend(extra.iter().map(|o| o as &dyn AsRef<OsStr>));
    args.extend([&"-o" as &dyn AsRef<OsStr>, &out]);
    bounded_paths(&args)
}

/// Asserts that the `p_sharp` column of the PLY cloud at `path` (`scalar_p_sharp`, named for
/// CloudCompare) is `expected`'s to 1e-6.
fn assert_p_sharp(path: &Path, expected: &[[f32; 3]]) {
    let table = bounded_data::format::read(path).unwrap();
    let p_sharp = table.property("scalar_p_sharp").expect("p_sharp");
    for (i, p) in expected.iter().enumerate() {
        let d = (p_sharp.get_f64(i) - f64::from(p[1])).abs();
        assert!(d < 1e-6, "{}: point {i} off by {d}", path.display());
    }
}

#[test]
fn a_context_model_labels_with_its_second_stage() {
    context_model_labels_with_its_second_stage(ContextSet::Neighbourhood);
}

#[test]
fn a_line_context_model_labels_with_its_second_stage() {
    context_model_labels_with_its_second_stage(ContextSet::WithLine);
}

fn context_model_labels_with_its_second_stage(context: ContextSet) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("context.bmodel");
    let options = ["--iterations", "20", "--runs", "1", "--scales", "32,16"];
    let flags: &[&str] = match context {
        ContextSet::Neighbourhood => &["--context"],
        ContextSet::WithLine => &["--context", "--context-line"],
    };
    let run = train(&model, &[&options[..], flags].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let file = ModelFile::load(&model).unwrap();
    let second = file.second_stage.as_deref().expect("a second stage");
    let names: Vec<&str> = second.feature_names.iter().map(String::as_str).collect();
    assert_eq!(names[..12], FeatureGroups::BOUNDED.names());
    assert_eq!(names[12..], context.names());
    assert_eq!(names[12..16], CONTEXT_NAMES);
    let detector = Detector::new(Classifier::from_file(file.clone()).unwrap()).unwrap();
    assert_eq!(detector.feature_config().context, context);

    // The library's way: first stage, its context, second stage.
    let cloud_path = dir.path().join("box.ply");
    let table = bounded_data::table::PointTable::new(common::box_cloud(2000, 4).cloud);
    bounded_data::format::write(&cloud_path, &table).unwrap();
    let cloud = bounded_data::format::read(&cloud_path).unwrap().cloud;
    let config = FeatureConfig {
        scales: vec![32, 16],
        groups: FeatureGroups::BOUNDED,
        context,
    };
    let classifier = Classifier::from_file(file.clone()).unwrap();
    let mut first = vec![[0f32; 3]; cloud.len()];
    let features = extract(&cloud, &config).unwrap();
    classifier.predict(features.as_slice(), &mut first).unwrap();
    let mut second = vec![[0f32; 3]; cloud.len()];
    let features = extract_in_context(&cloud, &config, &first).unwrap();
    let second_stage = classifier.second_stage().unwrap();
    second_stage
        .predict(features.as_slice(), &mut second)
        .unwrap();
    assert!(first != second, "the second stage changed no probability");

    // detect gives the second stage's probabilities, --fast the first's.
    let out = dir.path().join("out.ply");
    let run = detect(&cloud_path, &model, &[], &out);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_p_sharp(&out, &second);
    let fast = dir.path().join("fast.ply");
    let run = detect(&cloud_path, &model, &["--fast"], &fast);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_p_sharp(&fast, &first);

    // Refused, nothing written: --fast with a one-stage model, a second stage reading
    // context this build does not compute.
    let one_stage = dir.path().join("one.bmodel");
    file.first_stage().save(&one_stage).unwrap();
    let mut renamed = file.clone();
    renamed.second_stage.as_mut().unwrap().feature_names[12] = "ctx_unknown".into();
    let unknown = dir.path().join("renamed.bmodel");
    renamed.save(&unknown).unwrap();
    for (model, extra, message) in [
        (&one_stage, &["--fast"][..], "one stage"),
        (&unknown, &[][..], "ctx_unknown"),
    ] {
        let refused = dir.path().join("refused.ply");
        let run = detect(&cloud_path, model, extra, &refused);
        assert!(!run.status.success());
        assert!(stderr(&run).contains(message), "{}", stderr(&run));
        assert!(!refused.exists());
    }
}

/// The class and the three probabilities of every point of the PLY cloud at `path`.
fn classes_and_probabilities(path: &Path) -> (Vec<u8>, Vec<[f32; 3]>) {
    let table = bounded_data::format::read(path).unwrap();
    let column = |name: &str| table.property(name).expect(name).clone();
    let class = column("scalar_class");
    let p = ["scalar_p_nonedge", "scalar_p_sharp", "scalar_p_boundary"].map(column);
    (0..table.len())
        .map(|i| {
            (
                class.get_f64(i) as u8,
                p.each_ref().map(|c| c.get_f64(i) as f32),
            )
        })
        .unzip()
}

#[test]
fn calibrate_on_records_the_decision_that_detect_applies() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("calibrated.bmodel");
    let validation = "generated:cad:2001:2";
    let options = ["--iterations", "30", "--runs", "1", "--scales", "32,16"];
    let run = train(
        &model,
        &[&options[..], &["--calibrate-on", validation]].concat(),
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let file = ModelFile::load(&model).unwrap();
    // The decision the library chooses on those clouds (`Calibration::chosen_sensitivity`).
    let loaded = TrainingSource::parse(validation).unwrap().load().unwrap();
    let clouds: Vec<_> = (loaded.iter())
        .map(|(name, c)| TrainingCloud::new(name, &c.cloud, &c.labels))
        .collect();
    let argmax =
        Detector::new(Classifier::from_file(file.clone().with_sensitivity(None).unwrap()).unwrap())
            .unwrap();
    let chosen = Calibration::measure(&argmax, &clouds).unwrap();
    assert_eq!(file.sensitivity, chosen.chosen_sensitivity());
    assert!(stderr(&run).contains(&format!("deciding by {}", describe(file.sensitivity))));

    // detect applies the recorded rule unless --sensitivity replaces it (`argmax` included).
    let cloud = dir.path().join("box.ply");
    let table = bounded_data::table::PointTable::new(common::box_cloud(2000, 4).cloud);
    bounded_data::format::write(&cloud, &table).unwrap();
    let eager = dir.path().join("eager.bmodel");
    file.clone()
        .with_sensitivity(Some(0.95))
        .unwrap()
        .save(&eager)
        .unwrap();
    for (extra, rule) in [
        (&[][..], Some(0.95)),
        (&["--sensitivity", "argmax"][..], None),
        (&["--sensitivity", "0.3"][..], Some(0.3)),
    ] {
        let out = dir.path().join("out.ply");
        let run = detect(&cloud, &eager, extra, &out);
        assert!(run.status.success(), "{}", stderr(&run));
        let (classes, probabilities) = classes_and_probabilities(&out);
        let expected: Vec<u8> = (probabilities.iter())
            .map(|p| class_at(p, rule) as u8)
            .collect();
        assert_eq!(classes, expected, "{extra:?}");
        if rule == Some(0.95) {
            // Not the most probable class: the eager rule calls more points sharp.
            let sharp = |c: &[u8]| c.iter().filter(|&&c| c == 1).count();
            let by_argmax: Vec<u8> = (probabilities.iter())
                .map(|p| class_at(p, None) as u8)
                .collect();
            assert!(
                sharp(&classes) > sharp(&by_argmax),
                "{} vs {}",
                sharp(&classes),
                sharp(&by_argmax)
            );
        }
    }
    let run = detect(
        &cloud,
        &eager,
        &["--sensitivity", "most"],
        &dir.path().join("x.ply"),
    );
    assert!(!run.status.success());
    assert!(
        stderr(&run).contains("neither a number nor `argmax`"),
        "{}",
        stderr(&run)
    );
}

#[test]
fn noise_options_reach_the_generated_training_sets() {
    let dir = tempfile::tempdir().unwrap();
    let hash = |name: &str, noise: &[&str]| {
        let model = dir.path().join(name);
        let mut options = vec!["--iterations", "5", "--runs", "1"];
        options.extend(noise);
        let run = train(&model, &options);
        assert!(run.status.success(), "{}", stderr(&run));
        let file = ModelFile::load(&model).unwrap();
        assert!(file.provenance.command.contains(&noise.join(" ")));
        file.provenance.data_hash
    };
    let default = hash("default.bmodel", &[]);
    let clean = hash("clean.bmodel", &["--noise", "0"]);
    let normal = hash(
        "normal.bmodel",
        &["--noise", "1", "--noise-along", "normal"],
    );
    let any = hash("any.bmodel", &["--noise", "1"]);
    assert_eq!(
        default,
        hash("again.bmodel", &[]),
        "the data is reproducible"
    );
    for (a, b) in [(clean, normal), (clean, any), (normal, any)] {
        assert_ne!(a, b, "other noise, other training data");
    }
}

#[test]
fn bad_options_are_refused_before_training() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("bad.bmodel");
    let labelled = dir.path().join("labelled");
    std::fs::create_dir(&labelled).unwrap();
    for (run, expected) in [
        (
            train(&model, &["--hidden-widths", "16,0"]),
            "hidden widths must be positive",
        ),
        (train(&model, &["--noise", "0.2,-1"]), "--noise"),
        (
            // A directory is used as it is: noise options there would do nothing.
            bounded_paths(&[
                &"train", &"--data", &labelled, &"--noise", &"0.5", &"-o", &model,
            ]),
            "apply to generated sets",
        ),
    ] {
        let err = stderr(&run);
        assert!(!run.status.success());
        assert!(err.contains(expected) && !err.contains("panicked"), "{err}");
        assert!(!model.exists());
    }
}

/// Writes an ABC-style model: a `width` x `height` grid of vertices folded at a right angle
/// along the column `u = fold`, as an OBJ mesh and a features YAML naming that column a sharp
/// curve. Its labels: `height` sharp vertices (the fold), `2 (width + height) - 6` boundary
/// ones (the rim but the fold's two ends), the rest non-edge.
fn write_abc_model(dir: &Path, id: &str, width: usize, height: usize, fold: usize) {
    std::fs::create_dir_all(dir).unwrap();
    let index = |u: usize, v: usize| v * width + u + 1;
    let mut obj = String::from("# folded sheet\n");
    for v in 0..height {
        for u in 0..width {
            let (x, z) = if u <= fold { (u, 0) } else { (fold, u - fold) };
            obj.push_str(&format!("v {x} {v} {z}\n"));
        }
    }
    for v in 0..height - 1 {
        for u in 0..width - 1 {
            let (a, b, c, d) = (
                index(u, v),
                index(u + 1, v),
                index(u + 1, v + 1),
                index(u, v + 1),
            );
            obj.push_str(&format!("f {a} {b} {c}\nf {a} {c} {d}\n"));
        }
    }
    let fold_column: Vec<String> = (0..height)
        .map(|v| (index(fold, v) - 1).to_string())
        .collect();
    let yaml = format!(
        "curves:\n- sharp: true\n  type: Line\n  vert_indices: [{}]\nsurfaces: []\n",
        fold_column.join(", ")
    );
    std::fs::write(dir.join(format!("{id}_trimesh_000.obj")), obj).unwrap();
    std::fs::write(dir.join(format!("{id}_features_000.yml")), yaml).unwrap();
}

#[test]
fn abc_models_are_a_training_source() {
    let dir = tempfile::tempdir().unwrap();
    let abc = dir.path().join("abc");
    write_abc_model(&abc.join("00000001"), "00000001", 20, 20, 10);
    write_abc_model(&abc.join("00000002"), "00000002", 24, 20, 12);
    let model = dir.path().join("abc.bmodel");
    let data = format!("abc:{}", abc.display());
    let run = bounded_paths(&[
        &"train",
        &"--data",
        &data,
        &"--scales",
        &"16,8",
        &"--iterations",
        &"5",
        &"--runs",
        &"1",
        &"-o",
        &model,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    // 20 x 20 + 24 x 20 points; sharp 20 + 20; boundary (2 * 40 - 6) + (2 * 44 - 6).
    let err = stderr(&run);
    assert!(
        err.contains("2 clouds, 880 points (40 sharp, 156 boundary)"),
        "{err}"
    );
    assert_eq!(ModelFile::load(&model).unwrap().scales, vec![16, 8]);

    // A mesh without its features file is refused, naming it, before any model is written.
    std::fs::remove_file(abc.join("00000002/00000002_features_000.yml")).unwrap();
    std::fs::remove_file(&model).unwrap();
    let run = bounded_paths(&[&"train", &"--data", &data, &"-o", &model]);
    let err = stderr(&run);
    assert!(!run.status.success());
    assert!(
        err.contains("00000002_trimesh_000.obj: no features file"),
        "{err}"
    );
    assert!(!model.exists());
}
