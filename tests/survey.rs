//! `bounded detect` on the tiles of a survey: tile by tile with halos, the outputs hold the
//! labels and probabilities of the survey labelled as one cloud, bit for bit.

mod common;

use bounded_data::format;
use bounded_data::table::PointTable;
use bounded_geom::PointCloud;
use bounded_nn::Detector;
use common::{bounded_paths, box_cloud, stderr};

#[test]
fn tiles_get_the_labels_of_the_survey_as_one_cloud() {
    // A box cut into a 2 x 2 grid of LAS tiles across its faces.
    let cloud = box_cloud(6000, 5).cloud;
    let all: Vec<[f64; 3]> = (0..cloud.len()).map(|i| cloud.position_f64(i)).collect();
    let mid = |a: usize| {
        let (lo, hi) = all
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[a]), h.max(p[a])));
        0.5 * (lo + hi)
    };
    let (mx, my) = (mid(0), mid(1));
    let dir = tempfile::tempdir().unwrap();
    let mut inputs = Vec::new();
    let mut union = Vec::new();
    for cell in 0..4 {
        let points: Vec<[f64; 3]> = (all.iter())
            .filter(|p| usize::from(p[0] >= mx) + 2 * usize::from(p[1] >= my) == cell)
            .copied()
            .collect();
        let path = dir.path().join(format!("tile{cell}.las"));
        format::write(
            &path,
            &PointTable::new(PointCloud::from_f64(&points).unwrap()),
        )
        .unwrap();
        let table = format::read(&path).unwrap();
        let view = table.view();
        union.extend((0..table.len()).map(|i| view.position(i)));
        inputs.push(path);
    }
    let out = dir.path().join("out");
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"detect"];
    args.extend(inputs.iter().map(|p| p as &dyn AsRef<std::ffi::OsStr>));
    args.extend([
        &"-o" as &dyn AsRef<std::ffi::OsStr>,
        &out,
        &"--format",
        &"ply",
    ]);
    let run = bounded_paths(&args);
    let err = stderr(&run);
    assert!(run.status.success(), "{err}");
    assert!(
        err.contains("with halos") && err.contains("wrote 4 files to"),
        "{err}"
    );

    let whole = Detector::embedded()
        .unwrap()
        .detect(&PointCloud::from_f64(&union).unwrap())
        .unwrap();
    let mut first = 0;
    for input in &inputs {
        let table =
            format::read(&out.join(input.file_name().unwrap()).with_extension("ply")).unwrap();
        for (c, name) in ["scalar_p_nonedge", "scalar_p_sharp", "scalar_p_boundary"]
            .iter()
            .enumerate()
        {
            let column = table.property(name).unwrap();
            for i in 0..table.len() {
                let want = f64::from(whole.probabilities[first + i][c]);
                assert_eq!(
                    column.get_f64(i).to_bits(),
                    want.to_bits(),
                    "{name} of point {i}"
                );
            }
        }
        let class = table.property("scalar_class").unwrap();
        assert!(
            (0..table.len()).all(|i| class.get_f64(i) == f64::from(whole.classes[first + i] as u8))
        );
        first += table.len();
    }
    assert_eq!(first, all.len());
}

#[test]
fn a_file_in_blocks_is_written_as_the_file_labelled_whole() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("box.laz");
    format::write(&input, &PointTable::new(box_cloud(12_000, 3).cloud)).unwrap();
    let (whole, blocks) = (dir.path().join("whole.laz"), dir.path().join("blocks.laz"));
    let run = bounded_paths(&[&"detect", &input, &"-o", &whole]);
    assert!(run.status.success(), "{}", stderr(&run));
    let run = bounded_paths(&[
        &"detect",
        &input,
        &"-o",
        &blocks,
        &"--block-points",
        &"3000",
    ]);
    let err = stderr(&run);
    assert!(run.status.success() && err.contains("with halos"), "{err}");
    assert_eq!(
        format::read(&blocks).unwrap(),
        format::read(&whole).unwrap()
    );
    // Only LAS or LAZ is written in blocks, and that is said before any work.
    let ply = dir.path().join("blocks.ply");
    let run = bounded_paths(&[&"detect", &input, &"-o", &ply, &"--block-points", &"3000"]);
    let err = stderr(&run);
    assert!(
        !run.status.success() && err.contains("write .las or .laz"),
        "{err}"
    );
    assert!(!ply.exists());
}
