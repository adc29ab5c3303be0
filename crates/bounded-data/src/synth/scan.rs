//! Sampling a free-form surface: uniform random points, blue noise, and scan lines.
//!
//! All three draw parameters `(u, v)` and place the point on the displaced surface there,
//! so every point lies exactly on the geometry its label comes from. Random and blue-noise
//! points are uniform in area up to a linear density gradient (up to 1.6 : 0.4, as the
//! other kinds); scan lines are a lattice in the parameter domain, as an orthographic
//! scanner looking along the surface's mean normal makes them: rows whose spacing differs
//! from the spacing along them (up to 3 : 1 either way), a density that changes across the
//! rows, slight jitter, dropped points, and noise along the view ray.

use super::freeform::Base;
use super::grid::Grid;
use super::profile::P2;
use super::relief::Relief;
use super::sample::FILL_LEVELS;
use crate::table::retain_flagged;
use bounded_geom::vec3::{V3, norm, sub};
use rand::Rng;
use rand_distr::StandardNormal;

/// How a free-form surface is turned into points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FreeformSampling {
    /// Uniform random points.
    Random,
    /// Dart throwing with a minimum distance: irregular but even, as remeshed or
    /// photogrammetric clouds.
    BlueNoise,
    /// Scan lines: an anisotropic, jittered lattice with a varying density, dropouts and
    /// range noise along the view ray. Open bases only.
    Scan,
}

impl FreeformSampling {
    /// Short name, used in generated cloud names.
    pub fn name(self) -> &'static str {
        match self {
            FreeformSampling::Random => "random",
            FreeformSampling::BlueNoise => "blue",
            FreeformSampling::Scan => "scan",
        }
    }
}

/// The median nearest-neighbour distance of uniform random points, in units of
/// `1 / sqrt(points per unit area)`: `sqrt(ln 2 / pi)`.
const RANDOM_SPACING: f64 = 0.4697;

/// The median nearest-neighbour distance of dart throwing, in units of its minimum
/// distance.
const BLUE_SPACING: f64 = 1.1;

/// A density that changes linearly across the parameter domain: `factor` lies in
/// `[1 - gradient, 1 + gradient]`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Density {
    centre: P2,
    /// Direction scaled by `gradient / reach`.
    slope: P2,
    gradient: f64,
}

impl Density {
    fn random(base: &Base, rng: &mut impl Rng) -> Self {
        let [lo, hi] = base.domain();
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let t = rng.random_range(0.0..std::f64::consts::TAU);
        let d = [t.cos(), t.sin()];
        let reach = 0.5 * ((hi[0] - lo[0]) * d[0].abs() + (hi[1] - lo[1]) * d[1].abs());
        let gradient = if rng.random_bool(0.4) {
            0.0
        } else {
            rng.random_range(0.0..0.6)
        };
        let k = gradient / reach.max(f64::MIN_POSITIVE);
        Self {
            centre,
            slope: [d[0] * k, d[1] * k],
            gradient,
        }
    }

    fn factor(&self, uv: P2) -> f64 {
        1.0 + (uv[0] - self.centre[0]) * self.slope[0] + (uv[1] - self.centre[1]) * self.slope[1]
    }
}

/// A scan-line lattice in the parameter domain.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Lattice {
    centre: P2,
    /// Unit direction along the rows.
    along: P2,
    /// Point step along a row at the centre.
    step: f64,
    /// Distance between rows.
    row: f64,
    /// The step along a row changes by this fraction across the domain.
    gradient: f64,
    /// Half the domain's extent across the rows.
    half: f64,
    /// Standard deviation of the jitter, a fraction of the steps.
    jitter: f64,
    /// Probability that a point is dropped.
    dropout: f64,
}

/// A sampling mode with its parameters drawn.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Plan {
    Random(Density),
    BlueNoise {
        density: Density,
        /// Dart-throwing attempts and points reached per minimum distance squared.
        fill: (f64, f64),
    },
    Scan(Lattice),
}

