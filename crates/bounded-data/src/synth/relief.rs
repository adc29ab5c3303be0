//! Relief features on a free-form base: cross-section profiles swept along curves, the
//! displaced surface they make, its kink lines, and the rule that labels points from them.
//!
//! A feature is a curve on the base surface and a profile `h(s)`: the surface is moved along
//! the base normal by `h` of the signed distance `s` from the base point to the curve
//! (positive on the curve's left, seen from the normal side). Profiles are piecewise smooth
//! in `s`, so the sharp geometry is known exactly: the offsets where the slope `h'(s)`
//! jumps (a V groove's bottom and rims, a step's two edges) are the kink lines, found on the
//! surface by root finding, and the dihedral deviation across each kink is measured on the
//! displaced surface itself (one-sided normals a hair's breadth either side), so it holds on
//! curved bases too. Features never overlap (their supports are kept apart when placed), so
//! each point's displacement is the sum of independent profiles.

use super::freeform::Base;
use super::grid::bounds;
use super::mesh::Polyline;
use super::profile::P2;
use super::segments::{CurveTree, SegmentIndex};
use crate::DataError;
use bounded_geom::Class;
use bounded_geom::vec3::{V3, add, cross, dot, norm, normalize, scale, sub, tangent_frame};

/// What counts as a sharp feature of a free-form cloud, and how wide its label is; lengths
/// are in units of the cloud's median nearest-neighbour spacing, measured on the clean
/// points as the noise levels are.
///
/// A point is [`Class::Sharp`] when it lies within `band` spacings (3D distance) of a kink
/// line whose dihedral deviation there is at least `min_angle` degrees and whose feature
/// (a groove's depth, a ridge's or step's height) is at least `min_depth` spacings; else
/// [`Class::Boundary`] within [`W_BORDER`](super::W_BORDER) spacings of the border of an open
/// surface, as in the other kinds, whatever `band` is: `band` sets the feature curves' convention,
/// and boundaries keep the one convention of every generated set; else
/// non-edge. Labels are those of the clean points, and do not depend on holes (a dropout is
/// missing data, not a border of the object); they depend on the noise only through
/// `min_depth_per_noise` (off by default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabelRule {
    /// Smallest deviation from flat across a kink, in degrees, for it to be sharp. Default
    /// 10: the generator's creases go down to about that, and below it a kink turns the
    /// normal less than the curved bases do across a typical neighbourhood, so it cannot be
    /// told from curvature.
    pub min_angle: f64,
    /// Smallest depth or height of a feature, in spacings, for its kinks to be sharp.
    /// Default 0.25: a kink displacing the surface by less than a quarter spacing is below
    /// typical noise and cannot be found from positions.
    pub min_depth: f64,
    /// Half-width of the sharp band around a kink line, in spacings: 0.5 labels about one
    /// row, as the CAD sets do; 1 to 2 labels bands 2 to 4 spacings wide. Default 1: the
    /// narrow end of such bands, wide enough that irregular and scan-line sampling leave no
    /// gaps along a kink.
    pub band: f64,
    /// Smallest depth or height of a feature as a multiple of the cloud's noise level (its
    /// standard deviation, in spacings), on top of `min_depth`: a feature is sharp only when
    /// at least `max(min_depth, min_depth_per_noise x noise)` spacings deep. Default 0 (off).
    /// A groove a spacing deep under a spacing of range noise is not in the positions at
    /// all (see `docs/model.md`); with this rule a model is not asked to find it.
    pub min_depth_per_noise: f64,
}

impl Default for LabelRule {
    fn default() -> Self {
        Self {
            min_angle: 10.0,
            min_depth: 0.25,
            band: 1.0,
            min_depth_per_noise: 0.0,
        }
    }
}

impl LabelRule {
    /// The rule for a cloud with `noise` (standard deviation in spacings): `min_depth_per_noise`
    /// folded into `min_depth`.
    pub fn at_noise(&self, noise: f64) -> LabelRule {
        LabelRule {
            min_depth: self.min_depth.max(self.min_depth_per_noise * noise),
            min_depth_per_noise: 0.0,
            ..*self
        }
    }

    /// Checks the ranges: `min_angle` in 0..180, `min_depth` and `min_depth_per_noise` 0 or
    /// more, `band` above 0.
    pub fn validate(&self) -> Result<(), DataError> {
        let bad = |what: String| Err(DataError::Generator { what });
        if !(0.0..180.0).contains(&self.min_angle) {
            return bad(format!(
                "label min_angle {}: degrees, 0 up to 180",
                self.min_angle
            ));
        }
        if !(self.min_depth.is_finite() && self.min_depth >= 0.0) {
            return bad(format!(
                "label min_depth {}: a multiple of the point spacing, 0 or more",
                self.min_depth
            ));
        }
        if !(self.min_depth_per_noise.is_finite() && self.min_depth_per_noise >= 0.0) {
            return bad(format!(
                "label min_depth_per_noise {}: a multiple of the noise level, 0 or more",
                self.min_depth_per_noise
            ));
        }
        check_band(self.band)
    }
}

/// A sharp band (the free-form rule's, or a mesh kind's) must be a positive number of
/// spacings.
pub(crate) fn check_band(band: f64) -> Result<(), DataError> {
    if band.is_finite() && band > 0.0 {
        return Ok(());
    }
    Err(DataError::Generator {
        what: format!("label band {band}: a multiple of the point spacing, above 0"),
    })
}

/// A cross-section: displacement `h(s)` along the base normal (positive outward) against the
/// signed distance `s` to the feature's curve. Symmetric profiles depend on `|s|` only and
/// vanish beyond their half-width; one-sided ones (steps) rise from 0 at `s = 0` to their
/// height at `s = width` and keep it beyond.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Profile {
    /// `depth (1 - |s| / half_width)`: kinks at the bottom (deviation `2 atan(depth /
    /// half_width)`) and both rims (`atan(depth / half_width)`).
    V { half_width: f64, depth: f64 },
    /// Flat-bottomed (or flat-topped): `depth` within `flat`, falling linearly to 0 at
    /// `half_width`; kinks at `±flat` and `±half_width`.
    Trapezoid {
        half_width: f64,
        flat: f64,
        depth: f64,
    },
    /// Rounded: `depth (1 - (s / half_width)^2)`, kinks at the rims only.
    Round { half_width: f64, depth: f64 },
    /// `depth (1 + cos(pi s / half_width)) / 2`: smooth everywhere, no kink.
    Smooth { half_width: f64, depth: f64 },
    /// A step: `height clamp(s / width, 0, 1)`, kinks at 0 and `width`.
    Ramp { width: f64, height: f64 },
    /// A smooth step (smoothstep over `width`), no kink.
    SmoothRamp { width: f64, height: f64 },
}

