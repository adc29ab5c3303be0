//! The synthetic labelled training-set generator.
//!
//! Every shape is a triangle mesh whose feature edges come from its geometry: an edge used
//! by one triangle is a border (boundary class), an edge whose faces deviate from flat by
//! more than 10 degrees is a sharp crease. Finely tessellated smooth parts (cylinders,
//! spheres, tori, fillets) stay non-edge. Shapes get a random rotation, scale and
//! anisotropic stretch of up to 1.25 per axis before their features are extracted, then are
//! sampled in one of two [`Sampling`] modes (see there for the label rules), and perturbed by
//! Gaussian noise (a multiple of the median nearest-neighbour spacing, in every coordinate or
//! along the surface normal only; labels stay those of the clean points) and a few outliers
//! (non-edge). With [`SetConfig::face_spacing`] above 1 (spec option `faces=F`), mesh-vertex
//! shapes fill their planar faces more sparsely than their crease rows, as SPEC.md describes
//! the ABC clouds. With [`SetConfig::band`] (spec option `band=B`), every point within `B`
//! spacings of a crease is sharp: the band convention of the free-form kind, for a model
//! meant to call bands rather than one row. With [`SetConfig::thinning`] (spec options
//! `sparse=F` and `dense=R`), the points farther than `R` spacings from every crease are
//! thinned to the share `F`: a density step, as a CAD triangulation's vertices crowd along
//! its creases. With [`SetConfig::row_spacing`] above 1 (spec option `rows=R`), the crease
//! and border rows are spread along their lines, as the ABC clouds' are.
//!
//! The free-form kind ([`SetKind::Freeform`], see [`generate_freeform`]) is built
//! differently: smooth parametric bases (height fields, bent and twisted sheets, shells)
//! displaced along their normal by groove, ridge and step profiles swept along curves, so
//! the kinks are known exactly; it is labelled by a [`LabelRule`] (kinks of at least 10
//! degrees on features at least a quarter spacing deep, in a band of 1 spacing either
//! side by default) and sampled at random, as blue noise or in scan lines.
//!
//! Generation is deterministic: shape `i` of a set draws from its own ChaCha8 stream of the
//! set's seed, so the same configuration gives the same clouds bit for bit, in parallel or
//! not, and a set can be extended without changing its first shapes.
//!
//! ```
//! use bounded_data::synth::{SetConfig, SetKind, generate};
//! use bounded_geom::Class;
//!
//! let mut config = SetConfig::new(SetKind::Cad, 42, 2);
//! config.points = 1500..=2000;
//! let set = generate(&config).unwrap();
//! assert_eq!(set.len(), 2);
//! assert_eq!(set, generate(&config).unwrap());
//! let (name, cloud) = &set[0];
//! assert!(name.starts_with("cad_000000_"));
//! assert_eq!(cloud.labels.len(), cloud.cloud.len());
//! ```

mod freeform;
mod grid;
mod mesh;
mod perturb;
mod polyhedron;
mod profile;
pub mod recipe;
mod relief;
mod sample;
mod scan;
mod scene;
mod segments;
mod shapes;

pub use freeform::{BaseKind, FreeformSpec, generate_freeform};
pub use perturb::NoiseDirection;
pub use relief::LabelRule;
pub use sample::{Sampling, W_BORDER, W_SHARP};
pub use scan::FreeformSampling;
pub use scene::{DEMO_SHAPES, demo_scene};
pub use shapes::ShapeKind;

use crate::{DataError, LabelledCloud};
use bounded_geom::PointCloud;
use bounded_geom::vec3::{self, V3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use relief::check_band;
use std::ops::RangeInclusive;

/// The most shapes a set may have: its clouds are held in memory together.
pub const MAX_SHAPES: usize = 10_000;

/// The flavour of a generated set: which shapes and which sampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SetKind {
    /// ABC-like: mostly closed CAD shapes, mesh-vertex sampling.
    Cad,
    /// Default-like: the CAD shapes plus folded sheets, uniform random sampling.
    Random,
    /// Boundary-rich: mostly open sheets, tubes, bowls, open boxes and thin plates, both
    /// samplings.
    Boundary,
    /// Every shape equally often, both samplings.
    Mixed,
    /// Free-form surfaces (height fields, bent and twisted sheets, shells) carrying
    /// grooves, ridges, steps and reliefs along curves, labelled by a [`LabelRule`];
    /// random, blue-noise and scan-line sampling (see [`generate_freeform`]).
    Freeform,
}

impl SetKind {
    /// Lower-case name, the prefix of generated cloud names.
    pub fn name(self) -> &'static str {
        match self {
            SetKind::Cad => "cad",
            SetKind::Random => "random",
            SetKind::Boundary => "boundary",
            SetKind::Mixed => "mixed",
            SetKind::Freeform => "freeform",
        }
    }

    /// Relative frequency of `shape` in this set, whose shallow ridges weigh `shallow`
    /// ([`SetConfig::shallow`]).
    fn weight(self, shape: ShapeKind, shallow: f64) -> f64 {
        use ShapeKind as S;
        let cad = match shape {
            S::FractalCube => 3.0,
            S::Box | S::Stairs | S::Prism | S::Lathe | S::RoundedPrism | S::CutBlock => 2.0,
            S::Turned | S::Ribbed => 2.0,
            S::Wedge | S::Notch | S::Frustum | S::Cup => 1.5,
            S::Cylinder => 1.0,
            S::Cone | S::Sphere | S::Torus => 0.7,
            S::FoldedSheet | S::OpenBox => 0.5,
            S::Disc | S::PolygonSheet | S::Tube | S::Bowl | S::ThinPlate => 0.3,
            // In every kind, only as the set asks for them.
            S::ShallowRidges => return shallow,
        };
        match self {
            SetKind::Cad => cad,
            SetKind::Random if shape == S::FoldedSheet => 2.0,
            SetKind::Random => cad,
            SetKind::Boundary if shape.is_open() => 2.0,
            SetKind::Boundary => 0.4,
            SetKind::Mixed => 1.0,
            // Free-form sets hold no mesh shapes (see `SetConfig::spec`).
            SetKind::Freeform => 0.0,
        }
    }

    fn sampling(self, rng: &mut impl Rng) -> Sampling {
        match self {
            SetKind::Cad => Sampling::MeshVertex,
            SetKind::Random => Sampling::Random,
            SetKind::Boundary | SetKind::Mixed if rng.random_bool(0.5) => Sampling::MeshVertex,
            SetKind::Boundary | SetKind::Mixed | SetKind::Freeform => Sampling::Random,
        }
    }
}