impl Plan {
    /// Draws the parameters of `sampling` for about `target` points on `base` (of area
    /// `area`).
    pub(crate) fn random(
        sampling: FreeformSampling,
        base: &Base,
        target: usize,
        rng: &mut impl Rng,
    ) -> Self {
        match sampling {
            FreeformSampling::Random => Plan::Random(Density::random(base, rng)),
            FreeformSampling::BlueNoise => Plan::BlueNoise {
                density: Density::random(base, rng),
                fill: FILL_LEVELS[rng.random_range(0..2)],
            },
            FreeformSampling::Scan => {
                let [lo, hi] = base.domain();
                let t = rng.random_range(0.0..std::f64::consts::PI);
                let along = [t.cos(), t.sin()];
                let half =
                    0.5 * ((hi[0] - lo[0]) * along[1].abs() + (hi[1] - lo[1]) * along[0].abs());
                let uv_area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
                // Rows `k` times as far apart as the points along them, k in 1/3..3.
                let k = 3f64.powf(rng.random_range(-1.0..1.0));
                let step = (uv_area / (target as f64 * k)).sqrt();
                Plan::Scan(Lattice {
                    centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
                    along,
                    step,
                    row: k * step,
                    gradient: rng.random_range(0.0..0.5),
                    half,
                    jitter: rng.random_range(0.0..0.08),
                    dropout: rng.random_range(0.0..0.05),
                })
            }
        }
    }

    /// The expected median nearest-neighbour distance of the points, `area` being the
    /// surface's area.
    pub(crate) fn spacing(&self, area: f64, target: usize) -> f64 {
        let per_point = (area / target as f64).sqrt();
        match self {
            Plan::Random(_) => RANDOM_SPACING * per_point,
            Plan::BlueNoise { fill, .. } => BLUE_SPACING * fill.1.sqrt() * per_point,
            // A row's step is `step (1 + g t)`, t uniform in -1..1 across the rows, and its
            // points are as many as 1 / (1 + g t): half of them lie in rows whose step is
            // below step sqrt(1 - g^2).
            Plan::Scan(l) => (l.step * (1.0 - l.gradient * l.gradient).sqrt()).min(l.row),
        }
    }

    /// True for scan lines, whose noise runs along the view ray.
    pub(crate) fn is_scan(&self) -> bool {
        matches!(self, Plan::Scan(_))
    }
}

/// Samples about `target` points: positions on the displaced surface and their parameters.
pub(crate) fn sample(
    relief: &Relief,
    plan: &Plan,
    target: usize,
    rng: &mut impl Rng,
) -> (Vec<V3>, Vec<P2>) {
    match plan {
        Plan::Random(density) => random(relief, density, target, rng),
        Plan::BlueNoise { density, fill } => blue_noise(relief, density, *fill, target, rng),
        Plan::Scan(lattice) => scan(relief, lattice, rng),
    }
}

/// Uniform random points by rejection: parameters uniform in the domain, kept with
/// probability proportional to the displaced surface's area element times the density
/// factor.
fn random(
    relief: &Relief,
    density: &Density,
    target: usize,
    rng: &mut impl Rng,
) -> (Vec<V3>, Vec<P2>) {
    let [lo, hi] = relief.base.domain();
    let area_bound = relief.base.max_area_element() * (1.0 + density.gradient);
    let stretch_bound = relief.max_stretch();
    let mut points = Vec::with_capacity(target);
    let mut uvs = Vec::with_capacity(target);
    while points.len() < target {
        let uv = [
            rng.random_range(lo[0]..hi[0]),
            rng.random_range(lo[1]..hi[1]),
        ];
        // Three tests, the cheap ones first (the base, the local bound of the stretch):
        // together they keep a point with probability proportional to area element x
        // density x stretch, and only points near steep features pay for the last.
        let [u1, u2, u3] = [(); 3].map(|()| rng.random::<f64>());
        let (base, _, area) = relief.base.frame(uv);
        if u1 * area_bound > area * density.factor(uv) {
            continue;
        }
        let local = relief.stretch_bound(base);
        if u2 * stretch_bound > local {
            continue;
        }
        let (p, stretch) = relief.point_and_stretch(uv);
        if u3 * local > stretch {
            continue;
        }
        points.push(p);
        uvs.push(uv);
    }
    (points, uvs)
}