impl Profile {
    /// True for steps: the height holds on the whole positive side.
    pub(crate) fn one_sided(&self) -> bool {
        matches!(self, Profile::Ramp { .. } | Profile::SmoothRamp { .. })
    }

    /// The largest `|s|` (symmetric) or `s` (one-sided) where the profile still changes.
    pub(crate) fn reach(&self) -> f64 {
        match *self {
            Profile::V { half_width, .. }
            | Profile::Trapezoid { half_width, .. }
            | Profile::Round { half_width, .. }
            | Profile::Smooth { half_width, .. } => half_width,
            Profile::Ramp { width, .. } | Profile::SmoothRamp { width, .. } => width,
        }
    }

    /// The feature's size: its depth or height, unsigned.
    pub(crate) fn size(&self) -> f64 {
        match *self {
            Profile::V { depth, .. }
            | Profile::Trapezoid { depth, .. }
            | Profile::Round { depth, .. }
            | Profile::Smooth { depth, .. } => depth.abs(),
            Profile::Ramp { height, .. } | Profile::SmoothRamp { height, .. } => height.abs(),
        }
    }

    /// `h(s)`.
    pub(crate) fn value(&self, s: f64) -> f64 {
        let a = s.abs();
        match *self {
            Profile::V { half_width, depth } => depth * (1.0 - a / half_width).max(0.0),
            Profile::Trapezoid {
                half_width,
                flat,
                depth,
            } => depth * ((half_width - a) / (half_width - flat)).clamp(0.0, 1.0),
            Profile::Round { half_width, depth } => {
                depth * (1.0 - (a / half_width).powi(2)).max(0.0)
            }
            Profile::Smooth { half_width, depth } if a < half_width => {
                0.5 * depth * (1.0 + (std::f64::consts::PI * a / half_width).cos())
            }
            Profile::Smooth { .. } => 0.0,
            Profile::Ramp { width, height } => height * (s / width).clamp(0.0, 1.0),
            Profile::SmoothRamp { width, height } => {
                let t = (s / width).clamp(0.0, 1.0);
                height * t * t * (3.0 - 2.0 * t)
            }
        }
    }

    /// `|h'(s)|` away from the kinks: how steeply the displaced surface leaves the base.
    pub(crate) fn steepness(&self, s: f64) -> f64 {
        let a = s.abs();
        let slope = match *self {
            Profile::V { half_width, depth } if a < half_width => depth / half_width,
            Profile::Trapezoid {
                half_width,
                flat,
                depth,
            } if a > flat && a < half_width => depth / (half_width - flat),
            Profile::Round { half_width, depth } if a < half_width => {
                2.0 * depth * a / (half_width * half_width)
            }
            Profile::Smooth { half_width, depth } if a < half_width => {
                let k = std::f64::consts::PI / half_width;
                0.5 * depth * k * (k * a).sin()
            }
            Profile::Ramp { width, height } if s > 0.0 && s < width => height / width,
            Profile::SmoothRamp { width, height } if s > 0.0 && s < width => {
                let t = s / width;
                6.0 * height * t * (1.0 - t) / width
            }
            _ => 0.0,
        };
        slope.abs()
    }

    /// The largest [`steepness`](Self::steepness) anywhere.
    pub(crate) fn max_steepness(&self) -> f64 {
        let slope = match *self {
            Profile::V { half_width, depth } => depth / half_width,
            Profile::Trapezoid {
                half_width,
                flat,
                depth,
            } => depth / (half_width - flat),
            Profile::Round { half_width, depth } => 2.0 * depth / half_width,
            Profile::Smooth { half_width, depth } => {
                0.5 * std::f64::consts::PI * depth / half_width
            }
            Profile::Ramp { width, height } => height / width,
            Profile::SmoothRamp { width, height } => 1.5 * height / width,
        };
        slope.abs()
    }

    /// The signed offsets where the slope jumps: both sides of a symmetric profile.
    pub(crate) fn kinks(&self) -> Vec<f64> {
        match *self {
            Profile::V { half_width, .. } => vec![0.0, half_width, -half_width],
            Profile::Trapezoid {
                half_width, flat, ..
            } => vec![flat, -flat, half_width, -half_width],
            Profile::Round { half_width, .. } => vec![half_width, -half_width],
            Profile::Ramp { width, .. } => vec![0.0, width],
            Profile::Smooth { .. } | Profile::SmoothRamp { .. } => Vec::new(),
        }
    }
}

/// How the side of a one-sided feature is told where its curve is out of reach.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Side {
    /// Symmetric profile: no side.
    Either,
    /// The left of a closed counter-clockwise curve is its inside: a point-in-polygon test
    /// of the curve's `uv` vertices, `u` taken modulo `period` when it wraps (a shell's
    /// longitude).
    Inside { period: Option<f64> },
    /// A curve across the whole domain given as a graph (see [`Graph::left`]).
    Graph(Graph),
}

/// `g(t) = offset + slope (t - centre) + sum amplitude sin(frequency t + phase)`, the
/// curve `v = g(u)` traversed towards growing `u`, or when `transposed`, `u = g(v)`
/// traversed towards falling `v`: either way its left is the side of growing `v` or `u`
/// (the base normal being along `S_u x S_v`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Graph {
    pub(crate) transposed: bool,
    pub(crate) centre: f64,
    pub(crate) offset: f64,
    pub(crate) slope: f64,
    pub(crate) waves: Vec<[f64; 3]>,
}

impl Graph {
    pub(crate) fn at(&self, t: f64) -> f64 {
        self.offset
            + self.slope * (t - self.centre)
            + self
                .waves
                .iter()
                .map(|[a, f, p]| a * (f * t + p).sin())
                .sum::<f64>()
    }

    /// The curve's point at parameter `t` (`u`, or `v` when transposed).
    pub(crate) fn point(&self, t: f64) -> P2 {
        if self.transposed {
            [self.at(t), t]
        } else {
            [t, self.at(t)]
        }
    }

