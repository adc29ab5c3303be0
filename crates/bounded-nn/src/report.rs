//! Evaluation reports: a detector's confusions on labelled clouds, per model and as the
//! medians over models that the paper's tables give, beside published methods, as Markdown.
//!
//! ```
//! use bounded_nn::BinaryConfusion;
//! use bounded_nn::report::{MethodResults, medians_table};
//!
//! let method = MethodResults {
//!     name: "ours".into(),
//!     positive: "sharp".into(),
//!     models: vec![("cube".into(), BinaryConfusion { tp: 1, fp: 1, tn: 2, fn_: 0 })],
//! };
//! let table = medians_table(&[method]);
//! assert!(table.ends_with("| ours | sharp | 1 | 0.500 | 1.000 | 0.577 | 0.667 | 0.750 | 0.500 |\n"));
//! ```

use std::fmt::Write;

use bounded_features::FeatureConfig;
use bounded_geom::{Class, PointCloud};

use crate::fit::{FeatureSet, Step, feature_set};
use crate::{
    BinaryConfusion, Classifier, ConfusionMatrix, Detector, NnError, Scores, TrainingCloud,
};

/// One evaluated cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelResult {
    /// Cloud name (file stem).
    pub name: String,
    /// 3-class confusion (rows truth, columns prediction).
    pub matrix: ConfusionMatrix,
}

/// A method's per-model confusions, for tables and plots.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodResults {
    /// Method name as shown.
    pub name: String,
    /// What it counted as positive.
    pub positive: String,
    /// (model, confusion) in table order.
    pub models: Vec<(String, BinaryConfusion)>,
}

impl MethodResults {
    /// (recall, precision) of every model, for a precision-recall plot.
    pub fn recall_precision(&self) -> Vec<(f64, f64)> {
        (self.models.iter())
            .map(|(_, c)| (c.recall(), c.precision()))
            .collect()
    }

    /// `results` as the method `name`, with `positive` the positive class.
    pub fn of(name: &str, results: &[ModelResult], positive: Class) -> Self {
        Self {
            name: name.to_string(),
            positive: positive.name().to_string(),
            models: (results.iter())
                .map(|r| (r.name.clone(), r.matrix.binary(positive as u8)))
                .collect(),
        }
    }

    /// Median scores over the models; `None` without models.
    pub fn median(&self) -> Option<Scores> {
        let confusions: Vec<_> = self.models.iter().map(|m| m.1).collect();
        Scores::median(&confusions)
    }

    /// The models whose truth holds the positive class, under `name`. A model without
    /// positives that the method leaves empty scores 1 on every measure, so in a set where
    /// many hold none (closed shapes in a boundary set) the median over all of them says more
    /// about the set's mix than about the method.
    pub fn with_positives(&self, name: &str) -> Self {
        Self {
            name: name.to_string(),
            positive: self.positive.clone(),
            models: (self.models.iter())
                .filter(|(_, c)| c.tp + c.fn_ > 0)
                .cloned()
                .collect(),
        }
    }
}

/// The median scores over `results` with `positive` the positive class; `None` without
/// results.
pub fn median_scores(results: &[ModelResult], positive: Class) -> Option<Scores> {
    MethodResults::of("", results, positive).median()
}

/// One published result: a method's confusion on one model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Published<'a> {
    /// The method's name as shown.
    pub method: &'a str,
    /// What it counted as positive.
    pub positive: &'a str,
    /// The model (cloud) name.
    pub model: &'a str,
    /// Its counts on that model.
    pub confusion: BinaryConfusion,
}

