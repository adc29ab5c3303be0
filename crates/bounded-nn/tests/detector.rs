//! The library detector against the two-pass path it replaces: every feature of the whole
//! cloud, the first network, the context of its probabilities, the second network.

use bounded_features::{extract, extract_in_context};
use bounded_geom::{Class, PointCloud, uniform_stream};
use bounded_nn::{Classifier, Decision, Detector, N_CLASSES, argmax, class_at, default_model};
use std::path::Path;

/// The embedded model's probabilities by two full passes.
fn two_passes(cloud: &PointCloud) -> Vec<[f32; N_CLASSES]> {
    let model = default_model().unwrap();
    let detector = Detector::new(default_model().unwrap()).unwrap();
    let config = detector.feature_config();
    let plain = extract(cloud, config).unwrap();
    let mut first = vec![[0.0; N_CLASSES]; cloud.len()];
    model.predict(plain.as_slice(), &mut first).unwrap();
    let context = extract_in_context(cloud, config, &first).unwrap();
    let mut second = vec![[0.0; N_CLASSES]; cloud.len()];
    let second_stage: &Classifier = model.second_stage().unwrap();
    second_stage
        .predict(context.as_slice(), &mut second)
        .unwrap();
    second
}

fn assert_identical(cloud: &PointCloud, what: &str) {
    let reference = two_passes(cloud);
    let detector = Detector::embedded().unwrap();
    let detection = detector.detect(cloud).unwrap();
    let bits = |p: &[[f32; 3]]| -> Vec<u32> { p.iter().flatten().map(|v| v.to_bits()).collect() };
    assert!(
        bits(&detection.probabilities) == bits(&reference),
        "{what}: probabilities differ from two passes"
    );
    // The classes by the model's recorded decision.
    let sensitivity = default_model().unwrap().file().sensitivity;
    for (p, c) in reference.iter().zip(&detection.classes) {
        assert_eq!(class_at(p, sensitivity), *c);
    }
}

#[test]
fn both_stages_in_one_pass_equal_two_passes_on_a_random_cube() {
    // Random points on a unit cube's faces, in random order: many chunks wait for later ones
    // across the octree's planes, so halos are computed.
    let mut r = uniform_stream(5);
    let positions: Vec<[f64; 3]> = (0..120_000)
        .map(|_| {
            let face = (r() * 6.0) as usize;
            let (u, v) = (r(), r());
            let mut p = [0.0; 3];
            p[face / 2] = (face % 2) as f64;
            p[(face / 2 + 1) % 3] = u;
            p[(face / 2 + 2) % 3] = v;
            p
        })
        .collect();
    assert_identical(&PointCloud::from_f64(&positions).unwrap(), "cube");
}

#[test]
fn both_stages_in_one_pass_equal_two_passes_on_the_real_scans() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/datasets/scans");
    let files = ["room_scan1.pcd", "CSite1_red1-utm.pcd"];
    if !dir.is_dir() {
        eprintln!("skipped: {} is missing (the real scans)", dir.display());
        return;
    }
    for name in files {
        let table = bounded_data::format::read(&dir.join(name)).unwrap();
        assert_identical(&table.cloud, name);
    }
}

#[test]
fn the_first_stage_alone_and_the_sensitivity() {
    let mut r = uniform_stream(8);
    let positions: Vec<[f64; 3]> = (0..3000)
        .map(|_| {
            let (u, v) = (r() * 40.0 - 20.0, r() * 40.0);
            if u < 0.0 { [u, v, 0.0] } else { [0.0, v, u] }
        })
        .collect();
    let cloud = PointCloud::from_f64(&positions).unwrap();
    let full = Detector::embedded().unwrap();
    let fast = Detector::embedded().unwrap().first_stage_only().unwrap();
    let first = default_model().unwrap();
    let plain = extract(&cloud, full.feature_config()).unwrap();
    let mut expected = vec![[0.0; N_CLASSES]; cloud.len()];
    first.predict(plain.as_slice(), &mut expected).unwrap();
    assert_eq!(fast.detect(&cloud).unwrap().probabilities, expected);
    assert_eq!(fast.sensitivity(), None);
    // A one-stage model has no first stage to run alone.
    assert!(fast.first_stage_only().is_err());
    // More sensitivity, more sharp points, never fewer; the probabilities stay.
    let mut last = 0;
    let reference = full.detect(&cloud).unwrap();
    for s in [0.05, 0.3, 0.5, 0.7, 0.95] {
        let d = Detector::embedded()
            .unwrap()
            .with_sensitivity(s)
            .unwrap()
            .detect(&cloud)
            .unwrap();
        assert_eq!(d.probabilities, reference.probabilities);
        let sharp = d.class_counts()[Class::Sharp as usize];
        assert!(sharp >= last, "sensitivity {s}: {sharp} sharp after {last}");
        last = sharp;
    }
    assert!(last > reference.class_counts()[Class::Sharp as usize]);
    // The embedded model decides by its recorded rule (its first stage alone by the most
    // probable class, as above), `most_probable_class` by the most probable class.
    assert_eq!(full.sensitivity(), first.file().sensitivity);
    let argmax_classes = full.most_probable_class().detect(&cloud).unwrap().classes;
    for (p, c) in reference.probabilities.iter().zip(&argmax_classes) {
        assert_eq!(Class::from_code(argmax(p)), Some(*c));
    }
    for bad in [0.0, 1.0, -0.5, f32::NAN] {
        assert!(Detector::embedded().unwrap().with_sensitivity(bad).is_err());
        let decision = Decision::Sensitivity(bad);
        assert!(
            Detector::embedded()
                .unwrap()
                .with_decision(decision)
                .is_err()
        );
    }
    // A decision as users spell it sets the same rule as the call it names.
    let with = |text: &str| {
        let decision = text.parse::<Decision>().unwrap();
        Detector::embedded()
            .unwrap()
            .with_decision(decision)
            .unwrap()
    };
    assert_eq!(with("argmax").sensitivity(), None);
    assert_eq!(with("0.3").sensitivity(), Some(0.3));
    assert!("0.3x".parse::<Decision>().is_err());
}

#[test]
fn too_few_points_and_bad_scales_are_clear_errors() {
    let cloud = PointCloud::from_f64(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    let e = Detector::embedded().unwrap().detect(&cloud).unwrap_err();
    assert!(
        e.to_string().contains("3 points") && e.to_string().contains("128"),
        "{e}"
    );
    let e = Detector::embedded()
        .unwrap()
        .with_scales(&[64, 32])
        .unwrap_err();
    assert!(e.to_string().contains("trained on 16"), "{e}");
    // The model's own scales, smallest first.
    let embedded = Detector::embedded().unwrap();
    let mut ascending = embedded.feature_config().scales.clone();
    ascending.reverse();
    assert!(embedded.with_scales(&ascending).is_err());
}