/// Dart throwing over random candidates, the minimum distance shrinking where the density
/// factor is high.
fn blue_noise(
    relief: &Relief,
    density: &Density,
    (attempts, fill): (f64, f64),
    target: usize,
    rng: &mut impl Rng,
) -> (Vec<V3>, Vec<P2>) {
    let area = relief.base.area();
    let r0 = (fill * area / target as f64).sqrt();
    let candidates = (attempts / fill * target as f64) as usize;
    let (points, uvs) = random(relief, density, candidates, rng);
    let mut grid = Grid::new(
        r0 / (1.0 - density.gradient).sqrt(),
        super::grid::bounds(points.iter().copied()),
    );
    let mut kept = Vec::with_capacity(target + target / 4);
    for (p, uv) in points.into_iter().zip(uvs) {
        if !grid.any_within(p, r0 / density.factor(uv).sqrt()) {
            grid.insert(p);
            kept.push(uv);
        }
    }
    (grid.points().to_vec(), kept)
}

/// A jittered anisotropic lattice with a step that changes across the rows.
fn scan(relief: &Relief, l: &Lattice, rng: &mut impl Rng) -> (Vec<V3>, Vec<P2>) {
    let [lo, hi] = relief.base.domain();
    let across = [-l.along[1], l.along[0]];
    let reach = 0.5 * norm([hi[0] - lo[0], hi[1] - lo[1], 0.0]);
    let rows = (reach / l.row).ceil() as i64;
    let mut points = Vec::new();
    let mut uvs = Vec::new();
    for i in -rows..=rows {
        let y = i as f64 * l.row;
        let step = l.step * (1.0 + l.gradient * (y / l.half).clamp(-1.0, 1.0));
        let columns = (reach / step).ceil() as i64;
        for j in -columns..=columns {
            let jx: f64 = rng.sample(StandardNormal);
            let jy: f64 = rng.sample(StandardNormal);
            let (x, yj) = ((j as f64 + l.jitter * jx) * step, y + l.jitter * jy * l.row);
            let uv = [
                l.centre[0] + x * l.along[0] + yj * across[0],
                l.centre[1] + x * l.along[1] + yj * across[1],
            ];
            let inside = (0..2).all(|a| uv[a] >= lo[a] && uv[a] <= hi[a]);
            if !inside || rng.random::<f64>() < l.dropout {
                continue;
            }
            points.push(relief.point(uv));
            uvs.push(uv);
        }
    }
    (points, uvs)
}

/// Removes the points within a radius drawn from `radii` of `count` random points: holes
/// of missing data.
pub(crate) fn punch_holes(
    points: &mut Vec<V3>,
    uvs: &mut Vec<P2>,
    count: usize,
    radii: std::ops::Range<f64>,
    rng: &mut impl Rng,
) {
    for _ in 0..count {
        if points.is_empty() {
            return;
        }
        let centre = points[rng.random_range(0..points.len())];
        let r = rng.random_range(radii.clone());
        let keep: Vec<bool> = points.iter().map(|&p| norm(sub(p, centre)) >= r).collect();
        retain_flagged(points, &keep);
        retain_flagged(uvs, &keep);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::perturb::median_spacing;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn each_sampling_reaches_its_count_and_its_expected_spacing() {
        // A bare plane: points are their parameters, and the spacing the features are
        // drawn in (Plan::spacing) is what the sampling gives.
        let base = Base::HeightField {
            size: [1.0, 0.8],
            terms: Vec::new(),
        };
        let relief = Relief::new(base, Vec::new(), 0.01);
        for sampling in [
            FreeformSampling::Random,
            FreeformSampling::BlueNoise,
            FreeformSampling::Scan,
        ] {
            for seed in 0..3 {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let plan = Plan::random(sampling, &relief.base, 4000, &mut rng);
                let expect = plan.spacing(relief.base.area(), 4000);
                let (points, uvs) = sample(&relief, &plan, 4000, &mut rng);
                assert_eq!(points.len(), uvs.len());
                for (p, uv) in points.iter().zip(&uvs) {
                    assert_eq!(*p, [uv[0], uv[1], 0.0]);
                    assert!((0.0..=1.0).contains(&uv[0]) && (0.0..=0.8).contains(&uv[1]));
                }
                let n = points.len();
                if sampling == FreeformSampling::Random {
                    assert_eq!(n, 4000);
                }
                assert!(n > 3400 && n < 4600, "{sampling:?} {seed}: {n}");
                let measured = median_spacing(&points, expect);
                assert!(
                    (measured / expect - 1.0).abs() < 0.1,
                    "{sampling:?} {seed}: {measured} vs {expect}"
                );
            }
        }
    }
}
