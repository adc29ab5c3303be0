//! Criterion benchmark: streaming feature extraction, 4 default scales, on a
//! synthetic cube-surface cloud (1M points; `BOUNDED_BENCH_POINTS` overrides).

// criterion_group! generates an undocumented pub function.
#![allow(missing_docs)]

use bounded_features::{DEFAULT_CHUNK_POINTS, FeatureConfig, extract_chunks};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

mod synthetic;

fn features(c: &mut Criterion) {
    let n = std::env::var("BOUNDED_BENCH_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let cloud = synthetic::cube_surface(n, 42);
    let config = FeatureConfig::default();
    let mut group = c.benchmark_group("features");
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function(format!("extract_chunks_4_scales_{n}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            extract_chunks(&cloud, &config, DEFAULT_CHUNK_POINTS, |block| {
                sum += block.values()[0];
            })
            .expect("the synthetic cloud is large enough");
            sum
        })
    });
    group.finish();
}

criterion_group!(benches, features);
criterion_main!(benches);
