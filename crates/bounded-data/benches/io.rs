//! Read and write throughput of binary PLY, LAS, LAZ and E57 on an annotated cloud.
//!
//! `BOUNDED_IO_POINTS` sets the cloud size (default 10,000,000). Each point has float
//! x, y, z plus the annotation properties (class, three probabilities, colour): 28 bytes per
//! PLY record. Files live in a temporary directory, so reads come from the page cache. Writes
//! are measured to a new file and over an existing one.

// criterion_group! generates an undocumented pub function.
#![allow(missing_docs)]

use bounded_data::format::{read, write_annotated};
use bounded_data::table::PointTable;
use bounded_geom::{Class, PointCloud};
use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use std::time::Duration;

fn cloud(n: usize) -> (PointTable, Vec<Class>, Vec<[f32; 3]>) {
    // A 1000 x 1000 grid of 10 layers: deterministic, no RNG needed.
    let cloud = PointCloud::from_iter_f64(n, |i| {
        [
            (i % 1000) as f64 * 0.01,
            (i / 1000 % 1000) as f64 * 0.01,
            (i / 1_000_000) as f64,
        ]
    })
    .expect("a non-empty finite grid");
    let classes = (0..n).map(|i| Class::ALL[i % 3]).collect();
    let probabilities = (0..n).map(|i| [0.2, 0.3, (i % 7) as f32 * 0.1]).collect();
    (PointTable::new(cloud), classes, probabilities)
}

fn io(c: &mut Criterion) {
    let n = std::env::var("BOUNDED_IO_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000_000);
    let (table, classes, probabilities) = cloud(n);
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut group = c.benchmark_group("io");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements(n as u64));
    for ext in ["ply", "las", "laz", "e57"] {
        let path = dir.path().join(format!("bench.{ext}"));
        let write = || write_annotated(&path, &table, &classes, &probabilities).expect("write");
        // A new file, as `bounded detect -o` usually writes: the old one is removed untimed.
        group.bench_function(format!("write_{ext}"), |b| {
            b.iter_batched(
                || std::fs::remove_file(&path).ok(),
                |_| write(),
                BatchSize::PerIteration,
            )
        });
        // Replacing an existing file (an exchange, then deleting the old one: see
        // `bounded_geom::atomic`), as when `detect` reruns with the same output.
        group.bench_function(format!("replace_{ext}"), |b| b.iter(write));
        group.bench_function(format!("read_{ext}"), |b| {
            b.iter(|| read(&path).expect("read").len())
        });
    }
    group.finish();
}

criterion_group!(benches, io);
criterion_main!(benches);
