//! The covariance-analysis (CA) baseline of the paper's tables: a point is a sharp edge when
//! its surface variation `lambda_min / (lambda_1 + lambda_2 + lambda_3)` (the eigenvalues of
//! its neighbourhood's covariance, the `sigma` features) at one scale exceeds a threshold; the
//! scale and the threshold are the ones with the best MCC on a training set.

use bounded_features::{FeatureConfig, FeatureGroups};
use bounded_geom::Class;

use crate::fit::{FeatureSet, columns};
use crate::report::{FeaturedCloud, MethodResults};
use crate::{BinaryConfusion, NnError};

/// A fitted CA classifier (sharp edge or not).
#[derive(Debug, Clone, PartialEq)]
pub struct CaBaseline {
    /// The `sigma` columns of the chosen scale.
    column: [usize; 3],
    /// The chosen scale (neighbours).
    pub scale: usize,
    /// Sharp above this surface variation.
    pub threshold: f32,
}

impl CaBaseline {
    /// Fits on `train` (computed with `config`, which must hold the `sigma` group): every
    /// scale of `scales` with every threshold `1/300, 2/300, ... 99/300`, the first with the
    /// best MCC winning.
    pub fn fit(
        train: &FeatureSet,
        config: &FeatureConfig,
        scales: &[usize],
    ) -> Result<Self, NnError> {
        let sigma = FeatureGroups {
            sigma: true,
            ..FeatureGroups::NONE
        };
        let mut best: Option<(f64, Self)> = None;
        for &scale in scales {
            let target = FeatureConfig {
                scales: vec![scale],
                groups: sigma,
                ..FeatureConfig::default()
            };
            let sigma_columns = columns(config, &target)?;
            let column = [0, 1, 2].map(|i| sigma_columns[i]);
            for step in 1..100 {
                let candidate = Self {
                    column,
                    scale,
                    threshold: step as f32 / 300.0,
                };
                let mcc = candidate.confusion(train)?.mcc();
                if best.as_ref().is_none_or(|b| mcc > b.0) {
                    best = Some((mcc, candidate));
                }
            }
        }
        best.map(|b| b.1)
            .ok_or_else(|| NnError::InvalidConfig("the CA baseline needs a scale".into()))
    }

    /// 1 (sharp edge) or 0 for every row of `set` (computed with the configuration it was
    /// fitted on).
    pub fn predict(&self, set: &FeatureSet) -> Vec<u8> {
        (set.features.chunks_exact(set.per_point))
            .map(|row| u8::from(self.variation(row) > self.threshold))
            .collect()
    }

    /// The sharp-edge counts of [`predict`](Self::predict) on `set` against its labels.
    pub fn confusion(&self, set: &FeatureSet) -> Result<BinaryConfusion, NnError> {
        BinaryConfusion::from_labels(&set.labels, &self.predict(set), Class::Sharp as u8)
    }

    /// The results on `clouds` (their features computed with the fit's configuration), as
    /// the method `name` with sharp edges positive.
    pub fn results(&self, name: &str, clouds: &[FeaturedCloud]) -> Result<MethodResults, NnError> {
        let models = (clouds.iter())
            .map(|c| Ok((c.name.clone(), self.confusion(&c.features)?)))
            .collect::<Result<_, NnError>>()?;
        Ok(MethodResults {
            name: name.to_string(),
            positive: Class::Sharp.name().to_string(),
            models,
        })
    }

    /// The surface variation of a row at the chosen scale (0 for a zero covariance).
    fn variation(&self, row: &[f32]) -> f32 {
        let l = self.column.map(|c| row[c]);
        let sum = l[0] + l[1] + l[2];
        if sum > 0.0 {
            l[0].min(l[1]).min(l[2]) / sum
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of two scales (16 then 8) of sigma_1..3, d_perp, d_par: at scale 16 every point's
    /// surface variation is 1/4, at scale 8 the sharp points' 1/8 and the others' 1/128.
    fn set() -> (FeatureSet, FeatureConfig) {
        let config = FeatureConfig {
            scales: vec![16, 8],
            groups: FeatureGroups {
                sigma: true,
                d: true,
                ..FeatureGroups::NONE
            },
            ..FeatureConfig::default()
        };
        let labels = vec![0u8, 1, 0, 2, 1, 0];
        let mut features = Vec::new();
        for &l in &labels {
            features.extend([0.5, 0.25, 0.25, 9.0, 9.0]);
            let sharp = if l == 1 {
                [0.125, 0.375, 0.5]
            } else {
                [0.5, 0.4921875, 0.0078125]
            };
            features.extend(sharp.into_iter().chain([9.0, 9.0]));
        }
        let set = FeatureSet {
            features,
            labels,
            per_point: 10,
            in_context: false,
        };
        (set, config)
    }

    #[test]
    fn picks_the_separating_scale_and_the_first_perfect_threshold() {
        let (train, config) = set();
        let ca = CaBaseline::fit(&train, &config, &[16, 8]).unwrap();
        // Thresholds 1/300 and 2/300 call every point sharp (MCC 0); 3/300 is the first
        // above 1/128 and below 1/8.
        assert_eq!((ca.scale, ca.threshold), (8, 3.0 / 300.0));
        assert_eq!(ca.predict(&train), [0, 1, 0, 0, 1, 0]);
        let confusion = BinaryConfusion {
            tp: 2,
            fp: 0,
            tn: 4,
            fn_: 0,
        };
        assert_eq!(ca.confusion(&train).unwrap(), confusion);
        let mut wrong = train;
        wrong.labels[3] = 1;
        assert_eq!(ca.confusion(&wrong).unwrap().fn_, 1);
        let cloud = FeaturedCloud {
            name: "six".into(),
            cloud: bounded_geom::PointCloud::from_f64(&[[0.0; 3]; 6]).unwrap(),
            labels: vec![Class::NonEdge; 6],
            features: wrong,
        };
        let method = ca.results("CA", &[cloud]).unwrap();
        assert_eq!(
            (method.name.as_str(), method.positive.as_str()),
            ("CA", "sharp")
        );
        assert_eq!(method.models[0].0, "six");
        assert_eq!(method.models[0].1.fn_, 1);
    }

    #[test]
    fn needs_the_sigma_features_and_a_scale() {
        let (train, mut config) = set();
        assert!(CaBaseline::fit(&train, &config, &[]).is_err());
        let e = CaBaseline::fit(&train, &config, &[32]).unwrap_err();
        assert!(e.to_string().contains("scale 32"), "{e}");
        config.groups.sigma = false;
        let e = CaBaseline::fit(&train, &config, &[8]).unwrap_err();
        assert!(e.to_string().contains("sigma_1 not computed"), "{e}");
    }
}
