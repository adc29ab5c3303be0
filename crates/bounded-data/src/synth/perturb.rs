//! Perturbations applied after labelling: Gaussian noise and outliers.
//!
//! Labels stay those of the clean positions, as in the noisy evaluation sets.

use super::grid::{Grid, bounds};
use super::mesh::Mesh;
use super::sample::random_direction;
use bounded_geom::Class;
use bounded_geom::vec3::{V3, add, cross, dot, norm, normalize, scale, sub};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

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

/// Which way noise displaces points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoiseDirection {
    /// Every coordinate independently (sampling jitter).
    Isotropic,
    /// Along the surface normal only, as range noise displaces scanned points and as the
    /// noisy ABC evaluation clouds were made; on a crease or corner, along the mean of its
    /// faces' outward normals (a mesh's vertex normal).
    Normal,
}

impl NoiseDirection {
    /// What the noise moves along, in words ("the normal", "every coordinate").
    pub fn phrase(self) -> &'static str {
        match self {
            NoiseDirection::Normal => "the normal",
            NoiseDirection::Isotropic => "every coordinate",
        }
    }
}

/// Adds Gaussian noise of standard deviation `sigma` along each point's normal on `mesh`
/// (the points lie on it).
pub(crate) fn add_normal_noise(mesh: &Mesh, points: &mut [V3], sigma: f64, rng: &mut impl Rng) {
    if sigma <= 0.0 {
        return;
    }
    let normals = surface_normals(mesh, points);
    for (p, n) in points.iter_mut().zip(normals) {
        *p = add(*p, scale(n, sigma * rng.sample::<f64, _>(StandardNormal)));
    }
}

/// The unit normal of `mesh` at each of `points`: the normal of the triangle a point lies
/// on, or on an edge or vertex shared by several, the mean of their faces' normals, each
/// oriented away from the other triangles' corners (outward on a convex crease, away from
/// both faces on a concave one), so that the result does not depend on the triangles'
/// winding. A point on no triangle (off the mesh by more than 1e-7 of its diagonal) gets a
/// zero normal: it is not moved. Every point is tested against every triangle: the
/// generator's meshes have a few thousand at most.
fn surface_normals(mesh: &Mesh, points: &[V3]) -> Vec<V3> {
    let eps = 1e-7 * mesh.diagonal();
    let triangles: Vec<([V3; 3], V3)> = mesh
        .triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            (norm(n) > 0.0).then(|| ([a, b, c], normalize(n)))
        })
        .collect();
    points
        .par_iter()
        .map(|&p| {
            let on: Vec<&([V3; 3], V3)> = triangles
                .iter()
                .filter(|(corners, n)| contains(corners, *n, p, eps))
                .collect();
            let oriented = on.iter().map(|(_, n)| {
                let others: f64 = on
                    .iter()
                    .flat_map(|(corners, _)| corners)
                    .map(|&v| dot(*n, sub(v, p)))
                    .sum();
                if others > eps { scale(*n, -1.0) } else { *n }
            });
            // Each face once, however many of its triangles meet at the point.
            let mut faces: Vec<V3> = Vec::with_capacity(on.len());
            for n in oriented {
                if faces.iter().all(|&f| dot(f, n) < 1.0 - 1e-9) {
                    faces.push(n);
                }
            }
            let sum = faces.into_iter().fold([0.0; 3], add);
            if norm(sum) > 1e-9 {
                normalize(sum)
            } else {
                on.first().map_or([0.0; 3], |(_, n)| *n)
            }
        })
        .collect()
}

/// True when `p` lies on the triangle `corners` of unit normal `n`, within `eps`.
fn contains(corners: &[V3; 3], n: V3, p: V3, eps: f64) -> bool {
    let [a, b, c] = *corners;
    dot(sub(p, a), n).abs() <= eps
        && [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| dot(cross(sub(v, u), sub(p, u)), n) >= -eps * norm(sub(v, u)))
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

    /// `a` and `b` are parallel (either sign) unit vectors.
    fn parallel(a: V3, b: V3) -> bool {
        (dot(a, b).abs() - 1.0).abs() < 1e-9
    }

    #[test]
    fn surface_normals_of_a_cube_whatever_the_winding() {
        // The test cube's faces are wound alike on opposite sides, so half point inward.
        let cube = super::super::mesh::tests::cube();
        let s = 1.0 / 2f64.sqrt();
        let t = 1.0 / 3f64.sqrt();
        let cases = [
            ([0.3, 0.6, 0.0], [0.0, 0.0, 1.0]), // face
            ([0.3, 0.6, 1.0], [0.0, 0.0, 1.0]),
            ([0.5, 0.5, 0.0], [0.0, 0.0, 1.0]), // face diagonal: two triangles
            ([0.4, 0.0, 0.0], [0.0, s, s]),     // crease: the bisector
            ([1.0, 0.7, 1.0], [s, 0.0, s]),
            ([0.0, 0.0, 0.0], [t, t, t]), // corner
            ([1.0, 0.0, 1.0], [t, -t, t]),
            ([0.5, 0.5, 0.5], [0.0; 3]), // inside: on no face
        ];
        let points: Vec<V3> = cases.iter().map(|c| c.0).collect();
        for (n, (p, want)) in surface_normals(&cube, &points).into_iter().zip(cases) {
            if want == [0.0; 3] {
                assert_eq!(n, want, "{p:?}");
            } else {
                assert!(parallel(n, want), "{p:?}: {n:?}");
            }
        }
    }

    #[test]
    fn surface_normal_of_a_fold_is_its_bisector() {
        // Two unit squares meeting at 90 degrees along the y axis (z = 0 and x = 0).
        let mut fold = Mesh::default();
        let r = fold.vertices_of([
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
        ]);
        fold.quad(r[0], r[1], r[2], r[3]);
        fold.quad(r[1], r[4], r[5], r[2]);
        let s = 1.0 / 2f64.sqrt();
        let n = surface_normals(&fold, &[[0.0, 0.3, 0.0], [0.5, 0.3, 0.0]]);
        assert!(parallel(n[0], [s, 0.0, s]), "{:?}", n[0]);
        assert!(parallel(n[1], [0.0, 0.0, 1.0]), "{:?}", n[1]);
    }

    #[test]
    fn normal_noise_moves_face_points_along_their_face_normal_only() {
        let cube = super::super::mesh::tests::cube();
        let clean: Vec<V3> = (0..3000)
            .map(|i| {
                let (u, v) = (
                    f64::from(i % 50) / 50.0 + 0.01,
                    f64::from(i / 50) / 60.0 + 0.005,
                );
                [u, v, 0.0]
            })
            .collect();
        let mut noisy = clean.clone();
        add_normal_noise(&cube, &mut noisy, 0.05, &mut ChaCha8Rng::seed_from_u64(4));
        let mut var = 0.0;
        for (a, b) in clean.iter().zip(&noisy) {
            assert_eq!([a[0], a[1]], [b[0], b[1]]);
            var += (b[2] - a[2]).powi(2);
        }
        let sd = (var / clean.len() as f64).sqrt();
        assert!((sd - 0.05).abs() < 0.002, "{sd}");
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
            let d = bounded_geom::vec3::norm(*p);
            assert!((3.0..10.0).contains(&d), "{d}");
        }
    }
}
