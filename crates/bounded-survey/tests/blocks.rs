//! One file labelled in spatial blocks, each with its halo, gets the output of the file
//! labelled whole, for several block sizes and thread counts, and when a halo is too small.

use std::path::{Path, PathBuf};

use bounded_data::format;
use bounded_data::table::{Column, PointTable, Property};
use bounded_geom::{PointCloud, uniform_stream};
use bounded_nn::Detector;
use bounded_survey::{Event, Options, Plan, ReadOptions, SurveyError, TileReport, detect_survey};

/// A scene of 60 x 60 m at random: ground, a block building (sharp edges) and a
/// free-standing wall (boundaries); a LAS Classification of ground (2) under the wall only,
/// so that whether it is meaningful is a choice made from every point.
fn scene() -> PointTable {
    let mut r = uniform_stream(5);
    let mut points = Vec::new();
    for _ in 0..6400 {
        let (x, y) = (60.0 * r(), 60.0 * r());
        let roof = (14.0..=26.0).contains(&x) && (30.0..=42.0).contains(&y);
        points.push([x, y, if roof { 6.0 } else { 0.0 }]);
    }
    for _ in 0..1600 {
        let (t, z) = (48.0 * r(), 6.0 * r());
        let (x, y) = match (t / 12.0) as usize {
            0 => (14.0 + t, 30.0),
            1 => (26.0, 18.0 + t),
            2 => (50.0 - t, 42.0),
            _ => (14.0, 78.0 - t),
        };
        points.push([x, y, z]);
    }
    for _ in 0..900 {
        points.push([35.0 + 12.0 * r(), 18.0, 3.0 * r()]);
    }
    let classification = (points.iter())
        .map(|p| if p[1] == 18.0 { 2 } else { 1 })
        .collect();
    let mut table = PointTable::new(PointCloud::from_f64(&points).unwrap());
    table.set_property(Property::new("classification", Column::U8(classification)));
    table
}

/// Labels `input` into `output` as a survey of one file, on `threads` threads.
fn label(input: &Path, output: &Path, options: &Options, threads: usize) -> (TileReport, usize) {
    let plan = Plan::of(&[input.to_path_buf()], ReadOptions::default()).unwrap();
    let detector = Detector::embedded().unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut blocks = 0;
    let outputs = [output.to_path_buf()];
    let mut reports = pool
        .install(|| {
            detect_survey(&plan, &detector, &outputs, options, &mut |event| {
                if let Event::Loaded {
                    block: Some((_, n)),
                    ..
                } = event
                {
                    blocks = n;
                }
            })
        })
        .unwrap();
    (reports.remove(0), blocks)
}

/// The scene written to `dir` as `name`, and its path.
fn write_scene(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    format::write(&path, &scene()).unwrap();
    path
}

#[test]
fn a_file_in_blocks_gets_the_output_of_the_file_labelled_whole() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["las", "laz"] {
        let input = write_scene(dir.path(), &format!("scene.{ext}"));
        // The plan's frame, in which blocks are labelled, is the file's own.
        let plan = Plan::of(std::slice::from_ref(&input), ReadOptions::default()).unwrap();
        assert_eq!(plan.frame(), format::read(&input).unwrap().cloud.frame());
        let whole = dir.path().join(format!("whole.{ext}"));
        let (report, blocks) = label(&input, &whole, &Options::default(), 2);
        assert_eq!((blocks, report.halo), (0, 0), "labelled whole: {report:?}");
        let reference = format::read(&whole).unwrap();
        let sharp_and_boundary: usize = report.class_counts[1..].iter().sum();
        assert!(sharp_and_boundary > 300, "{report:?}");
        // The ground under the wall keeps its class: the results go to Extra Bytes.
        assert!(reference.property("input_classification").is_none());
        assert!(reference.property("class").is_some());
        for (block_points, threads) in [(1500, 1), (1500, 2), (4000, 2)] {
            let options = Options {
                block_points,
                ..Options::default()
            };
            let out = dir
                .path()
                .join(format!("blocks{block_points}-{threads}.{ext}"));
            let (report, blocks) = label(&input, &out, &options, threads);
            assert!(blocks >= 8900 / block_points, "{blocks} blocks");
            assert!(report.halo > 0 && report.points == 8900, "{report:?}");
            assert_eq!(format::read(&out).unwrap(), reference, "{}", out.display());
            if ext == "las" {
                let bytes = |p: &Path| std::fs::read(p).unwrap();
                assert!(
                    bytes(&out) == bytes(&whole),
                    "{} byte for byte",
                    out.display()
                );
            }
        }
    }
    // Nothing is left beside the outputs.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
}

#[test]
fn a_block_halo_too_small_grows_and_the_output_stays_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_scene(dir.path(), "scene.las");
    let whole = dir.path().join("whole.las");
    label(&input, &whole, &Options::default(), 2);
    let options = Options {
        block_points: 2000,
        radius: Some(0.5),
        ..Options::default()
    };
    let out = dir.path().join("blocks.las");
    let (report, blocks) = label(&input, &out, &options, 2);
    assert!(
        report.attempts > blocks && report.radius > 1.0,
        "{report:?}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
}

#[test]
fn a_file_in_blocks_written_as_another_format_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_scene(dir.path(), "scene.laz");
    let plan = Plan::of(&[input], ReadOptions::default()).unwrap();
    let options = Options {
        block_points: 2000,
        ..Options::default()
    };
    let out = [dir.path().join("out.ply")];
    let detector = Detector::embedded().unwrap();
    let mut events = 0;
    let e = detect_survey(&plan, &detector, &out, &options, &mut |_| events += 1).unwrap_err();
    assert!(matches!(e, SurveyError::Invalid(_)), "{e}");
    let message = e.to_string();
    assert!(
        message.contains("scene.laz") && message.contains("out.ply") && message.contains(".las"),
        "{message}"
    );
    assert_eq!(events, 0);
    assert!(!out[0].exists());
}