impl Sampling {
    /// Short name, used in generated cloud names.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::MeshVertex => "mesh",
            Sampling::Random => "random",
        }
    }
}

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct SetConfig {
    /// The flavour of the set.
    pub kind: SetKind,
    /// Seed of the whole set.
    pub seed: u64,
    /// Number of clouds.
    pub shapes: usize,
    /// Points per cloud, drawn uniformly per shape (mesh-vertex mode reaches it within ~20%).
    pub points: RangeInclusive<usize>,
    /// Noise levels, each shape picking one uniformly: the standard deviation (per coordinate,
    /// or along the normal; see `noise_direction`) as a multiple of the cloud's median
    /// nearest-neighbour spacing.
    pub noise_levels: Vec<f64>,
    /// Which way the noise displaces points.
    pub noise_direction: NoiseDirection,
    /// Fraction of outliers added to the 30% of shapes that get any.
    pub outlier_fraction: f64,
    /// The labels of the free-form kind (the mesh kinds keep theirs: see [`Sampling`]).
    pub label_rule: LabelRule,
    /// The sparsest fill of planar faces in mesh-vertex mode, in multiples of the crease
    /// rows' spacing: each such shape draws its [`ShapeSpec::face_spacing`] uniformly from 1
    /// to this (at most [`MAX_FACE_SPACING`]; 1, the default, fills every face alike).
    pub face_spacing: f64,
    /// The sparsest crease and border rows in mesh-vertex mode, in multiples of their usual
    /// step along the line: each such shape draws its [`ShapeSpec::row_spacing`] uniformly
    /// from 1 to this (at most [`MAX_ROW_SPACING`]; 1, the default, leaves the rows as they
    /// were). The ABC clouds' sharp rows are 1.25-1.44 median spacings apart along their
    /// creases, the default rows 0.8-1.1; `rows=1.5` puts them 1.0-1.6 apart (docs/model.md).
    pub row_spacing: f64,
    /// The weight of [`ShapeKind::ShallowRidges`] among the mesh kinds' shapes, whose weights
    /// sum to about 30 in the CAD sets (0, the default, draws none and leaves every other
    /// draw of a set as it was; 30 makes about half the shapes shallow ridges).
    pub shallow: f64,
    /// The mesh kinds' sharp band ([`ShapeSpec::band`]): `None`, the default, labels one row.
    pub band: Option<f64>,
    /// The free-form kind's [`FreeformSpec::feature_size`] (1, the default, draws as before).
    pub feature_size: f64,
    /// The mesh kinds' [`ShapeSpec::thinning`]: `None`, the default, thins nothing.
    pub thinning: Option<Thinning>,
}

/// Points farther than `radius` spacings from every crease are kept with probability
/// `keep`; the rest all stay. The draws come from a stream of the shape's seed that nothing
/// else draws from, so a thinned cloud (before noise) is a subset of the unthinned one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thinning {
    /// Half-width of the dense band around every crease, in units of the cloud's median
    /// nearest-neighbour spacing before thinning (spec option `dense=`, 2 by default).
    pub radius: f64,
    /// The share of the other points kept (spec option `sparse=`, 0 to 1; 1 keeps all).
    pub keep: f64,
}

impl Default for Thinning {
    /// Dense within 2 spacings, nothing thinned: a set asks for `sparse=`.
    fn default() -> Self {
        Self {
            radius: 2.0,
            keep: 1.0,
        }
    }
}

impl Thinning {
    /// The radius must lie in `0..=MAX_DENSE_RADIUS`, the share kept in `(0, 1]`.
    fn validate(&self) -> Result<(), DataError> {
        check_within(self.radius, 0.0..=MAX_DENSE_RADIUS, || {
            format!(
                "dense band {}: a multiple of the point spacing, 0 to {MAX_DENSE_RADIUS}",
                self.radius
            )
        })?;
        check_within(self.keep, f64::MIN_POSITIVE..=1.0, || {
            format!(
                "sparse share {}: the share of points kept, above 0 and at most 1",
                self.keep
            )
        })
    }
}

/// The widest [`Thinning::radius`]: a band that wide covers most of a cloud of the default
/// size, so nothing is left to thin.
pub const MAX_DENSE_RADIUS: f64 = 16.0;

/// The largest [`SetConfig::shallow`]: a set of nothing but shallow ridges teaches nothing
/// of the other creases.
pub const MAX_SHALLOW: f64 = 1000.0;

/// The largest [`SetConfig::feature_size`]: features 8 times the default's are up to about 100
/// spacings wide (steps 160), and too few of them fit on a cloud of the default size.
pub const MAX_FEATURE_SIZE: f64 = 8.0;

/// The largest [`SetConfig::row_spacing`]: rows twice their usual step apart are barely
/// rows, the faces' points as close to the crease as its own.
pub const MAX_ROW_SPACING: f64 = 2.0;

/// The largest [`SetConfig::face_spacing`]: sparser planes hold almost no points between
/// their crease rows.
pub const MAX_FACE_SPACING: f64 = 8.0;

impl SetConfig {
    /// A configuration with the defaults: 5,000..30,000 points, noise levels 0, 0.1, 0.2,
    /// 0.4 and 0.6 x spacing in every coordinate, 0.2% outliers. (The noisy ABC clouds are
    /// displaced along the normal only, sigma about 0.5 x spacing, as
    /// [`NoiseDirection::Normal`] does; training with such noise did not close their gap.)
    pub fn new(kind: SetKind, seed: u64, shapes: usize) -> Self {
        Self {
            kind,
            seed,
            shapes,
            points: 5_000..=30_000,
            noise_levels: vec![0.0, 0.1, 0.2, 0.4, 0.6],
            noise_direction: NoiseDirection::Isotropic,
            outlier_fraction: 0.002,
            label_rule: LabelRule::default(),
            face_spacing: 1.0,
            row_spacing: 1.0,
            shallow: 0.0,
            band: None,
            feature_size: 1.0,
            thinning: None,
        }
    }

