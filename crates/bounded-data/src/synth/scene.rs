//! The demo scene: a few generated shapes side by side, for `bounded demo` and for trying the
//! detector without any files.

use super::{NoiseDirection, Sampling, ShapeKind, ShapeSpec, generate_shape};
use crate::{DataError, LabelledCloud};
use bounded_geom::PointCloud;

/// The demo scene's shapes: creases and corners, a smooth torus, an open bowl (border and
/// smooth), a stair (concave and convex creases) and an open box (creases and borders).
pub const DEMO_SHAPES: [ShapeKind; 5] = [
    ShapeKind::FractalCube,
    ShapeKind::Torus,
    ShapeKind::Bowl,
    ShapeKind::Stairs,
    ShapeKind::OpenBox,
];

/// Points of every shape of the demo scene.
const DEMO_POINTS: usize = 16_000;

/// The demo scene of `seed`: the [`DEMO_SHAPES`] in order along x, each randomly sampled with
/// 16,000 points and light noise (0.1 spacings), scaled to fit a unit box at `x = 1.4 i`.
pub fn demo_scene(seed: u64) -> Result<LabelledCloud, DataError> {
    let mut points = Vec::new();
    let mut labels = Vec::new();
    for (i, &kind) in DEMO_SHAPES.iter().enumerate() {
        let spec = ShapeSpec {
            kind,
            sampling: Sampling::Random,
            points: DEMO_POINTS,
            noise: 0.1,
            noise_direction: NoiseDirection::Isotropic,
            outlier_fraction: 0.0,
            seed: seed.wrapping_mul(31).wrapping_add(i as u64),
            face_spacing: 1.0,
            row_spacing: 1.0,
            band: None,
            thinning: None,
        };
        let shape = generate_shape(&spec)?;
        let cloud = &shape.cloud;
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for j in 0..cloud.len() {
            let p = cloud.position_f64(j);
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let size = (0..3).map(|a| hi[a] - lo[a]).fold(1e-12, f64::max);
        for j in 0..cloud.len() {
            let p = cloud.position_f64(j);
            points.push([
                (p[0] - lo[0]) / size + 1.4 * i as f64,
                (p[1] - lo[1]) / size,
                (p[2] - lo[2]) / size,
            ]);
        }
        labels.extend_from_slice(&shape.labels);
    }
    let cloud = PointCloud::from_f64(&points).map_err(|source| DataError::Geom {
        path: "demo scene".into(),
        source,
    })?;
    Ok(LabelledCloud { cloud, labels })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_side_by_side_in_unit_boxes() {
        let scene = demo_scene(7).unwrap();
        assert_eq!(scene.cloud.len(), DEMO_SHAPES.len() * DEMO_POINTS);
        assert_eq!(scene.labels.len(), scene.cloud.len());
        for (i, shape) in (0..scene.cloud.len())
            .collect::<Vec<_>>()
            .chunks(DEMO_POINTS)
            .enumerate()
        {
            let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
            for &j in shape {
                let p = scene.cloud.position_f64(j);
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            let x0 = 1.4 * i as f64;
            assert!((lo[0] - x0).abs() < 1e-5 && lo[1].abs() < 1e-5 && lo[2].abs() < 1e-5);
            let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
            assert!((extent - 1.0).abs() < 1e-5, "shape {i}: {lo:?} {hi:?}");
        }
        assert!(
            scene.class_counts().iter().all(|&n| n > 0),
            "{:?}",
            scene.class_counts()
        );
        assert_eq!(demo_scene(7).unwrap(), scene);
    }
}
