//! Surveys larger than memory: BoundED detection tile by tile, each tile with a halo that
//! provably makes its labels those of the whole survey labelled as one cloud.
//!
//! A survey is a list of files (the tiles of an airborne or mobile-mapping survey, say). Its
//! [`Plan`] holds each file's bounds (a LAS or LAZ header's, or one read of any other
//! format). [`detect_survey`] then labels one tile at a time: the tile's points and, read-only,
//! the points of the other files within a radius of its box (the halo, [`halo`]), as one
//! cloud in the survey's frame and point order; it keeps the tile's results, and writes them
//! before it reads the next tile. Peak memory is the largest tile with its halo, not the
//! survey. Every tile point's result is checked to depend only on loaded points
//! ([`proof`]); where one does not, the halo grows and the tile is labelled again, so the
//! labels and probabilities are those of the one-cloud run, bit for bit. [`detect_tile`]
//! labels one tile alone, for a distributed run (one task per tile; the Python package's
//! `bounded.distributed` runs them on Dask). A survey of one LAS or LAZ file too large to
//! hold ([`Options::block_points`]) is labelled in spatial blocks of that file, each with its
//! halo and the same proof, in three streaming passes (see `blocks.rs`); its output is the
//! file labelled whole, byte for byte.
//!
//! Files may overlap in extent: the survey is the union of all their points, as when they
//! are labelled as one cloud, so a surface scanned by two overlapping files has the points of
//! both in every neighbourhood (and a position both hold counts once, as any repeat).
//!
//! ```
//! use bounded_data::format;
//! use bounded_data::table::PointTable;
//! use bounded_geom::PointCloud;
//! use bounded_nn::Detector;
//! use bounded_survey::{Options, Plan, ReadOptions, detect_survey};
//!
//! // A folded sheet (planes meeting along x = 0), cut into two files at y = 20.
//! let sheet = |y0: usize| -> Vec<[f64; 3]> {
//!     (0..40 * 20)
//!         .map(|i| {
//!             let (u, v) = ((i % 40) as f64 - 20.0, (y0 + i / 40) as f64);
//!             if u < 0.0 { [u, v, 0.0] } else { [0.0, v, u] }
//!         })
//!         .collect()
//! };
//! let dir = tempfile::tempdir()?;
//! let inputs = [dir.path().join("south.xyz"), dir.path().join("north.xyz")];
//! for (path, y0) in inputs.iter().zip([0, 20]) {
//!     format::write(path, &PointTable::new(PointCloud::from_f64(&sheet(y0))?))?;
//! }
//! let plan = Plan::of(&inputs, ReadOptions::default())?;
//! let outputs = [dir.path().join("south.ply"), dir.path().join("north.ply")];
//! let detector = Detector::embedded()?;
//! let reports = detect_survey(&plan, &detector, &outputs, &Options::default(), &mut |_| {})?;
//! assert_eq!(reports[0].points, 800);
//!
//! // The same labels as the two files labelled as one cloud.
//! let union: Vec<[f64; 3]> = sheet(0).into_iter().chain(sheet(20)).collect();
//! let whole = detector.detect(&PointCloud::from_f64(&union)?)?;
//! let north = format::read(&outputs[1])?;
//! let classes = north.property("scalar_class").unwrap();
//! assert!((0..800).all(|i| classes.get_f64(i) == whole.classes[800 + i] as u8 as f64));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod blocks;
mod detect;
mod error;
pub mod halo;
mod outputs;
mod plan;
pub mod proof;

pub use detect::{BLOCK_POINTS, Event, Options, TileReport, detect_survey, detect_tile};
pub use error::SurveyError;
pub use outputs::{output_paths, stdout_format};
pub use plan::{Input, Plan, ReadOptions};
