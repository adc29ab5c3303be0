//! Pictures for people to look at: shaded splat renderings of clouds coloured by class and
//! precision-recall plots, drawn on a small RGB canvas and saved as PNG.
//!
//! ```
//! use bounded_data::picture::{View, render_classes};
//! use bounded_geom::{Class, PointCloud};
//!
//! let cloud = PointCloud::from_f64(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])?;
//! let classes = [Class::NonEdge, Class::Sharp, Class::Boundary];
//! let canvas = render_classes(&cloud, &classes, View::default(), 64, 48);
//! let dir = tempfile::tempdir()?;
//! canvas.save_png(&dir.path().join("three.png"))?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod canvas;
mod plot;
mod render;

pub use canvas::{Canvas, Rgb, check_png};
pub use plot::{PALETTE, Series, precision_recall};
pub use render::{View, render, render_classes};
