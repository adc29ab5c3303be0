//! Point clouds and neighbourhood search for BoundED.
//!
//! [`PointCloud`] keeps the original coordinates' origin in `f64` and the points
//! re-centred in `f32`, so clouds in UTM coordinates (5,403,150 m, where `f32`
//! alone resolves only 0.5 m) keep millimetre precision.
//!
//! ```
//! use bounded_geom::PointCloud;
//! let cloud = PointCloud::from_f64(&[[5_403_150.0, 10.0, 1.0], [5_403_151.0, 10.0, 1.0]]).unwrap();
//! assert_eq!(cloud.len(), 2);
//! assert_eq!(cloud.position_f64(1), [5_403_151.0, 10.0, 1.0]);
//! ```

mod class;
mod cloud;
mod error;

pub use class::Class;
pub use cloud::PointCloud;
pub use error::GeomError;
