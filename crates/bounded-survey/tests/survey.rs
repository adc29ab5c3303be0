//! A generated survey cut into a grid of tiles: labelled tile by tile with halos, it gets the
//! classes and probabilities of the union labelled as one cloud, bit for bit.

use std::path::{Path, PathBuf};

use bounded_data::format;
use bounded_data::table::PointTable;
use bounded_geom::{KnnIndex, PointCloud, uniform_stream};
use bounded_nn::{Detection, Detector};
use bounded_survey::{Input, Options, Plan, ReadOptions, SurveyError, TileReport, detect_survey};

/// Survey extent (metres), its tiles per axis and side.
const SIDE: f64 = 60.0;
const GRID: usize = 3;

/// A scene of 60 x 60 m: ground, a block building (roof and walls: sharp edges) and a
/// free-standing wall (boundaries), sampled at random, or on a grid of `step` metres
/// (many equal neighbour distances) when `step` is given.
fn scene(step: Option<f64>) -> Vec<[f64; 3]> {
    let mut r = uniform_stream(5);
    let mut points = Vec::new();
    let mut area =
        |n: usize, at: &mut dyn FnMut(f64, f64) -> [f64; 3], r: &mut dyn FnMut() -> f64| {
            match step {
                // A regular lattice of the parameters, rounded onto the grid below.
                Some(_) => {
                    let m = (n as f64).sqrt().round() as usize;
                    for i in 0..m * m {
                        points.push(at((i % m) as f64 / m as f64, (i / m) as f64 / m as f64));
                    }
                }
                None => (0..n).for_each(|_| {
                    let (u, v) = (r(), r());
                    points.push(at(u, v));
                }),
            }
        };
    let q = |x: f64| step.map_or(x, |s| (x / s).round() * s);
    // Ground, around the building's footprint.
    area(
        6400,
        &mut |u, v| {
            let (x, y) = (q(u * SIDE), q(v * SIDE));
            let z = if (14.0..=26.0).contains(&x) && (30.0..=42.0).contains(&y) {
                6.0
            } else {
                0.0
            };
            [x, y, z]
        },
        &mut r,
    );
    // Walls of the building, 6 m high.
    area(
        1600,
        &mut |u, v| {
            let t = u * 48.0;
            let (x, y) = match (t / 12.0) as usize {
                0 => (14.0 + t, 30.0),
                1 => (26.0, 30.0 + t - 12.0),
                2 => (26.0 - (t - 24.0), 42.0),
                _ => (14.0, 42.0 - (t - 36.0)),
            };
            [q(x), q(y), q(v * 6.0)]
        },
        &mut r,
    );
    // A free-standing wall, 3 m high, across a seam of the tiles.
    area(
        900,
        &mut |u, v| [q(35.0 + 12.0 * u), q(18.0), q(3.0 * v)],
        &mut r,
    );
    points
}

/// The tile of position `p`: its cell of the `GRID` x `GRID` grid, the cell borders moved by
/// up to `jitter` metres per point (so that neighbouring files overlap in extent).
fn cell(p: [f64; 3], jitter: f64, r: &mut impl FnMut() -> f64) -> usize {
    let at = |c: f64, r: &mut dyn FnMut() -> f64| {
        let c = c + jitter * (2.0 * r() - 1.0);
        ((c / SIDE * GRID as f64).floor().max(0.0) as usize).min(GRID - 1)
    };
    let i = at(p[0], r);
    let j = at(p[1], r);
    j * GRID + i
}

