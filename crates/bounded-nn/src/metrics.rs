//! Classification metrics: confusion counts, per-model scores and medians over models.
//!
//! Zero denominators (a model without positive points, or a prediction without any) are
//! defined, never NaN. The rule: a ratio whose denominator is 0 is 1 when the model made no
//! mistake of the kind the ratio measures, else 0. So a cloud without edges on which nothing is
//! predicted as edge scores 1 everywhere, and one where edges exist but none is predicted gets
//! precision 0, recall 0 and MCC 0.

use crate::{N_CLASSES, NnError};

/// Counts of a binary decision for one positive class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BinaryConfusion {
    /// Positive points predicted positive.
    pub tp: u64,
    /// Negative points predicted positive.
    pub fp: u64,
    /// Negative points predicted negative.
    pub tn: u64,
    /// Positive points predicted negative.
    pub fn_: u64,
}

impl BinaryConfusion {
    /// Counts from class codes, `positive` being the positive class and all others negative.
    pub fn from_labels(truth: &[u8], predicted: &[u8], positive: u8) -> Result<Self, NnError> {
        Ok(ConfusionMatrix::from_labels(truth, predicted)?.binary(positive))
    }

    /// Number of points counted.
    pub fn total(&self) -> u64 {
        self.tp + self.fp + self.tn + self.fn_
    }

    /// `tp / (tp + fp)`; with nothing predicted positive: 1 if there was nothing to find.
    pub fn precision(&self) -> f64 {
        ratio(self.tp, self.tp + self.fp, self.fn_ == 0)
    }

    /// `tp / (tp + fn)`; without positive points: 1 if none was predicted.
    pub fn recall(&self) -> f64 {
        ratio(self.tp, self.tp + self.fn_, self.fp == 0)
    }

    /// `2 tp / (2 tp + fp + fn)`, the harmonic mean of precision and recall; 0/0 gives 1.
    pub fn f1(&self) -> f64 {
        ratio(2 * self.tp, 2 * self.tp + self.fp + self.fn_, true)
    }

    /// Intersection over union of the positive class, `tp / (tp + fp + fn)`; 0/0 gives 1.
    pub fn iou(&self) -> f64 {
        ratio(self.tp, self.tp + self.fp + self.fn_, true)
    }

    /// `(tp + tn) / total`; an empty count gives 1.
    pub fn accuracy(&self) -> f64 {
        ratio(self.tp + self.tn, self.total(), true)
    }

    /// Matthews correlation coefficient. When a row or column of the confusion is empty the
    /// formula is 0/0: then 1 for an error-free prediction, else 0 (no better than chance).
    pub fn mcc(&self) -> f64 {
        let [tp, fp, tn, fn_] = [self.tp, self.fp, self.tn, self.fn_].map(|v| v as f64);
        let denominator = ((tp + fp) * (tp + fn_) * (tn + fp) * (tn + fn_)).sqrt();
        if denominator == 0.0 {
            return if self.fp == 0 && self.fn_ == 0 {
                1.0
            } else {
                0.0
            };
        }
        (tp * tn - fp * fn_) / denominator
    }

    /// All six scores.
    pub fn scores(&self) -> Scores {
        Scores {
            precision: self.precision(),
            recall: self.recall(),
            mcc: self.mcc(),
            f1: self.f1(),
            accuracy: self.accuracy(),
            iou: self.iou(),
        }
    }
}

fn ratio(numerator: u64, denominator: u64, error_free: bool) -> f64 {
    match denominator {
        0 if error_free => 1.0,
        0 => 0.0,
        d => numerator as f64 / d as f64,
    }
}

/// The scores of one model (or their medians over several).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scores {
    /// Precision of the positive class.
    pub precision: f64,
    /// Recall of the positive class.
    pub recall: f64,
    /// Matthews correlation coefficient.
    pub mcc: f64,
    /// F1 score of the positive class.
    pub f1: f64,
    /// Accuracy over all points.
    pub accuracy: f64,
    /// IoU of the positive class.
    pub iou: f64,
}

impl Scores {
    /// The median of every score over `models` (each score separately, as the paper's tables
    /// do); `None` without models.
    pub fn median(models: &[BinaryConfusion]) -> Option<Self> {
        let scores: Vec<Scores> = models.iter().map(BinaryConfusion::scores).collect();
        let of = |f: fn(&Scores) -> f64| median(&scores.iter().map(f).collect::<Vec<_>>());
        Some(Self {
            precision: of(|s| s.precision)?,
            recall: of(|s| s.recall)?,
            mcc: of(|s| s.mcc)?,
            f1: of(|s| s.f1)?,
            accuracy: of(|s| s.accuracy)?,
            iou: of(|s| s.iou)?,
        })
    }
}

/// Median of `values` (mean of the two middle values for an even count); `None` when empty.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some((sorted[n / 2 - 1] + sorted[n / 2]) / 2.0),
    }
}

/// Three-class confusion matrix, `counts[truth][predicted]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ConfusionMatrix {
    /// Number of points of true class `t` predicted as class `p`, at `[t][p]`.
    pub counts: [[u64; N_CLASSES]; N_CLASSES],
}

