//! Feature throughput and peak memory on a synthetic cube-surface cloud.
//!
//! `cargo run --release -p bounded-features --example throughput -- [points] [chunk]`
//! prints points per second of the streaming extraction at the default 4 scales (wall
//! clock and per CPU-second) and the process' peak resident memory per point (VmHWM
//! from /proc/self/status).

use std::time::Instant;

use bounded_features::{DEFAULT_CHUNK_POINTS, FeatureConfig, extract_chunks};

#[path = "../benches/synthetic/mod.rs"]
mod synthetic;

/// Peak resident set size in bytes, if the platform reports it.
fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// User + system CPU seconds of this process (fields 14 and 15 of /proc/self/stat,
/// in clock ticks of 1/100 s), if the platform reports them.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name, which may contain spaces.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(1_000_000), |a| a.parse())?;
    let chunk: usize = args
        .next()
        .map_or(Ok(DEFAULT_CHUNK_POINTS), |a| a.parse())?;
    let cloud = synthetic::cube_surface(n, 42);
    let before = peak_rss().unwrap_or(0);
    let config = FeatureConfig::default();
    let cpu_start = cpu_seconds().unwrap_or(0.0);
    let start = Instant::now();
    let mut checksum = 0.0f64;
    let mut done = 0usize;
    extract_chunks(&cloud, &config, chunk, |block| {
        done += block.len();
        checksum += block.values().iter().map(|&v| f64::from(v)).sum::<f64>();
    })?;
    let secs = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds().unwrap_or(0.0) - cpu_start;
    let peak = peak_rss().unwrap_or(0);
    println!(
        "points {done}  threads {}  chunk {chunk}  time {secs:.3} s  {:.0} points/s",
        rayon::current_num_threads(),
        done as f64 / secs
    );
    // On a shared machine wall time depends on other load; CPU time does not.
    println!(
        "cpu {cpu:.2} s = {:.0} points per CPU-second",
        done as f64 / cpu
    );
    println!(
        "peak RSS {:.1} MiB = {:.1} B/point (cloud alone {:.1} B/point)  checksum {checksum:.6e}",
        peak as f64 / (1 << 20) as f64,
        peak as f64 / n as f64,
        before as f64 / n as f64
    );
    Ok(())
}
