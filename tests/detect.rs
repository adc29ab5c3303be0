//! `bounded detect` on a generated cloud in every format, reading the output back.

mod common;

use bounded_data::format;
use bounded_data::table::{Column, PointTable, Property};
use bounded_geom::Class;
use common::{bounded_paths, box_cloud, stderr};

#[test]
fn detect_in_every_format_keeps_points_and_properties_and_finds_creases() {
    let labelled = box_cloud(6000, 3);
    let n = labelled.cloud.len();
    let mut table = PointTable::new(labelled.cloud.clone());
    let intensity: Vec<u16> = (0..n).map(|i| (i % 1000) as u16).collect();
    table.set_property(Property::new("intensity", Column::U16(intensity)));
    let dir = tempfile::tempdir().unwrap();
    for ext in ["ply", "pcd", "xyz", "txt", "csv", "las", "laz", "e57"] {
        let input = dir.path().join(format!("in.{ext}"));
        let output = dir.path().join(format!("out.{ext}"));
        format::write(&input, &table).unwrap();
        let run = bounded_paths(&[&"detect", &input, &"-o", &output]);
        assert!(run.status.success(), "{ext}: {}", stderr(&run));
        assert!(
            stderr(&run).contains("sharp edge"),
            "{ext}: summary missing"
        );
        if cfg!(target_os = "linux") {
            let err = stderr(&run);
            let mib: f64 = (err.split("peak memory ").nth(1))
                .and_then(|rest| rest.split(" MiB").next())
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("{ext}: no peak memory in {err}"));
            assert!((1.0..4096.0).contains(&mib), "{ext}: {err}");
        }

        let back = format::read(&output).unwrap();
        assert_eq!(back.len(), n, "{ext}: point count");
        let read_in = format::read(&input).unwrap();
        assert!(
            positions(&back) == positions(&read_in),
            "{ext}: points moved"
        );
        let intensity_back = back.property("intensity").expect("intensity kept");
        assert_eq!(intensity_back.get_f64(17), 17.0, "{ext}: intensity value");
        // PLY and text outputs name the results for CloudCompare.
        let prefix = if matches!(ext, "ply" | "xyz" | "txt" | "csv") {
            "scalar_"
        } else {
            ""
        };
        for name in ["p_nonedge", "p_sharp", "p_boundary"] {
            let name = format!("{prefix}{name}");
            assert!(back.property(&name).is_some(), "{ext}: {name} missing");
        }
        // LAS keeps the class in its Classification field with its own codes.
        let class_name = if ext.starts_with("la") {
            "classification".to_string()
        } else {
            format!("{prefix}class")
        };
        let class = back.property(&class_name).expect("class column");
        let sharp_code = if ext.starts_with("la") { 64.0 } else { 1.0 };
        let (mut found, mut true_sharp) = (0usize, 0usize);
        for (i, &truth) in labelled.labels.iter().enumerate() {
            if truth == Class::Sharp {
                true_sharp += 1;
                found += usize::from(class.get_f64(i) == sharp_code);
            }
        }
        assert!(
            found * 2 > true_sharp,
            "{ext}: only {found} of {true_sharp} crease points detected"
        );
    }
}

#[test]
fn detect_writes_positions_back_at_full_precision() {
    // UTM-like coordinates: the output must keep them bit for bit, not the f32 offsets.
    let labelled = box_cloud(3000, 5);
    let shifted: Vec<[f64; 3]> = (0..labelled.cloud.len())
        .map(|i| {
            let p = labelled.cloud.position_f64(i);
            [
                // Sub-millimetre digits no f32 offset holds.
                p[0] + 512_000.123_456_7 + i as f64 * 1.1e-7,
                p[1] + 5_403_150.987_654_3,
                p[2] + 300.0,
            ]
        })
        .collect();
    // An ASCII PLY of the doubles themselves, which the cloud's f32 offsets cannot give back.
    let header = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\n\
         property double z\nend_header\n",
        shifted.len()
    );
    let rows: String = shifted
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("utm.ply"), dir.path().join("out.ply"));
    std::fs::write(&input, header + &rows).unwrap();
    let run = bounded_paths(&[&"detect", &input, &"-o", &output]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(positions(&format::read(&output).unwrap()), shifted);
}