    /// Checks the noise levels, the outlier fraction and the label rule; [`generate`]
    /// does, so a caller writing files can check before creating any.
    pub fn validate(&self) -> Result<(), DataError> {
        if self.shapes > MAX_SHAPES {
            return Err(DataError::Generator {
                what: format!(
                    "{} shapes are more than the {MAX_SHAPES} a set may have (about 2 x 10^8 \
                     points, held in memory together)",
                    self.shapes
                ),
            });
        }
        self.noise_levels.iter().try_for_each(|&l| check_noise(l))?;
        check_outlier_fraction(self.outlier_fraction)?;
        check_face_spacing(self.face_spacing)?;
        check_row_spacing(self.row_spacing)?;
        check_feature_size(self.feature_size)?;
        self.band.map_or(Ok(()), check_band)?;
        self.thinning.as_ref().map_or(Ok(()), Thinning::validate)?;
        check_within(self.shallow, 0.0..=MAX_SHALLOW, || {
            format!(
                "shallow ridges' weight {}: 0 to {MAX_SHALLOW} (the other shapes' sum to about 30)",
                self.shallow
            )
        })?;
        self.label_rule.validate()
    }

    /// The parameters of cloud `index`, drawn from the set's seed.
    pub fn spec(&self, index: usize) -> CloudSpec {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index as u64);
        if self.kind == SetKind::Freeform {
            CloudSpec::Freeform(self.freeform_spec(&mut rng))
        } else {
            CloudSpec::Mesh(self.mesh_spec(&mut rng))
        }
    }

    /// A free-form cloud: the base by weight, then its sampling (scan lines on sheets
    /// only), points, noise and outliers.
    fn freeform_spec(&self, rng: &mut ChaCha8Rng) -> FreeformSpec {
        let total: f64 = BaseKind::ALL.iter().map(|b| b.weight()).sum();
        let mut pick = rng.random::<f64>() * total;
        let base = BaseKind::ALL
            .into_iter()
            .find(|b| {
                pick -= b.weight();
                pick < 0.0
            })
            .unwrap_or(BaseKind::HeightField);
        let x = rng.random::<f64>();
        let sampling = if base.is_sheet() && x < 0.4 {
            FreeformSampling::Scan
        } else if x < 0.7 {
            FreeformSampling::BlueNoise
        } else {
            FreeformSampling::Random
        };
        let (points, noise, outlier_fraction) = self.amounts(rng);
        FreeformSpec {
            base,
            sampling,
            points,
            noise,
            noise_direction: self.noise_direction,
            outlier_fraction,
            label_rule: self.label_rule,
            feature_size: self.feature_size,
            seed: rng.random(),
        }
    }

    /// Points, noise level and outlier fraction of one cloud.
    fn amounts(&self, rng: &mut ChaCha8Rng) -> (usize, f64, f64) {
        let (lo, hi) = (*self.points.start(), *self.points.end());
        let points = if lo < hi {
            rng.random_range(lo..=hi)
        } else {
            lo
        };
        let noise = if self.noise_levels.is_empty() {
            0.0
        } else {
            self.noise_levels[rng.random_range(0..self.noise_levels.len())]
        };
        let outlier_fraction = if rng.random_bool(0.3) {
            self.outlier_fraction
        } else {
            0.0
        };
        (points, noise, outlier_fraction)
    }

    /// A mesh shape: the kind by the set's weights, then sampling, points, noise, outliers.
    fn mesh_spec(&self, rng: &mut ChaCha8Rng) -> ShapeSpec {
        let weight = |s: ShapeKind| self.kind.weight(s, self.shallow);
        let total: f64 = ShapeKind::ALL.iter().map(|&s| weight(s)).sum();
        let mut pick = rng.random::<f64>() * total;
        let kind = ShapeKind::ALL
            .into_iter()
            .find(|&s| {
                pick -= weight(s);
                pick < 0.0
            })
            .unwrap_or(ShapeKind::Box);
        let sampling = self.kind.sampling(rng);
        let (points, noise, outlier_fraction) = self.amounts(rng);
        let seed = rng.random();
        // Drawn last, so that sparse faces and rows leave every other draw of the shape as it
        // was.
        let face_spacing = if self.face_spacing > 1.0 {
            rng.random_range(1.0..=self.face_spacing)
        } else {
            1.0
        };
        let row_spacing = if self.row_spacing > 1.0 {
            rng.random_range(1.0..=self.row_spacing)
        } else {
            1.0
        };
        ShapeSpec {
            kind,
            sampling,
            points,
            noise,
            noise_direction: self.noise_direction,
            outlier_fraction,
            seed,
            face_spacing,
            row_spacing,
            band: self.band,
            thinning: self.thinning,
        }
    }

    /// The name of cloud `index`: `<set>_<index>_<shape or base>_<sampling>`.
    pub fn name(&self, index: usize, spec: &CloudSpec) -> String {
        let (shape, sampling) = match spec {
            CloudSpec::Mesh(s) => (s.kind.name(), s.sampling.name()),
            CloudSpec::Freeform(s) => (s.base.name(), s.sampling.name()),
        };
        format!("{}_{index:06}_{shape}_{sampling}", self.kind.name())
    }
}

/// Everything that defines one cloud of a set.
#[derive(Debug, Clone, PartialEq)]
pub enum CloudSpec {
    /// A mesh shape (every kind but the free-form one).
    Mesh(ShapeSpec),
    /// A free-form surface.
    Freeform(FreeformSpec),
}

