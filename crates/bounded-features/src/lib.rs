//! BoundED's multi-scale local neighbourhood statistics.
//!
//! For every point and every scale `k` (neighbour count, the point included) the
//! neighbourhood is centred and scaled to a unit-free frame, split by its normal into
//! an upper and a lower set, and described by 12 numbers: `sigma_u` (3), `sigma_l` (3),
//! `d` (2), `s` (2), `c` (2). See `SPEC.md`, "Features", and [`FeatureGroups`].
//!
//! Choices the paper leaves open, as implemented here:
//! - covariances are population covariances (divided by the count), accumulated in
//!   `f64` on coordinates centred on the query point;
//! - the normalisation factor `2 / (sqrt(s1) + sqrt(s2))` falls back to 1 when it is not
//!   finite (all neighbours identical), so output is always finite;
//! - the normal is oriented so the query point lies on its upper side, and, when the
//!   query point lies exactly in the plane, so its first non-zero component is positive;
//! - a neighbour exactly on the U / L split plane joins U or L by a fixed pattern of its
//!   rank that halves any run of ranks about evenly: rounding splits a rotated plane's
//!   points so, while on a plane along the axes every offset is exactly 0 and `>= 0`
//!   would put them all in U, giving a wall or a CAD face features that no rotated copy
//!   of it has;
//! - points that repeat a position count once: the neighbourhoods are those of the
//!   distinct positions, whose features the repeats share, so a cloud stored with repeats
//!   (real scans have them) gets the features of the same cloud stored once;
//! - the normal of `floor(k/2) = 0` points (k = 1) and of fully degenerate
//!   neighbourhoods is `[0, 0, 1]`; sets with fewer than 2 points have zero `sigma`,
//!   and `d` is zero when either set is empty.
//!
//! For a second classifier (auto-context), [`extract_in_context`] and
//! [`extract_chunks_in_context`] put beside each scale's features values describing a first
//! classifier's probabilities over the same neighbourhood ([`ContextSet`]: the four of
//! [`CONTEXT_NAMES`], or those and where the sharp probability lies as a line).
//!
//! Results are bit-identical whatever the chunk size and thread count. Translating,
//! rotating or scaling a cloud changes its `f32` coordinates by rounding only; the
//! features follow continuously except where a neighbour lies within rounding of the
//! U / L split plane and changes sides, a discontinuity of the method itself (the
//! tests allow it for at most 1% of points, at a tolerance of 1e-3).
//!
//! ```
//! use bounded_features::{FeatureConfig, FeatureGroups, PointCloud, extract};
//!
//! // A 12 x 12 grid on the plane z = 0, with absolute coordinates.
//! let positions: Vec<[f64; 3]> = (0..144)
//!     .map(|i| [1000.0 + (i % 12) as f64, 2000.0 + (i / 12) as f64, 5.0])
//!     .collect();
//! let cloud = PointCloud::from_f64(&positions).unwrap();
//! let config = FeatureConfig {
//!     scales: vec![32, 16],
//!     groups: FeatureGroups::BOUNDED,
//!     ..FeatureConfig::default()
//! };
//! let features = extract(&cloud, &config).unwrap();
//!
//! // Point 78 = (6, 6): 2 scales x 12 values; on a plane it has no offset along the
//! // normal (s_perp, the 11th value of a scale).
//! let x = features.point(78);
//! assert_eq!(x.len(), 2 * 12);
//! assert!(x[10].abs() < 1e-6 && x[12 + 10].abs() < 1e-6);
//! ```

mod config;
mod context;
mod error;
mod extract;
mod local;
mod staged;

/// The point cloud type the features take, re-exported so that this crate alone is enough.
pub use bounded_geom::{GeomError, PointCloud};
pub use config::{DEFAULT_SCALES, FeatureConfig, FeatureGroups};
pub use context::{CONTEXT_NAMES, CONTEXT_PER_SCALE, ContextSet};
pub use error::FeatureError;
pub use extract::{
    DEFAULT_CHUNK_POINTS, FeatureBlock, Features, extract, extract_chunks,
    extract_chunks_in_context, extract_in_context, values_per_point, values_per_scale,
};
pub use staged::{PENDING_CHUNKS, extract_chunks_staged};
