//! `bounded demo`: no files needed. A generated scene with creases, smooth parts and
//! boundaries is labelled by the embedded model and scored against its exact labels.

use super::rate;
use crate::cli::DemoArgs;
use crate::pipeline;
use anyhow::{Context, Result};
use bounded_data::LabelledCloud;
use bounded_data::format;
use bounded_data::picture::{View, render_classes};
use bounded_data::synth::{NoiseDirection, Sampling, ShapeKind, ShapeSpec, generate_shape};
use bounded_data::table::{Column, PointTable, Property};
use bounded_geom::{Class, PointCloud};
use bounded_nn::ConfusionMatrix;

/// The scene's shapes: creases and corners, a smooth torus, an open bowl (border and
/// smooth), a stair (concave and convex creases) and an open box (creases and borders).
const SCENE: [ShapeKind; 5] = [
    ShapeKind::FractalCube,
    ShapeKind::Torus,
    ShapeKind::Bowl,
    ShapeKind::Stairs,
    ShapeKind::OpenBox,
];

/// Generates the demo scene: the shapes side by side, each scaled to a unit box.
pub fn scene(seed: u64) -> Result<LabelledCloud> {
    let mut points = Vec::new();
    let mut labels = Vec::new();
    for (i, &kind) in SCENE.iter().enumerate() {
        let spec = ShapeSpec {
            kind,
            sampling: Sampling::Random,
            points: 16_000,
            noise: 0.1,
            noise_direction: NoiseDirection::Isotropic,
            outlier_fraction: 0.0,
            seed: seed.wrapping_mul(31).wrapping_add(i as u64),
        };
        let shape = generate_shape(&spec)?;
        let cloud = &shape.cloud;
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for j in 0..cloud.len() {
            let p = cloud.position_f64(j);
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let size = (0..3).map(|a| hi[a] - lo[a]).fold(1e-12, f64::max);
        for j in 0..cloud.len() {
            let p = cloud.position_f64(j);
            points.push([
                (p[0] - lo[0]) / size + 1.4 * i as f64,
                (p[1] - lo[1]) / size,
                (p[2] - lo[2]) / size,
            ]);
        }
        labels.extend_from_slice(&shape.labels);
    }
    Ok(LabelledCloud {
        cloud: PointCloud::from_f64(&points)?,
        labels,
    })
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let scene = scene(args.seed)?;
    let detection = pipeline::detect(&pipeline::detector(Default::default())?, &scene.cloud, true)?;

    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    let (ply, png) = (args.output.join("demo.ply"), args.output.join("demo.png"));
    let mut table = PointTable::new(scene.cloud.clone());
    let truth = Class::codes(&scene.labels);
    table.set_property(Property::new("truth", Column::U8(truth.clone())));
    format::write_annotated(&ply, &table, &detection.classes, &detection.probabilities)?;
    let view = View {
        azimuth: 20.0,
        elevation: 35.0,
    };
    render_classes(&scene.cloud, &detection.classes, view, 1600, 600).save_png(&png)?;

    let matrix = ConfusionMatrix::from_labels(&truth, &detection.codes())?;
    let n = scene.cloud.len();
    println!(
        "demo scene: {n} points ({} shapes), detection {:.2} s ({})",
        SCENE.len(),
        detection.elapsed.as_secs_f64(),
        rate(n, detection.elapsed.as_secs_f64())
    );
    for class in [Class::Sharp, Class::Boundary] {
        let s = matrix.binary(class as u8).scores();
        println!(
            "{:>9}: precision {:.3} recall {:.3} F1 {:.3} MCC {:.3} IoU {:.3}",
            class.name(),
            s.precision,
            s.recall,
            s.f1,
            s.mcc,
            s.iou
        );
    }
    println!("wrote {} and {}", ply.display(), png.display());
    Ok(())
}