/// Everything that defines one generated cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeSpec {
    /// The shape.
    pub kind: ShapeKind,
    /// How it is sampled.
    pub sampling: Sampling,
    /// About how many points (exactly, in random mode, before outliers).
    pub points: usize,
    /// Noise standard deviation (per coordinate, or along the normal), as a multiple of the
    /// median spacing.
    pub noise: f64,
    /// Which way the noise displaces points.
    pub noise_direction: NoiseDirection,
    /// Outliers, as a fraction of the points.
    pub outlier_fraction: f64,
    /// Seed of the shape's geometry, pose and sampling.
    pub seed: u64,
    /// In mesh-vertex mode, the minimum distance of the fill on planar faces, in multiples
    /// of the crease rows' and curved faces' (1: the same everywhere).
    pub face_spacing: f64,
    /// In mesh-vertex mode, the step of the crease and border rows along their lines, in
    /// multiples of the usual one (1: 1.0-1.2 times the faces' minimum distance).
    pub row_spacing: f64,
    /// Half-width of the sharp band, in units of the cloud's median nearest-neighbour
    /// spacing (measured on the clean points, as the noise is): every point that close to a
    /// crease is sharp, as the free-form kind's [`LabelRule::band`] labels its kinks, so that
    /// a model can be trained for bands on every kind. `None` keeps one row (see
    /// [`Sampling`]), which is about `band` 0.66 in random mode.
    pub band: Option<f64>,
    /// Sparse away from the creases (see [`Thinning`]); `None` thins nothing.
    pub thinning: Option<Thinning>,
}

/// Generates a whole set in parallel, in index order.
pub fn generate(config: &SetConfig) -> Result<Vec<(String, LabelledCloud)>, DataError> {
    config.validate()?;
    (0..config.shapes)
        .into_par_iter()
        .map(|i| generate_one(config, i))
        .collect()
}

/// Generates shape `index` of a set, with its name.
pub fn generate_one(
    config: &SetConfig,
    index: usize,
) -> Result<(String, LabelledCloud), DataError> {
    let spec = config.spec(index);
    let name = config.name(index, &spec);
    let cloud = match &spec {
        CloudSpec::Mesh(s) => generate_shape(s),
        CloudSpec::Freeform(s) => generate_freeform(s),
    };
    let cloud = cloud.map_err(|e| match e {
        DataError::Geom { source, .. } => DataError::Geom {
            path: name.clone().into(),
            source,
        },
        other => other,
    })?;
    Ok((name, cloud))
}

/// Generates one labelled cloud.
///
/// Fails when `spec.points` is 0 (an empty cloud) or its noise, face spacing, band,
/// thinning or outlier fraction is out of range (see [`SetConfig::validate`]).
pub fn generate_shape(spec: &ShapeSpec) -> Result<LabelledCloud, DataError> {
    check_noise(spec.noise)?;
    check_face_spacing(spec.face_spacing)?;
    check_row_spacing(spec.row_spacing)?;
    spec.band.map_or(Ok(()), check_band)?;
    spec.thinning.as_ref().map_or(Ok(()), Thinning::validate)?;
    check_outlier_fraction(spec.outlier_fraction)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut mesh = spec.kind.build(&mut rng);
    let pose = Pose::random(&mut rng, 1.25);
    mesh.map(|p| pose.apply(p));
    let mesh = mesh.welded();
    let features = mesh.features();
    let mut sampled = sample::sample(
        &mesh,
        &features,
        spec.sampling,
        spec.points,
        spec.face_spacing,
        spec.row_spacing,
        &mut rng,
    );
    let spacing = perturb::median_spacing(&sampled.points, sampled.spacing_hint);
    if let Some(band) = spec.band {
        sample::widen_sharp(&mut sampled, &features.sharp, band * spacing);
    }
    if let Some(thinning) = spec.thinning.filter(|t| t.keep < 1.0) {
        let mut own = ChaCha8Rng::seed_from_u64(spec.seed);
        own.set_stream(1);
        let radius = thinning.radius * spacing;
        sample::thin_away_from(
            &mut sampled,
            &features.sharp,
            radius,
            thinning.keep,
            &mut own,
        );
    }
    let sigma = spec.noise * spacing;
    match spec.noise_direction {
        NoiseDirection::Isotropic => perturb::add_noise(&mut sampled.points, sigma, &mut rng),
        NoiseDirection::Normal => {
            perturb::add_normal_noise(&mesh, &mut sampled.points, sigma, &mut rng)
        }
    }
    let outliers = (spec.outlier_fraction * sampled.points.len() as f64).round() as usize;
    perturb::add_outliers(
        &mut sampled.points,
        &mut sampled.labels,
        outliers,
        spacing,
        &mut rng,
    );
    let cloud = PointCloud::from_f64(&sampled.points).map_err(|source| DataError::Geom {
        path: spec.kind.name().into(),
        source,
    })?;
    Ok(LabelledCloud {
        cloud,
        labels: sampled.labels,
    })
}

/// A noise level must be finite and 0 or more (a multiple of the spacing).
fn check_noise(level: f64) -> Result<(), DataError> {
    if level.is_finite() && level >= 0.0 {
        return Ok(());
    }
    Err(DataError::Generator {
        what: format!("noise level {level}: a multiple of the point spacing, 0 or more"),
    })
}

/// `Ok` when `value` lies in `range` (a NaN never does), else the generator's error that
/// `what` words.
fn check_within(
    value: f64,
    range: RangeInclusive<f64>,
    what: impl FnOnce() -> String,
) -> Result<(), DataError> {
    if range.contains(&value) {
        return Ok(());
    }
    Err(DataError::Generator { what: what() })
}

/// A face spacing must lie in `1..=MAX_FACE_SPACING`.
fn check_face_spacing(spacing: f64) -> Result<(), DataError> {
    check_within(spacing, 1.0..=MAX_FACE_SPACING, || {
        format!(
            "face spacing {spacing}: a multiple of the crease rows' spacing, 1 to \
             {MAX_FACE_SPACING}"
        )
    })
}

/// A row spacing must lie in `1..=MAX_ROW_SPACING`.
fn check_row_spacing(spacing: f64) -> Result<(), DataError> {
    check_within(spacing, 1.0..=MAX_ROW_SPACING, || {
        format!("row spacing {spacing}: a multiple of the rows' usual step, 1 to {MAX_ROW_SPACING}")
    })
}

