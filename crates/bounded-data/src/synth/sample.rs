//! The two sampling modes and their labels.
//!
//! * Mesh-vertex mode mimics the ABC clouds (vertices of a CAD triangulation): one row of
//!   points exactly on every crease and border, spaced like the faces, then faces filled by
//!   dart throwing with a minimum distance, which gives near-regular spacing. Row points take
//!   the class of their row (sharp rows first, so sharp wins where a crease meets a border);
//!   every other point is non-edge. Planar faces may be filled more sparsely than the rows
//!   and the curved faces (a face spacing above 1), as a CAD triangulation leaves a plane
//!   with few vertices where it follows a crease or a curve closely.
//! * Random mode mimics the Default clouds: uniform random points on the surface. A point is
//!   sharp when it lies within [`W_SHARP`] x the local spacing of a crease, else boundary
//!   within [`W_BORDER`] x the local spacing of a border, else non-edge.
//!
//! Both modes vary the density linearly across a shape (up to 1.6 : 0.4), so the spacing
//! differs somewhat within a shape as well as between shapes.

use super::grid::{Grid, bounds};
use super::mesh::{Features, Mesh, Polyline};
use super::segments::SegmentIndex;
use crate::table::retain_flagged;
use bounded_geom::Class;
use bounded_geom::vec3::{V3, add, dot, lerp, norm, normalize, scale, sub};
use rand::Rng;
use rand_distr::StandardNormal;

/// How a shape's surface is turned into points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sampling {
    /// Vertices of a near-regular triangulation, with one row of points on each crease and
    /// border (the look of the ABC clouds).
    MeshVertex,
    /// Uniform random points with distance-band labels (the look of the Default clouds).
    Random,
}

/// Half-width of the sharp band in random mode, in units of the local spacing
/// `s = 1 / sqrt(points per unit area)`.
///
/// Calibrated on the geometry of PCEDNet's `TwoPlane90` ground truth (uniform random points,
/// 90-degree crease): its sharp points lie within 0.31..0.33 s of the crease. The band covers
/// both faces, so about 0.66 points per `s` of crease are sharp: one sparse row.
pub const W_SHARP: f64 = 0.33;

/// Half-width of the boundary band in random mode, in units of the local spacing: twice
/// [`W_SHARP`] because a border has points on one side only, so it gets as many labelled
/// points per unit length as a crease.
pub const W_BORDER: f64 = 0.66;

/// Dart-throwing fill levels: (attempts per `r^2` of surface, points per `r^2` reached with
/// minimum distance `r`), measured on a cube. More attempts give a more regular fill.
pub(crate) const FILL_LEVELS: [(f64, f64); 4] =
    [(2.0, 0.465), (4.0, 0.531), (7.0, 0.569), (10.0, 0.587)];

/// Points and labels on the clean surface.
pub(crate) struct Sampled {
    /// Positions.
    pub(crate) points: Vec<V3>,
    /// One class per position.
    pub(crate) labels: Vec<Class>,
    /// A rough nearest-neighbour distance, a cell size for later spatial queries.
    pub(crate) spacing_hint: f64,
}

/// A density that changes linearly along a random direction: `factor` is in `[1 - g, 1 + g]`.
struct Density {
    centre: V3,
    direction: V3,
    gradient: f64,
}

impl Density {
    fn random(mesh: &Mesh, rng: &mut impl Rng) -> Self {
        let n = mesh.vertices.len().max(1) as f64;
        let centre = scale(
            mesh.vertices.iter().fold([0.0; 3], |a, &v| add(a, v)),
            1.0 / n,
        );
        let direction = normalize(random_direction(rng));
        let reach = mesh
            .vertices
            .iter()
            .map(|&v| dot(sub(v, centre), direction).abs())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let gradient = if rng.random_bool(0.4) {
            0.0
        } else {
            rng.random_range(0.0..0.6)
        };
        Self {
            centre,
            direction: scale(direction, gradient / reach),
            gradient,
        }
    }

    fn factor(&self, p: V3) -> f64 {
        1.0 + dot(sub(p, self.centre), self.direction)
    }
}

/// Picks uniformly distributed points on a mesh's surface.
struct Surface<'a> {
    mesh: &'a Mesh,
    cumulative: Vec<f64>,
    /// Integral of the density factor over the surface (exact: the factor is linear).
    weighted_area: f64,
}

