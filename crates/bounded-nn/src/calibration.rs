//! Calibration: whether a predicted probability means what it says. A reliability diagram
//! bins the predictions of one class by probability and compares each bin's mean probability
//! with how often the class is true there; the expected calibration error (ECE) is the mean
//! gap, weighted by the bins' counts.

use std::fmt::Write;

use bounded_geom::Class;

use crate::{
    BinaryConfusion, Classifier, Detector, ModelFile, N_CLASSES, NnError, Scores, TrainingCloud,
    class_at,
};

/// The decision rules [`Calibration`] scores and chooses from: the most probable class
/// (`None`), then the sensitivities a user would choose from, in steps of 0.1 (see
/// [`Detector::with_sensitivity`](crate::Detector::with_sensitivity)).
pub const DECISIONS: [Option<f32>; 10] = [
    None,
    Some(0.1),
    Some(0.2),
    Some(0.3),
    Some(0.4),
    Some(0.5),
    Some(0.6),
    Some(0.7),
    Some(0.8),
    Some(0.9),
];

/// How much more median MCC than the most probable class a sensitivity needs on the validation
/// clouds to become a model's default. On 30 clouds a few thousandths are chance: a model that
/// took sensitivity 0.6 for 0.0025 more scored 0.013-0.038 less with it than with the most
/// probable class on noisy generated clouds never trained on (docs/model.md, candidate WI).
pub const MARGIN: f64 = 0.01;

/// The sharp-edge confusion of one cloud's `probabilities` against its `truth` (class codes)
/// at each of `decisions` (sensitivities; `None`, the most probable class), from one
/// detection.
pub fn sweep(
    probabilities: &[[f32; N_CLASSES]],
    truth: &[u8],
    decisions: &[Option<f32>],
) -> Vec<BinaryConfusion> {
    let sharp = Class::Sharp as u8;
    decisions
        .iter()
        .map(|&s| {
            let mut c = BinaryConfusion::default();
            for (p, &t) in probabilities.iter().zip(truth) {
                let predicted = class_at(p, s) as u8 == sharp;
                match (t == sharp, predicted) {
                    (true, true) => c.tp += 1,
                    (false, true) => c.fp += 1,
                    (false, false) => c.tn += 1,
                    (true, false) => c.fn_ += 1,
                }
            }
            c
        })
        .collect()
}

/// One bin of a reliability diagram.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Bin {
    /// Predictions that fell in the bin.
    pub count: u64,
    /// Sum of their probabilities.
    pub probability_sum: f64,
    /// How many of them were of the class.
    pub positives: u64,
}

impl Bin {
    /// Mean predicted probability (0 for an empty bin).
    pub fn mean_probability(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.probability_sum / self.count as f64
        }
    }

    /// Observed frequency of the class (0 for an empty bin).
    pub fn frequency(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.positives as f64 / self.count as f64
        }
    }
}

/// A reliability diagram of equal-width probability bins, filled one prediction at a time
/// (so many clouds can go into one).
#[derive(Debug, Clone, PartialEq)]
pub struct Reliability {
    /// Bin `i` holds probabilities in `[i / n, (i + 1) / n)`; the last also holds 1.
    pub bins: Vec<Bin>,
}

impl Reliability {
    /// An empty diagram of `bins` bins (at least 1).
    pub fn new(bins: usize) -> Self {
        Self {
            bins: vec![Bin::default(); bins.max(1)],
        }
    }

    /// Adds one prediction: the class's `probability` and whether the point is of the class.
    /// Probabilities outside [0, 1] go to the nearest end bin; NaN is not counted.
    pub fn add(&mut self, probability: f32, positive: bool) {
        if probability.is_nan() {
            return;
        }
        let n = self.bins.len();
        let p = probability.clamp(0.0, 1.0);
        let bin = &mut self.bins[((p * n as f32) as usize).min(n - 1)];
        bin.count += 1;
        bin.probability_sum += f64::from(p);
        bin.positives += u64::from(positive);
    }

    /// Predictions counted.
    pub fn count(&self) -> u64 {
        self.bins.iter().map(|b| b.count).sum()
    }

