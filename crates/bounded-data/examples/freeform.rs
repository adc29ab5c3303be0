//! Writes generated free-form clouds as labelled PLY files (positions and a `class`
//! property: 0 non-edge, 1 sharp, 2 boundary) to look at with `bounded render`, and prints
//! each cloud's class fractions.
//!
//! `cargo run --release -p bounded-data --example freeform -- OUT_DIR [SEED] [COUNT] [BAND]`
//!
//! BAND is the label rule's half-width in spacings (default 1; 0.5 labels one row).

use bounded_data::format;
use bounded_data::synth::{SetConfig, SetKind, generate_one};
use bounded_geom::Class;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: freeform OUT_DIR [SEED] [COUNT] [BAND]";
    let out = PathBuf::from(args.next().ok_or(usage)?);
    let seed = args.next().map_or(Ok(1), |s| s.parse())?;
    let count = args.next().map_or(Ok(4), |s| s.parse())?;
    let mut config = SetConfig::new(SetKind::Freeform, seed, count);
    if let Some(band) = args.next() {
        config.label_rule.band = band.parse()?;
    }
    config.validate()?;
    std::fs::create_dir_all(&out)?;
    for i in 0..count {
        let (name, cloud) = generate_one(&config, i)?;
        let n = cloud.cloud.len();
        let counts = cloud.class_counts();
        let percent = |c: Class| 100.0 * counts[c as usize] as f64 / n as f64;
        let path = out.join(format!("{name}.ply"));
        format::write_labelled(&path, &cloud)?;
        println!(
            "{}: {n} points, {:.1}% sharp, {:.1}% boundary",
            path.display(),
            percent(Class::Sharp),
            percent(Class::Boundary)
        );
    }
    Ok(())
}
