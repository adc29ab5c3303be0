//! A synthetic surface cloud for the benchmark and the throughput example.

use bounded_geom::PointCloud;

/// `n` points uniformly on the surface of the unit cube (six faces, sharp edges and
/// corners), generated straight into the cloud's `f32` storage (12 bytes per point).
pub fn cube_surface(n: usize, seed: u64) -> PointCloud {
    let mut state = seed;
    let mut next = move || {
        // SplitMix64 in [0, 1).
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let points = (0..n)
        .map(|i| {
            let (u, v) = (next() - 0.5, next() - 0.5);
            let side = if i % 2 == 0 { 0.5 } else { -0.5 };
            match i % 6 / 2 {
                0 => [side, u, v],
                1 => [u, side, v],
                _ => [u, v, side],
            }
        })
        .collect();
    PointCloud::from_local([0.0; 3], points).expect("generated coordinates are finite")
}
