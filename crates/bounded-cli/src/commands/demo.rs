//! `bounded demo`: no files needed. A generated scene with creases, smooth parts and
//! boundaries is labelled by the embedded model and scored against its exact labels.

use super::rate;
use crate::cli::DemoArgs;
use crate::pipeline;
use anyhow::{Context, Result};
use bounded_data::format;
use bounded_data::picture::{View, render_classes};
use bounded_data::synth::{DEMO_SHAPES, demo_scene};
use bounded_data::table::{Column, PointTable, Property};
use bounded_geom::Class;
use bounded_nn::ConfusionMatrix;

pub fn run(args: &DemoArgs) -> Result<()> {
    let scene = demo_scene(args.seed)?;
    let detection = pipeline::detect(
        &pipeline::detector(&Default::default())?,
        &scene.cloud,
        true,
    )?;

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
        DEMO_SHAPES.len(),
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