impl ConfusionMatrix {
    /// Counts from class codes of the same points.
    pub fn from_labels(truth: &[u8], predicted: &[u8]) -> Result<Self, NnError> {
        if truth.len() != predicted.len() {
            return Err(NnError::Shape(format!(
                "{} true labels but {} predictions",
                truth.len(),
                predicted.len()
            )));
        }
        let mut matrix = Self::default();
        for (&t, &p) in truth.iter().zip(predicted) {
            let (t, p) = (usize::from(t), usize::from(p));
            if t >= N_CLASSES || p >= N_CLASSES {
                return Err(NnError::Data(format!(
                    "class code {} is not 0, 1 or 2",
                    t.max(p)
                )));
            }
            matrix.counts[t][p] += 1;
        }
        Ok(matrix)
    }

    /// Adds another matrix's counts (e.g. to pool several models).
    pub fn add(&mut self, other: &Self) {
        for (row, other) in self.counts.iter_mut().zip(&other.counts) {
            for (c, o) in row.iter_mut().zip(other) {
                *c += o;
            }
        }
    }

    /// The binary counts for `positive` against all other classes.
    pub fn binary(&self, positive: u8) -> BinaryConfusion {
        let positive = usize::from(positive);
        let mut b = BinaryConfusion::default();
        for (t, row) in self.counts.iter().enumerate() {
            for (p, &count) in row.iter().enumerate() {
                match (t == positive, p == positive) {
                    (true, true) => b.tp += count,
                    (false, true) => b.fp += count,
                    (false, false) => b.tn += count,
                    (true, false) => b.fn_ += count,
                }
            }
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn scores_match_hand_computed_values() {
        let c = BinaryConfusion {
            tp: 6,
            fp: 2,
            tn: 10,
            fn_: 3,
        };
        assert!(close(c.precision(), 6.0 / 8.0));
        assert!(close(c.recall(), 6.0 / 9.0));
        assert!(close(c.f1(), 12.0 / 17.0));
        assert!(close(c.iou(), 6.0 / 11.0));
        assert!(close(c.accuracy(), 16.0 / 21.0));
        // (60 - 6) / sqrt(8 * 9 * 12 * 13) = 54 / sqrt(11232) = 0.509525...
        assert!(close(c.mcc(), 54.0 / 11232f64.sqrt()));
        assert!((c.mcc() - 0.509_525).abs() < 1e-6);
    }

    #[test]
    fn zero_denominators_are_defined() {
        // No edges anywhere, none predicted: perfect.
        let clean = BinaryConfusion {
            tn: 5,
            ..Default::default()
        };
        assert_eq!(
            clean.scores(),
            Scores {
                precision: 1.0,
                recall: 1.0,
                mcc: 1.0,
                f1: 1.0,
                accuracy: 1.0,
                iou: 1.0
            }
        );
        // Edges exist, none predicted.
        let blind = BinaryConfusion {
            tn: 5,
            fn_: 2,
            ..Default::default()
        };
        assert_eq!(
            (blind.precision(), blind.recall(), blind.mcc(), blind.f1()),
            (0.0, 0.0, 0.0, 0.0)
        );
        // No edges, some predicted.
        let noisy = BinaryConfusion {
            tn: 5,
            fp: 2,
            ..Default::default()
        };
        assert_eq!(
            (noisy.precision(), noisy.recall(), noisy.mcc()),
            (0.0, 0.0, 0.0)
        );
        // Everything positive and correct.
        let all = BinaryConfusion {
            tp: 3,
            ..Default::default()
        };
        assert_eq!(all.mcc(), 1.0);
    }

    #[test]
    fn confusion_matrix_collapses_to_binary() {
        let truth = [0, 0, 1, 1, 2, 2, 2];
        let pred = [0, 1, 1, 2, 2, 0, 2];
        let m = ConfusionMatrix::from_labels(&truth, &pred).unwrap();
        assert_eq!(m.counts, [[1, 1, 0], [0, 1, 1], [1, 0, 2]]);
        assert_eq!(
            m.binary(1),
            BinaryConfusion {
                tp: 1,
                fp: 1,
                tn: 4,
                fn_: 1
            }
        );
        assert_eq!(
            m.binary(2),
            BinaryConfusion {
                tp: 2,
                fp: 1,
                tn: 3,
                fn_: 1
            }
        );
        assert_eq!(
            BinaryConfusion::from_labels(&truth, &pred, 2).unwrap(),
            m.binary(2)
        );
        let mut twice = m;
        twice.add(&m);
        assert_eq!(twice.counts[2][2], 4);
        assert!(ConfusionMatrix::from_labels(&[0], &[0, 1]).is_err());
        assert!(ConfusionMatrix::from_labels(&[3], &[0]).is_err());
    }

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        let models = [
            BinaryConfusion {
                tp: 1,
                fp: 0,
                tn: 1,
                fn_: 0,
            },
            BinaryConfusion {
                tp: 0,
                fp: 1,
                tn: 0,
                fn_: 1,
            },
            BinaryConfusion {
                tp: 1,
                fp: 1,
                tn: 1,
                fn_: 1,
            },
        ];
        // Accuracies 1, 0, 0.5 -> median 0.5; MCCs 1, -1, 0 -> median 0.
        let m = Scores::median(&models).unwrap();
        assert_eq!((m.accuracy, m.mcc), (0.5, 0.0));
        assert!(Scores::median(&[]).is_none());
    }
}
