//! The Rust library's features of a cloud file, for the Python tests to compare with
//! `bounded.features` (and for timing the library beside the binding).
//!
//! `features CLOUD OUT SCALES` reads CLOUD (any format), extracts the BoundED features at
//! SCALES (comma-separated, largest first) and writes them to OUT as little-endian f32,
//! `[point][scale][feature]`; it prints the extraction's wall time.

use bounded_data::format;
use bounded_features::{FeatureConfig, extract};
use std::io::Write;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [cloud, out, scales] = args.as_slice() else {
        return Err("usage: features CLOUD OUT SCALES".into());
    };
    let table = format::read(cloud.as_ref())?;
    let config = FeatureConfig {
        scales: scales.split(',').map(str::parse).collect::<Result<_, _>>()?,
        ..FeatureConfig::default()
    };
    let start = Instant::now();
    let features = extract(&table.cloud, &config)?;
    eprintln!(
        "{} points: features in {:.3} s",
        table.len(),
        start.elapsed().as_secs_f64()
    );
    let bytes: Vec<u8> = (features.as_slice().iter()).flat_map(|v| v.to_le_bytes()).collect();
    std::fs::File::create(out)?.write_all(&bytes)?;
    Ok(())
}
