//! Focal loss (Lin et al. 2017), written out.
//!
//! `FL = -alpha_t (1 - p_t)^gamma log p_t`, averaged over the batch, where `p_t` is the softmax
//! probability of the true class. Edge points are a few percent of a cloud; `gamma > 0` shrinks
//! the loss of the many easy (mostly non-edge) points so the rare classes drive training. With
//! `gamma = 0` and no `alpha` it is plain cross-entropy.

use burn::prelude::*;
use burn::tensor::activation::log_softmax;

use crate::N_CLASSES;

/// Focal loss over the three classes.
#[derive(Config, Debug, PartialEq)]
pub struct FocalLoss {
    /// Focusing exponent (2 in the paper; 0 gives cross-entropy).
    #[config(default = 2.0)]
    pub gamma: f32,
    /// Optional per-class weights `alpha_t`, indexed by class code.
    pub alpha: Option<[f32; N_CLASSES]>,
}

impl FocalLoss {
    /// Mean focal loss (shape `[1]`) of `logits` `[n, 3]` against class codes `targets` `[n]`.
    pub fn forward(&self, logits: Tensor<2>, targets: Tensor<1, Int>) -> Tensor<1> {
        let [n, _] = logits.dims();
        let device = logits.device();
        let log_pt = log_softmax(logits, 1)
            .gather(1, targets.clone().reshape([n, 1]))
            .reshape([n]);
        let mut loss = log_pt.clone().neg();
        if self.gamma != 0.0 {
            // Skipped for gamma = 0: the derivative of x^0 at x = 0 would be 0 * inf = NaN.
            let one_minus_pt = log_pt.exp().neg().add_scalar(1.0).clamp_min(0.0);
            loss = loss * one_minus_pt.powf_scalar(self.gamma);
        }
        if let Some(alpha) = self.alpha {
            let alpha =
                Tensor::<1>::from_data(TensorData::new(alpha.to_vec(), [N_CLASSES]), &device);
            loss = loss * alpha.select(0, targets);
        }
        loss.mean()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu_device;
    use burn::nn::loss::CrossEntropyLossConfig;

    /// Logits (ln 2, 0, 0) give probabilities (1/2, 1/4, 1/4); two points of classes 0 and 1.
    fn batch(device: &Device) -> (Tensor<2>, Tensor<1, Int>) {
        let ln2 = std::f32::consts::LN_2;
        let logits = Tensor::<2>::from_data([[ln2, 0.0, 0.0], [ln2, 0.0, 0.0]], device);
        let targets = Tensor::<1, Int>::from_data([0, 1], device);
        (logits, targets)
    }

    fn value(loss: Tensor<1>) -> f32 {
        loss.into_scalar::<f32>()
    }

    #[test]
    fn gamma_two_matches_hand_computed_value() {
        let device = cpu_device();
        let (logits, targets) = batch(&device);
        // Point 0: p_t = 1/2 -> (1/2)^2 ln 2 = 0.173287. Point 1: p_t = 1/4 -> (3/4)^2 ln 4 = 0.779791.
        let got = value(FocalLoss::new().forward(logits, targets));
        assert!((got - (0.173_287 + 0.779_791) / 2.0).abs() < 1e-5, "{got}");
    }

    #[test]
    fn alpha_weights_each_point_by_its_class() {
        let device = cpu_device();
        let (logits, targets) = batch(&device);
        let loss = FocalLoss::new().with_alpha(Some([0.25, 2.0, 1.0]));
        let got = value(loss.forward(logits, targets));
        assert!(
            (got - (0.25 * 0.173_287 + 2.0 * 0.779_791) / 2.0).abs() < 1e-5,
            "{got}"
        );
    }

    #[test]
    fn gamma_zero_is_cross_entropy() {
        let device = cpu_device();
        let (logits, targets) = batch(&device);
        // Hand value: (ln 2 + ln 4) / 2 = 1.039721.
        let focal = value(
            FocalLoss::new()
                .with_gamma(0.0)
                .forward(logits.clone(), targets.clone()),
        );
        assert!((focal - 1.039_721).abs() < 1e-5, "{focal}");
        let ce = value(
            CrossEntropyLossConfig::new()
                .init(&device)
                .forward(logits, targets),
        );
        assert!((focal - ce).abs() < 1e-6, "{focal} vs {ce}");
    }

    #[test]
    fn confident_correct_points_cost_almost_nothing() {
        let device = cpu_device();
        let logits = Tensor::<2>::from_data([[20.0, 0.0, 0.0]], &device);
        let targets = Tensor::<1, Int>::from_data([0], &device);
        assert!(value(FocalLoss::new().forward(logits, targets)) < 1e-12);
    }
}
