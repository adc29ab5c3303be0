//! Bad input through the binary: non-zero exit, one line naming the problem, no panic, no
//! output file.

mod common;

use common::{bounded_paths, has_files};
use std::path::Path;

/// Runs detect on `input` into a fresh directory and checks the failure contract; returns
/// the error line.
fn fails(input: &Path, output_name: &str) -> String {
    let out_dir = tempfile::tempdir().unwrap();
    let output = out_dir.path().join(output_name);
    let run = bounded_paths(&[&"detect", &input, &"-o", &output]);
    let err = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(!run.status.success(), "{}: accepted", input.display());
    assert!(
        !err.contains("panicked"),
        "{}: panic: {err}",
        input.display()
    );
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{}: not one line: {err}", input.display());
    assert!(lines[0].starts_with("error: "), "{err}");
    assert!(
        !repeats_a_cause(lines[0]),
        "{}: cause repeated: {err}",
        input.display()
    );
    assert!(
        !has_files(out_dir.path()),
        "{}: output left behind",
        input.display()
    );
    lines[0].to_string()
}

/// True when the line ends in "X: X" (a cause printed twice).
fn repeats_a_cause(line: &str) -> bool {
    line.match_indices(": ")
        .any(|(at, _)| line[..at].ends_with(&line[at + 2..]))
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn ascii_ply(points: &[[f32; 3]]) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    );
    for p in points {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    s
}

fn grid(n: usize) -> Vec<[f32; 3]> {
    (0..n)
        .map(|i| [(i % 40) as f32, (i / 40) as f32, 0.0])
        .collect()
}

#[test]
fn empty_file() {
    let dir = tempfile::tempdir().unwrap();
    let line = fails(&write(dir.path(), "empty.ply", b""), "out.ply");
    assert!(line.contains("empty.ply"), "{line}");
}

#[test]
fn header_only() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply(&grid(500));
    let header = &text[..text.find("end_header\n").unwrap() + 11];
    let line = fails(
        &write(dir.path(), "header.ply", header.as_bytes()),
        "out.ply",
    );
    assert!(line.contains("header.ply"), "{line}");
}

#[test]
fn truncated_binary() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    for p in grid(600) {
        for v in p {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    let line = fails(&write(dir.path(), "cut.ply", &bytes), "out.ply");
    assert!(line.contains("cut.ply"), "{line}");
}

#[test]
fn nan_coordinate() {
    let dir = tempfile::tempdir().unwrap();
    let mut text: String = grid(500)
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    text += "1 nan 2\n";
    let input = write(dir.path(), "nan.xyz", text.as_bytes());
    let line = fails(&input, "out.xyz");
    assert!(
        line.contains("nan.xyz") && line.contains("point 500 has a non-finite coordinate"),
        "{line}"
    );
    assert!(line.contains("--drop-non-finite"), "{line}");
    // On request the point is left out, said so, and the others are labelled.
    let output = dir.path().join("out.xyz");
    let run = bounded_paths(&[&"detect", &input, &"-o", &output, &"--drop-non-finite"]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(err.contains("left out 1 point with a NaN"), "{err}");
    let table = bounded_data::format::read(&output).unwrap();
    assert_eq!(table.len(), 500);
    assert!(bounded_data::labels::class_column(&table).is_some());
}

#[test]
fn fewer_points_than_the_largest_scale() {
    let dir = tempfile::tempdir().unwrap();
    let line = fails(
        &write(dir.path(), "small.ply", ascii_ply(&grid(50)).as_bytes()),
        "out.ply",
    );
    assert!(line.contains("50 points") && line.contains("128"), "{line}");
}

#[test]
fn unknown_extension() {
    let dir = tempfile::tempdir().unwrap();
    let line = fails(&write(dir.path(), "cloud.foo", b"1 2 3\n"), "out.ply");
    assert!(line.contains("cloud.foo"), "{line}");
    let input = write(dir.path(), "good.ply", ascii_ply(&grid(500)).as_bytes());
    let line = fails(&input, "out.bar");
    assert!(line.contains("out.bar"), "{line}");
}

#[test]
fn corrupt_laz_stream_gives_one_line_without_a_panic() {
    // A LAZ file the `laz` fuzz target made (bounded-data's las tests build it): its
    // compressed colours make the laz crate's decoder panic, which the reader catches and the
    // binary keeps off stderr (`las::quiet_decoder_panics`).
    const FILE: [&str; 15] = [
        "4c415346000010000000000000000000000000000000000001044f5448455200000000000000000000000000",
        "0000000000000000000000000000426f756e6445442d727320302e312e300000000000000000000000000000",
        "00005001ea077701db0100000100000087240000000000000000000000000000000000000000000000000000",
        "0000000000403e000000000000103e000000000000f03f0000806666e62d40000080999999f93f0000000000",
        "0000400000406366e63d400000000000008a3e0000c09c999909400000000000005abe000000000000104000",
        "0000000000000000000000000000000000000000000000000000002c010000000000002c0100000000000000",
        "0000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
        "0000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
        "000000000000000000000000000000000000000000000000006c61737a697020656e636f6465640000bc562e",
        "0068747470733a2f2f6c61737a69702e6f726700000000000000000000000000000300000002020000000000",
        "0050c30000ffffffffffffffffffffffffffffffff02000a001e0003000b0006000300e10100000000000000",
        "040000000000000000000000000000000000000000000000000000008b00000000000000000000120000000a",
        "0000000000000008000000000000000000000000000000000000000000000012000000000000000000000000",
        "000000000000000000000000000000000000ffffffffffffffffffffffffffffffff0000000000000000008b",
        "00000000000000000000120000000a0000000000000000000000000000005e5e5e",
    ];
    let hex = FILE.concat();
    let bytes: Vec<u8> = (0..hex.len() / 2)
        .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let err = fails(&write(dir.path(), "corrupt.laz", &bytes), "out.ply");
    assert!(
        err.contains("LAZ: the compressed point data is corrupt"),
        "{err}"
    );
}

#[test]
fn truncated_e57() {
    let dir = tempfile::tempdir().unwrap();
    let line = fails(&write(dir.path(), "scan.e57", b"ASTM-E57 cut"), "out.ply");
    assert!(line.contains("scan.e57") && line.contains("E57"), "{line}");
}

#[test]
fn missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let line = fails(&dir.path().join("missing.ply"), "out.ply");
    assert!(line.contains("missing.ply"), "{line}");
}

#[test]
fn unwritable_output_directory() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "good.ply", ascii_ply(&grid(500)).as_bytes());
    let run = bounded_paths(&[&"detect", &input, &"-o", &"/nonexistent-dir/out.ply"]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!repeats_a_cause(err.trim_end()), "{err}");
    assert!(err.contains("/nonexistent-dir"), "{err}");
}

#[test]
fn unlabelled_clouds_for_eval_and_render() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "plain.xyz", b"0 0 0\n1 0 0\n0 1 0\n");
    let out = tempfile::tempdir().unwrap();
    let picture = out.path().join("plain.png");
    for (args, expected) in [
        (
            vec![
                &"eval" as &dyn AsRef<std::ffi::OsStr>,
                &"--data",
                &dir.path(),
            ],
            "no labels",
        ),
        (vec![&"render", &input, &"-o", &picture], "--by detect"),
    ] {
        let run = bounded_paths(&args);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("plain.xyz") && err.contains(expected), "{err}");
    }
    assert!(!has_files(out.path()));
}
