//! How the noisy ABC sample was made, and what that noise leaves to find: for each cloud
//! present in both a clean and a noisy PCEDNet directory (same points, same order), the
//! displacement of every point split along and across the file's normal (in units of the
//! clean median spacing; along it also its root mean square, in spacings and as a share of the
//! bounding box's diagonal, which tells whether the noise was scaled to the spacing or to the
//! object), and the MCC of two oracles that call a noisy point sharp when it
//! lies within `t` spacings of the exact crease line (the line through the two clean sharp
//! points nearest to it), `t` the best of a few: one measures that distance as it is, the
//! other across the point's true normal (the part along it dropped). The first knows the
//! creases only; the second knows the surface too, and since the noise moves points along
//! their normals, it sees the clean offsets. The normals are read only for this study, never
//! as features.
//!
//! `cargo run --release -p bounded-data --example noise_study -- \
//!     ../shared/datasets/pcednet/abc ../shared/datasets/pcednet/abc_noise_0.04`

use bounded_data::dataset::cloud_files;
use bounded_data::labels::{Convention, from_table, load};
use bounded_data::table::PointTable;
use bounded_data::{LabelledCloud, format};
use bounded_geom::vec3::{V3, cross, dot, norm, normalize, scale, sub};
use bounded_geom::{Class, KnnIndex};
use bounded_nn::{BinaryConfusion, median};
use std::path::{Path, PathBuf};

/// Neighbours searched for the clean sharp points nearest to a noisy point.
const K: usize = 32;
/// Oracle thresholds tried, in spacings.
const THRESHOLDS: [f64; 9] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: noise_study CLEAN_DIR NOISY_DIR";
    let clean_dir = PathBuf::from(args.next().ok_or(usage)?);
    let noisy_dir = PathBuf::from(args.next().ok_or(usage)?);
    println!(
        "| cloud | points | along normal, median / rms | rms along / diagonal | across normal | line oracle MCC (t) | line and normal oracle MCC (t) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let (mut line, mut line_and_normal) = (Vec::new(), Vec::new());
    for clean_path in cloud_files(&clean_dir)? {
        let noisy_path = noisy_dir.join(clean_path.file_name().ok_or("bad file name")?);
        if !noisy_path.exists() {
            continue;
        }
        let study = study(&clean_path, &noisy_path)?;
        println!(
            "| {} | {} | {:.3} / {:.3} | {:.5} | {:.3} | {:.3} ({}) | {:.3} ({}) |",
            clean_path.file_stem().unwrap_or_default().to_string_lossy(),
            study.points,
            study.along,
            study.rms_along,
            study.rms_along * study.spacing / study.diagonal,
            study.across,
            study.line.mcc,
            study.line.threshold,
            study.line_and_normal.mcc,
            study.line_and_normal.threshold
        );
        line.push(study.line.mcc);
        line_and_normal.push(study.line_and_normal.mcc);
    }
    println!(
        "median oracle MCC: {:.3} knowing the crease lines, {:.3} knowing the normals too",
        median(&line).unwrap_or(f64::NAN),
        median(&line_and_normal).unwrap_or(f64::NAN)
    );
    Ok(())
}

struct Study {
    points: usize,
    /// Median |displacement . normal| / spacing.
    along: f64,
    /// Root mean square of displacement . normal / spacing.
    rms_along: f64,
    /// The clean cloud's median nearest-neighbour distance.
    spacing: f64,
    /// The clean cloud's bounding-box diagonal.
    diagonal: f64,
    /// Median length of the displacement's rest / spacing.
    across: f64,
    line: Oracle,
    line_and_normal: Oracle,
}

/// The best MCC of "sharp when the offset from the crease is below `threshold`".
struct Oracle {
    mcc: f64,
    threshold: f64,
}

fn study(clean_path: &Path, noisy_path: &Path) -> Result<Study, Box<dyn std::error::Error>> {
    let table = format::read(clean_path)?;
    let normals = unit_normals(&table, clean_path)?;
    let clean = from_table(table, Convention::PCEDNET, clean_path)?;
    let noisy = load(noisy_path, Convention::PCEDNET)?;
    if clean.labels != noisy.labels {
        return Err(format!(
            "{}: labels differ from the clean cloud",
            noisy_path.display()
        )
        .into());
    }
    let (c, p) = (positions(&clean), positions(&noisy));
    let neighbours = neighbours(&clean)?;
    let nearest: Vec<f64> = (0..c.len())
        .map(|i| dist(c[i], c[neighbours[i * K + 1] as usize]))
        .collect();
    let spacing = median(&nearest).ok_or("empty cloud")?;
    let (mut along, mut across) = (Vec::new(), Vec::new());
    for (i, &n) in normals.iter().enumerate() {
        let d = sub(p[i], c[i]);
        let a = dot(d, n);
        along.push(a.abs() / spacing);
        across.push((dot(d, d) - a * a).max(0.0).sqrt() / spacing);
    }
    // The crease nearest to each noisy point, found once for both oracles.
    let creases: Vec<Crease> = (0..c.len())
        .map(|i| nearest_crease(&clean, &c, &neighbours[i * K..(i + 1) * K], p[i]))
        .collect();
    let oracle = |normal: &dyn Fn(usize) -> Option<V3>| {
        let offsets: Vec<f64> = (0..c.len())
            .map(|i| creases[i].offset(&c, p[i], normal(i)) / spacing)
            .collect();
        THRESHOLDS.iter().fold(
            Oracle {
                mcc: f64::NEG_INFINITY,
                threshold: 0.0,
            },
            |best, &threshold| {
                let mcc = mcc(&offsets, &clean.labels, threshold);
                if mcc > best.mcc {
                    Oracle { mcc, threshold }
                } else {
                    best
                }
            },
        )
    };
    Ok(Study {
        points: c.len(),
        along: median(&along).unwrap_or(f64::NAN),
        rms_along: (along.iter().map(|a| a * a).sum::<f64>() / along.len() as f64).sqrt(),
        spacing,
        diagonal: diagonal(&c),
        across: median(&across).unwrap_or(f64::NAN),
        line: oracle(&|_| None),
        line_and_normal: oracle(&|i| Some(normals[i])),
    })
}