    /// Expected calibration error: the bins' gaps between mean probability and frequency,
    /// weighted by their counts (0 for no predictions).
    pub fn expected_calibration_error(&self) -> f64 {
        let total = self.count();
        if total == 0 {
            return 0.0;
        }
        (self.bins.iter())
            .map(|b| b.count as f64 * (b.mean_probability() - b.frequency()).abs())
            .sum::<f64>()
            / total as f64
    }

    /// The diagram as a Markdown table (non-empty bins).
    pub fn table(&self) -> String {
        let n = self.bins.len() as f64;
        let mut out = String::from(
            "| probability | points | mean probability | observed frequency |\n|---|---|---|---|\n",
        );
        for (i, b) in self.bins.iter().enumerate().filter(|(_, b)| b.count > 0) {
            let _ = writeln!(
                out,
                "| {:.2}-{:.2} | {} | {:.3} | {:.3} |",
                i as f64 / n,
                (i + 1) as f64 / n,
                b.count,
                b.mean_probability(),
                b.frequency()
            );
        }
        out
    }
}

/// A detector's probabilities over labelled clouds: reliability diagrams of `p_sharp` and
/// `p_boundary`, and the sharp-edge confusions at every one of [`DECISIONS`], per cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// `p_sharp` against the sharp labels, all clouds.
    pub sharp: Reliability,
    /// `p_boundary` against the boundary labels, all clouds.
    pub boundary: Reliability,
    /// Per cloud, the confusion at each of [`DECISIONS`].
    pub sweeps: Vec<Vec<BinaryConfusion>>,
}

