//! Writes the PLACEHOLDER default model `models/default.bmodel`.
//!
//! The real default model is trained by the project's CLI on real features. Until then the
//! crate embeds this one so that `default_model()` works: a small training run on a synthetic
//! toy rule over uniform random inputs in [0, 1) (4 scales x 12 features, the feature layout of
//! SPEC.md): boundary when `s_par` of the largest scale > 0.7, else sharp when `d_perp` of the
//! largest scale > 0.7, else non-edge. It knows nothing about point clouds.
//!
//! `cargo run --release -p bounded-nn --example toy_model [output path]`

use bounded_nn::{Dataset, ModelConfig, ModelFile, TrainConfig, train};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const FEATURES: [&str; 12] = [
    "sigma_u1", "sigma_u2", "sigma_u3", "sigma_l1", "sigma_l2", "sigma_l3", "d_perp", "d_par",
    "s_perp", "s_par", "c_perp", "c_par",
];
const SCALES: [usize; 4] = [128, 64, 32, 16];
const D_PERP: usize = 6;
const S_PAR: usize = 9;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/models/default.bmodel").into());
    let model = ModelConfig::new(SCALES.len(), FEATURES.len());
    let n = model.n_inputs();
    let mut rng = StdRng::seed_from_u64(2024);
    let points = 50_000;
    let features: Vec<f32> = (0..points * n).map(|_| rng.random()).collect();
    let labels: Vec<u8> = features
        .chunks_exact(n)
        .map(|x| match (x[S_PAR] > 0.7, x[D_PERP] > 0.7) {
            (true, _) => 2,
            (false, true) => 1,
            _ => 0,
        })
        .collect();
    let data = Dataset::new(&features, &labels, n)?;
    let config = TrainConfig::new(model)
        .with_iterations(400)
        .with_batch_size(4096)
        .with_runs(1)
        .with_seed(7);
    let trained = train(&data, &config, |p| {
        if let Some(v) = p.val_loss {
            eprintln!(
                "iteration {:4}: loss {:.4}, validation loss {v:.4}",
                p.iteration, p.loss
            );
        }
    })?;
    let command =
        "cargo run --release -p bounded-nn --example toy_model (PLACEHOLDER: synthetic toy rule)";
    let file = ModelFile::from_trained(
        &trained,
        SCALES.to_vec(),
        FEATURES.iter().map(|s| s.to_string()).collect(),
        command.into(),
    )?;
    file.save(&out)?;
    println!("wrote {out} (validation loss {:.4})", trained.val_loss);
    Ok(())
}
