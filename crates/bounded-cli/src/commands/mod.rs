//! One module per subcommand; each parses nothing and only wires the library crates together.

mod bench;
mod demo;
mod detect;
mod eval;
mod generate;
mod render;
mod train;

use crate::cli::Command;
use crate::progress;
use anyhow::Result;
use bounded_data::LabelledCloud;
use bounded_data::dataset::{self, Role};
use bounded_data::peers::PeerResult;
use bounded_geom::Class;
use bounded_nn::report::{self, MethodResults, ModelResult, Published};
use bounded_nn::{BinaryConfusion, Detector, TrainingCloud};
use std::path::Path;

/// Runs one subcommand.
pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Detect(args) => detect::run(&args),
        Command::Train(args) => train::run(&args),
        Command::Eval(args) => eval::run(&args),
        Command::Generate(args) => generate::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Bench(args) => bench::run(&args),
    }
}

/// The labelled evaluation clouds of `dir` (its evaluation role, or every cloud), with a bar.
fn load_set(dir: &Path, smooth_edge: Class) -> Result<Vec<(String, LabelledCloud)>> {
    let bar = progress::bar("load", 0, "clouds");
    let clouds = dataset::load(dir, &[Role::Evaluation], smooth_edge, &mut |done, all| {
        bar.set_length(all as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(clouds?)
}

/// The clouds as the library's labelled clouds.
fn training_clouds(clouds: &[(String, LabelledCloud)]) -> Vec<TrainingCloud<'_>> {
    (clouds.iter())
        .map(|(name, c)| TrainingCloud::new(name, &c.cloud, &c.labels))
        .collect()
}

/// Classifies every cloud and compares with its labels, with a bar.
fn evaluate(detector: &Detector, clouds: &[(String, LabelledCloud)]) -> Result<Vec<ModelResult>> {
    let bar = progress::bar("evaluate", clouds.len() as u64, "clouds");
    let results = report::evaluate(detector, &training_clouds(clouds), &mut |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    Ok(results?)
}

/// The published methods of `dataset` among `peers`, restricted to `models`.
fn peer_methods(peers: &[PeerResult], dataset: &str, models: &[String]) -> Vec<MethodResults> {
    let rows = (peers.iter().filter(|p| p.dataset == dataset)).map(|p| Published {
        method: &p.description,
        positive: &p.gt_positive,
        model: &p.model,
        confusion: BinaryConfusion {
            tp: p.tp,
            fp: p.fp,
            tn: p.tn,
            fn_: p.fn_,
        },
    });
    report::peer_methods(rows, models)
}

/// The process' peak resident memory so far (VmHWM of /proc/self/status) in MiB, where the
/// platform reports it.
fn peak_memory() -> Option<String> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(format!("{:.0} MiB", kib / 1024.0))
}

/// Points per second, for summaries.
fn rate(points: usize, seconds: f64) -> String {
    let per_second = points as f64 / seconds.max(1e-9);
    if per_second >= 1e6 {
        format!("{:.2} M points/s", per_second / 1e6)
    } else {
        format!("{:.0} k points/s", per_second / 1e3)
    }
}