/// Writes the points of `scene` to one file per cell (`ext` their format) in `dir`; with
/// `jitter`, the cells overlap, and every tenth point within `jitter` of a border is in two
/// files (a position both hold). Returns the files and the survey's points as one cloud,
/// in file order, as read back.
fn write_tiles(
    dir: &Path,
    points: &[[f64; 3]],
    jitter: f64,
    ext: &str,
) -> (Vec<PathBuf>, Vec<[f64; 3]>) {
    let mut r = uniform_stream(9);
    let mut cells = vec![Vec::new(); GRID * GRID];
    for (i, &p) in points.iter().enumerate() {
        let c = cell(p, jitter, &mut r);
        cells[c].push(p);
        let other = cell(p, jitter, &mut r);
        if jitter > 0.0 && other != c && i % 10 == 0 {
            cells[other].push(p);
        }
    }
    let mut paths = Vec::new();
    let mut union = Vec::new();
    for (c, points) in cells.iter().enumerate() {
        let path = dir.join(format!("tile{c}.{ext}"));
        format::write(
            &path,
            &PointTable::new(PointCloud::from_f64(points).unwrap()),
        )
        .unwrap();
        let table = format::read(&path).unwrap();
        let view = table.view();
        union.extend((0..table.len()).map(|i| view.position(i)));
        paths.push(path);
    }
    (paths, union)
}

/// The outputs of `inputs` in `dir`: PLY files of the same names.
fn outputs(dir: &Path, inputs: &[PathBuf]) -> Vec<PathBuf> {
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    (inputs.iter())
        .map(|p| out.join(p.file_name().unwrap()).with_extension("ply"))
        .collect()
}

/// Asserts that the outputs hold the union's results, bit for bit, in order.
fn assert_union_results(outputs: &[PathBuf], union: &Detection) {
    let mut first = 0;
    for output in outputs {
        let table = format::read(output).unwrap();
        let column = |name: &str| table.property(name).unwrap();
        for i in 0..table.len() {
            let want = &union.probabilities[first + i];
            for (c, name) in ["scalar_p_nonedge", "scalar_p_sharp", "scalar_p_boundary"]
                .iter()
                .enumerate()
            {
                let got = column(name).get_f64(i);
                assert_eq!(
                    got.to_bits(),
                    f64::from(want[c]).to_bits(),
                    "{}: point {i}",
                    output.display()
                );
            }
            assert_eq!(
                column("scalar_class").get_f64(i),
                f64::from(union.classes[first + i] as u8)
            );
        }
        first += table.len();
    }
    assert_eq!(first, union.classes.len());
}

/// Labels the survey of `inputs` tile by tile and as one cloud, checks they agree and
/// returns the tiles' reports.
fn run(dir: &Path, inputs: &[PathBuf], union: &[[f64; 3]], options: &Options) -> Vec<TileReport> {
    let detector = Detector::embedded().unwrap();
    let plan = Plan::of(inputs, ReadOptions::default()).unwrap();
    let whole = PointCloud::from_f64(union).unwrap();
    assert_eq!(
        whole.frame(),
        plan.frame(),
        "the plan's frame is the union's"
    );
    let reference = detector.detect(&whole).unwrap();
    let outputs = outputs(dir, inputs);
    let mut written = Vec::new();
    let reports = detect_survey(&plan, &detector, &outputs, options, &mut |event| {
        if let bounded_survey::Event::Written { tile, .. } = event {
            written.push(tile);
        }
    })
    .unwrap();
    assert_eq!(written, (0..inputs.len()).collect::<Vec<_>>());
    assert_union_results(&outputs, &reference);
    let classes: usize = reference.class_counts()[1..].iter().sum();
    assert!(
        classes > 200,
        "the scene has edges and boundaries: {:?}",
        reference.class_counts()
    );
    reports
}

#[test]
fn tiles_without_overlap_get_the_union_labels() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, union) = write_tiles(dir.path(), &scene(None), 0.0, "las");
    let reports = run(dir.path(), &inputs, &union, &Options::default());
    for (tile, report) in reports.iter().enumerate() {
        // Each tile loaded a halo; the corner tiles not the whole survey.
        assert!(
            report.halo > 0 && report.needed <= report.radius,
            "{report:?}"
        );
        if [0, 2, 6, 8].contains(&tile) {
            assert!(report.points + report.halo < union.len(), "{report:?}");
        }
    }
}