impl<'a> Surface<'a> {
    fn new(mesh: &'a Mesh, density: &Density) -> Self {
        let mut total = 0.0;
        let mut surface = Self {
            mesh,
            cumulative: Vec::with_capacity(mesh.triangles.len()),
            weighted_area: 0.0,
        };
        for &t in &mesh.triangles {
            surface.weighted_area += surface.weighted_area_of(t, density);
            total += mesh.triangle_area(t);
            surface.cumulative.push(total);
        }
        surface
    }

    /// A random point and the index of its triangle.
    fn point(&self, rng: &mut impl Rng) -> (V3, usize) {
        let total = self.cumulative.last().copied().unwrap_or(0.0);
        let x = rng.random::<f64>() * total;
        let t = self
            .cumulative
            .partition_point(|&c| c <= x)
            .min(self.cumulative.len() - 1);
        let [a, b, c] = self.mesh.triangles[t].map(|i| self.mesh.vertices[i as usize]);
        let (r1, r2): (f64, f64) = (rng.random::<f64>().sqrt(), rng.random());
        let p = add(
            add(scale(a, 1.0 - r1), scale(b, r1 * (1.0 - r2))),
            scale(c, r1 * r2),
        );
        (p, t)
    }

    /// The density factor at the centroid of triangle `t`, times its area.
    fn weighted_area_of(&self, t: [u32; 3], density: &Density) -> f64 {
        let [a, b, c] = t.map(|i| self.mesh.vertices[i as usize]);
        self.mesh.triangle_area(t) * density.factor(scale(add(add(a, b), c), 1.0 / 3.0))
    }
}

/// A uniformly distributed random direction (unnormalised Gaussian vector).
pub(crate) fn random_direction(rng: &mut impl Rng) -> V3 {
    loop {
        let v: V3 = [(); 3].map(|()| rng.sample(StandardNormal));
        if norm(v) > 1e-6 {
            return v;
        }
    }
}

/// Samples about `target` points on a welded, non-empty `mesh` whose features are `features`;
/// in mesh-vertex mode, planar faces are filled with `face_spacing` (1 or more) times the
/// minimum distance of the rows and the curved faces, and the rows' points are `row_spacing`
/// (1 or more) times their usual step apart along their lines.
pub(crate) fn sample(
    mesh: &Mesh,
    features: &Features,
    sampling: Sampling,
    target: usize,
    face_spacing: f64,
    row_spacing: f64,
    rng: &mut impl Rng,
) -> Sampled {
    let density = Density::random(mesh, rng);
    let surface = Surface::new(mesh, &density);
    match sampling {
        Sampling::MeshVertex => mesh_vertex(
            &surface,
            &density,
            features,
            target,
            face_spacing,
            row_spacing,
            rng,
        ),
        Sampling::Random => random(&surface, &density, features, target, rng),
    }
}