/// A feature size must lie in `0.25..=MAX_FEATURE_SIZE`: below a quarter, the largest
/// features are under two spacings wide.
fn check_feature_size(size: f64) -> Result<(), DataError> {
    check_within(size, 0.25..=MAX_FEATURE_SIZE, || {
        format!("feature size {size}: a multiple of the default sizes, 0.25 to {MAX_FEATURE_SIZE}")
    })
}

/// An outlier fraction must lie in 0..=1.
fn check_outlier_fraction(fraction: f64) -> Result<(), DataError> {
    check_within(fraction, 0.0..=1.0, || {
        format!("outlier fraction {fraction}: a fraction of the points, 0 to 1")
    })
}

/// A random similarity plus a mild anisotropic stretch.
pub(crate) struct Pose {
    /// Rotation times stretch times scale, row-major.
    matrix: [V3; 3],
    offset: V3,
}

impl Pose {
    /// A random rotation, scale and offset, each axis stretched by up to `max_stretch`
    /// either way (1: a similarity, which keeps angles and so labels).
    pub(crate) fn random(rng: &mut impl Rng, max_stretch: f64) -> Self {
        // A uniformly random rotation from a Gaussian quaternion.
        let q: [f64; 4] = [(); 4].map(|()| rng.sample(rand_distr::StandardNormal));
        let rotation = bounded_geom::rotation_of_quaternion(q);
        let size = 10f64.powf(rng.random_range(-1.0..1.0));
        let stretch: V3 = [(); 3].map(|()| size * max_stretch.powf(rng.random_range(-1.0..1.0)));
        let matrix = rotation.map(|row| [0, 1, 2].map(|c| row[c] * stretch[c]));
        let offset = [(); 3].map(|()| size * rng.random_range(-10.0..10.0));
        Self { matrix, offset }
    }

    pub(crate) fn apply(&self, p: V3) -> V3 {
        [0, 1, 2].map(|r| vec3::dot(self.matrix[r], p) + self.offset[r])
    }
}

impl SetKind {
    /// Every kind.
    pub const ALL: [SetKind; 5] = [
        SetKind::Cad,
        SetKind::Random,
        SetKind::Boundary,
        SetKind::Mixed,
        SetKind::Freeform,
    ];

    /// The kind called `name` (see [`SetKind::name`]).
    pub fn from_name(name: &str) -> Result<SetKind, DataError> {
        let known = || SetKind::ALL.map(SetKind::name).join(", ");
        (SetKind::ALL.into_iter().find(|k| k.name() == name)).ok_or_else(|| DataError::Generator {
            what: format!("unknown set kind {name:?} ({})", known()),
        })
    }
}

impl SetConfig {
    /// The set of `generated:KIND:SEED[:SHAPES[:OPTION...]]` (60 shapes by default), with
    /// the defaults of [`SetConfig::new`] but for its options (see
    /// [`with_options`](Self::with_options)), for example
    /// `generated:freeform:4:80:depth=1:band=0.5:noise=3` or `generated:cad:5:40:faces=3`.
    pub fn from_spec(spec: &str) -> Result<SetConfig, DataError> {
        let bad = |what: &str| DataError::Generator {
            what: format!("{spec:?}: {what}"),
        };
        let fields: Vec<&str> = spec.split(':').collect();
        let (kind, seed, shapes, rules) = match fields[..] {
            ["generated", kind, seed] => (kind, seed, "60", &[][..]),
            ["generated", kind, seed, shapes, ref rules @ ..] => (kind, seed, shapes, rules),
            _ => return Err(bad("expected generated:KIND:SEED[:SHAPES[:OPTION...]]")),
        };
        let seed = seed.parse().map_err(|_| bad("bad seed"))?;
        let shapes = (shapes.parse().ok().filter(|&n: &usize| n > 0))
            .ok_or_else(|| bad("the shape count must be a whole number above 0"))?;
        SetConfig::new(SetKind::from_name(kind)?, seed, shapes)
            .with_options(rules)
            .map_err(|e| match e {
                DataError::Generator { what } => bad(&what),
                other => other,
            })
    }

    /// This set with `options`, each `NAME=NUMBER`, checked: for the free-form kind the
    /// label rules `depth=`, `angle=`, `band=` and `noise=` (its [`LabelRule`]'s
    /// `min_depth`, `min_angle`, `band` and `min_depth_per_noise`) and `size=`
    /// ([`feature_size`](Self::feature_size)); for the mesh kinds
    /// `faces=` ([`face_spacing`](Self::face_spacing)), `rows=`
    /// ([`row_spacing`](Self::row_spacing)), `shallow=`
    /// ([`shallow`](Self::shallow)), `band=` ([`band`](Self::band)), `sparse=` and `dense=`
    /// ([`thinning`](Self::thinning)'s share kept and radius). An option of the other kinds
    /// is refused.
    pub fn with_options(mut self, options: &[&str]) -> Result<SetConfig, DataError> {
        let bad = |what: String| DataError::Generator { what };
        let freeform = self.kind == SetKind::Freeform;
        for option in options {
            let not_an_option = || {
                bad(format!(
                    "{option:?} is not depth=, angle=, band=, noise=, size=, faces=, rows=, \
                     shallow=, sparse= or dense= a number"
                ))
            };
            let (name, value) = option.split_once('=').ok_or_else(not_an_option)?;
            let value = value.parse::<f64>().map_err(|_| not_an_option())?;
            let label = &mut self.label_rule;
            let (field, for_freeform) = match name {
                "depth" => (&mut label.min_depth, true),
                "angle" => (&mut label.min_angle, true),
                "band" if !freeform => (self.band.insert(value), false),
                "band" => (&mut label.band, true),
                "noise" => (&mut label.min_depth_per_noise, true),
                "size" => (&mut self.feature_size, true),
                "faces" => (&mut self.face_spacing, false),
                "rows" => (&mut self.row_spacing, false),
                "shallow" => (&mut self.shallow, false),
                "sparse" => (&mut self.thinning.get_or_insert_default().keep, false),
                "dense" => (&mut self.thinning.get_or_insert_default().radius, false),
                _ => return Err(not_an_option()),
            };
            if for_freeform != freeform {
                return Err(bad(if for_freeform {
                    format!("{name}= is an option of the freeform kind")
                } else {
                    format!("{name}= is for the mesh kinds, not freeform")
                }));
            }
            *field = value;
        }
        self.validate()?;
        Ok(self)
    }