#[test]
fn the_band_model_is_chosen_by_name_and_calls_wider_creases() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("box.ply");
    format::write(&input, &PointTable::new(box_cloud(6000, 3).cloud)).unwrap();
    let output = dir.path().join("out.ply");
    let sharp = |embedded: &[&str]| {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"detect", &input, &"-o", &output];
        args.extend(embedded.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let run = bounded_paths(&args);
        assert!(run.status.success(), "{embedded:?}: {}", stderr(&run));
        classes(&output).iter().filter(|&&c| c == 1.0).count()
    };
    let row = sharp(&[]);
    assert_eq!(sharp(&["--embedded", "row"]), row);
    // Bands about three rows wide along the box's creases, against one row.
    let band = sharp(&["--embedded", "band"]);
    assert!(2 * band > 3 * row && row > 0, "band {band}, row {row}");
    let run = bounded_paths(&[&"detect", &input, &"-o", &output, &"--embedded", &"bands"]);
    assert!(
        stderr(&run).contains("no embedded model is called `bands`"),
        "{}",
        stderr(&run)
    );
    let run = bounded_paths(&[
        &"detect",
        &input,
        &"-o",
        &output,
        &"--embedded",
        &"band",
        &"--model",
        &input,
    ]);
    assert!(
        stderr(&run).contains("cannot be used with"),
        "{}",
        stderr(&run)
    );
    // A model file called as an embedded model, where there is none, is pointed to it.
    let run = bounded_paths(&[&"detect", &input, &"-o", &output, &"--model", &"band"]);
    assert!(
        stderr(&run).contains("(--embedded band names"),
        "{}",
        stderr(&run)
    );
}

/// The positions of a table as read: the exact ones if it keeps them, else the cloud's.
fn positions(table: &PointTable) -> Vec<[f64; 3]> {
    match &table.exact_positions {
        Some(exact) => (0..exact.len()).map(|i| exact.get(i)).collect(),
        None => (0..table.len())
            .map(|i| table.cloud.position_f64(i))
            .collect(),
    }
}

/// The classes written to `path` (the class property, under any of its names).
fn classes(path: &std::path::Path) -> Vec<f64> {
    let table = format::read(path).unwrap();
    let class = bounded_data::labels::class_column(&table).expect("class column");
    (0..table.len()).map(|i| class.get_f64(i)).collect()
}