/// The published methods among `rows` on the models in `models`, each with its models in row
/// order, the methods in the order they first appear.
pub fn peer_methods<'a>(
    rows: impl IntoIterator<Item = Published<'a>>,
    models: &[String],
) -> Vec<MethodResults> {
    let mut methods: Vec<MethodResults> = Vec::new();
    for row in rows {
        if !models.iter().any(|m| m == row.model) {
            continue;
        }
        let model = (row.model.to_string(), row.confusion);
        match methods.iter_mut().find(|m| m.name == row.method) {
            Some(m) => m.models.push(model),
            None => methods.push(MethodResults {
                name: row.method.to_string(),
                positive: row.positive.to_string(),
                models: vec![model],
            }),
        }
    }
    methods
}

/// Classifies every cloud with `detector` and compares with its labels; calls
/// `progress(clouds done, clouds)` after each.
pub fn evaluate(
    detector: &Detector,
    clouds: &[TrainingCloud<'_>],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<ModelResult>, NnError> {
    let mut results = Vec::with_capacity(clouds.len());
    for c in clouds {
        let named = |source| NnError::Cloud {
            name: c.name.to_string(),
            source: Box::new(source),
        };
        let detection = detector.detect(c.cloud).map_err(named)?;
        let matrix = ConfusionMatrix::from_labels(&Class::codes(c.labels), &detection.codes())
            .map_err(named)?;
        results.push(ModelResult {
            name: c.name.to_string(),
            matrix,
        });
        progress(results.len(), clouds.len());
    }
    Ok(results)
}

/// A labelled cloud with its features computed once, at a configuration that holds those of
/// many models (the ablations': the nested neighbourhoods make a smaller configuration with
/// the same largest scale a subset of columns), so each is scored without a feature pass.
#[derive(Debug, Clone, PartialEq)]
pub struct FeaturedCloud {
    /// Its name.
    pub name: String,
    /// The points, for a detector (which computes its own features).
    pub cloud: PointCloud,
    /// One class per point.
    pub labels: Vec<Class>,
    /// The features and class codes of every point.
    pub features: FeatureSet,
}

impl FeaturedCloud {
    /// `cloud` with its features at `config`, reporting them to `progress`.
    pub fn new(
        name: String,
        cloud: PointCloud,
        labels: Vec<Class>,
        config: &FeatureConfig,
        progress: &mut dyn FnMut(Step<'_>),
    ) -> Result<Self, NnError> {
        let labelled = TrainingCloud {
            name: &name,
            cloud: &cloud,
            labels: &labels,
        };
        let features = feature_set(&[labelled], config, None, progress)?;
        Ok(Self {
            name,
            cloud,
            labels,
            features,
        })
    }

    /// The cloud as a labelled cloud, for [`evaluate`].
    pub fn labelled(&self) -> TrainingCloud<'_> {
        TrainingCloud {
            name: &self.name,
            cloud: &self.cloud,
            labels: &self.labels,
        }
    }

    /// The result of the one-stage `classifier` over the `columns` of the features (see
    /// [`crate::fit::columns`]).
    pub fn classify(
        &self,
        classifier: &Classifier,
        columns: &[usize],
    ) -> Result<ModelResult, NnError> {
        let predicted = classifier.classify(&self.features.select(columns).features)?;
        Ok(ModelResult {
            name: self.name.clone(),
            matrix: ConfusionMatrix::from_labels(&self.features.labels, &predicted)?,
        })
    }
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
    // The median over the models with positives, where some hold none.
    let holding = method.with_positives("");
    if holding.models.len() < method.models.len()
        && let Some(median) = holding.median()
    {
        let name = format!("**median of the {} with positives**", holding.models.len());
        row(&mut out, &name, &median);
    }
    out
}

/// Markdown table of the median scores of several methods, side by side (a method without
/// models is left out).
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
        let [non_edge, sharp, boundary] = total.counts[class as usize];
        let _ = writeln!(
            out,
            "| {} | {non_edge} | {sharp} | {boundary} |",
            class.name()
        );
    }
    out
}