fn mesh_vertex(
    surface: &Surface,
    density: &Density,
    features: &Features,
    target: usize,
    face_spacing: f64,
    row_spacing: f64,
    rng: &mut impl Rng,
) -> Sampled {
    let (attempts_per_area, fill_density) = FILL_LEVELS[rng.random_range(0..FILL_LEVELS.len())];
    // Each triangle's minimum distance, relative to the rows' (a planar face's holds
    // `face_spacing^2` times fewer points per area), and the rows' minimum distance `r0`
    // that keeps the count near `target`.
    let (spread, r0) = if face_spacing > 1.0 {
        let spread: Vec<f64> = (surface.mesh.planar_triangles().iter())
            .map(|&p| if p { face_spacing } else { 1.0 })
            .collect();
        // The area the fill covers at the rows' spacing.
        let filled_area: f64 = (surface.mesh.triangles.iter().zip(&spread))
            .map(|(&t, &m)| surface.weighted_area_of(t, density) / (m * m))
            .sum();
        // Rows beside sparser planes hold points the plane's fill does not make up for:
        // about `length / r0 x (1 - 1 / face_spacing)`, so the count is
        // `a / r0^2 + b / r0`, solved for `r0`.
        let length: f64 = (features.sharp.iter().chain(&features.border))
            .map(Polyline::length)
            .sum();
        let (a, b, n) = (
            fill_density * filled_area,
            length * (1.0 - 1.0 / face_spacing),
            target as f64,
        );
        (spread, (b + (b * b + 4.0 * a * n).sqrt()) / (2.0 * n))
    } else {
        let r0 = (fill_density * surface.weighted_area / target as f64).sqrt();
        (vec![1.0; surface.mesh.triangles.len()], r0)
    };
    let radius = |p: V3| r0 / density.factor(p).sqrt();
    let mut grid = Grid::new(
        face_spacing.max(1.0) * r0 / (1.0 - density.gradient).sqrt(),
        bounds(surface.mesh.vertices.iter().copied()),
    );
    let mut labels = Vec::with_capacity(target + target / 4);
    // Crease rows are a little sparser than the minimum distance, like the face points'
    // typical nearest-neighbour distance; `row_spacing` spreads them further, as the ABC
    // clouds' rows are (drawn before it, so that it changes nothing else).
    let row_step = rng.random_range(1.0..1.2) * row_spacing;
    for (class, lines) in [
        (Class::Sharp, &features.sharp),
        (Class::Boundary, &features.border),
    ] {
        for line in lines {
            for p in resample(line, |p| row_step * radius(p)) {
                if !grid.any_within(p, 0.5 * radius(p)) {
                    grid.insert(p);
                    labels.push(class);
                }
            }
        }
    }
    let attempts = (attempts_per_area * surface.weighted_area / (r0 * r0)) as usize;
    for _ in 0..attempts {
        let (p, t) = surface.point(rng);
        if !grid.any_within(p, spread[t] * radius(p)) {
            grid.insert(p);
            labels.push(Class::NonEdge);
        }
    }
    Sampled {
        points: grid.points().to_vec(),
        labels,
        spacing_hint: r0,
    }
}

/// Points along a polyline, evenly spaced by arc length at about `step(p)` (measured at the
/// polyline's middle), ends included (a loop's start once).
fn resample(line: &Polyline, step: impl Fn(V3) -> f64) -> Vec<V3> {
    let length = line.length();
    let middle = point_at(line, 0.5 * length);
    let n = (length / step(middle)).round().max(1.0) as usize;
    let count = if line.closed { n } else { n + 1 };
    (0..count)
        .map(|k| point_at(line, length * k as f64 / n as f64))
        .collect()
}

/// The point at arc length `s` along a polyline.
fn point_at(line: &Polyline, s: f64) -> V3 {
    let mut left = s;
    let mut last = line.points[0];
    for (a, b) in line.segments() {
        let len = norm(sub(b, a));
        if left <= len {
            return lerp(a, b, if len > 0.0 { left / len } else { 0.0 });
        }
        left -= len;
        last = b;
    }
    last
}

fn random(
    surface: &Surface,
    density: &Density,
    features: &Features,
    target: usize,
    rng: &mut impl Rng,
) -> Sampled {
    // Points per unit area at p is target * factor(p) / weighted_area.
    let spacing = |p: V3| (surface.weighted_area / (target as f64 * density.factor(p))).sqrt();
    let widest = spacing_max(surface, density, target);
    let box_ = bounds(surface.mesh.vertices.iter().copied());
    let sharp = SegmentIndex::new(&features.sharp, W_SHARP * widest, box_);
    let border = SegmentIndex::new(&features.border, W_BORDER * widest, box_);
    let mut points = Vec::with_capacity(target);
    let mut labels = Vec::with_capacity(target);
    while points.len() < target {
        let (p, _) = surface.point(rng);
        if rng.random::<f64>() * (1.0 + density.gradient) > density.factor(p) {
            continue;
        }
        let s = spacing(p);
        labels.push(if sharp.within(p, W_SHARP * s) {
            Class::Sharp
        } else if border.within(p, W_BORDER * s) {
            Class::Boundary
        } else {
            Class::NonEdge
        });
        points.push(p);
    }
    Sampled {
        points,
        labels,
        // Mean nearest-neighbour distance of uniform random points: half the spacing.
        spacing_hint: 0.5 * (surface.weighted_area / target as f64).sqrt(),
    }
}

/// Widens the sharp labels to a band: every point within `radius` of a crease becomes sharp
/// (sharp wins over boundary, as on the rows); points already sharp stay so.
pub(crate) fn widen_sharp(sampled: &mut Sampled, creases: &[Polyline], radius: f64) {
    let near = near_creases(&sampled.points, creases, radius);
    for (near, class) in near.into_iter().zip(&mut sampled.labels) {
        if near {
            *class = Class::Sharp;
        }
    }
}

