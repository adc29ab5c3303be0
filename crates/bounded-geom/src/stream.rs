//! SplitMix64: deterministic uniform numbers without a dependency, for examples and the
//! generated clouds of tests (the generator proper uses `rand_chacha`).

/// Uniform numbers in [0, 1) from SplitMix64 seeded with `seed`: the same seed gives the
/// same stream on every platform.
pub fn uniform_stream(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_of_seed_zero_starts_with_its_reference_value() {
        // SplitMix64's first output for seed 0 is 0xe220a8397b1dcdaf (Vigna's reference).
        let first = uniform_stream(0)();
        assert_eq!(
            first,
            (0xe220_a839_7b1d_cdafu64 >> 11) as f64 / (1u64 << 53) as f64
        );
        let mut s = uniform_stream(42);
        assert!((0..1000).map(|_| s()).all(|v| (0.0..1.0).contains(&v)));
        assert_ne!(uniform_stream(1)(), uniform_stream(2)());
    }
}
