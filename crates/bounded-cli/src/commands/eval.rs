//! `bounded eval`: scores of a model on labelled clouds, per model and as medians, with the
//! published peers on the same models.

use crate::cli::{EvalArgs, PositiveArg};
use crate::{pipeline, progress};
use anyhow::{Context, Result};
use bounded_data::LabelledCloud;
use bounded_data::dataset::{self, Role};
use bounded_data::peers::{self, PeerResult};
use bounded_geom::Class;
use bounded_nn::{BinaryConfusion, ConfusionMatrix, Detector, Scores};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// One evaluated cloud.
pub struct ModelResult {
    /// Cloud name (file stem).
    pub name: String,
    /// 3-class confusion (rows truth, columns prediction).
    pub matrix: ConfusionMatrix,
}

/// A method's per-model confusions, for tables and plots.
pub struct MethodResults {
    /// Method name as shown.
    pub name: String,
    /// What it counted as positive.
    pub positive: String,
    /// (model, confusion) in table order.
    pub models: Vec<(String, BinaryConfusion)>,
}

impl MethodResults {
    /// Median scores over the models.
    pub fn median(&self) -> Option<Scores> {
        let confusions: Vec<_> = self.models.iter().map(|m| m.1).collect();
        Scores::median(&confusions)
    }
}

/// Reads the labelled evaluation clouds of `dir` (the evaluation role, or every cloud).
pub fn load_set(dir: &Path, smooth_edge: Class) -> Result<Vec<(String, LabelledCloud)>> {
    let bar = progress::bar("load", 0, "clouds");
    let clouds = dataset::load(dir, &[Role::Evaluation], smooth_edge, &mut |done, all| {
        bar.set_length(all as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(clouds?)
}

/// Classifies every cloud and compares with its labels.
pub fn evaluate(
    detector: &Detector,
    clouds: &[(String, LabelledCloud)],
) -> Result<Vec<ModelResult>> {
    let bar = progress::bar("evaluate", clouds.len() as u64, "clouds");
    let results = clouds
        .iter()
        .map(|(name, labelled)| {
            let detection =
                pipeline::detect(detector, &labelled.cloud, false).with_context(|| name.clone())?;
            let truth = Class::codes(&labelled.labels);
            bar.inc(1);
            Ok(ModelResult {
                name: name.clone(),
                matrix: ConfusionMatrix::from_labels(&truth, &detection.codes())?,
            })
        })
        .collect();
    bar.finish_and_clear();
    results
}

/// Our results as a method, with `positive` as the positive class.
pub fn as_method(name: &str, results: &[ModelResult], positive: Class) -> MethodResults {
    MethodResults {
        name: name.to_string(),
        positive: positive.name().to_string(),
        models: results
            .iter()
            .map(|r| (r.name.clone(), r.matrix.binary(positive as u8)))
            .collect(),
    }
}

/// The published methods of `dataset`, restricted to the models in `models`, in file order.
pub fn peer_methods(peers: &[PeerResult], dataset: &str, models: &[String]) -> Vec<MethodResults> {
    let mut methods: Vec<MethodResults> = Vec::new();
    for peer in peers.iter().filter(|p| p.dataset == dataset) {
        if !models.contains(&peer.model) {
            continue;
        }
        let confusion = BinaryConfusion {
            tp: peer.tp,
            fp: peer.fp,
            tn: peer.tn,
            fn_: peer.fn_,
        };
        match methods.iter_mut().find(|m| m.name == peer.description) {
            Some(m) => m.models.push((peer.model.clone(), confusion)),
            None => methods.push(MethodResults {
                name: peer.description.clone(),
                positive: peer.gt_positive.clone(),
                models: vec![(peer.model.clone(), confusion)],
            }),
        }
    }
    methods
}

/// Markdown table of per-model scores of one method, with the median row.
pub fn per_model_table(method: &MethodResults) -> String {
    let mut out = String::from(
        "| model | precision | recall | MCC | F1 | accuracy | IoU |\n|---|---|---|---|---|---|---|\n",
    );
    let row = |out: &mut String, name: &str, s: &Scores| {
        let _ = writeln!(
            out,
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            s.precision, s.recall, s.mcc, s.f1, s.accuracy, s.iou
        );
    };
    for (name, confusion) in &method.models {
        row(&mut out, name, &confusion.scores());
    }
    if let Some(median) = method.median() {
        row(&mut out, "**median**", &median);
    }
    out
}

/// Markdown table of the median scores of several methods, side by side.
pub fn medians_table(methods: &[MethodResults]) -> String {
    let mut out = String::from(
        "| method | positive | models | precision | recall | MCC | F1 | accuracy | IoU |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for m in methods {
        if let Some(s) = m.median() {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                m.name,
                m.positive,
                m.models.len(),
                s.precision,
                s.recall,
                s.mcc,
                s.f1,
                s.accuracy,
                s.iou
            );
        }
    }
    out
}

/// The 3-class confusion summed over `results`.
pub fn pooled(results: &[ModelResult]) -> ConfusionMatrix {
    let mut total = ConfusionMatrix::default();
    for r in results {
        total.add(&r.matrix);
    }
    total
}

/// Markdown table of the 3-class confusion summed over `results` (rows truth).
pub fn confusion_table(results: &[ModelResult]) -> String {
    let total = pooled(results);
    let mut out =
        String::from("| truth \\ predicted | non-edge | sharp | boundary |\n|---|---|---|---|\n");
    for class in Class::ALL {
        let row = total.counts[class as usize];
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} |",
            class.name(),
            row[0],
            row[1],
            row[2]
        );
    }
    out
}

pub fn run(args: &EvalArgs) -> Result<()> {
    let start = Instant::now();
    let detector = pipeline::detector(args.model.as_deref(), args.scales.as_deref(), args.fast)?;
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
    let ours = as_method("BoundED-rs", &results, positive);
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
        "{} clouds, {points} points, {:.1} s",
        clouds.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
