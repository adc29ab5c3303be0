//! Perturbations applied after labelling: Gaussian noise and outliers.
//!
//! Labels stay those of the clean positions, as in the noisy evaluation sets.

use super::grid::{Grid, bounds};
use super::sample::random_direction;
use super::vec3::{V3, add, normalize, scale};
use bounded_geom::Class;
use rand::Rng;
use rand_distr::StandardNormal;

/// Median nearest-neighbour distance; `hint` is a rough guess of it (the query reach is
/// twice the hint, so points further than that from all others are ignored).
pub(crate) fn median_spacing(points: &[V3], hint: f64) -> f64 {
    let mut grid = Grid::new(2.0 * hint, bounds(points.iter().copied()));
    for &p in points {
        grid.insert(p);
    }
    let mut d: Vec<f64> = points
        .iter()
        .filter_map(|&p| grid.nearest_other(p))
        .collect();
    if d.is_empty() {
        return hint;
    }
    let mid = d.len() / 2;
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Adds isotropic Gaussian noise of standard deviation `sigma` per coordinate.
pub(crate) fn add_noise(points: &mut [V3], sigma: f64, rng: &mut impl Rng) {
    if sigma <= 0.0 {
        return;
    }
    for p in points {
        *p = add(
            *p,
            [(); 3].map(|()| sigma * rng.sample::<f64, _>(StandardNormal)),
        );
    }
}

/// Appends `count` outliers (non-edge): copies of random points pushed 3..10 `spacing`
/// off in a random direction.
pub(crate) fn add_outliers(
    points: &mut Vec<V3>,
    labels: &mut Vec<Class>,
    count: usize,
    spacing: f64,
    rng: &mut impl Rng,
) {
    let surface_points = points.len();
    if surface_points == 0 {
        return;
    }
    for _ in 0..count {
        let base = points[rng.random_range(0..surface_points)];
        let offset = scale(
            normalize(random_direction(rng)),
            spacing * rng.random_range(3.0..10.0),
        );
        points.push(add(base, offset));
        labels.push(Class::NonEdge);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn median_spacing_of_a_grid_is_its_step() {
        let points: Vec<V3> = (0..400)
            .map(|i| [f64::from(i % 20) * 0.1, f64::from(i / 20) * 0.1, 0.0])
            .collect();
        assert!((median_spacing(&points, 0.1) - 0.1).abs() < 1e-12);
    }

    #[test]
    fn noise_has_the_requested_standard_deviation() {
        let mut points = vec![[0.0; 3]; 20_000];
        add_noise(&mut points, 0.5, &mut ChaCha8Rng::seed_from_u64(9));
        let var = points.iter().map(|p| p[2] * p[2]).sum::<f64>() / points.len() as f64;
        // Standard error of a variance estimate from 20k samples: about 1%.
        assert!((var.sqrt() - 0.5).abs() < 0.01, "{}", var.sqrt());
    }

    #[test]
    fn outliers_are_non_edge_and_off_the_surface() {
        let mut points = vec![[0.0; 3]];
        let mut labels = vec![Class::Sharp];
        add_outliers(
            &mut points,
            &mut labels,
            50,
            1.0,
            &mut ChaCha8Rng::seed_from_u64(1),
        );
        assert_eq!(points.len(), 51);
        assert!(labels[1..].iter().all(|&c| c == Class::NonEdge));
        for p in &points[1..] {
            let d = super::super::vec3::norm(*p);
            assert!((3.0..10.0).contains(&d), "{d}");
        }
    }
}