    /// True on the curve's left.
    pub(crate) fn left(&self, uv: P2) -> bool {
        if self.transposed {
            uv[0] > self.at(uv[1])
        } else {
            uv[1] > self.at(uv[0])
        }
    }
}

/// A curve on the base: parameter points, the base points they map to (the polyline whose
/// distances define `s`), and how its side is told.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Curve {
    pub(crate) uv: Vec<P2>,
    pub(crate) points: Vec<V3>,
    pub(crate) closed: bool,
    pub(crate) side: Side,
}

/// A profile swept along a curve.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Feature {
    pub(crate) profile: Profile,
    pub(crate) curve: Curve,
}

/// A kink line on the displaced surface, with the deviation across it at each vertex.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct KinkLine {
    pub(crate) points: Vec<V3>,
    /// Dihedral deviation from flat at each point, degrees.
    pub(crate) deviation: Vec<f64>,
    /// The feature's depth or height.
    pub(crate) size: f64,
    pub(crate) closed: bool,
}

/// A base surface with its features, ready to be evaluated.
pub(crate) struct Relief {
    pub(crate) base: Base,
    pub(crate) features: Vec<Feature>,
    /// Per feature: the distance tree of its curve and its support.
    reach: Vec<(CurveTree, f64)>,
    /// Per closed feature: its curve's parameter polygon, for the inside test.
    polygons: Vec<Option<Polygon>>,
    /// The features each region may be within reach of.
    lookup: Lookup,
    /// The one-sided features, whose far side is raised wherever it is.
    one_sided: Vec<u32>,
    /// The length unit of numerical steps: about the point spacing.
    unit: f64,
}

/// One-sided features are queried this far (in units) beyond their slope, so their side is
/// told by distance wherever it is in doubt.
const SIDE_MARGIN: f64 = 2.0;

/// Kink lines are searched up to this multiple of a feature's support: root finding may
/// step a little beyond a rim that lies at the support's edge.
const KINK_REACH: f64 = 1.25;

/// Kinks are measured this far either side (in units) and one-sided normals use steps a
/// tenth of it, so no stencil straddles the kink; the base's own turn between the two
/// (2e-6 units over its curvature radius) is far below any threshold.
const KINK_OFFSET: f64 = 1e-6;

impl Feature {
    /// How far from its curve the feature is queried (for overlap tests too).
    pub(crate) fn support(&self, unit: f64) -> f64 {
        let margin = if self.profile.one_sided() {
            SIDE_MARGIN * unit
        } else {
            0.0
        };
        self.profile.reach() + margin
    }
}

impl Relief {
    pub(crate) fn new(base: Base, features: Vec<Feature>, unit: f64) -> Self {
        let reach = features
            .iter()
            .map(|f| {
                let line = Polyline {
                    points: f.curve.points.clone(),
                    closed: f.curve.closed,
                };
                (CurveTree::new(&line), f.support(unit))
            })
            .collect();
        let polygons = features
            .iter()
            .map(|f| f.curve.closed.then(|| Polygon::new(&f.curve.uv)))
            .collect();
        let lookup = Lookup::new(&features, unit);
        let one_sided = (0..features.len() as u32)
            .filter(|&i| features[i as usize].profile.one_sided())
            .collect();
        Self {
            base,
            features,
            reach,
            polygons,
            lookup,
            one_sided,
            unit,
        }
    }

    /// Signed distance from base point `p` (normal `n`) to feature `i`'s curve, if within
    /// `reach` (at most [`KINK_REACH`]) times its support.
    fn signed_distance(&self, i: usize, p: V3, n: V3, reach: f64) -> Option<f64> {
        let (tree, r) = &self.reach[i];
        let near = tree.nearest(p, reach * r)?;
        let left = dot(cross(n, near.direction), sub(p, near.point)) >= 0.0;
        Some(if left { near.distance } else { -near.distance })
    }

    /// True when `uv` lies on the left of feature `i`'s curve (one-sided features, out of
    /// reach of the curve).
    fn left_far(&self, i: usize, uv: P2) -> bool {
        let curve = &self.features[i].curve;
        match &curve.side {
            Side::Either => false,
            Side::Graph(g) => g.left(uv),
            Side::Inside { period } => {
                let u = match period {
                    Some(t) => {
                        let c = curve.uv[0][0];
                        c + (uv[0] - c + 0.5 * t).rem_euclid(*t) - 0.5 * t
                    }
                    None => uv[0],
                };
                self.polygons[i]
                    .as_ref()
                    .is_some_and(|p| p.contains([u, uv[1]]))
            }
        }
    }

    /// Total displacement at `uv` (base point `p`, normal `n`), and the steepness of the
    /// feature profile there.
    fn height(&self, uv: P2, p: V3, n: V3) -> (f64, f64) {
        let mut h = 0.0;
        let mut steep = 0.0;
        let near = self.lookup.get(p);
        for &i in near {
            let f = &self.features[i as usize];
            match self.signed_distance(i as usize, p, n, 1.0) {
                Some(s) => {
                    h += f.profile.value(s);
                    steep = f.profile.steepness(s).max(steep);
                }
                None if f.profile.one_sided() && self.left_far(i as usize, uv) => {
                    h += f.profile.value(f64::INFINITY);
                }
                None => {}
            }
        }
        for &i in &self.one_sided {
            if !near.contains(&i) && self.left_far(i as usize, uv) {
                h += self.features[i as usize].profile.value(f64::INFINITY);
            }
        }
        (h, steep)
    }

    /// The displaced surface at `uv`.
    pub(crate) fn point(&self, uv: P2) -> V3 {
        self.point_and_stretch(uv).0
    }

    /// The displaced surface at `uv` and how much it stretches the base's area there: the
    /// profile's slope stretch `sqrt(1 + h'^2)` (its change of the base curvature, of
    /// order depth / radius, is left out: an approximately uniform density).
    pub(crate) fn point_and_stretch(&self, uv: P2) -> (V3, f64) {
        let (p, n, _) = self.base.frame(uv);
        let (h, steep) = self.height(uv, p, n);
        (add(p, scale(n, h)), (1.0 + steep * steep).sqrt())
    }

    /// The unit normal of the displaced surface at `uv`, by central differences over
    /// `step` along the base's tangent plane (across a kink: the mean of its faces).
    pub(crate) fn normal(&self, uv: P2, step: f64) -> V3 {
        let (p, n, _) = self.base.frame(uv);
        let (e1, e2) = tangent_frame(n);
        let at = |d: V3| self.point(self.base.project(add(p, d)));
        let du = sub(at(scale(e1, step)), at(scale(e1, -step)));
        let dv = sub(at(scale(e2, step)), at(scale(e2, -step)));
        normalize(cross(du, dv))
    }