/// The exact crease near a noisy point, as clean point indices.
enum Crease {
    /// No clean sharp point among the neighbours.
    None,
    /// One clean sharp point.
    Point(usize),
    /// The line through the two nearest clean sharp points.
    Line(usize, usize),
}

/// The crease through the clean sharp points of `neighbours` nearest to `q`.
fn nearest_crease(clean: &LabelledCloud, c: &[V3], neighbours: &[u32], q: V3) -> Crease {
    let mut sharp: Vec<(f64, usize)> = neighbours
        .iter()
        .map(|&j| j as usize)
        .filter(|&j| clean.labels[j] == Class::Sharp)
        .map(|j| (dist(q, c[j]), j))
        .collect();
    sharp.sort_by(|a, b| a.0.total_cmp(&b.0));
    match sharp[..] {
        [] => Crease::None,
        [(_, a)] => Crease::Point(a),
        [(_, a), (_, b), ..] => Crease::Line(a, b),
    }
}

impl Crease {
    /// Distance from `q` (infinite without a crease), measured across `normal` when one is
    /// given (its part along `normal` dropped first).
    fn offset(&self, c: &[V3], q: V3, normal: Option<V3>) -> f64 {
        let across = |v: V3| match normal {
            Some(n) => sub(v, scale(n, dot(v, n))),
            None => v,
        };
        match *self {
            Crease::None => f64::INFINITY,
            Crease::Point(a) => {
                let aq = across(sub(q, c[a]));
                dot(aq, aq).sqrt()
            }
            Crease::Line(a, b) => {
                let ab = sub(c[b], c[a]);
                let aq = across(sub(q, c[a]));
                let normal = cross(ab, aq);
                dot(normal, normal).sqrt() / dot(ab, ab).sqrt()
            }
        }
    }
}

/// MCC of "sharp when `offset < t`" against `labels`.
fn mcc(offsets: &[f64], labels: &[Class], t: f64) -> f64 {
    let mut counts = BinaryConfusion::default();
    for (&o, &l) in offsets.iter().zip(labels) {
        *match (l == Class::Sharp, o < t) {
            (true, true) => &mut counts.tp,
            (false, true) => &mut counts.fp,
            (false, false) => &mut counts.tn,
            (true, false) => &mut counts.fn_,
        } += 1;
    }
    counts.mcc()
}

/// The file's normals (`nx`, `ny`, `nz`), scaled to unit length.
fn unit_normals(table: &PointTable, path: &Path) -> Result<Vec<V3>, String> {
    let column = |name: &str| {
        table
            .property(name)
            .ok_or_else(|| format!("{}: no {name}", path.display()))
    };
    let (nx, ny, nz) = (column("nx")?, column("ny")?, column("nz")?);
    Ok((0..table.len())
        .map(|i| normalize([nx.get_f64(i), ny.get_f64(i), nz.get_f64(i)]))
        .collect())
}

/// The `K` nearest clean neighbours of every point, rows in cloud order.
fn neighbours(clean: &LabelledCloud) -> Result<Vec<u32>, Box<dyn std::error::Error>> {
    let index = KnnIndex::new(&clean.cloud)?;
    let mut rows = vec![0u32; clean.cloud.len() * K];
    index.for_each_chunk(K, 16_384, |chunk| {
        for (row, &query) in chunk.queries().iter().enumerate() {
            let query = query as usize;
            rows[query * K..(query + 1) * K].copy_from_slice(chunk.row(row));
        }
    })?;
    Ok(rows)
}

fn positions(labelled: &LabelledCloud) -> Vec<V3> {
    (0..labelled.cloud.len())
        .map(|i| labelled.cloud.position_f64(i))
        .collect()
}

/// The length of the diagonal of the points' axis-aligned bounding box.
fn diagonal(points: &[V3]) -> f64 {
    let extent = |axis: usize| {
        let values = points.iter().map(|p| p[axis]);
        values.clone().fold(f64::NEG_INFINITY, f64::max) - values.fold(f64::INFINITY, f64::min)
    };
    norm([extent(0), extent(1), extent(2)])
}

fn dist(a: V3, b: V3) -> f64 {
    norm(sub(a, b))
}