/// `n` with thousands separators (1,045,348), for summaries.
pub fn grouped(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_are_separated() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(522_674), "522,674");
        assert_eq!(grouped(1_045_348), "1,045,348");
    }

    fn confusion(tp: u64, fp: u64, tn: u64, fn_: u64) -> BinaryConfusion {
        BinaryConfusion { tp, fp, tn, fn_ }
    }

    fn result(name: &str, counts: [[u64; 3]; 3]) -> ModelResult {
        ModelResult {
            name: name.into(),
            matrix: ConfusionMatrix { counts },
        }
    }

    #[test]
    fn per_model_rows_and_the_median_row() {
        // a: precision 1/2, recall 1, MCC 2 / sqrt(2 * 1 * 3 * 2) = 0.5774, F1 2/3, accuracy
        // 3/4, IoU 1/2. b: precision 1, recall 1/4, MCC 5 / sqrt(1 * 4 * 5 * 8) = 0.3953, F1
        // 2/5, accuracy 6/9, IoU 1/4. The median of two is their mean, score by score.
        let method = MethodResults {
            name: "m".into(),
            positive: "sharp".into(),
            models: vec![
                ("a".into(), confusion(1, 1, 2, 0)),
                ("b".into(), confusion(1, 0, 5, 3)),
            ],
        };
        let table = per_model_table(&method);
        let rows: Vec<&str> = table.lines().skip(2).collect();
        assert_eq!(
            rows,
            [
                "| a | 0.500 | 1.000 | 0.577 | 0.667 | 0.750 | 0.500 |",
                "| b | 1.000 | 0.250 | 0.395 | 0.400 | 0.667 | 0.250 |",
                "| **median** | 0.750 | 0.625 | 0.486 | 0.533 | 0.708 | 0.375 |",
            ]
        );
    }

    #[test]
    fn a_second_median_leaves_out_the_models_without_positives() {
        // c holds no positive and none is found: F1 1. The median of a (2/3), b (2/5) and c
        // is a's; without c it is (2/3 + 2/5) / 2 = 0.533, as in the table above.
        let method = MethodResults {
            name: "m".into(),
            positive: "boundary".into(),
            models: vec![
                ("a".into(), confusion(1, 1, 2, 0)),
                ("b".into(), confusion(1, 0, 5, 3)),
                ("c".into(), confusion(0, 0, 7, 0)),
            ],
        };
        assert!((method.median().unwrap().f1 - 2.0 / 3.0).abs() < 1e-12);
        let holding = method.with_positives("m, with positives");
        assert_eq!(holding.name, "m, with positives");
        assert_eq!(holding.positive, "boundary");
        assert_eq!(holding.models, method.models[..2]);
        let rows: Vec<String> = per_model_table(&method)
            .lines()
            .skip(5)
            .map(String::from)
            .collect();
        assert_eq!(
            rows,
            [
                "| **median** | 1.000 | 1.000 | 0.577 | 0.667 | 0.750 | 0.500 |",
                "| **median of the 2 with positives** | 0.750 | 0.625 | 0.486 | 0.533 | 0.708 | 0.375 |",
            ]
        );
        // Where every model holds positives, the table has one median row.
        assert_eq!(per_model_table(&holding).lines().count(), 5);
    }

    #[test]
    fn medians_side_by_side_without_empty_methods() {
        let ours = MethodResults::of(
            "ours",
            &[result("a", [[2, 1, 0], [0, 1, 0], [0, 0, 0]])],
            Class::Sharp,
        );
        assert_eq!(ours.models, [("a".to_string(), confusion(1, 1, 2, 0))]);
        let empty = MethodResults {
            name: "none".into(),
            positive: "sharp".into(),
            models: vec![],
        };
        let table = medians_table(&[ours, empty]);
        assert_eq!(table.lines().count(), 3, "{table}");
        assert!(
            table.ends_with(
                "| ours | sharp | 1 | 0.500 | 1.000 | 0.577 | 0.667 | 0.750 | 0.500 |\n"
            )
        );
    }

    #[test]
    fn pooled_confusion_sums_the_models() {
        let results = [
            result("a", [[5, 1, 0], [2, 3, 0], [0, 0, 1]]),
            result("b", [[1, 0, 2], [0, 4, 0], [1, 0, 0]]),
        ];
        assert_eq!(pooled(&results).counts, [[6, 1, 2], [2, 7, 0], [1, 0, 1]]);
        // Sharp: a has tp 3, fn 2, fp 1 and b tp 4, fn 0, fp 0: recalls 0.6 and 1.
        let median = median_scores(&results, Class::Sharp).unwrap();
        assert!((median.recall - 0.8).abs() < 1e-12, "{median:?}");
        assert_eq!(median_scores(&[], Class::Sharp), None);
        let table = confusion_table(&results);
        let rows: Vec<&str> = table.lines().skip(2).collect();
        assert_eq!(
            rows,
            [
                "| non-edge | 6 | 1 | 2 |",
                "| sharp | 2 | 7 | 0 |",
                "| boundary | 1 | 0 | 1 |"
            ]
        );
    }

    #[test]
    fn published_rows_grouped_by_method_on_the_given_models() {
        let row = |method, model, tp| Published {
            method,
            positive: "sharp+smooth",
            model,
            confusion: confusion(tp, 0, 0, 0),
        };
        let rows = [
            row("X", "a", 1),
            row("Y", "a", 2),
            row("X", "c", 3),
            row("X", "b", 4),
        ];
        let methods = peer_methods(rows, &["a".to_string(), "b".to_string()]);
        let got: Vec<(&str, Vec<(&str, u64)>)> = (methods.iter())
            .map(|m| {
                (
                    m.name.as_str(),
                    m.models.iter().map(|(n, c)| (n.as_str(), c.tp)).collect(),
                )
            })
            .collect();
        assert_eq!(
            got,
            [("X", vec![("a", 1), ("b", 4)]), ("Y", vec![("a", 2)])]
        );
        assert_eq!(methods[0].positive, "sharp+smooth");
    }

    #[test]
    fn a_featured_cloud_scores_a_smaller_configuration_on_its_columns() {
        use bounded_features::{FeatureGroups, extract};
        // A folded sheet: a crease along x = 0.
        let positions: Vec<[f64; 3]> = (0..30 * 30)
            .map(|i| {
                let (u, v) = ((i % 30) as f64 - 15.0, (i / 30) as f64);
                if u < 0.0 { [u, v, 0.0] } else { [0.0, v, u] }
            })
            .collect();
        let cloud = PointCloud::from_f64(&positions).unwrap();
        let labels: Vec<Class> = (0..positions.len())
            .map(|i| [Class::NonEdge, Class::Sharp][usize::from(i % 30 == 15)])
            .collect();
        let full = FeatureConfig {
            scales: vec![32, 16, 8],
            groups: FeatureGroups::ALL,
            ..FeatureConfig::default()
        };
        let featured = FeaturedCloud::new(
            "fold".into(),
            cloud.clone(),
            labels.clone(),
            &full,
            &mut |_| {},
        )
        .unwrap();
        let target = FeatureConfig {
            scales: vec![32, 8],
            groups: FeatureGroups::BOUNDED,
            ..FeatureConfig::default()
        };
        let columns = crate::fit::columns(&full, &target).unwrap();
        let classifier = Classifier::from_file(crate::file::tests::random_file(2, 12, 3)).unwrap();
        let result = featured.classify(&classifier, &columns).unwrap();

        let direct = extract(&cloud, &target).unwrap();
        assert_eq!(
            featured.features.select(&columns).features,
            direct.as_slice()
        );
        let predicted = classifier.classify(direct.as_slice()).unwrap();
        let matrix = ConfusionMatrix::from_labels(&Class::codes(&labels), &predicted).unwrap();
        assert_eq!(
            result,
            ModelResult {
                name: "fold".into(),
                matrix
            }
        );
        assert_eq!(featured.labelled().labels, labels);
    }
}