impl Calibration {
    /// Runs `detector` over `clouds` once each.
    pub fn measure(detector: &Detector, clouds: &[TrainingCloud<'_>]) -> Result<Self, NnError> {
        let mut calibration = Self {
            sharp: Reliability::new(10),
            boundary: Reliability::new(10),
            sweeps: Vec::with_capacity(clouds.len()),
        };
        for c in clouds {
            let detection = detector.detect(c.cloud).map_err(|e| NnError::Cloud {
                name: c.name.to_string(),
                source: Box::new(e),
            })?;
            let truth = Class::codes(c.labels);
            for (p, &t) in detection.probabilities.iter().zip(&truth) {
                calibration.sharp.add(p[1], t == Class::Sharp as u8);
                calibration.boundary.add(p[2], t == Class::Boundary as u8);
            }
            (calibration.sweeps).push(sweep(&detection.probabilities, &truth, &DECISIONS));
        }
        Ok(calibration)
    }

    /// Median sharp-edge MCC over the clouds at each of [`DECISIONS`].
    pub fn median_mcc(&self) -> Vec<f64> {
        (0..DECISIONS.len())
            .map(|i| {
                let at: Vec<_> = self.sweeps.iter().map(|s| s[i]).collect();
                Scores::median(&at).map_or(0.0, |s| s.mcc)
            })
            .collect()
    }

    /// The sensitivity of the highest median MCC (the first of equals) if it beats the most
    /// probable class by more than [`MARGIN`], else the most probable class: what training
    /// records in a model file measured on validation clouds (`ModelFile::sensitivity`).
    pub fn chosen_sensitivity(&self) -> Option<f32> {
        let mcc = self.median_mcc();
        let best = (1..mcc.len()).fold(1, |b, i| if mcc[i] > mcc[b] { i } else { b });
        if mcc[best] > mcc[0] + MARGIN {
            DECISIONS[best]
        } else {
            None
        }
    }
}

/// A decision rule in words: "sensitivity 0.6", or "the most probable class" for `None`.
pub fn describe(sensitivity: Option<f32>) -> String {
    sensitivity.map_or("the most probable class".into(), |s| {
        format!("sensitivity {s}")
    })
}

/// `file` deciding by the rule [`Calibration::chosen_sensitivity`] picks on the labelled
/// `validation` clouds, as training records it, with the measurement it was
/// chosen on; without clouds, by the most probable class. The clouds must be the training
/// kinds but never trained on, nor evaluated on: the choice is the model's default for every
/// user.
pub fn with_chosen_sensitivity(
    file: ModelFile,
    validation: &[TrainingCloud<'_>],
) -> Result<(ModelFile, Calibration), NnError> {
    let detector = Detector::new(Classifier::from_file(file.clone())?)?.most_probable_class();
    let calibration = Calibration::measure(&detector, validation)?;
    let file = file.with_sensitivity(calibration.chosen_sensitivity())?;
    Ok((file, calibration))
}

/// The bench's calibration section, in Markdown: the expected calibration errors and the
/// p_sharp reliability of `on_validation` (the measurement the decision of `detector` was
/// chosen on, over the clouds `validation` names), that decision, and the median sharp MCC
/// against the sensitivity on the validation clouds and on each of the named `sets`.
pub fn section(
    detector: &Detector,
    validation: &str,
    on_validation: Calibration,
    sets: &[(&str, Vec<TrainingCloud<'_>>)],
) -> Result<String, NnError> {
    let mut out = format!(
        "## Calibration and sensitivity\n\nValidation clouds ({validation}, training noise): \
         expected calibration error of p_sharp {:.4}, of p_boundary {:.4}; the model's default \
         decision, {} (the most probable class unless a sensitivity beats its median sharp MCC \
         by more than {MARGIN}; every table above; `--sensitivity` overrides it).\n\n\
         p_sharp reliability on them:\n\n{}\nMedian sharp MCC against `--sensitivity`:\n\n",
        on_validation.sharp.expected_calibration_error(),
        on_validation.boundary.expected_calibration_error(),
        describe(detector.sensitivity()),
        on_validation.sharp.table()
    );
    let mut rows = vec![("validation", on_validation)];
    for (name, clouds) in sets {
        rows.push((name, Calibration::measure(detector, clouds)?));
    }
    out.push_str(&sensitivity_table(&rows));
    Ok(out)
}

/// Markdown table of the median sharp MCC of each named calibration at every one of
/// [`DECISIONS`], one row each.
pub fn sensitivity_table(rows: &[(&str, Calibration)]) -> String {
    let mut out = String::from("| set |");
    for s in DECISIONS {
        match s {
            None => out.push_str(" most probable |"),
            Some(s) => {
                let _ = write!(out, " {s} |");
            }
        }
    }
    let _ = writeln!(out, "\n|---|{}", "---|".repeat(DECISIONS.len()));
    for (name, c) in rows {
        let _ = write!(out, "| {name} |");
        for mcc in c.median_mcc() {
            let _ = write!(out, " {mcc:.3} |");
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_error() {
        let mut r = Reliability::new(10);
        // Bins 0, 1, 8 and 9 get one prediction each: gaps 0.05, 0.85, 0.85, 0.05.
        for (p, positive) in [(0.05, false), (0.15, true), (0.85, false), (0.95, true)] {
            r.add(p, positive);
        }
        assert_eq!(r.count(), 4);
        assert!((r.expected_calibration_error() - 0.45).abs() < 1e-6);
        assert_eq!(r.bins[1].frequency(), 1.0);
        assert!((r.bins[8].mean_probability() - 0.85).abs() < 1e-6);
        // Ends: 1 in the last bin, out-of-range values clamped, NaN left out.
        r.add(1.0, true);
        r.add(-0.5, false);
        r.add(f32::NAN, true);
        assert_eq!((r.bins[9].count, r.bins[0].count, r.count()), (2, 2, 6));
    }

    #[test]
    fn sweep_counts_by_hand() {
        // Truth: sharp, sharp, non-edge, boundary.
        let p = [
            [0.3, 0.7, 0.0],
            [0.6, 0.4, 0.0],
            [0.8, 0.2, 0.0],
            [0.1, 0.5, 0.4],
        ];
        let truth = [1, 1, 0, 2];
        let at = sweep(&p, &truth, &[Some(0.35), Some(0.65), Some(0.9), None]);
        // 0.35: threshold 0.65, only the first is sharp.
        assert_eq!((at[0].tp, at[0].fp, at[0].tn, at[0].fn_), (1, 0, 2, 1));
        // 0.65: threshold 0.35: the first, second and fourth (0.5 >= 0.4).
        assert_eq!((at[1].tp, at[1].fp, at[1].tn, at[1].fn_), (2, 1, 1, 0));
        // 0.9: threshold 0.1: all four.
        assert_eq!((at[2].tp, at[2].fp, at[2].tn, at[2].fn_), (2, 2, 0, 0));
        // Most probable class: the first and the fourth.
        assert_eq!((at[3].tp, at[3].fp, at[3].tn, at[3].fn_), (1, 1, 1, 1));
    }

    /// A cloud of one sharp point and one other, scored perfectly (MCC 1).
    const PERFECT: BinaryConfusion = BinaryConfusion {
        tp: 1,
        fp: 0,
        tn: 1,
        fn_: 0,
    };

    /// The calibration of clouds with these confusions at each of [`DECISIONS`].
    fn of(sweeps: Vec<Vec<BinaryConfusion>>) -> Calibration {
        Calibration {
            sharp: Reliability::new(2),
            boundary: Reliability::new(2),
            sweeps,
        }
    }

    #[test]
    fn sensitivity_table_by_hand() {
        let all_sharp = BinaryConfusion {
            tp: 1,
            fp: 1,
            tn: 0,
            fn_: 0,
        };
        // At the lowest sensitivity the cloud is perfect (MCC 1), elsewhere all sharp (0).
        let mut at = vec![all_sharp; DECISIONS.len()];
        at[1] = PERFECT;
        let c = of(vec![at]);
        assert_eq!(c.chosen_sensitivity(), Some(0.1));
        let table = sensitivity_table(&[("a", c)]);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(
            lines[0],
            "| set | most probable | 0.1 | 0.2 | 0.3 | 0.4 | 0.5 | 0.6 | 0.7 | 0.8 | 0.9 |"
        );
        assert_eq!(lines[1], format!("|---|{}", "---|".repeat(10)));
        let zeros = " 0.000 |".repeat(8);
        assert_eq!(lines[2], format!("| a | 0.000 | 1.000 |{zeros}"));
        assert_eq!(lines.len(), 3);
    }

    #[test]
    fn the_most_probable_class_wins_ties_and_medians_decide() {
        let none = BinaryConfusion {
            tp: 0,
            fp: 0,
            tn: 1,
            fn_: 1,
        };
        // Every decision perfect: the most probable class is kept.
        assert_eq!(of(vec![vec![PERFECT; 10]]).chosen_sensitivity(), None);
        // Sensitivity 0.7 perfect on two clouds of three, the most probable class on one:
        // the median picks 0.7.
        let mut a = vec![none; 10];
        a[7] = PERFECT;
        let mut b = vec![none; 10];
        b[0] = PERFECT;
        let c = of(vec![a.clone(), a, b]);
        assert_eq!(c.median_mcc()[7], 1.0);
        assert_eq!(c.chosen_sensitivity(), Some(0.7));
    }

    #[test]
    fn a_sensitivity_needs_the_margin() {
        let confusion = |tp, fp, tn, fn_| BinaryConfusion { tp, fp, tn, fn_ };
        // MCC (90 * 890 - 10 * 10) / sqrt(100 * 100 * 900 * 900) = 80000 / 90000.
        let argmax = confusion(90, 10, 890, 10);
        // (91 * 890 - 10 * 9) / sqrt(101 * 100 * 900 * 899) = 80900 / 90398.6: 0.0060 more.
        let slightly = confusion(91, 10, 890, 9);
        // (95 * 895 - 5 * 5) / sqrt(100 * 100 * 900 * 900) = 85000 / 90000: 0.0556 more.
        let clearly = confusion(95, 5, 895, 5);
        let mut at = vec![argmax; DECISIONS.len()];
        at[6] = slightly;
        let c = of(vec![at.clone()]);
        assert!((c.median_mcc()[0] - 80000.0 / 90000.0).abs() < 1e-12);
        assert!((c.median_mcc()[6] - 0.894925).abs() < 1e-6);
        assert_eq!(c.chosen_sensitivity(), None);
        at[3] = clearly;
        assert_eq!(of(vec![at]).chosen_sensitivity(), Some(0.3));
    }

    #[test]
    fn calibrated_predictions_have_no_error() {
        let mut r = Reliability::new(5);
        // 10 predictions of 0.3, 3 of them right; 4 of 0.75, 3 of them right.
        for i in 0..10 {
            r.add(0.3, i < 3);
        }
        for i in 0..4 {
            r.add(0.75, i < 3);
        }
        assert!(r.expected_calibration_error() < 1e-6, "{r:?}");
        assert_eq!(Reliability::new(0).bins.len(), 1);
        assert_eq!(Reliability::new(3).expected_calibration_error(), 0.0);
        assert!(
            r.table().contains("| 0.20-0.40 | 10 | 0.300 | 0.300 |"),
            "{}",
            r.table()
        );
    }
}