    /// A bound of [`point_and_stretch`]'s stretch at parameters whose base point is `p`:
    /// the largest of the features that may reach it.
    ///
    /// [`point_and_stretch`]: Self::point_and_stretch
    pub(crate) fn stretch_bound(&self, p: V3) -> f64 {
        self.lookup.index(p).map_or(1.0, |i| self.lookup.stretch[i])
    }

    /// The largest slope stretch of any feature: bounds [`stretch_bound`].
    ///
    /// [`stretch_bound`]: Self::stretch_bound
    pub(crate) fn max_stretch(&self) -> f64 {
        self.features
            .iter()
            .map(|f| f.profile.max_steepness())
            .fold(0.0, f64::max)
            .hypot(1.0)
    }

    /// Every kink line of every feature, with its deviation measured on the surface.
    pub(crate) fn kink_lines(&self) -> Vec<KinkLine> {
        let mut lines = Vec::new();
        for (i, f) in self.features.iter().enumerate() {
            let kinks = f.profile.kinks();
            for &k in &kinks {
                lines.extend(self.offset_line(i, k));
            }
            if !f.curve.closed && !f.profile.one_sided() {
                for k in kinks.into_iter().filter(|&k| k > 0.0) {
                    lines.extend(self.caps(i, k));
                }
            }
        }
        lines
    }

    /// The kink line at signed offset `k` along feature `i`'s curve, split where a vertex
    /// could not be placed.
    fn offset_line(&self, i: usize, k: f64) -> Vec<KinkLine> {
        let curve = &self.features[i].curve;
        let n = curve.points.len();
        // Every other curve vertex (and an open curve's last): at most 2 degrees of turn
        // and well under a spacing apart, as designed.
        let last = (!curve.closed && (n - 1) % 2 == 1).then_some(n - 1);
        let vertices: Vec<Option<(V3, f64)>> = (0..n)
            .step_by(2)
            .chain(last)
            .map(|j| {
                let q = curve.points[j];
                let (prev, next) = if curve.closed {
                    ((j + n - 1) % n, (j + 1) % n)
                } else {
                    (j.saturating_sub(1), (j + 1).min(n - 1))
                };
                let t = normalize(sub(curve.points[next], curve.points[prev]));
                let b = normalize(cross(self.base.frame(curve.uv[j]).1, t));
                self.kink_at(i, q, b, k, false)
            })
            .collect();
        self.runs(i, vertices, curve.closed)
    }

    /// The half circles closing the kink lines at `±k` round both ends of an open curve.
    fn caps(&self, i: usize, k: f64) -> Vec<KinkLine> {
        let curve = &self.features[i].curve;
        let n = curve.points.len();
        let steps = ((std::f64::consts::PI * k / (0.25 * self.unit)).ceil() as usize).max(8);
        let mut out = Vec::new();
        for (end, inner) in [(n - 1, n.saturating_sub(2)), (0, 1.min(n - 1))] {
            let q = curve.points[end];
            let t = normalize(sub(q, curve.points[inner]));
            let b = normalize(cross(self.base.frame(curve.uv[end]).1, t));
            let vertices = (0..=steps)
                .map(|m| {
                    let psi = std::f64::consts::PI * (m as f64 / steps as f64 - 0.5);
                    let d = add(scale(t, psi.cos()), scale(b, psi.sin()));
                    self.kink_at(i, q, d, k, true)
                })
                .collect();
            out.extend(self.runs(i, vertices, false));
        }
        out
    }

    /// The kink at distance `k` from curve point `q` in the tangent direction `d`: its
    /// displaced position and deviation (signed distance, or unsigned round a cap).
    fn kink_at(&self, i: usize, q: V3, d: V3, k: f64, unsigned: bool) -> Option<(V3, f64)> {
        let target = if unsigned { k.abs() } else { k };
        let uv_at = |l: f64| self.base.project(add(q, scale(d, l)));
        let distance = |l: f64| {
            let uv = uv_at(l);
            let (p, n, _) = self.base.frame(uv);
            let s = self.signed_distance(i, p, n, KINK_REACH)?;
            Some(if unsigned { s.abs() } else { s })
        };
        // The distance grows about one for one along d, so a fixed-point step converges.
        let mut l = target;
        let mut found = false;
        for _ in 0..40 {
            let err = target - distance(l)?;
            if err.abs() <= 1e-9 * self.unit {
                found = true;
                break;
            }
            l += err;
        }
        if !found {
            return None;
        }
        let eps = KINK_OFFSET * self.unit;
        let step = 0.1 * eps;
        let a = self.normal(uv_at(l - eps), step);
        let b = self.normal(uv_at(l + eps), step);
        let deviation = norm(cross(a, b)).atan2(dot(a, b)).to_degrees();
        Some((self.point(uv_at(l)), deviation))
    }

    /// Splits placed vertices into kink lines at the gaps.
    fn runs(&self, i: usize, vertices: Vec<Option<(V3, f64)>>, closed: bool) -> Vec<KinkLine> {
        let size = self.features[i].profile.size();
        let all = vertices.iter().all(Option::is_some);
        let mut out = Vec::new();
        let mut line = KinkLine {
            points: Vec::new(),
            deviation: Vec::new(),
            size,
            closed: closed && all,
        };
        for v in vertices {
            match v {
                Some((p, d)) => {
                    line.points.push(p);
                    line.deviation.push(d);
                }
                None if line.points.is_empty() => {}
                None => out.push(std::mem::replace(
                    &mut line,
                    KinkLine {
                        points: Vec::new(),
                        deviation: Vec::new(),
                        size,
                        closed: false,
                    },
                )),
            }
        }
        if !line.points.is_empty() {
            out.push(line);
        }
        out
    }

    /// The border of the displaced surface, if open: its `uv` border loop resampled so
    /// that consecutive base points lie at most a tenth of the unit apart.
    pub(crate) fn border(&self) -> Option<Polyline> {
        let sides = self.base.border();
        if sides.is_empty() {
            return None;
        }
        let mut points = Vec::new();
        for [a, b] in sides {
            let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let coarse = 64;
            let length: f64 = (0..coarse)
                .map(|m| {
                    let (p, q) = (at(m as f64 / 64.0), at((m + 1) as f64 / 64.0));
                    norm(sub(self.base.frame(q).0, self.base.frame(p).0))
                })
                .sum();
            let n = ((1.5 * length / (0.1 * self.unit)).ceil() as usize).max(coarse);
            points.extend((0..n).map(|m| self.point(at(m as f64 / n as f64))));
        }
        Some(Polyline {
            points,
            closed: true,
        })
    }