#[test]
fn tiles_are_labelled_as_one_cloud_without_seams() {
    // A box cut in two across its faces: alone, each half ends at the cut, which is then a
    // boundary; together the cut is flat surface.
    let labelled = box_cloud(8000, 11);
    let all: Vec<[f64; 3]> = (0..labelled.cloud.len())
        .map(|i| labelled.cloud.position_f64(i))
        .collect();
    let cut = 0.5
        * (all.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min)
            + all.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max));
    let (left, right): (Vec<_>, Vec<_>) = all.iter().partition(|p| p[0] < cut);
    let text = |points: &[&[f64; 3]]| -> String {
        (points.iter())
            .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
            .collect()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    std::fs::write(path("left.xyz"), text(&left)).unwrap();
    std::fs::write(path("right.xyz"), text(&right)).unwrap();
    let both: Vec<&[f64; 3]> = left.iter().chain(&right).copied().collect();
    std::fs::write(path("whole.xyz"), text(&both)).unwrap();

    let tiles = [path("left.xyz"), path("right.xyz")];
    let run = bounded_paths(&[
        &"detect",
        &tiles[0],
        &tiles[1],
        &"-o",
        &path("out"),
        &"--format",
        &"ply",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("wrote 2 files to"),
        "{}",
        stderr(&run)
    );
    let joint: Vec<f64> = [path("out/left.ply"), path("out/right.ply")]
        .iter()
        .flat_map(|p| classes(p))
        .collect();
    let run = bounded_paths(&[&"detect", &path("whole.xyz"), &"-o", &path("whole.ply")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let whole = classes(&path("whole.ply"));
    let same = joint.iter().zip(&whole).filter(|(a, b)| a == b).count();
    assert!(
        same * 1000 >= whole.len() * 999,
        "{same} of {} alike",
        whole.len()
    );

    // Labelled apart, the points at the cut become boundary; together they are not.
    let mut apart = Vec::new();
    for tile in &tiles {
        let out = tile.with_extension("ply");
        let run = bounded_paths(&[&"detect", tile, &"-o", &out]);
        assert!(run.status.success(), "{}", stderr(&run));
        apart.extend(classes(&out));
    }
    // `--separate` labels them apart in one run.
    let run = bounded_paths(&[
        &"detect",
        &"--separate",
        &tiles[0],
        &tiles[1],
        &"-o",
        &path("separate"),
        &"--format",
        &"ply",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let separate: Vec<f64> = [path("separate/left.ply"), path("separate/right.ply")]
        .iter()
        .flat_map(|p| classes(p))
        .collect();
    assert_eq!(separate, apart, "--separate differs from one run per tile");
    let spacing = 0.02 * (cut - all.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min));
    let at_cut = |labels: &[f64]| {
        (both.iter().zip(labels))
            .filter(|(p, c)| (p[0] - cut).abs() < spacing && **c == 2.0)
            .count()
    };
    let (apart, joint) = (at_cut(&apart), at_cut(&joint));
    assert!(
        apart > 20 && joint * 10 < apart,
        "boundary at the cut: apart {apart}, joint {joint}"
    );
}

#[test]
fn directory_outputs_refuse_clashing_or_replacing_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let table = PointTable::new(box_cloud(600, 2).cloud);
    for sub in ["a", "b"] {
        std::fs::create_dir(dir.path().join(sub)).unwrap();
        format::write(&dir.path().join(sub).join("t.ply"), &table).unwrap();
    }
    let (a, b) = (dir.path().join("a/t.ply"), dir.path().join("b/t.ply"));
    let fails = |args: &[&dyn AsRef<std::ffi::OsStr>], expected: &str| {
        let run = bounded_paths(args);
        let err = stderr(&run);
        assert!(!run.status.success() && err.contains(expected), "{err}");
    };
    fails(
        &[&"detect", &a, &b, &"-o", &dir.path().join("out")],
        "rename one",
    );
    fails(
        &[&"detect", &a, &b, &"-o", &dir.path().join("a")],
        "would replace it",
    );
    fails(
        &[
            &"detect",
            &a,
            &"-o",
            &dir.path().join("o.ply"),
            &"--format",
            &"las",
        ],
        "--format",
    );
    fails(&[&"detect", &a, &b, &"-o", &a], "this is a file");
    assert!(!dir.path().join("out").exists(), "nothing created");
    // A run that fails after the checks (a missing input) leaves no directory behind either.
    let missing = dir.path().join("missing.ply");
    fails(
        &[&"detect", &a, &missing, &"-o", &dir.path().join("new/out")],
        "missing.ply",
    );
    assert!(
        !dir.path().join("new").exists(),
        "failed run created its output directory"
    );
    fails(
        &[&"detect", &a, &missing, &"-o", &a.join("under_a_file")],
        "is not a directory",
    );

    // One input to a path ending in a separator: a directory, created.
    let into = format!("{}/", dir.path().join("single").display());
    let run = bounded_paths(&[&"detect", &a, &"-o", &into]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(dir.path().join("single/t.ply").is_file());
}

#[test]
fn the_input_is_never_replaced_and_bad_thread_counts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.ply");
    format::write(&input, &PointTable::new(box_cloud(600, 2).cloud)).unwrap();
    let before = std::fs::read(&input).unwrap();
    let link = dir.path().join("link.ply");
    std::fs::hard_link(&input, &link).unwrap();
    let spelled = dir.path().join(".").join("in.ply");
    for output in [&input, &link, &spelled] {
        let run = bounded_paths(&[&"detect", &input, &"-o", output]);
        assert!(!run.status.success(), "{}", output.display());
        assert!(stderr(&run).contains("is this input"), "{}", stderr(&run));
    }
    // Into the input's own directory under its own name: refused as well.
    let run = bounded_paths(&[&"detect", &input, &link, &"-o", &dir.path()]);
    assert!(!run.status.success() && stderr(&run).contains("is this input"));
    assert_eq!(std::fs::read(&input).unwrap(), before, "input changed");

    // `--format .las` is the extension las.
    let out = dir.path().join("out");
    let into = format!("{}/", out.display());
    let run = bounded_paths(&[&"detect", &input, &"-o", &into, &"--format", &".las"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(out.join("in.las").is_file() && !out.join("in..las").exists());

    for threads in ["0", "100000"] {
        let run = bounded_paths(&[&"--threads", &threads, &"detect", &input, &"-o", &out]);
        assert!(!run.status.success(), "--threads {threads} accepted");
        assert!(stderr(&run).contains("thread"), "{}", stderr(&run));
    }
}

#[test]
fn a_failed_output_names_those_written_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let table = PointTable::new(box_cloud(600, 2).cloud);
    let (a, b) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
    format::write(&a, &table).unwrap();
    format::write(&b, &table).unwrap();
    let out = dir.path().join("out");
    // The second output's path is taken by a directory: its write fails.
    std::fs::create_dir_all(out.join("b.ply")).unwrap();
    let run = bounded_paths(&[&"detect", &a, &b, &"-o", &out]);
    let err = stderr(&run);
    assert!(!run.status.success(), "{err}");
    assert!(err.contains("1 of 2 outputs were written"), "{err}");
    assert!(
        err.contains("a.ply") && out.join("a.ply").is_file(),
        "{err}"
    );
}

#[test]
fn annotation_flags_choose_names_class_field_and_colours() {
    let labelled = box_cloud(3000, 7);
    let n = labelled.cloud.len();
    let mut table = PointTable::new(labelled.cloud.clone());
    // A ground classification, which `auto` must not replace.
    table.set_property(Property::new("classification", Column::U8(vec![2; n])));
    let dir = tempfile::tempdir().unwrap();
    let (las, ply) = (dir.path().join("in.las"), dir.path().join("in.ply"));
    format::write(&las, &table).unwrap();
    format::write(&ply, &table).unwrap();
    let run = |input: &std::path::Path, output: &str, flags: &[&str]| {
        let output = dir.path().join(output);
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"detect", &input, &"-o", &output];
        args.extend(flags.iter().map(|f| f as &dyn AsRef<std::ffi::OsStr>));
        let run = bounded_paths(&args);
        assert!(run.status.success(), "{flags:?}: {}", stderr(&run));
        format::read(&output).unwrap()
    };
    let value = |t: &PointTable, name: &str| {
        let c = t.property(name).unwrap_or_else(|| panic!("no {name}"));
        (0..t.len()).map(|i| c.get_f64(i)).collect::<Vec<_>>()
    };
    // auto: the ground classes stay, the class goes to an extra field.
    let auto = run(&las, "auto.las", &[]);
    assert_eq!(value(&auto, "classification"), vec![2.0; n]);
    let class = value(&auto, "class");
    // classification with codes: the class codes replace them, the input's are kept aside.
    let coded = run(&las, "coded.las", &["--class-to", "classification:3,9,12"]);
    assert_eq!(value(&coded, "input_classification"), vec![2.0; n]);
    let codes = value(&coded, "classification");
    for (c, code) in class.iter().zip(&codes) {
        assert_eq!(*code, [3.0, 9.0, 12.0][*c as usize]);
    }
    // Plain names and added class colours in PLY.
    let plain = run(
        &ply,
        "plain.ply",
        &["--flavour", "plain", "--colours", "add"],
    );
    // The same PLY input by default: its classes under CloudCompare's name (the LAS copy's
    // positions are quantised, so its classes may differ at a threshold).
    let named = run(&ply, "named.ply", &[]);
    assert_eq!(value(&plain, "class"), value(&named, "scalar_class"));
    assert!(plain.property("scalar_class").is_none());
    assert!(plain.property("class_red").is_some() && plain.property("red").is_none());
    let bad = bounded_paths(&[
        &"detect",
        &ply,
        &"-o",
        &dir.path().join("x.ply"),
        &"--colours",
        &"all",
    ]);
    assert!(!bad.status.success());
    assert!(
        stderr(&bad).contains("expected keep, replace or add"),
        "{}",
        stderr(&bad)
    );
}

#[test]
fn stale_temporary_files_in_the_output_directory_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.ply");
    format::write(&input, &PointTable::new(box_cloud(2000, 9).cloud)).unwrap();
    // What a run killed while writing leaves behind, and a file that only looks alike.
    let stale = dir.path().join(".bounded-0123456789abcdef.part");
    std::fs::write(&stale, b"partial").unwrap();
    std::fs::write(dir.path().join(".bounded-notes.txt"), b"").unwrap();
    let run = bounded_paths(&[&"detect", &input, &"-o", &dir.path().join("out.ply")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(
        err.contains(&format!("note: {} is the temporary file", stale.display())),
        "{err}"
    );
    assert_eq!(err.matches("note:").count(), 1, "{err}");
    assert!(stale.exists(), "never removed without asking");
}

#[test]
fn standard_input_and_output_give_the_file_results() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("in.ply"), dir.path().join("out.ply"));
    format::write(&input, &PointTable::new(box_cloud(2500, 11).cloud)).unwrap();
    let run = bounded_paths(&[&"detect", &input, &"-o", &output]);
    assert!(run.status.success(), "{}", stderr(&run));
    let piped = |args: &[&str]| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_bounded"))
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let bytes = std::fs::read(&input).unwrap();
        child.stdin.take().unwrap().write_all(&bytes).unwrap();
        child.wait_with_output().unwrap()
    };
    // PLY from its first bytes, written as PLY: the file run's bytes.
    let out = piped(&["detect", "-", "-o", "-", "--format", "ply"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(out.stdout, std::fs::read(&output).unwrap());
    // Standard output needs a format when the input has no extension.
    let out = piped(&["detect", "-", "-o", "-"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("--format names its format"),
        "{}",
        stderr(&out)
    );
    // Standard input has no name to write under in a directory, alone or beside files.
    let into = dir.path().join("labelled/");
    let into = into.to_str().unwrap();
    let input = input.to_str().unwrap();
    for args in [
        vec!["detect", "-", "-o", into],
        vec!["detect", input, "-", "-o", into],
    ] {
        let out = piped(&args);
        assert!(!out.status.success(), "{args:?}");
        assert!(
            stderr(&out).contains("-: no file name to write under"),
            "{}",
            stderr(&out)
        );
    }
}
