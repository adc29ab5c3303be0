//! `bounded eval`: scores of a model on labelled clouds, per model and as medians, with the
//! published peers on the same models.

use super::{evaluate, load_set, peer_methods};
use crate::cli::{EvalArgs, PositiveArg};
use crate::pipeline;
use anyhow::Result;
use bounded_data::peers;
use bounded_geom::Class;
use bounded_nn::calibration::describe;
use bounded_nn::report::{MethodResults, confusion_table, medians_table, per_model_table};
use std::time::Instant;

pub fn run(args: &EvalArgs) -> Result<()> {
    let start = Instant::now();
    let detector = pipeline::detector(&args.model)?;
    let smooth = if args.smooth_as_sharp {
        Class::Sharp
    } else {
        Class::NonEdge
    };
    let positive = match args.positive {
        PositiveArg::Sharp => Class::Sharp,
        PositiveArg::Boundary => Class::Boundary,
    };
    let clouds = load_set(&args.data, smooth)?;
    let results = evaluate(&detector, &clouds)?;
    let ours = MethodResults::of("BoundED-rs", &results, positive);
    println!("{}", per_model_table(&ours));
    println!("{}", confusion_table(&results));
    if let Some(path) = &args.peers {
        let dataset = args
            .data
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let models: Vec<String> = ours.models.iter().map(|m| m.0.clone()).collect();
        let peers = peer_methods(&peers::read(path)?, &dataset, &models);
        if peers.is_empty() {
            eprintln!(
                "note: {} has no published results for dataset {dataset:?}",
                path.display()
            );
        }
        let mut methods = vec![ours];
        methods.extend(peers);
        println!("{}", medians_table(&methods));
    }
    let points: usize = clouds.iter().map(|c| c.1.cloud.len()).sum();
    eprintln!(
        "{} clouds, {points} points, classes by {}, {:.1} s",
        clouds.len(),
        describe(detector.sensitivity()),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
