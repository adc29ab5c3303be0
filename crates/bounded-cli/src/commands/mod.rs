//! One module per subcommand; each parses nothing and only wires the library crates together.

mod bench;
mod demo;
mod detect;
mod eval;
mod generate;
mod render;
mod train;

use crate::cli::Command;
use anyhow::Result;

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
