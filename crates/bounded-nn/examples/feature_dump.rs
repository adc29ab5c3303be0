//! Writes generated clouds with their labels and features for experiments outside Rust.
//!
//! `cargo run --release -p bounded-nn --example feature_dump -- SPEC OUT`: the set `SPEC`
//! (as `bounded train --data` takes it, label rules included, for example
//! `generated:freeform:4:40:depth=1:noise=3:band=2`) with the training noise, one raw
//! little-endian `f32` file per cloud in OUT: a header of two `u32` (rows, columns), then
//! rows of x, y, z, class, then the default 48 features.

use std::path::Path;

use bounded_data::synth::recipe;
use bounded_features::{FeatureConfig, extract};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [spec, out] = args.as_slice() else {
        return Err("usage: feature_dump SPEC OUT".into());
    };
    std::fs::create_dir_all(out)?;
    let features = FeatureConfig::default();
    for (name, labelled) in recipe::generate(&[spec.as_str()], 1)? {
        let f = extract(&labelled.cloud, &features)?;
        let columns = 4 + f.per_point();
        let mut bytes = Vec::with_capacity(8 + 4 * columns * f.len());
        bytes.extend((f.len() as u32).to_le_bytes());
        bytes.extend((columns as u32).to_le_bytes());
        for (i, p) in labelled.cloud.points().iter().enumerate() {
            let class = labelled.labels[i] as u8 as f32;
            for v in p.iter().chain([&class]).chain(f.point(i)) {
                bytes.extend(v.to_le_bytes());
            }
        }
        bounded_geom::atomic::write(&Path::new(out).join(format!("{name}.f32")), &bytes)?;
    }
    Ok(())
}
