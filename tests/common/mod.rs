//! Helpers shared by the end-to-end tests: run the `bounded` binary, make small clouds.
#![allow(dead_code)] // each test file uses a different subset

use bounded_data::LabelledCloud;
use bounded_data::synth::{NoiseDirection, Sampling, ShapeKind, ShapeSpec, generate_shape};
use std::path::Path;
use std::process::{Command, Output};

/// Runs `bounded` with `args`.
pub fn bounded(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bounded"))
        .args(args)
        .output()
        .expect("the bounded binary runs")
}

/// Runs `bounded` with path arguments.
pub fn bounded_paths(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bounded"))
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .expect("the bounded binary runs")
}

/// stderr as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A generated cube-like cloud with exact labels (creases and corners).
pub fn box_cloud(points: usize, seed: u64) -> LabelledCloud {
    generate_shape(&ShapeSpec {
        kind: ShapeKind::Box,
        sampling: Sampling::Random,
        points,
        noise: 0.0,
        noise_direction: NoiseDirection::Isotropic,
        outlier_fraction: 0.0,
        seed,
        face_spacing: 1.0,
        row_spacing: 1.0,
        band: None,
        thinning: None,
    })
    .expect("generated")
}

/// Whether `dir` holds any file at all.
pub fn has_files(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_some())
}