    /// This set with noise `levels` (when given; else its own) along `direction`, checked.
    pub fn with_noise(
        mut self,
        levels: Option<&[f64]>,
        direction: NoiseDirection,
    ) -> Result<SetConfig, DataError> {
        if let Some(levels) = levels {
            self.noise_levels = levels.to_vec();
        }
        self.noise_direction = direction;
        self.validate()?;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bounded_geom::Class;

    fn small(kind: SetKind, seed: u64, shapes: usize) -> SetConfig {
        let mut c = SetConfig::new(kind, seed, shapes);
        c.points = 1000..=1500;
        c
    }

    #[test]
    fn same_seed_same_clouds_other_seed_other_clouds() {
        let a = generate(&small(SetKind::Mixed, 5, 6)).unwrap();
        let b = generate(&small(SetKind::Mixed, 5, 6)).unwrap();
        assert_eq!(a, b);
        // Shape 3 alone equals shape 3 of the set (per-shape streams).
        assert_eq!(generate_one(&small(SetKind::Mixed, 5, 6), 3).unwrap(), a[3]);
        let c = generate(&small(SetKind::Mixed, 6, 6)).unwrap();
        assert!(a.iter().zip(&c).all(|(x, y)| x.1 != y.1));
    }

    #[test]
    fn freeform_sets_are_deterministic_and_extend_without_changing() {
        let a = generate(&small(SetKind::Freeform, 5, 4)).unwrap();
        assert_eq!(a, generate(&small(SetKind::Freeform, 5, 4)).unwrap());
        // Generated one by one (no thread pool) and as a longer set: the same clouds.
        let longer = generate(&small(SetKind::Freeform, 5, 5)).unwrap();
        assert_eq!(&longer[..4], &a[..]);
        for (i, cloud) in a.iter().enumerate() {
            assert_eq!(
                &generate_one(&small(SetKind::Freeform, 5, 4), i).unwrap(),
                cloud
            );
            assert!(
                cloud.0.starts_with(&format!("freeform_{i:06}_")),
                "{}",
                cloud.0
            );
        }
        let other = generate(&small(SetKind::Freeform, 6, 4)).unwrap();
        assert!(a.iter().zip(&other).all(|(x, y)| x.1 != y.1));
        // The label rule is checked with the rest of the configuration.
        let mut bad = small(SetKind::Freeform, 5, 1);
        bad.label_rule.band = -1.0;
        assert!(matches!(generate(&bad), Err(DataError::Generator { .. })));
    }

    /// Every shape kind in both sampling modes (seed: the kind's index), from `template`.
    fn every_shape(template: ShapeSpec) -> impl Iterator<Item = ShapeSpec> {
        ShapeKind::ALL
            .into_iter()
            .enumerate()
            .flat_map(move |(i, kind)| {
                let template = template.clone();
                [Sampling::MeshVertex, Sampling::Random].map(move |sampling| ShapeSpec {
                    kind,
                    sampling,
                    seed: i as u64,
                    ..template.clone()
                })
            })
    }

    #[test]
    fn every_shape_in_both_modes_gives_finite_labelled_points() {
        let template = ShapeSpec {
            kind: ShapeKind::Box,
            sampling: Sampling::Random,
            points: 4000,
            noise: 0.2,
            noise_direction: NoiseDirection::Isotropic,
            outlier_fraction: 0.01,
            seed: 0,
            face_spacing: 1.0,
            row_spacing: 1.0,
            band: None,
            thinning: None,
        };
        for spec in every_shape(template) {
            let (kind, sampling) = (spec.kind, spec.sampling);
            let c = generate_shape(&spec).unwrap();
            let n = c.cloud.len();
            // A thin plate's two sides lie closer than the minimum distance, so
            // mesh-vertex mode fills them about as densely as one sheet.
            let low = if kind == ShapeKind::ThinPlate {
                1600
            } else {
                2700
            };
            assert!(n > low && n < 5300, "{kind:?} {sampling:?}: {n}");
            assert_eq!(c.labels.len(), n);
            let counts = c.class_counts();
            assert_eq!(
                counts[Class::Boundary as usize] > 0,
                kind.is_open(),
                "{kind:?} {counts:?}"
            );
            // Edge points are a minority everywhere.
            assert!(counts[0] > n / 2, "{kind:?} {sampling:?} {counts:?}");
        }
    }

    #[test]
    fn normal_noise_moves_every_point_of_every_shape() {
        // A point found on no triangle would get no normal and silently stay clean.
        let template = ShapeSpec {
            kind: ShapeKind::Box,
            sampling: Sampling::Random,
            points: 3000,
            noise: 0.3,
            noise_direction: NoiseDirection::Normal,
            outlier_fraction: 0.0,
            seed: 0,
            face_spacing: 1.0,
            row_spacing: 1.0,
            band: None,
            thinning: None,
        };
        for spec in every_shape(template) {
            let noisy = generate_shape(&spec).unwrap();
            let clean = generate_shape(&ShapeSpec {
                noise: 0.0,
                ..spec.clone()
            })
            .unwrap();
            let still = (0..clean.cloud.len())
                .filter(|&j| clean.cloud.position_f64(j) == noisy.cloud.position_f64(j))
                .count();
            let (kind, sampling) = (spec.kind, spec.sampling);
            assert_eq!(still, 0, "{kind:?} {sampling:?}: {still} points not moved");
        }
    }

    #[test]
    fn noise_matches_the_requested_level() {
        // A flat disc: the noise is the only off-plane displacement. Its orientation is
        // random, so measure the spread along the fitted normal: the smallest
        // eigenvalue of the covariance, compared through the trace-free ratio below.
        for level in [0.2, 0.6] {
            let spec = ShapeSpec {
                kind: ShapeKind::Disc,
                sampling: Sampling::MeshVertex,
                points: 6000,
                noise: level,
                noise_direction: NoiseDirection::Isotropic,
                outlier_fraction: 0.0,
                seed: 11,
                face_spacing: 1.0,
                row_spacing: 1.0,
                band: None,
                thinning: None,
            };
            let clean = generate_shape(&ShapeSpec {
                noise: 0.0,
                ..spec.clone()
            })
            .unwrap();
            let noisy = generate_shape(&spec).unwrap();
            let pts = |c: &LabelledCloud| -> Vec<V3> {
                (0..c.cloud.len())
                    .map(|i| c.cloud.position_f64(i))
                    .collect()
            };
            let (a, b) = (pts(&clean), pts(&noisy));
            assert_eq!(a.len(), b.len());
            let spacing = perturb::median_spacing(&a, 1.0);
            let d: Vec<f64> = a
                .iter()
                .zip(&b)
                .flat_map(|(p, q)| vec3::sub(*q, *p))
                .collect();
            let sd = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
            assert!(
                (sd / spacing - level).abs() < 0.05 * level,
                "{level}: {}",
                sd / spacing
            );
        }
    }

    #[test]
    fn out_of_range_noise_or_outliers_are_refused() {
        let spec = ShapeSpec {
            kind: ShapeKind::Box,
            sampling: Sampling::Random,
            points: 500,
            noise: 0.0,
            noise_direction: NoiseDirection::Normal,
            outlier_fraction: 0.0,
            seed: 1,
            face_spacing: 1.0,
            row_spacing: 1.0,
            band: None,
            thinning: None,
        };
        assert!(generate_shape(&spec).is_ok());
        // Every bad value is a generator error naming what is wrong.
        type Set = fn(&mut ShapeSpec, f64);
        let cases: [(&str, Set, [f64; 3]); 4] = [
            (
                "noise level",
                |s, v| s.noise = v,
                [-0.1, f64::NAN, f64::INFINITY],
            ),
            (
                "outlier fraction",
                |s, v| s.outlier_fraction = v,
                [-0.01, 1.5, f64::NAN],
            ),
            (
                "row spacing",
                |s, v| s.row_spacing = v,
                [0.5, MAX_ROW_SPACING + 1.0, f64::NAN],
            ),
            (
                "face spacing",
                |s, v| s.face_spacing = v,
                [0.5, MAX_FACE_SPACING + 1.0, f64::NAN],
            ),
        ];
        for (what, set, values) in cases {
            for value in values {
                let mut bad = spec.clone();
                set(&mut bad, value);
                let err = generate_shape(&bad).unwrap_err();
                assert!(matches!(err, DataError::Generator { .. }), "{err}");
                assert!(err.to_string().contains(what), "{what} {value}: {err}");
            }
        }
        let mut set = small(SetKind::Cad, 1, 2);
        assert!(set.validate().is_ok());
        set.noise_levels = vec![0.2, -1.0];
        assert!(matches!(generate(&set), Err(DataError::Generator { .. })));
    }

    #[test]
    fn a_sharp_band_widens_the_labels_and_moves_no_point() {
        let one_row = small(SetKind::Cad, 5, 3);
        let band = one_row.clone().with_options(&["band=1.5"]).unwrap();
        assert_eq!(band.band, Some(1.5));
        let (a, b) = (generate(&one_row).unwrap(), generate(&band).unwrap());
        let (mut rows, mut widened) = (0, 0);
        for ((_, a), (_, b)) in a.iter().zip(&b) {
            assert_eq!(a.cloud, b.cloud);
            for (&was, &now) in a.labels.iter().zip(&b.labels) {
                // Rows stay sharp; only sharp labels are added.
                assert!(was == now || now == Class::Sharp, "{was:?} -> {now:?}");
                rows += usize::from(was == Class::Sharp);
                widened += usize::from(was != now);
            }
        }
        // Three spacings across against one row; in clouds this small the rows hold about a
        // third of the points and neighbouring creases' bands overlap, so fewer are added.
        assert!(2 * widened > rows, "{rows} in rows, {widened} added");
        // The free-form kind keeps its own band; a band must be positive.
        let freeform = SetConfig::new(SetKind::Freeform, 1, 2).with_options(&["band=2"]);
        let freeform = freeform.unwrap();
        assert_eq!((freeform.band, freeform.label_rule.band), (None, 2.0));
        for bad in ["band=0", "band=-1", "band=inf"] {
            let set = SetConfig::new(SetKind::Random, 1, 2).with_options(&[bad]);
            assert!(matches!(set, Err(DataError::Generator { .. })), "{bad}");
        }
    }

    #[test]
    fn shallow_ridges_only_where_asked_for() {
        let plain = small(SetKind::Cad, 9, 40);
        let shallow = SetConfig {
            shallow: 30.0,
            ..plain.clone()
        };
        let kinds = |set: &SetConfig| -> Vec<ShapeKind> {
            (0..set.shapes)
                .map(|i| match set.spec(i) {
                    CloudSpec::Mesh(s) => s.kind,
                    CloudSpec::Freeform(_) => panic!("a mesh kind gives mesh shapes"),
                })
                .collect()
        };
        assert!(!kinds(&plain).contains(&ShapeKind::ShallowRidges));
        let drawn = (kinds(&shallow).iter())
            .filter(|&&k| k == ShapeKind::ShallowRidges)
            .count();
        // About half at a weight of 30 (the CAD weights sum to 30.6).
        assert!((10..=30).contains(&drawn), "{drawn} of 40");
        // Their clouds hold sharp points on the shallow creases.
        let i = (kinds(&shallow).iter())
            .position(|&k| k == ShapeKind::ShallowRidges)
            .unwrap();
        let CloudSpec::Mesh(spec) = shallow.spec(i) else {
            unreachable!()
        };
        let c = generate_shape(&spec).unwrap();
        assert!(c.class_counts()[Class::Sharp as usize] > 0);
        // The option is a mesh kind's, and bounded.
        let parsed = SetConfig::new(SetKind::Random, 1, 2).with_options(&["shallow=5"]);
        assert_eq!(parsed.unwrap().shallow, 5.0);
        for bad in ["shallow=-1", "shallow=1e9"] {
            let set = SetConfig::new(SetKind::Cad, 1, 2).with_options(&[bad]);
            assert!(matches!(set, Err(DataError::Generator { .. })), "{bad}");
        }
        let freeform = SetConfig::new(SetKind::Freeform, 1, 2).with_options(&["shallow=5"]);
        assert!(freeform.is_err());
    }

    #[test]
    fn thinned_sets_keep_their_shapes_every_sharp_point_and_a_share_of_the_rest() {
        let mut plain = small(SetKind::Cad, 8, 6);
        plain.noise_levels = vec![0.0];
        plain.outlier_fraction = 0.0;
        let thin = plain.clone().with_options(&["sparse=0.2", "dense=3"]);
        let thin = thin.unwrap();
        let want = Thinning {
            radius: 3.0,
            keep: 0.2,
        };
        assert_eq!(thin.thinning, Some(want));
        let (mut kept, mut all) = (0, 0);
        for i in 0..plain.shapes {
            let (CloudSpec::Mesh(a), CloudSpec::Mesh(b)) = (plain.spec(i), thin.spec(i)) else {
                panic!("a mesh kind gives mesh shapes");
            };
            assert_eq!(b.thinning, Some(want));
            assert_eq!(
                ShapeSpec {
                    thinning: None,
                    ..b.clone()
                },
                a
            );
            let (full, thinned) = (generate_shape(&a).unwrap(), generate_shape(&b).unwrap());
            assert_eq!(generate_shape(&b).unwrap(), thinned);
            // The thinned cloud is the full one's subset, in order, every sharp point kept.
            let point = |c: &LabelledCloud, j| (c.cloud.position_f64(j), c.labels[j]);
            let mut rest = (0..full.cloud.len()).map(|j| point(&full, j));
            for j in 0..thinned.cloud.len() {
                let p = point(&thinned, j);
                assert!(
                    rest.any(|q| q == p),
                    "shape {i}: point {j} is not the full cloud's"
                );
            }
            let sharp = |c: &LabelledCloud| c.class_counts()[Class::Sharp as usize];
            assert_eq!(sharp(&thinned), sharp(&full), "shape {i}");
            (kept, all) = (kept + thinned.cloud.len(), all + full.cloud.len());
        }
        // These small clouds (1,000-1,500 points) lie half or more within 3 spacings of a
        // crease; a fifth of the rest stays.
        assert!(kept * 10 < all * 9 && kept * 5 > all, "{kept} of {all}");
        // A dense band alone thins nothing: the same clouds as without it.
        let band_only = plain.clone().with_options(&["dense=3"]).unwrap();
        assert_eq!(generate(&band_only).unwrap(), generate(&plain).unwrap());
        for bad in [
            "sparse=0",
            "sparse=1.5",
            "dense=-1",
            "dense=100",
            "sparse=nan",
        ] {
            let set = SetConfig::new(SetKind::Cad, 1, 2).with_options(&[bad]);
            assert!(matches!(set, Err(DataError::Generator { .. })), "{bad}");
        }
        let freeform = SetConfig::new(SetKind::Freeform, 1, 2).with_options(&["sparse=0.5"]);
        assert!(freeform.is_err());
    }

    /// The specs of every shape of two sets of a mesh kind, side by side.
    fn mesh_specs(a: &SetConfig, b: &SetConfig) -> Vec<(ShapeSpec, ShapeSpec)> {
        (0..a.shapes)
            .map(|i| match (a.spec(i), b.spec(i)) {
                (CloudSpec::Mesh(a), CloudSpec::Mesh(b)) => (a, b),
                _ => panic!("a mesh kind gives mesh shapes"),
            })
            .collect()
    }

    #[test]
    fn spread_rows_change_only_the_row_spacing_drawn() {
        let plain = small(SetKind::Cad, 8, 12);
        let spread = plain.clone().with_options(&["rows=1.5"]).unwrap();
        assert_eq!(
            plain,
            SetConfig {
                row_spacing: 1.0,
                ..spread.clone()
            }
        );
        for (a, b) in mesh_specs(&plain, &spread) {
            assert_eq!(a.row_spacing, 1.0);
            assert!((1.0..=1.5).contains(&b.row_spacing), "{}", b.row_spacing);
            assert_eq!(
                ShapeSpec {
                    row_spacing: 1.0,
                    ..b
                },
                a
            );
        }
        for bad in ["rows=0.9", "rows=2.5"] {
            let err = plain.clone().with_options(&[bad]).unwrap_err().to_string();
            assert!(err.contains("row spacing"), "{err}");
        }
    }

    #[test]
    fn sparse_faces_keep_the_shapes_and_raise_the_share_of_crease_rows() {
        let plain = small(SetKind::Cad, 8, 12);
        let sparse = SetConfig {
            face_spacing: 3.0,
            ..plain.clone()
        };
        let (mut rows_plain, mut rows_sparse) = (0.0, 0.0);
        for (a, b) in mesh_specs(&plain, &sparse) {
            // Everything but the face spacing is drawn as before.
            assert_eq!(a.face_spacing, 1.0);
            assert!((1.0..=3.0).contains(&b.face_spacing), "{}", b.face_spacing);
            assert_eq!(
                ShapeSpec {
                    face_spacing: 1.0,
                    row_spacing: 1.0,
                    band: None,
                    thinning: None,
                    ..b.clone()
                },
                a
            );
            let share = |spec: &ShapeSpec| {
                let c = generate_shape(spec).unwrap();
                let n = c.cloud.len() as f64;
                let target = spec.points as f64;
                assert!(n > 0.6 * target && n < 1.4 * target, "{spec:?}: {n}");
                let counts = c.class_counts();
                (counts[Class::Sharp as usize] + counts[Class::Boundary as usize]) as f64 / n
            };
            rows_plain += share(&a);
            rows_sparse += share(&b);
        }
        // With the same number of points, denser rows beside sparser planes hold more of them.
        assert!(
            rows_sparse > 1.2 * rows_plain,
            "{rows_sparse} vs {rows_plain}"
        );
    }
}