#[test]
fn overlapping_tiles_with_shared_positions_get_the_union_labels() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, union) = write_tiles(dir.path(), &scene(None), 2.0, "ply");
    let plan = Plan::of(&inputs, ReadOptions::default()).unwrap();
    let (a, b) = (&plan.inputs()[0], &plan.inputs()[1]);
    assert!(a.hi[0] > b.lo[0], "neighbouring files overlap in extent");
    assert!(bounded_geom::Distinct::of(&PointCloud::from_f64(&union).unwrap()).is_some());
    run(dir.path(), &inputs, &union, &Options::default());
}

#[test]
fn a_halo_too_small_grows_and_the_labels_stay_the_unions() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, union) = write_tiles(dir.path(), &scene(None), 0.0, "las");
    let options = Options {
        radius: Some(0.5),
        ..Options::default()
    };
    let reports = run(dir.path(), &inputs, &union, &options);
    for report in &reports {
        assert!(report.attempts > 1 && report.radius > 1.0, "{report:?}");
        assert!(report.labelled > report.points + report.halo, "{report:?}");
    }
}

#[test]
fn quantised_coordinates_with_tied_distances_get_the_union_labels() {
    let dir = tempfile::tempdir().unwrap();
    let points = scene(Some(0.5));
    let (inputs, union) = write_tiles(dir.path(), &points, 0.0, "las");
    // Ties at the cut of the largest neighbourhood, broken by index: the tiles keep the
    // union's point order, so they break them the same way.
    let cloud = PointCloud::from_f64(&union).unwrap();
    let k0 = Detector::embedded()
        .unwrap()
        .feature_config()
        .largest_scale();
    let distinct = bounded_geom::Distinct::of(&cloud);
    let index = match &distinct {
        Some(d) => KnnIndex::of_subset(&cloud, d.firsts()).unwrap(),
        None => KnnIndex::new(&cloud).unwrap(),
    };
    let mut tied = 0;
    let dist = |a: u32, b: u32| {
        let (p, q) = (cloud.points()[a as usize], cloud.points()[b as usize]);
        (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f32>()
    };
    let mut row = vec![0; k0 + 1];
    for q in (0..cloud.len() as u32).step_by(97) {
        if index.nearest(q, &mut row).is_ok() && dist(q, row[k0 - 1]) == dist(q, row[k0]) {
            tied += 1;
        }
    }
    assert!(tied > 10, "{tied} sampled points with a tie at the cut");
    run(dir.path(), &inputs, &union, &Options::default());
}

#[test]
fn a_point_outside_its_declared_bounds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, _) = write_tiles(dir.path(), &scene(None), 0.0, "las");
    let mut declared = Plan::of(&inputs, ReadOptions::default())
        .unwrap()
        .inputs()
        .to_vec();
    declared[4].hi[0] -= 1.0;
    let plan = Plan::new(declared).unwrap();
    let outputs = outputs(dir.path(), &inputs);
    let detector = Detector::embedded().unwrap();
    let e =
        detect_survey(&plan, &detector, &outputs, &Options::default(), &mut |_| {}).unwrap_err();
    let message = e.to_string();
    // Found when file 4 is first read: as a halo of tile 0 or 1, or as its own tile.
    assert!(
        matches!(
            e,
            SurveyError::OutsideBounds { .. } | SurveyError::Stopped { .. }
        ),
        "{message}"
    );
    assert!(
        message.contains("tile4.las: point") && message.contains("outside the bounds"),
        "{message}"
    );
    assert!(!outputs[4].exists());
    let bad = Input {
        lo: [1.0; 3],
        hi: [0.0; 3],
        ..plan.inputs()[0].clone()
    };
    assert!(
        Plan::new(vec![bad])
            .unwrap_err()
            .to_string()
            .contains("not a box")
    );
}
