//! The features of a cloud do not depend on its units or on a far outlier: the cloud stores
//! its offsets in a frame that keeps them usable (see `bounded_geom::PointCloud`).

mod common;

use bounded_features::{FeatureConfig, FeatureGroups, extract};
use bounded_geom::PointCloud;
use common::Rng;

/// `n` random points on the surface of the cube `[0, side]^3` moved to `at`: creases,
/// corners and flat faces.
fn cube(n: usize, side: f64, at: [f64; 3], seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let face = (rng.next() * 6.0) as usize;
            let mut p = [rng.next(), rng.next(), rng.next()].map(|c| c * side);
            p[face % 3] = if face < 3 { 0.0 } else { side };
            std::array::from_fn(|a| at[a] + p[a])
        })
        .collect()
}

fn features(points: &[[f64; 3]]) -> Vec<u32> {
    let config = FeatureConfig {
        scales: vec![32, 16, 8, 4],
        groups: FeatureGroups::BOUNDED,
        ..FeatureConfig::default()
    };
    let cloud = PointCloud::from_f64(points).unwrap();
    let f = extract(&cloud, &config).unwrap();
    f.as_slice().iter().map(|v| v.to_bits()).collect()
}

#[test]
fn clouds_scaled_by_powers_of_four_have_the_same_features_bit_for_bit() {
    let points = cube(3000, 1.0, [0.2, -0.4, 3.0], 1);
    let reference = features(&points);
    let unscaled = PointCloud::from_f64(&points).unwrap();
    for exponent in [70, -80, 40, -40, 600, -600] {
        let s = 2f64.powi(exponent);
        let scaled: Vec<[f64; 3]> = points.iter().map(|p| p.map(|c| c * s)).collect();
        // The same offsets, in a frame scaled by `s`: the same positions, scaled.
        let cloud = PointCloud::from_f64(&scaled).unwrap();
        assert!(
            (0..points.len())
                .all(|i| cloud.position_f64(i) == unscaled.position_f64(i).map(|c| c * s)),
            "2^{exponent}"
        );
        assert!(features(&scaled) == reference, "2^{exponent}");
    }
    // Other factors round positions differently (and so break neighbour ties otherwise:
    // 94% of the values stay within 1e-3 at 1e39), but nothing overflows or underflows
    // (before, 1e39 gave NaN everywhere and 1e20-1e38 or 1e-25 lost the neighbourhoods).
    for s in [1e39, 1e25, 1e-25, 1e-39] {
        let scaled: Vec<[f64; 3]> = points.iter().map(|p| p.map(|c| c * s)).collect();
        let f = features(&scaled);
        assert!(f.iter().all(|&v| f32::from_bits(v).is_finite()), "{s}");
        let close = (f.iter().zip(&reference))
            .filter(|(a, b)| (f32::from_bits(**a) - f32::from_bits(**b)).abs() < 1e-3)
            .count();
        assert!(close * 10 > 9 * f.len(), "{s}: {close} of {}", f.len());
    }
}

#[test]
fn a_far_outlier_changes_no_other_point_s_features() {
    // A unit cube and one point 1e7 away; a 10 m object at UTM coordinates and one point
    // at the origin.
    for (object, outlier) in [
        (cube(3000, 1.0, [0.0; 3], 2), [1e7, 0.0, 0.0]),
        (
            cube(3000, 10.0, [500_000.0, 5_403_150.0, 300.0], 3),
            [0.0; 3],
        ),
    ] {
        let alone = features(&object);
        let mut with = object.clone();
        with.push(outlier);
        let f = features(&with);
        assert!(f[..alone.len()] == alone[..], "{outlier:?}");
    }
}
