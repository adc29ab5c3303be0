//! `bounded`: find sharp edges and boundaries in 3D point clouds.
//!
//! A thin binary: it parses arguments and wires the library crates together
//! (bounded-data for files, bounded-features for the statistics, bounded-nn for the classifier).

mod atomic;
mod canvas;
mod cli;
mod commands;
mod peers;
mod pipeline;
mod plot;
mod progress;
mod render;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    if let Some(threads) = args.threads {
        // Only fails when a pool already exists, which cannot happen this early.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global();
    }
    match commands::run(args.command) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            // One line: the error and its causes, outermost first.
            let causes: Vec<String> = error.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", causes.join(": "));
            std::process::ExitCode::FAILURE
        }
    }
}
