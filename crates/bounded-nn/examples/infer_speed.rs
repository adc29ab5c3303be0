//! Measures inference throughput of the embedded default network (hand-written forward pass,
//! rayon over all cores) and, for comparison, Burn's own forward pass on the CPU backend.
//!
//! `cargo run --release -p bounded-nn --example infer_speed -- [points] [repeats]`
//! (defaults: 2000000 points, 5 repeats; the best repeat is reported).

use std::time::Instant;

use bounded_nn::{cpu_device, default_model};
use burn::prelude::*;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>());
    let points = args.next().transpose()?.unwrap_or(2_000_000);
    let repeats = args.next().transpose()?.unwrap_or(5).max(1);
    let classifier = default_model()?;
    let n = classifier.n_inputs();
    let mut rng = StdRng::seed_from_u64(1);
    let features: Vec<f32> = (0..points * n).map(|_| rng.random()).collect();
    let mut out = vec![[0.0f32; 3]; points];

    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        classifier.predict(&features, &mut out)?;
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!(
        "hand-written: {points} points in {best:.4} s = {:.2} M points/s ({} rayon threads)",
        points as f64 / best / 1e6,
        rayon::current_num_threads()
    );

    let device = cpu_device();
    let model = classifier.file().to_burn(&device)?;
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        let x = Tensor::<2>::from_data(TensorData::new(features.clone(), [points, n]), &device);
        let probabilities = burn::tensor::activation::softmax(model.forward(x), 1).into_data();
        best = best.min(start.elapsed().as_secs_f64());
        assert_eq!(probabilities.num_elements(), points * 3);
    }
    println!("burn forward: {:.2} M points/s", points as f64 / best / 1e6);
    Ok(())
}