/// Whether each of `points` lies within `radius` of a crease.
fn near_creases(points: &[V3], creases: &[Polyline], radius: f64) -> Vec<bool> {
    let index = SegmentIndex::new(creases, radius, bounds(points.iter().copied()));
    points.iter().map(|&p| index.within(p, radius)).collect()
}

/// Thins the points farther than `radius` from every crease, keeping each with probability
/// `keep`; every point within `radius` stays, and labels go with their points. This makes the
/// density step of a CAD triangulation whose vertices crowd along its creases and leave its
/// faces sparse: where the two meet, a point's nearest neighbours lie on the dense side.
pub(crate) fn thin_away_from(
    sampled: &mut Sampled,
    creases: &[Polyline],
    radius: f64,
    keep: f64,
    rng: &mut impl Rng,
) {
    let kept: Vec<bool> = (near_creases(&sampled.points, creases, radius).into_iter())
        .map(|near| near || rng.random::<f64>() < keep)
        .collect();
    retain_flagged(&mut sampled.points, &kept);
    retain_flagged(&mut sampled.labels, &kept);
}

fn spacing_max(surface: &Surface, density: &Density, target: usize) -> f64 {
    (surface.weighted_area / (target as f64 * (1.0 - density.gradient))).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn unit_cube() -> Mesh {
        super::super::profile::extrude(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            1.0,
            true,
            [true, true],
        )
        .welded()
    }

    /// Distance from p to the nearest of the unit cube's 12 edges.
    fn cube_edge_distance(p: V3) -> f64 {
        (0..3)
            .map(|axis| {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let du = p[u].min(1.0 - p[u]);
                let dv = p[v].min(1.0 - p[v]);
                du.hypot(dv)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn mesh_vertex_cube_labels_exactly_the_edge_rows() {
        let cube = unit_cube();
        let f = cube.features();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let s = sample(&cube, &f, Sampling::MeshVertex, 6000, 1.0, 1.0, &mut rng);
        let mut sharp = 0;
        for (p, &c) in s.points.iter().zip(&s.labels) {
            let on_edge = cube_edge_distance(*p) < 1e-9;
            assert_eq!(on_edge, c == Class::Sharp, "{p:?} {c:?}");
            sharp += usize::from(on_edge);
        }
        // 12 unit edges with a row step of 1.0..1.2 x r0: about 12 / step points.
        let expect = 12.0 / s.spacing_hint;
        assert!(
            (sharp as f64) < 1.05 * expect && (sharp as f64) > 0.75 * expect,
            "{sharp} vs {expect}"
        );
        // No face point comes closer to an edge than half the minimum distance.
        let min_face = s
            .points
            .iter()
            .zip(&s.labels)
            .filter(|(_, c)| **c == Class::NonEdge)
            .map(|(p, _)| cube_edge_distance(*p))
            .fold(f64::INFINITY, f64::min);
        assert!(min_face > 0.3 * s.spacing_hint, "{min_face}");
        // The count is near the target (fill density calibration).
        let n = s.points.len() as f64;
        assert!(n > 0.75 * 6000.0 && n < 1.3 * 6000.0, "{n}");
    }

    /// The median distance from each of `points` to its nearest other one (brute force).
    fn median_nearest(points: &[V3]) -> f64 {
        let mut d: Vec<f64> = (points.iter().enumerate())
            .map(|(i, &p)| {
                (points.iter().enumerate())
                    .filter(|&(j, _)| j != i)
                    .map(|(_, &q)| norm(sub(p, q)))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// The median nearest-neighbour distance among the non-edge points and among the sharp
    /// ones.
    fn face_and_row_spacing(s: &Sampled) -> (f64, f64) {
        let of = |class| {
            let p: Vec<V3> = (s.points.iter().zip(&s.labels))
                .filter(|(_, c)| **c == class)
                .map(|(p, _)| *p)
                .collect();
            median_nearest(&p)
        };
        (of(Class::NonEdge), of(Class::Sharp))
    }

    #[test]
    fn spread_rows_step_further_along_the_creases_only() {
        let cube = unit_cube();
        let f = cube.features();
        let [(face_a, row_a), (face_b, row_b)] = [1.0, 1.6].map(|row_spacing| {
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            face_and_row_spacing(&sample(
                &cube,
                &f,
                Sampling::MeshVertex,
                4000,
                1.0,
                row_spacing,
                &mut rng,
            ))
        });
        // The same step drawn, times 1.6: a cube's edges are straight, so each row's
        // neighbours are its step apart (rounded to a whole number of steps per edge).
        assert!((1.5..1.7).contains(&(row_b / row_a)), "{row_a} -> {row_b}");
        // The faces keep their minimum distance.
        assert!(
            (0.95..1.05).contains(&(face_b / face_a)),
            "{face_a} -> {face_b}"
        );
    }

    #[test]
    fn sparse_faces_spread_the_fill_of_planes_only() {
        let cube = unit_cube();
        let f = cube.features();
        let spacings = [1.0, 2.0].map(|face_spacing| {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let s = sample(
                &cube,
                &f,
                Sampling::MeshVertex,
                4000,
                face_spacing,
                1.0,
                &mut rng,
            );
            let n = s.points.len() as f64;
            assert!(n > 0.7 * 4000.0 && n < 1.3 * 4000.0, "{face_spacing}: {n}");
            face_and_row_spacing(&s)
        });
        // Face points lie about twice as far apart, relative to the crease rows' step.
        let ratio = |(face, row): (f64, f64)| face / row;
        let spread = ratio(spacings[1]) / ratio(spacings[0]);
        assert!((1.7..2.3).contains(&spread), "{spacings:?}");
        // A surface without planar faces is sampled as before, point for point.
        use std::f64::consts::{FRAC_PI_2, TAU};
        let arc = super::super::profile::arc([0.0, 0.0], 1.0, -FRAC_PI_2, FRAC_PI_2);
        let sphere = super::super::profile::revolve(&arc, 72, TAU, false).welded();
        let f = sphere.features();
        let [a, b] = [1.0, 3.0].map(|face_spacing| {
            let mut rng = ChaCha8Rng::seed_from_u64(6);
            sample(
                &sphere,
                &f,
                Sampling::MeshVertex,
                1500,
                face_spacing,
                1.0,
                &mut rng,
            )
            .points
        });
        assert_eq!(a, b);
    }

    #[test]
    fn random_cube_labels_a_band_of_a_third_spacing() {
        let cube = unit_cube();
        let f = cube.features();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let s = sample(&cube, &f, Sampling::Random, 6000, 1.0, 1.0, &mut rng);
        assert_eq!(s.points.len(), 6000);
        // The local spacing is at most sqrt(6 / (6000 * 0.4)) = 0.05.
        let max_band = W_SHARP * 0.05;
        for (p, &c) in s.points.iter().zip(&s.labels) {
            let d = cube_edge_distance(*p);
            if c == Class::Sharp {
                assert!(d < max_band, "{d}");
            }
            assert_ne!(c, Class::Boundary);
        }
        // Every point closer than the smallest possible band (spacing >= sqrt(6/(6000*1.6)))
        // is sharp.
        let min_band = W_SHARP * (6.0 / (6000.0 * 1.6_f64)).sqrt();
        for (p, &c) in s.points.iter().zip(&s.labels) {
            if cube_edge_distance(*p) < min_band {
                assert_eq!(c, Class::Sharp);
            }
        }
    }

    #[test]
    fn a_widened_band_labels_every_point_within_its_radius_and_keeps_the_rows() {
        let cube = unit_cube();
        let f = cube.features();
        for (sampling, seed) in [(Sampling::MeshVertex, 3), (Sampling::Random, 4)] {
            let mut s = sample(
                &cube,
                &f,
                sampling,
                6000,
                1.0,
                1.0,
                &mut ChaCha8Rng::seed_from_u64(seed),
            );
            let before = s.labels.clone();
            widen_sharp(&mut s, &f.sharp, 0.04);
            let mut widened = 0;
            for ((p, &c), &was) in s.points.iter().zip(&s.labels).zip(&before) {
                let d = cube_edge_distance(*p);
                let want = if d < 0.04 || was == Class::Sharp {
                    Class::Sharp
                } else {
                    Class::NonEdge
                };
                assert_eq!(c, want, "{sampling:?} at {p:?}: {d}");
                widened += usize::from(was != c);
            }
            // Strips 0.04 wide either side of 12 unit edges cover 0.96 of the area 6: about
            // 960 of 6000 points, of which the one-row labels held 240 (random) to 360 (rows).
            assert!(widened > 400, "{sampling:?}: {widened}");
        }
    }

    #[test]
    fn thinning_keeps_every_point_near_a_crease_and_a_share_of_the_rest() {
        let cube = unit_cube();
        let f = cube.features();
        for (sampling, seed) in [(Sampling::MeshVertex, 7), (Sampling::Random, 8)] {
            let draw = || {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                sample(&cube, &f, sampling, 8000, 1.0, 1.0, &mut rng)
            };
            let (full, mut thin) = (draw(), draw());
            thin_away_from(
                &mut thin,
                &f.sharp,
                0.1,
                0.25,
                &mut ChaCha8Rng::seed_from_u64(9),
            );
            // The thinned points are the full cloud's, in order, with their labels; every one
            // within 0.1 of an edge is kept.
            let mut rest = full.points.iter().zip(&full.labels);
            let (mut near, mut far, mut far_kept) = (0, 0, 0);
            for (p, c) in thin.points.iter().zip(&thin.labels) {
                for (q, d) in rest.by_ref() {
                    let close = cube_edge_distance(*q) < 0.1;
                    if q == p {
                        assert_eq!(d, c);
                        near += usize::from(close);
                        far_kept += usize::from(!close);
                        far += usize::from(!close);
                        break;
                    }
                    assert!(!close, "{sampling:?}: {q:?} near an edge was dropped");
                    far += 1;
                }
            }
            far += rest.filter(|(q, _)| cube_edge_distance(**q) >= 0.1).count();
            // Within 0.1 of its border lies 1 - 0.8^2 = 0.36 of each face: about 36% of the
            // points (the density varies across the cube, the rows add some); a quarter of the
            // others stays (binomial, 5 sigma).
            let share = near as f64 / full.points.len() as f64;
            assert!((0.28..0.48).contains(&share), "{sampling:?}: {share}");
            let sigma = (far as f64 * 0.25 * 0.75).sqrt();
            assert!(
                (far_kept as f64 - 0.25 * far as f64).abs() < 5.0 * sigma,
                "{sampling:?}: {far_kept} of {far}"
            );
            assert_eq!(thin.labels.len(), thin.points.len());
        }
    }

    #[test]
    fn disc_border_points_are_boundary_and_only_they() {
        let disc = super::super::profile::revolve(
            &[[0.0, 0.0], [1.0, 0.0]],
            72,
            std::f64::consts::TAU,
            false,
        )
        .welded();
        let f = disc.features();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let s = sample(&disc, &f, Sampling::MeshVertex, 3000, 1.0, 1.0, &mut rng);
        // The border is the 72-gon inscribed in the unit circle: its points have radius in
        // [cos(2.5 deg), 1].
        let inner = (2.5_f64).to_radians().cos();
        let mut boundary = 0;
        for (p, &c) in s.points.iter().zip(&s.labels) {
            let r = p[0].hypot(p[1]);
            assert_ne!(c, Class::Sharp);
            if c == Class::Boundary {
                boundary += 1;
                assert!(r >= inner - 1e-9 && r <= 1.0 + 1e-9, "{r}");
            } else {
                assert!(r < 1.0 - 0.3 * s.spacing_hint, "{r}");
            }
        }
        let expect = std::f64::consts::TAU / s.spacing_hint;
        assert!((boundary as f64) > 0.75 * expect, "{boundary} vs {expect}");
    }

    #[test]
    fn sphere_has_no_edge_points_in_either_mode() {
        use std::f64::consts::{FRAC_PI_2, TAU};
        let arc = super::super::profile::arc([0.0, 0.0], 1.0, -FRAC_PI_2, FRAC_PI_2);
        let sphere = super::super::profile::revolve(&arc, 72, TAU, false).welded();
        let f = sphere.features();
        for sampling in [Sampling::MeshVertex, Sampling::Random] {
            let mut rng = ChaCha8Rng::seed_from_u64(4);
            let s = sample(&sphere, &f, sampling, 2000, 1.0, 1.0, &mut rng);
            assert!(
                s.labels.iter().all(|&c| c == Class::NonEdge),
                "{sampling:?}"
            );
        }
    }
}
