//! Measures training speed of the default network at the paper's batch size on random data.
//!
//! `cargo run --release -p bounded-nn --example train_speed -- [iterations] [points]`
//! (defaults: 200 iterations, 200000 points). Prints seconds per iteration and the time 3000
//! iterations would take.

use std::time::Instant;

use bounded_nn::{Dataset, ModelConfig, TrainConfig, train};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>());
    let iterations = args.next().transpose()?.unwrap_or(200);
    let points = args.next().transpose()?.unwrap_or(200_000);
    let config = ModelConfig::new(4, 12);
    let mut rng = StdRng::seed_from_u64(0);
    let features: Vec<f32> = (0..points * config.n_inputs())
        .map(|_| rng.random())
        .collect();
    let labels: Vec<u8> = (0..points).map(|_| rng.random_range(0..3)).collect();
    let data = Dataset::new(&features, &labels, config.n_inputs())?;
    let train_config = TrainConfig::new(config)
        .with_iterations(iterations)
        .with_runs(1);
    let start = Instant::now();
    let mut loop_speed = 0.0;
    let trained = train(&data, &train_config, |p| {
        loop_speed = p.iterations_per_second
    })?;
    let total = start.elapsed().as_secs_f64();
    println!(
        "{iterations} iterations at batch {}: {:.4} s/iteration in the loop (3000 iterations: {:.1} s), {total:.2} s in all with setup (val loss {:.4}, rayon threads {})",
        train_config.batch_size,
        1.0 / loop_speed,
        3000.0 / loop_speed,
        trained.val_loss,
        rayon::current_num_threads()
    );
    Ok(())
}
