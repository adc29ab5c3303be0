//! `bounded`: find sharp edges and boundaries in 3D point clouds.
//!
//! A thin binary: it parses arguments and wires the library crates together
//! (bounded-data for files, bounded-features for the statistics, bounded-nn for the classifier).

mod cli;
mod commands;
mod pipeline;
mod progress;

use clap::Parser;

fn main() -> std::process::ExitCode {
    remove_temporaries_on_signals();
    bounded_data::las::quiet_decoder_panics();
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
            eprintln!("error: {}", one_line(&error));
            std::process::ExitCode::FAILURE
        }
    }
}

/// On SIGINT or SIGTERM: removes the temporary files of the outputs being written (the
/// targets stay as they were) and exits with 128 + the signal number (130 / 143), as shells
/// report a process ended by it. SIGKILL cannot be caught: its temporary files stay behind
/// (`bounded_geom::atomic::stale_temporaries` finds them).
fn remove_temporaries_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    // Without a handler (only a bad signal number fails) signals end it without clean-up.
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            bounded_geom::atomic::remove_temporaries();
            std::process::exit(128 + signal);
        }
    });
}

/// The error and its causes on one line, outermost first; a cause whose text an outer
/// message already quotes (the library errors name their source) is not repeated.
fn one_line(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain().map(|c| c.to_string()) {
        if line.contains(&cause) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&cause);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn causes_are_joined_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let quoted = anyhow::Error::new(io).context("a.ply: no such file");
        assert_eq!(one_line(&quoted), "a.ply: no such file");
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let plain = anyhow::Error::new(io).context("reading a.ply");
        assert_eq!(one_line(&plain), "reading a.ply: no such file");
    }
}
