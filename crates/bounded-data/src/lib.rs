//! Point-cloud formats, labelled datasets, pictures and the synthetic training-set generator
//! for BoundED.
//!
//! Formats (chosen by file extension): PLY, PCD, XYZ/TXT/CSV, LAS/LAZ, E57, and NumPy `.npy`
//! as input; annotated outputs (the detection results added to the input) in [`annotate`].
//!
//! The generator ([`synth`]) is the default cargo feature `generator`; a user of the formats
//! alone builds without it (and its random-number crates) with `default-features = false`.

mod e57;
mod error;
mod labelled;
mod npy;
mod records;

pub mod abc;
pub mod annotate;
pub mod dataset;
pub mod format;
pub mod labels;
pub mod las;
pub mod pcd;
pub mod peers;
pub mod picture;
pub mod ply;
#[cfg(feature = "generator")]
pub mod synth;
pub mod table;
pub mod xyz;

pub use error::DataError;
pub use labelled::LabelledCloud;
