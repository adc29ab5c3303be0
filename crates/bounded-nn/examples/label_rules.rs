//! How well the embedded model's `p_sharp` separates the free-form generator's sharp labels,
//! for a grid of label rules (`LabelRule`: smallest depth, smallest angle, band half-width):
//! per rule, over the same generated clouds (the rule changes labels, not geometry), the
//! median sharp fraction, ROC AUC of `p_sharp`, MCC at the argmax and the best MCC over
//! thresholds (a ceiling for information, never a setting). Rules whose labels the features
//! rank well are the ones a model can be trained on.
//!
//! `cargo run --release -p bounded-nn --example label_rules -- [clouds] [seed] [model] [noise]
//! [per-noise]` (default 12 clouds of seed 2004, the training-side free-form validation seed,
//! with the training noise along the normal; the embedded model unless a model file is given,
//! `-` for the embedded one; `noise`: comma-separated levels in spacings instead of the
//! training's, `-` for those; `per-noise`: every rule's `min_depth_per_noise`, default 0).

use bounded_data::synth::{LabelRule, SetConfig, SetKind, generate, recipe};
use bounded_geom::Class;
use bounded_nn::Detector;
use bounded_nn::metrics::{BinaryConfusion, median};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let clouds: usize = args.next().map_or(Ok(12), |a| a.parse())?;
    let seed: u64 = args.next().map_or(Ok(2004), |a| a.parse())?;
    let detector = match args.next() {
        Some(path) if path != "-" => Detector::load(path)?,
        _ => Detector::embedded()?,
    };
    let noise: Vec<f64> = match args.next() {
        Some(levels) if levels != "-" => (levels.split(','))
            .map(str::parse)
            .collect::<Result<_, _>>()?,
        _ => recipe::TRAINING_NOISE.to_vec(),
    };
    let min_depth_per_noise: f64 = args.next().map_or(Ok(0.0), |a| a.parse())?;
    println!("| min depth | min angle | band | sharp % | AUC | MCC argmax | best MCC (at) |");
    println!("|---|---|---|---|---|---|---|");
    for band in [0.5, 1.0] {
        for min_angle in [10.0, 20.0, 30.0] {
            for min_depth in [0.25, 0.5, 1.0, 2.0] {
                let mut config = SetConfig::new(SetKind::Freeform, seed, clouds)
                    .with_noise(Some(&noise), recipe::TRAINING_NOISE_ALONG)?;
                config.label_rule = LabelRule {
                    min_angle,
                    min_depth,
                    band,
                    min_depth_per_noise,
                };
                config.validate()?;
                let (mut share, mut auc, mut argmax, mut best, mut at) =
                    (vec![], vec![], vec![], vec![], vec![]);
                for (_, labelled) in generate(&config)? {
                    let sharp: Vec<bool> = (labelled.labels.iter())
                        .map(|&c| c == Class::Sharp)
                        .collect();
                    let positives = sharp.iter().filter(|&&s| s).count();
                    if positives == 0 || positives == sharp.len() {
                        continue;
                    }
                    let d = detector.detect(&labelled.cloud)?;
                    let p: Vec<f32> = d.probabilities.iter().map(|p| p[1]).collect();
                    share.push(100.0 * positives as f64 / sharp.len() as f64);
                    auc.push(roc_auc(&p, &sharp));
                    let found: Vec<bool> = d.classes.iter().map(|&c| c == Class::Sharp).collect();
                    argmax.push(mcc(&sharp, &found)?);
                    let (m, t) = (1..20)
                        .map(|k| {
                            let t = k as f32 * 0.05;
                            let found: Vec<bool> = p.iter().map(|&v| v > t).collect();
                            (mcc(&sharp, &found).unwrap_or(0.0), t)
                        })
                        .fold((f64::MIN, 0.0), |a, b| if b.0 > a.0 { b } else { a });
                    best.push(m);
                    at.push(f64::from(t));
                }
                let m = |v: &[f64]| median(v).unwrap_or(f64::NAN);
                println!(
                    "| {min_depth} | {min_angle} | {band} | {:.1} | {:.3} | {:.3} | {:.3} ({:.2}) |",
                    m(&share),
                    m(&auc),
                    m(&argmax),
                    m(&best),
                    m(&at)
                );
            }
        }
    }
    Ok(())
}

/// Sharp MCC of `found` against `truth`.
fn mcc(truth: &[bool], found: &[bool]) -> Result<f64, bounded_nn::NnError> {
    let codes = |v: &[bool]| v.iter().map(|&b| u8::from(b)).collect::<Vec<_>>();
    Ok(BinaryConfusion::from_labels(&codes(truth), &codes(found), 1)?.mcc())
}

/// The probability that a random positive scores above a random negative (ties count half).
fn roc_auc(scores: &[f32], positive: &[bool]) -> f64 {
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]));
    let (mut rank_sum, mut i) = (0.0, 0);
    while i < order.len() {
        let mut j = i;
        while j < order.len() && scores[order[j]] == scores[order[i]] {
            j += 1;
        }
        // Ranks i+1..=j share their mean.
        let mean = (i + 1 + j) as f64 / 2.0;
        rank_sum += mean * order[i..j].iter().filter(|&&k| positive[k]).count() as f64;
        i = j;
    }
    let p = positive.iter().filter(|&&b| b).count() as f64;
    let n = scores.len() as f64 - p;
    (rank_sum - p * (p + 1.0) / 2.0) / (p * n)
}