    /// Labels `points` (on the displaced surface) by `rule`, `spacing` being their median
    /// nearest-neighbour distance.
    pub(crate) fn labels(
        &self,
        points: &[V3],
        spacing: f64,
        rule: &LabelRule,
        kinks: &[KinkLine],
        border: Option<&Polyline>,
    ) -> Vec<Class> {
        let sharp_lines: Vec<Polyline> = kinks
            .iter()
            .filter(|line| line.size >= rule.min_depth * spacing)
            .flat_map(|line| sharp_runs(line, rule.min_angle))
            .collect();
        let box_ = bounds(points.iter().copied());
        let (sharp_r, border_r) = (rule.band * spacing, super::W_BORDER * spacing);
        let sharp = SegmentIndex::new(&sharp_lines, sharp_r, box_);
        let border = SegmentIndex::new(border.map_or(&[], std::slice::from_ref), border_r, box_);
        points
            .iter()
            .map(|&p| {
                if sharp.within(p, sharp_r) {
                    Class::Sharp
                } else if border.within(p, border_r) {
                    Class::Boundary
                } else {
                    Class::NonEdge
                }
            })
            .collect()
    }
}

/// The parts of a kink line whose deviation is at least `min_angle`: runs of two or more
/// qualifying vertices (a closed line wholly qualifying stays closed).
fn sharp_runs(line: &KinkLine, min_angle: f64) -> Vec<Polyline> {
    let ok: Vec<bool> = line.deviation.iter().map(|&d| d >= min_angle).collect();
    let n = ok.len();
    if line.closed && ok.iter().all(|&b| b) {
        return vec![Polyline {
            points: line.points.clone(),
            closed: true,
        }];
    }
    // A closed line is walked from a failing vertex so no run is cut at the start.
    let start = if line.closed {
        ok.iter().position(|&b| !b).unwrap_or(0)
    } else {
        0
    };
    let count = if line.closed { n + 1 } else { n };
    let mut out = Vec::new();
    let mut run: Vec<V3> = Vec::new();
    for m in 0..count {
        let j = (start + m) % n.max(1);
        if ok[j] {
            run.push(line.points[j]);
        } else if !run.is_empty() {
            out.push(std::mem::take(&mut run));
        }
    }
    out.push(run);
    out.into_iter()
        .filter(|r| r.len() >= 2)
        .map(|points| Polyline {
            points,
            closed: false,
        })
        .collect()
}

/// A coarse grid over the features' reach, each cell listing (in order) the features
/// whose support may reach into it: a point consults those few, not every feature.
struct Lookup {
    lo: V3,
    cell: f64,
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
    /// Per cell, the largest slope stretch of its features.
    stretch: Vec<f64>,
}

impl Lookup {
    fn new(features: &[Feature], unit: f64) -> Self {
        let reach: Vec<f64> = features.iter().map(|f| f.support(unit)).collect();
        let [mut lo, mut hi] = bounds(features.iter().flat_map(|f| f.curve.points.iter().copied()));
        let widest = reach.iter().copied().fold(0.0, f64::max);
        lo = lo.map(|c| c - widest);
        hi = hi.map(|c| c + widest);
        // At most 48 cells along the longest side, none smaller than 4 units.
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        let cell = (extent / 48.0).max(4.0 * unit).max(f64::MIN_POSITIVE);
        let dims = [0, 1, 2].map(|a| (((hi[a] - lo[a]) / cell).floor() as usize + 1).max(1));
        let mut cells = vec![
            Vec::new();
            if features.is_empty() {
                0
            } else {
                dims.iter().product()
            }
        ];
        let coord = |x: f64, a: usize| {
            ((x - lo[a]) / cell)
                .floor()
                .clamp(0.0, (dims[a] - 1) as f64) as usize
        };
        for (i, f) in features.iter().enumerate() {
            // Samples at most half a cell apart: a point within reach of the curve is
            // within reach plus a quarter cell of one of them.
            let r = reach[i] + 0.25 * cell;
            let mut since = f64::INFINITY;
            let points = &f.curve.points;
            for (j, &p) in points.iter().enumerate() {
                if j > 0 {
                    since += norm(sub(p, points[j - 1]));
                }
                if since < 0.5 * cell && j + 1 < points.len() {
                    continue;
                }
                since = 0.0;
                let [x0, y0, z0] = [0, 1, 2].map(|a| coord(p[a] - r, a));
                let [x1, y1, z1] = [0, 1, 2].map(|a| coord(p[a] + r, a));
                for z in z0..=z1 {
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let list = &mut cells[(z * dims[1] + y) * dims[0] + x];
                            if list.last() != Some(&(i as u32)) {
                                list.push(i as u32);
                            }
                        }
                    }
                }
            }
        }
        let stretch = cells
            .iter()
            .map(|list| {
                list.iter()
                    .map(|&i| features[i as usize].profile.max_steepness())
                    .fold(0.0, f64::max)
                    .hypot(1.0)
            })
            .collect();
        Self {
            lo,
            cell,
            dims,
            cells,
            stretch,
        }
    }

    /// The index of the cell holding `p`, if any.
    fn index(&self, p: V3) -> Option<usize> {
        let mut index = 0;
        for a in (0..3).rev() {
            let c = ((p[a] - self.lo[a]) / self.cell).floor();
            if !(c >= 0.0 && c < self.dims[a] as f64) {
                return None;
            }
            index = index * self.dims[a] + c as usize;
        }
        (index < self.cells.len()).then_some(index)
    }

    /// The features that may reach `p`.
    fn get(&self, p: V3) -> &[u32] {
        self.index(p).map_or(&[], |i| self.cells[i].as_slice())
    }
}

/// A closed parameter polygon with its edges bucketed into bands of `v`: an even-odd
/// inside test that crosses the few edges of the point's band only.
struct Polygon {
    points: Vec<P2>,
    lo: P2,
    hi: P2,
    band: f64,
    bands: Vec<Vec<u32>>,
}

