//! SIGTERM / SIGINT while `bounded detect` writes its output: the temporary file (or the
//! scratch directory of a file labelled in blocks) is removed and the exit code is 128 + the
//! signal.

#![cfg(unix)]

mod common;

use bounded_data::format;
use bounded_data::table::PointTable;
use common::box_cloud;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The temporary files and scratch directories of the atomic writer in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".bounded-") && n.ends_with(".part"))
        .collect()
}

/// Runs `detect` on `input` into `output` (with `extra` arguments) and sends `signal` as
/// soon as a temporary file or directory exists beside the output. The exit code, or None
/// when the run ended before it was seen writing (too small a cloud: the caller retries with
/// a larger one).
fn interrupt_while_writing(
    input: &Path,
    output: &Path,
    extra: &[&str],
    signal: &str,
) -> Option<i32> {
    let dir = output.parent().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_bounded"))
        .args([
            "detect".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "detect failed unprompted: {status:?}");
            std::fs::remove_file(output).unwrap();
            return None;
        }
        if !temporaries(dir).is_empty() {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(600), "detect hangs");
        std::thread::sleep(Duration::from_micros(200));
    }
    let pid = child.id().to_string();
    let sent = Command::new("kill").args([signal, &pid]).status().unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    if status.success() {
        // It finished between the sighting and the signal.
        std::fs::remove_file(output).unwrap();
        return None;
    }
    status.code()
}

#[test]
fn a_signal_while_writing_removes_the_temporary_file_and_exits_128_plus_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.ply");
    // Text output: the slowest to write, so the temporary file lives longest.
    let output = dir.path().join("out.xyz");
    for (signal, code) in [("-TERM", 143), ("-INT", 130)] {
        let mut points = 20_000;
        let got = loop {
            let cloud = box_cloud(points, 1).cloud;
            format::write(&input, &PointTable::new(cloud)).unwrap();
            if let Some(got) = interrupt_while_writing(&input, &output, &[], signal) {
                break got;
            }
            assert!(points < 5_000_000, "never caught detect writing");
            points *= 4;
        };
        assert_eq!(got, code, "{signal} with {points} points");
        assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "{signal}");
        assert!(!output.exists(), "{signal}: no output");
    }
}

#[test]
fn a_signal_while_a_file_is_labelled_in_blocks_removes_the_scratch_directory() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.las");
    let output = dir.path().join("out.las");
    format::write(&input, &PointTable::new(box_cloud(40_000, 1).cloud)).unwrap();
    let blocks = ["--block-points", "5000"];
    for (signal, code) in [("-TERM", 143), ("-INT", 130)] {
        let got = interrupt_while_writing(&input, &output, &blocks, signal);
        assert_eq!(got, Some(code), "{signal}");
        assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "{signal}");
        assert!(!output.exists(), "{signal}: no output");
    }
}
