//! Detection speed on a cloud file: both stages of the embedded model, then its first stage
//! alone, interleaved `runs` times, with points/s, the halo's recomputed points and peak memory.
//!
//! `cargo run --release -p bounded-nn --example detect -- cloud.ply [runs]`

use bounded_nn::Detector;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: detect CLOUD [RUNS]")?;
    let runs: usize = args.next().map_or(Ok(3), |r| r.parse())?;
    let t = Instant::now();
    let cloud = bounded_data::format::read(path.as_ref())?.cloud;
    println!(
        "{path}: {} points, read in {:.2} s",
        cloud.len(),
        t.elapsed().as_secs_f64()
    );
    let both = Detector::embedded()?;
    let first = Detector::embedded()?.first_stage_only()?;
    for run in 1..=runs {
        for (name, detector) in [("both stages", &both), ("first stage", &first)] {
            let d = detector.detect(&cloud)?;
            let s = d.elapsed.as_secs_f64();
            println!(
                "run {run} {name}: {s:.3} s, {:.0} k points/s, classification {:.3} s, \
                 recomputed {} points ({:.1}%)",
                cloud.len() as f64 / s / 1e3,
                d.classification.as_secs_f64(),
                d.recomputed,
                100.0 * d.recomputed as f64 / cloud.len() as f64
            );
        }
    }
    if let Ok(status) = std::fs::read_to_string("/proc/self/status")
        && let Some(line) = status.lines().find(|l| l.starts_with("VmHWM"))
    {
        println!("peak memory {}", line.trim_start_matches("VmHWM:").trim());
    }
    Ok(())
}
