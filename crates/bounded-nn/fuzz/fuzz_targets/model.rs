//! Fuzzes model files: any bytes must give a classifier or an error, never a panic, an abort
//! or a huge allocation; a classifier then predicts for two points.
#![no_main]

use bounded_nn::{Classifier, ModelFile, N_CLASSES};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(file) = ModelFile::from_bytes(data) else {
        return;
    };
    let Ok(classifier) = Classifier::from_file(file) else {
        return;
    };
    let n = classifier.n_inputs();
    let features: Vec<f32> = (0..2 * n).map(|i| (i % 7) as f32 * 0.5 - 1.0).collect();
    let mut out = vec![[0f32; N_CLASSES]; 2];
    let _ = classifier.predict(&features, &mut out);
});