impl Polygon {
    fn new(points: &[P2]) -> Self {
        let [lo, hi] = bounds(points.iter().map(|&[u, v]| [u, v, 0.0]));
        let (lo, hi) = ([lo[0], lo[1]], [hi[0], hi[1]]);
        let count = (points.len() / 8).max(1);
        let band = ((hi[1] - lo[1]) / count as f64).max(f64::MIN_POSITIVE);
        let index = |v: f64| (((v - lo[1]) / band) as usize).min(count - 1);
        let mut bands = vec![Vec::new(); count];
        let n = points.len();
        for i in 0..n {
            let (a, b) = (points[i][1], points[(i + 1) % n][1]);
            for slot in &mut bands[index(a.min(b))..=index(a.max(b))] {
                slot.push(i as u32);
            }
        }
        Self {
            points: points.to_vec(),
            lo,
            hi,
            band,
            bands,
        }
    }

    fn contains(&self, p: P2) -> bool {
        if p[0] < self.lo[0] || p[0] > self.hi[0] || p[1] < self.lo[1] || p[1] > self.hi[1] {
            return false;
        }
        let k = (((p[1] - self.lo[1]) / self.band) as usize).min(self.bands.len() - 1);
        let n = self.points.len();
        let mut inside = false;
        for &i in &self.bands[k] {
            let (a, b) = (self.points[i as usize], self.points[(i as usize + 1) % n]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::perturb::median_spacing;
    use rand::SeedableRng;

    /// A straight curve from `from` to `to` in the parameter domain, lifted onto `base`.
    fn straight(base: &Base, from: P2, to: P2, side: Side) -> Curve {
        let n = 400;
        let uv: Vec<P2> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .collect();
        let points = uv.iter().map(|&q| base.frame(q).0).collect();
        Curve {
            uv,
            points,
            closed: false,
            side,
        }
    }

    /// The points of `relief` at the parameters `((i + 1/2) a, (j + 1/2) a)` of an `n x m`
    /// grid offset by `lo`.
    fn grid(relief: &Relief, lo: P2, n: usize, m: usize, a: f64) -> Vec<V3> {
        (0..n * m)
            .map(|k| {
                let (i, j) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
                relief.point([lo[0] + i * a, lo[1] + j * a])
            })
            .collect()
    }

    /// Distance from `p` to the line parallel to y through `(x, 0, z)`.
    fn to_line(p: V3, [x, z]: [f64; 2]) -> f64 {
        (p[0] - x).hypot(p[2] - z)
    }

    /// A plane sheet `[0, 24] x [0, 10]` with a V groove along v at u = 10.3 (running 5
    /// beyond both borders), `half_width` 2 and depth 2: walls at 45 degrees.
    fn plane_groove(depth: f64, half_width: f64) -> Relief {
        let base = Base::HeightField {
            size: [24.0, 10.0],
            terms: Vec::new(),
        };
        let curve = straight(&base, [10.3, -5.0], [10.3, 15.0], Side::Either);
        let profile = Profile::V {
            half_width,
            depth: -depth,
        };
        Relief::new(base, vec![Feature { profile, curve }], 1.0)
    }

    /// The kink lines lying along the curve (not round its end caps: their points all
    /// share one x), with their deviations over `0 <= y <= 10` (away from the ends, where
    /// the profile turns round the curve's end).
    fn straight_deviations(lines: &[KinkLine]) -> Vec<(f64, Vec<f64>)> {
        lines
            .iter()
            .filter(|l| {
                l.points
                    .iter()
                    .all(|p| (p[0] - l.points[0][0]).abs() < 1e-9)
            })
            .map(|l| {
                let inside = l
                    .points
                    .iter()
                    .zip(&l.deviation)
                    .filter(|(p, _)| (0.0..=10.0).contains(&p[1]));
                (l.points[0][0], inside.map(|(_, d)| *d).collect())
            })
            .collect()
    }

    #[test]
    fn v_groove_on_a_plane_has_the_hand_computed_kinks_and_bands() {
        let relief = plane_groove(2.0, 2.0);
        let lines = relief.kink_lines();
        // Bottom at u = 10.3 deviates by 2 atan(D / W) = 90 degrees, the rims at 10.3 +- 2
        // by atan(D / W) = 45.
        let straight = straight_deviations(&lines);
        assert_eq!(straight.len(), 3);
        for (u, deviation) in straight {
            let want = if (u - 10.3).abs() < 1e-9 { 90.0 } else { 45.0 };
            assert!(
                (u - 10.3).abs() < 1e-9 || ((u - 10.3).abs() - 2.0).abs() < 1e-9,
                "{u}"
            );
            assert!(
                deviation.iter().all(|d| (d - want).abs() < 1e-6),
                "{u} {deviation:?}"
            );
        }
        // The bottom line lies at depth 2, the rims on the plane.
        for l in &lines {
            for p in l.points.iter().filter(|p| (0.0..=10.0).contains(&p[1])) {
                let t = (p[0] - 10.3).abs();
                let want = if t < 2.0 { -2.0 * (1.0 - t / 2.0) } else { 0.0 };
                assert!((p[2] - want).abs() < 1e-9, "{p:?}");
            }
        }
        let points = grid(&relief, [0.0, 0.0], 24, 10, 1.0);
        let spacing = median_spacing(&points, 1.0);
        assert!((spacing - 1.0).abs() < 1e-12, "{spacing}");
        let border = relief.border();
        for band in [0.5, 1.0, 1.5, 2.0] {
            let rule = LabelRule {
                band,
                ..LabelRule::default()
            };
            let labels = relief.labels(&points, spacing, &rule, &lines, border.as_ref());
            for (p, c) in points.iter().zip(&labels) {
                let d = [[10.3, -2.0], [8.3, 0.0], [12.3, 0.0]]
                    .map(|l| to_line(*p, l))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                let edge = p[0].min(24.0 - p[0]).min(p[1]).min(10.0 - p[1]);
                let want = if d < band {
                    Class::Sharp
                } else if edge < crate::synth::W_BORDER {
                    Class::Boundary
                } else {
                    Class::NonEdge
                };
                assert_eq!(*c, want, "band {band} at {p:?}: {d}");
            }
            // By hand: the columns at u - 10.3 = -3.8, -2.8, .., 3.2 lie 1.8, 0.8, 0.28,
            // 1.13, 0.28, 1.13, 0.2, 1.2 from the nearest kink line (on the 45-degree walls
            // sqrt 2 times their distance across).
            let columns = labels.iter().filter(|&&c| c == Class::Sharp).count() / 10;
            let want = match band {
                0.5 => 3,
                1.0 => 4,
                1.5 => 7,
                _ => 8,
            };
            assert_eq!(columns, want, "band {band}");
        }
    }

    #[test]
    fn v_groove_on_a_cylinder_has_the_hand_computed_kinks_and_bands() {
        // A trough of radius 10 (axis at z = 10 along y), groove along its bottom line.
        let (r, w, d) = (10.0_f64, 2.0_f64, 1.0_f64);
        let base = Base::Bent {
            radius: r,
            size: [20.0, 10.0],
        };
        let curve = straight(&base, [0.0, -5.0], [0.0, 15.0], Side::Either);
        let profile = Profile::V {
            half_width: w,
            depth: -d,
        };
        let relief = Relief::new(base, vec![Feature { profile, curve }], 1.0);
        // The section's distance from the axis is r(t) = R + D (1 - 2 R sin(|t|/2) / W)
        // (s is the chord to the bottom line): the normal tilts from the radius by
        // atan(|r'| / r), at the bottom atan(D R / (W (R + D))) either way, at the rims
        // (t = 2 asin(W / 2R)) atan(D cos(t / 2) / W).
        let rim_t = 2.0 * (w / (2.0 * r)).asin();
        let bottom = 2.0 * (d * r / (w * (r + d))).atan().to_degrees();
        let rim = (d * (rim_t / 2.0).cos() / w).atan().to_degrees();
        let lines = relief.kink_lines();
        let straight = straight_deviations(&lines);
        assert_eq!(straight.len(), 3);
        let mut seen = [0; 2];
        for (x, deviation) in straight {
            let at_bottom = x.abs() < 1e-9;
            seen[usize::from(at_bottom)] += 1;
            let want = if at_bottom { bottom } else { rim };
            // Within the base's turn between the two one-sided normals.
            assert!(
                deviation.iter().all(|d| (d - want).abs() < 1e-4),
                "{x}: {want}"
            );
        }
        assert_eq!(seen, [2, 1]);
        let axis = |t: f64, radius: f64| [radius * t.sin(), r - radius * t.cos()];
        let kinks = [axis(0.0, r + d), axis(rim_t, r), axis(-rim_t, r)];
        let points = grid(&relief, [-10.0, 0.0], 20, 10, 1.0);
        let spacing = median_spacing(&points, 1.0);
        // Neighbours along the section are chords of the unit arc.
        assert!(
            (spacing - 2.0 * r * (0.5 / r).sin()).abs() < 1e-12,
            "{spacing}"
        );
        for band in [0.5, 1.5] {
            let rule = LabelRule {
                band,
                ..LabelRule::default()
            };
            let labels = relief.labels(&points, spacing, &rule, &lines, None);
            let mut sharp = 0;
            for (p, c) in points.iter().zip(&labels) {
                let dist = kinks
                    .map(|k| to_line(*p, k))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                assert!((dist - band * spacing).abs() > 1e-3, "a tie at {p:?}");
                assert_eq!(*c == Class::Sharp, dist < band * spacing, "{p:?}: {dist}");
                sharp += usize::from(*c == Class::Sharp);
            }
            assert!(sharp >= 20, "band {band}: {sharp}");
        }
    }

    /// A plane sheet `[0, 20] x [0, 8]` with a step across it at u = 8.4: from 0 it rises
    /// to `height` over `width`, on the side of growing u.
    fn plane_step(width: f64, height: f64) -> Relief {
        let base = Base::HeightField {
            size: [20.0, 8.0],
            terms: Vec::new(),
        };
        let graph = Graph {
            transposed: true,
            centre: 4.0,
            offset: 8.4,
            slope: 0.0,
            waves: Vec::new(),
        };
        // Transposed graphs run towards falling v.
        let curve = straight(&base, [8.4, 12.0], [8.4, -4.0], Side::Graph(graph));
        let profile = Profile::Ramp { width, height };
        Relief::new(base, vec![Feature { profile, curve }], 1.0)
    }

    #[test]
    fn step_edges_are_sharp_when_the_slope_change_passes_the_threshold() {
        let relief = plane_step(1.0, 1.0);
        let points = grid(&relief, [0.0, 0.0], 20, 8, 1.0);
        // The ramp rises along u: flat at 0 before it, at 1 after it.
        for p in &points {
            let want = ((p[0] - 8.4) / 1.0).clamp(0.0, 1.0);
            assert!((p[2] - want).abs() < 1e-12, "{p:?}");
        }
        let lines = relief.kink_lines();
        // Both edges (u = 8.4 at height 0, u = 9.4 at height 1) deviate by atan(1) = 45.
        let straight = straight_deviations(&lines);
        assert_eq!((lines.len(), straight.len()), (2, 2));
        for (_, deviation) in straight {
            assert!(deviation.len() > 100 && deviation.iter().all(|d| (d - 45.0).abs() < 1e-6));
        }
        let spacing = median_spacing(&points, 1.0);
        assert!((spacing - 1.0).abs() < 1e-12);
        let edges = [[8.4, 0.0], [9.4, 1.0]];
        let sharp = |rule: &LabelRule| {
            let labels = relief.labels(&points, spacing, rule, &lines, None);
            for (p, c) in points.iter().zip(&labels) {
                let d = edges
                    .map(|e| to_line(*p, e))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                let within = d < rule.band * spacing;
                assert!(*c != Class::Sharp || within, "{p:?}");
            }
            labels.iter().filter(|&&c| c == Class::Sharp).count()
        };
        // Band 1: the columns at u = 7.5 (0.9 from the foot), 8.5 (on the ramp, 0.14
        // from the foot) and 9.5 (0.1 from the top edge): 3 columns of 8 points.
        assert_eq!(sharp(&LabelRule::default()), 3 * 8);
        // 45 degrees is below a threshold of 50: nothing is sharp.
        let strict = LabelRule {
            min_angle: 50.0,
            ..LabelRule::default()
        };
        assert_eq!(sharp(&strict), 0);
        // A wide ramp, half a spacing high over 6: atan(1 / 12) = 4.8 degrees, not sharp
        // at the default 10 though it is deeper than min_depth.
        let gentle = plane_step(6.0, 0.5);
        let lines = gentle.kink_lines();
        let want = (1.0f64 / 12.0).atan().to_degrees();
        for (_, deviation) in straight_deviations(&lines) {
            assert!(deviation.iter().all(|d| (d - want).abs() < 1e-6));
        }
        let points = grid(&gentle, [0.0, 0.0], 20, 8, 1.0);
        let labels = gentle.labels(&points, 1.0, &LabelRule::default(), &lines, None);
        assert!(labels.iter().all(|&c| c == Class::NonEdge));
    }

    #[test]
    fn a_groove_shallower_than_min_depth_is_not_sharp() {
        // Half-width 0.5, depth 0.2: rims at atan(0.4) = 21.8 degrees, bottom 43.6, but
        // 0.2 spacings deep, below the default 0.25.
        let relief = plane_groove(0.2, 0.5);
        let lines = relief.kink_lines();
        let points = grid(&relief, [0.0, 0.0], 24, 10, 1.0);
        let spacing = median_spacing(&points, 1.0);
        let count = |rule: &LabelRule| {
            let labels = relief.labels(&points, spacing, rule, &lines, None);
            labels.iter().filter(|&&c| c == Class::Sharp).count()
        };
        assert_eq!(count(&LabelRule::default()), 0);
        let lenient = LabelRule {
            min_depth: 0.1,
            ..LabelRule::default()
        };
        // The columns at u - 10.3 = -0.8, 0.2 and 1.2 lie 0.3, 0.22 and 0.7 from a kink
        // line, within 1; those at -1.8 and 2.2 1.3 and 1.7.
        assert_eq!(count(&lenient), 3 * 10);
        // Relative to the noise: 0.2 spacings deep is at least 2 x 0.05 and 2 x 0.1, not
        // 2 x 0.15.
        let per_noise = LabelRule {
            min_depth_per_noise: 2.0,
            ..lenient
        };
        assert_eq!(count(&per_noise.at_noise(0.0)), 3 * 10);
        assert_eq!(count(&per_noise.at_noise(0.05)), 3 * 10);
        assert_eq!(count(&per_noise.at_noise(0.1)), 3 * 10);
        assert_eq!(count(&per_noise.at_noise(0.15)), 0);
        assert_eq!(per_noise.at_noise(0.15).min_depth, 2.0 * 0.15);
    }

    #[test]
    fn profiles_kink_where_their_slope_jumps() {
        let (w, d) = (2.0, 1.0);
        for profile in [
            Profile::V {
                half_width: w,
                depth: d,
            },
            Profile::Trapezoid {
                half_width: w,
                flat: 0.5,
                depth: d,
            },
            Profile::Round {
                half_width: w,
                depth: d,
            },
            Profile::Smooth {
                half_width: w,
                depth: d,
            },
            Profile::Ramp {
                width: w,
                height: d,
            },
            Profile::SmoothRamp {
                width: w,
                height: d,
            },
        ] {
            let h = 1e-7;
            let slope = |s: f64| (profile.value(s + h) - profile.value(s - h)) / (2.0 * h);
            let kinks = profile.kinks();
            for i in -300..=300 {
                let s = f64::from(i) * 0.01 + 0.003;
                let near_kink = kinks.iter().any(|k| (s - k).abs() < 1e-3);
                if !near_kink {
                    assert!(
                        (slope(s).abs() - profile.steepness(s)).abs() < 1e-5,
                        "{profile:?} {s}"
                    );
                    assert!(profile.steepness(s) <= profile.max_steepness() + 1e-12);
                }
            }
            for &k in &kinks {
                let jump = (slope(k + 1e-4) - slope(k - 1e-4)).abs();
                assert!(jump > 0.1, "{profile:?} at {k}: {jump}");
            }
            assert_eq!(
                profile.value(10.0 * w),
                if profile.one_sided() { d } else { 0.0 }
            );
            assert_eq!(profile.value(-10.0 * w), 0.0);
        }
    }

    #[test]
    fn label_rules_out_of_range_are_refused() {
        assert!(LabelRule::default().validate().is_ok());
        for (rule, what) in [
            (
                LabelRule {
                    min_angle: 180.0,
                    ..LabelRule::default()
                },
                "min_angle",
            ),
            (
                LabelRule {
                    min_depth_per_noise: -1.0,
                    ..LabelRule::default()
                },
                "min_depth_per_noise",
            ),
            (
                LabelRule {
                    min_angle: f64::NAN,
                    ..LabelRule::default()
                },
                "min_angle",
            ),
            (
                LabelRule {
                    min_depth: -0.1,
                    ..LabelRule::default()
                },
                "min_depth",
            ),
            (
                LabelRule {
                    band: 0.0,
                    ..LabelRule::default()
                },
                "band",
            ),
            (
                LabelRule {
                    band: f64::INFINITY,
                    ..LabelRule::default()
                },
                "band",
            ),
        ] {
            let e = rule.validate().unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        }
    }

    #[test]
    fn steps_are_told_apart_alike_near_and_far_from_their_curves() {
        // Where a step's curve is within reach, its side comes from the nearest segment;
        // beyond, from the inside or graph test: both must agree where they meet.
        let (unit, mut checked) = (0.02, 0);
        for (k, base) in crate::synth::BaseKind::ALL.into_iter().enumerate() {
            for seed in 0..3 {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 * k as u64 + seed);
                let relief = crate::synth::freeform::random_relief(
                    Base::random(base, &mut rng),
                    unit,
                    1.0,
                    &mut rng,
                );
                for (i, f) in relief.features.iter().enumerate() {
                    if !f.profile.one_sided() {
                        continue;
                    }
                    let r = f.support(unit);
                    let (points, uvs) = (&f.curve.points, &f.curve.uv);
                    for j in (0..points.len()).step_by(7) {
                        let n = relief.base.frame(uvs[j]).1;
                        let next = points[(j + 1).min(points.len() - 1)];
                        let prev = points[j.saturating_sub(1)];
                        let b = normalize(cross(n, sub(next, prev)));
                        for side in [-1.0, 1.0] {
                            let uv = relief
                                .base
                                .project(add(points[j], scale(b, side * 0.9 * r)));
                            let (p, n, _) = relief.base.frame(uv);
                            let Some(s) = relief.signed_distance(i, p, n, 1.0) else {
                                continue;
                            };
                            if s.abs() < 0.8 * r {
                                continue;
                            }
                            assert_eq!(relief.left_far(i, uv), s > 0.0, "{base:?} {seed} {i}");
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }
}
