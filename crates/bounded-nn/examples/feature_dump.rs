//! Writes generated clouds with their labels and features for experiments outside Rust.
//!
//! `cargo run --release -p bounded-nn --example feature_dump -- KIND SEED CLOUDS OUT
//! [depth] [per-noise] [band]`: one raw little-endian `f32` file per cloud in OUT, a header of two
//! `u32` (rows, columns), then rows of x, y, z, class, then the default 48 features, with
//! the training noise along the normal; for free-form sets `depth`, `per-noise` and `band` set
//! the label rule's `min_depth`, `min_depth_per_noise` and `band`.

use std::path::Path;

use bounded_data::synth::{LabelRule, NoiseDirection, SetConfig, SetKind, generate};
use bounded_features::{FeatureConfig, extract};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [kind, seed, clouds, out, rest @ ..] = args.as_slice() else {
        return Err("usage: feature_dump KIND SEED CLOUDS OUT [depth] [per-noise] [band]".into());
    };
    let kind = SetKind::from_name(kind)?;
    let noise = [0.0, 0.0, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0];
    let mut config = SetConfig::new(kind, seed.parse()?, clouds.parse()?)
        .with_noise(Some(&noise), NoiseDirection::Normal)?;
    let defaults = LabelRule::default();
    config.label_rule = LabelRule {
        min_depth: rest.first().map_or(Ok(defaults.min_depth), |a| a.parse())?,
        min_depth_per_noise: rest.get(1).map_or(Ok(0.0), |a| a.parse())?,
        band: rest.get(2).map_or(Ok(defaults.band), |a| a.parse())?,
        ..defaults
    };
    config.validate()?;
    std::fs::create_dir_all(out)?;
    let features = FeatureConfig::default();
    for (name, labelled) in generate(&config)? {
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
