//! The tiles of a survey and their bounds, known before any tile is labelled.
//!
//! A tile is one input file. A LAS or LAZ file's bounds come from its header, without a
//! point read; any other format is read once for them (and read again when its tile or a
//! neighbour's halo needs its points). A survey of a single LAS or LAZ file larger than
//! `Options::block_points` is labelled in spatial blocks of that file (`crate::blocks`), never
//! held whole; every other tile is held whole while it is labelled.
//!
//! Files may overlap in extent (flight lines, say): the survey is the union of their points,
//! every point of every file present, exactly as when they are labelled as one cloud.

use std::path::{Path, PathBuf};

use bounded_data::format::{self, Format};
use bounded_data::table::PointTable;
use bounded_geom::Frame;

use crate::SurveyError;

/// One input of a survey: its file and the box that holds its points.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// The file.
    pub path: PathBuf,
    /// The lower corner of its bounding box (absolute coordinates).
    pub lo: [f64; 3],
    /// The upper corner.
    pub hi: [f64; 3],
    /// Its number of points (as declared, for LAS and LAZ).
    pub points: u64,
}

/// How the inputs are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReadOptions {
    /// Leave out points with a NaN or infinite coordinate instead of refusing the file (see
    /// `bounded_data::format::read_finite`); the survey is then the union of the others.
    pub drop_non_finite: bool,
}

impl ReadOptions {
    /// Reads `path` with every property, as these options say; returns the table and how
    /// many points were left out.
    pub fn read(&self, path: &Path) -> Result<(PointTable, usize), SurveyError> {
        Ok(if self.drop_non_finite {
            format::read_finite(path)?
        } else {
            (format::read(path)?, 0)
        })
    }
}

/// The tiles of a survey, in input order, and the survey's bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    inputs: Vec<Input>,
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Plan {
    /// Plans the survey of the files `paths`, one tile each, in this order (the order of
    /// the points of the survey as one cloud).
    pub fn of(paths: &[PathBuf], read: ReadOptions) -> Result<Self, SurveyError> {
        let inputs = paths
            .iter()
            .map(|path| input(path, read))
            .collect::<Result<_, _>>()?;
        Self::new(inputs)
    }

    /// The plan of inputs whose bounds are known (a plan's own, sent to another process).
    /// Fails for no input, a file given twice or a box that is not one.
    pub fn new(inputs: Vec<Input>) -> Result<Self, SurveyError> {
        if inputs.is_empty() {
            return Err(SurveyError::Invalid("no input".into()));
        }
        for (k, input) in inputs.iter().enumerate() {
            if inputs[..k].iter().any(|i| i.path == input.path) {
                return Err(SurveyError::Invalid(format!(
                    "{} is given twice",
                    input.path.display()
                )));
            }
            let finite = (input.lo.iter().chain(&input.hi)).all(|c| c.is_finite());
            if !finite || (0..3).any(|a| input.lo[a] > input.hi[a]) {
                return Err(SurveyError::Invalid(format!(
                    "{}: the bounds {:?} to {:?} are not a box",
                    input.path.display(),
                    input.lo,
                    input.hi
                )));
            }
        }
        let lo = std::array::from_fn(|a| inputs.iter().map(|i| i.lo[a]).fold(f64::MAX, f64::min));
        let hi = std::array::from_fn(|a| inputs.iter().map(|i| i.hi[a]).fold(f64::MIN, f64::max));
        Ok(Self { inputs, lo, hi })
    }

    /// The inputs, one tile each, in order.
    pub fn inputs(&self) -> &[Input] {
        &self.inputs
    }

    /// The lower and upper corners of the survey's bounding box.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.lo, self.hi)
    }

    /// The frame every tile's cloud is built in: the one that the survey's points as one
    /// cloud get from their bounding box ([`Frame::of_bounds`]), so that a point has the same
    /// `f32` offsets in every tile it is loaded in and in the whole survey. A survey of a few
    /// points so far from the rest that the whole cloud would centre on the bulk of the points
    /// instead (see `bounded_geom::PointCloud`) keeps the box's centre here: its labels are
    /// then those of the union built in this frame.
    pub fn frame(&self) -> Frame {
        Frame::of_bounds(self.lo, self.hi)
    }
}

/// The input at `path` and its bounds: from the header of a LAS or LAZ file, else from its
/// points.
fn input(path: &Path, read: ReadOptions) -> Result<Input, SurveyError> {
    if let Format::Las { .. } = Format::from_path(path)? {
        let (lo, hi, points) = bounded_data::las::header_bounds(path)?;
        return Ok(Input {
            path: path.to_path_buf(),
            lo,
            hi,
            points,
        });
    }
    let (table, _) = read.read(path)?;
    let view = table.view();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for i in 0..table.len() {
        let p = view.position(i);
        for a in 0..3 {
            (lo[a], hi[a]) = (lo[a].min(p[a]), hi[a].max(p[a]));
        }
    }
    Ok(Input {
        path: path.to_path_buf(),
        lo,
        hi,
        points: table.len() as u64,
    })
}
