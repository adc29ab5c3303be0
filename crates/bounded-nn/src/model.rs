//! The network: pairwise scale fusion as a binary tree, then a small classification MLP.
//!
//! Input per point: `n_scales x features_per_scale` numbers, largest scale first. Level 0 fuses
//! scales (0,1), (2,3), ... each with its own fully connected layer + leaky ReLU; every further
//! level fuses adjacent results the same way until one vector remains (4 scales: (k0,k1) and
//! (k2,k3), then the two results). The MLP then applies FC + leaky ReLU + dropout per hidden
//! layer and a final FC to the three class logits (0 non-edge, 1 sharp, 2 boundary).

use burn::module::Param;
use burn::nn::Linear;
use burn::prelude::*;
use burn::tensor::activation::relu;
use rand::Rng;
use serde::{Deserialize, Serialize};

use bounded_geom::Class;

use crate::backend::read_f32;
use crate::{NnError, Standardisation};

/// The widest layer a configuration may have: 4096 inputs by 4096 outputs are 16.8M weights
/// (64 MiB), far beyond any useful width for 48 features yet safe to allocate.
const MAX_WIDTH: usize = 4096;

/// Number of output classes: non-edge, sharp edge, boundary.
pub const N_CLASSES: usize = Class::ALL.len();

/// Names of the classes, in code order (as [`Class::name`] gives them).
pub const CLASS_NAMES: [&str; N_CLASSES] = [
    Class::ALL[0].name(),
    Class::ALL[1].name(),
    Class::ALL[2].name(),
];

/// Shape and regularisation of the network.
///
/// The defaults (fusion widths 12 then 16, hidden widths 16 and 16) give 1595 trainable
/// parameters for 4 scales x 12 features, the ~1.6k of the paper. Fusion level `l` uses
/// `fusion_widths[l]`; levels beyond the list reuse its last width, so one configuration serves
/// every ablation (2, 4, 8 or 16 scales).
#[derive(Config, Debug, PartialEq)]
pub struct ModelConfig {
    /// Number of scales (a power of two, at least 2).
    pub n_scales: usize,
    /// Features per scale (12 for all features; fewer in the feature ablations).
    pub features_per_scale: usize,
    /// Output width of every fusion level (the last entry repeats for deeper trees).
    #[config(default = "vec![12, 16]")]
    pub fusion_widths: Vec<usize>,
    /// Widths of the hidden layers of the classification MLP.
    #[config(default = "vec![16, 16]")]
    pub hidden_widths: Vec<usize>,
    /// Dropout probability after every hidden layer (training only).
    #[config(default = 0.5)]
    pub dropout: f64,
    /// Slope of the leaky ReLU for negative inputs (PyTorch's default).
    #[config(default = 0.01)]
    pub leaky_slope: f64,
}

impl ModelConfig {
    /// Checks that the configuration describes a buildable network.
    pub fn validate(&self) -> Result<(), NnError> {
        let bad = |msg: String| Err(NnError::InvalidConfig(msg));
        if self.n_scales < 2 || !self.n_scales.is_power_of_two() {
            return bad(format!(
                "n_scales must be a power of two >= 2, got {}",
                self.n_scales
            ));
        }
        if self.features_per_scale == 0 {
            return bad("features_per_scale must be positive".into());
        }
        if self.fusion_widths.is_empty() || self.fusion_widths.contains(&0) {
            return bad(format!(
                "fusion widths must be non-empty and positive: {:?}",
                self.fusion_widths
            ));
        }
        if self.hidden_widths.contains(&0) {
            return bad(format!(
                "hidden widths must be positive: {:?}",
                self.hidden_widths
            ));
        }
        if let Some(w) =
            (self.fusion_widths.iter().chain(&self.hidden_widths)).find(|&&w| w > MAX_WIDTH)
        {
            return bad(format!(
                "a layer width of {w} is above the largest allowed, {MAX_WIDTH} (the paper's \
                 network is 16-48 wide; a layer's weights grow as the square of its width)"
            ));
        }
        if !(0.0..1.0).contains(&self.dropout) {
            return bad(format!("dropout must be in [0, 1), got {}", self.dropout));
        }
        if !self.leaky_slope.is_finite() {
            return bad("leaky_slope must be finite".into());
        }
        // Every size the network is built from must be computable: a model file may declare
        // any number, and the weights it holds are checked against these products.
        let too_large = || {
            bad(format!(
                "the network's sizes overflow: {} scales of {} features, fusion widths {:?}, \
                 hidden widths {:?}",
                self.n_scales, self.features_per_scale, self.fusion_widths, self.hidden_widths
            ))
        };
        if self.n_scales.checked_mul(self.features_per_scale).is_none() {
            return too_large();
        }
        let (mut nodes, mut width, mut level) = (self.n_scales, self.features_per_scale, 0);
        while nodes > 1 {
            let out = self.fusion_width(level);
            if width
                .checked_mul(2)
                .and_then(|d| d.checked_mul(out))
                .is_none()
            {
                return too_large();
            }
            (nodes, width, level) = (nodes / 2, out, level + 1);
        }
        for &h in self.hidden_widths.iter().chain(&[N_CLASSES]) {
            if width.checked_mul(h).is_none() {
                return too_large();
            }
            width = h;
        }
        Ok(())
    }

    /// Number of fully connected layers: `n_scales - 1` fusion layers, the hidden layers and
    /// the output layer (counted without building [`layer_shapes`](Self::layer_shapes), which
    /// is as long; call after [`validate`](Self::validate)).
    pub fn n_layers(&self) -> usize {
        self.n_scales - 1 + self.hidden_widths.len() + 1
    }

    /// Number of inputs per point: `n_scales * features_per_scale`.
    pub fn n_inputs(&self) -> usize {
        self.n_scales * self.features_per_scale
    }

    /// Output width of fusion level `level`.
    fn fusion_width(&self, level: usize) -> usize {
        let last = self.fusion_widths.len().saturating_sub(1);
        self.fusion_widths[level.min(last)]
    }

    /// The fusion levels as `(pairs, d_in, d_out)`: each of the `pairs` layers maps the
    /// concatenation of two adjacent nodes (`d_in` numbers) to `d_out`.
    pub fn fusion_levels(&self) -> Vec<(usize, usize, usize)> {
        let mut levels = Vec::new();
        let (mut nodes, mut width) = (self.n_scales, self.features_per_scale);
        while nodes > 1 {
            let out = self.fusion_width(levels.len());
            levels.push((nodes / 2, 2 * width, out));
            nodes /= 2;
            width = out;
        }
        levels
    }

    /// `(d_in, d_out)` of every fully connected layer in export order: fusion layers level by
    /// level and pair by pair, then the hidden layers, then the output layer.
    pub fn layer_shapes(&self) -> Vec<(usize, usize)> {
        let mut shapes = Vec::new();
        let mut width = self.features_per_scale;
        for (pairs, d_in, d_out) in self.fusion_levels() {
            shapes.extend(std::iter::repeat_n((d_in, d_out), pairs));
            width = d_out;
        }
        for &h in &self.hidden_widths {
            shapes.push((width, h));
            width = h;
        }
        shapes.push((width, N_CLASSES));
        shapes
    }

    /// Number of trainable parameters (weights and biases of all layers).
    pub fn n_params(&self) -> usize {
        self.layer_shapes().iter().map(|(i, o)| i * o + o).sum()
    }

    /// Random initial weights, uniform in `±1/sqrt(d_in)` (PyTorch's and Burn's default for
    /// linear layers), drawn from `rng` so that training is reproducible by seed alone.
    pub fn random_weights(&self, rng: &mut impl Rng) -> Vec<LayerWeights> {
        self.layer_shapes()
            .into_iter()
            .map(|(d_in, d_out)| {
                let bound = 1.0 / (d_in as f32).sqrt();
                let mut draw =
                    |n: usize| (0..n).map(|_| rng.random_range(-bound..=bound)).collect();
                LayerWeights {
                    d_in,
                    d_out,
                    weight: draw(d_in * d_out),
                    bias: draw(d_out),
                }
            })
            .collect()
    }

    /// Checks that `weights` has the layer count and shapes of this configuration (call after
    /// [`validate`](Self::validate)). The count is compared first, so that a configuration
    /// declaring a huge network allocates nothing for it.
    pub fn check_weights(&self, weights: &[LayerWeights]) -> Result<(), NnError> {
        if weights.len() != self.n_layers() {
            return Err(NnError::InconsistentModel(format!(
                "{} layers given, the configuration has {}",
                weights.len(),
                self.n_layers()
            )));
        }
        let shapes = self.layer_shapes();
        for (k, (w, &(d_in, d_out))) in weights.iter().zip(&shapes).enumerate() {
            if (w.d_in, w.d_out) != (d_in, d_out)
                || w.weight.len() != d_in * d_out
                || w.bias.len() != d_out
            {
                return Err(NnError::InconsistentModel(format!(
                    "layer {k}: {}x{} with {} weights and {} biases, expected {d_in}x{d_out}",
                    w.d_in,
                    w.d_out,
                    w.weight.len(),
                    w.bias.len()
                )));
            }
        }
        Ok(())
    }

    /// Builds the Burn model on `device` from `weights` (in [`layer_shapes`](Self::layer_shapes)
    /// order) that standardises its inputs with `standardisation`.
    pub fn init(
        &self,
        standardisation: &Standardisation,
        weights: &[LayerWeights],
        device: &Device,
    ) -> Result<Model, NnError> {
        self.validate()?;
        self.check_weights(weights)?;
        if standardisation.len() != self.n_inputs() {
            return Err(NnError::Shape(format!(
                "standardisation has {} inputs, the model {}",
                standardisation.len(),
                self.n_inputs()
            )));
        }
        let mut layers: Vec<Linear> = weights.iter().map(|w| w.to_linear(device)).collect();
        let output = layers
            .pop()
            .expect("check_weights ensures at least the output layer");
        let hidden = layers.split_off(layers.len() - self.hidden_widths.len());
        let constant =
            |v: Vec<f32>| Tensor::<1>::from_data(TensorData::new(v, [self.n_inputs()]), device);
        Ok(Model {
            fusion: layers,
            hidden,
            output,
            mean: constant(standardisation.mean.clone()),
            inv_std: constant(standardisation.inv_std()),
            n_scales: self.n_scales,
            features_per_scale: self.features_per_scale,
            dropout: self.dropout,
            leaky_slope: self.leaky_slope,
        })
    }
}

/// Weights of one fully connected layer, `y = W x + b`, as plain numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerWeights {
    /// Input width.
    pub d_in: usize,
    /// Output width.
    pub d_out: usize,
    /// `W`, row-major `[d_out][d_in]` (PyTorch's layout).
    pub weight: Vec<f32>,
    /// `b`, `d_out` values.
    pub bias: Vec<f32>,
}

impl LayerWeights {
    /// The Burn layer (Burn stores `W` transposed, `[d_in][d_out]`).
    fn to_linear(&self, device: &Device) -> Linear {
        let mut transposed = vec![0.0; self.weight.len()];
        for (o, row) in self.weight.chunks_exact(self.d_in).enumerate() {
            for (i, &w) in row.iter().enumerate() {
                transposed[i * self.d_out + o] = w;
            }
        }
        let weight =
            Tensor::<2>::from_data(TensorData::new(transposed, [self.d_in, self.d_out]), device);
        let bias = Tensor::<1>::from_data(TensorData::new(self.bias.clone(), [self.d_out]), device);
        Linear {
            weight: Param::from_tensor(weight),
            bias: Some(Param::from_tensor(bias)),
        }
    }

    /// Reads a Burn layer back.
    fn from_linear(linear: &Linear) -> Result<Self, NnError> {
        let [d_in, d_out] = linear.weight.dims();
        let transposed = read_f32(linear.weight.val())?;
        let mut weight = vec![0.0; transposed.len()];
        for (i, row) in transposed.chunks_exact(d_out).enumerate() {
            for (o, &w) in row.iter().enumerate() {
                weight[o * d_in + i] = w;
            }
        }
        let bias = match &linear.bias {
            Some(b) => read_f32(b.val())?,
            None => vec![0.0; d_out],
        };
        Ok(Self {
            d_in,
            d_out,
            weight,
            bias,
        })
    }
}

/// The Burn model (trainable; see [`crate::Classifier`] for fast inference).
#[derive(Module, Debug)]
pub struct Model {
    /// Fusion layers, level by level, pair by pair.
    fusion: Vec<Linear>,
    /// Hidden layers of the classification MLP.
    hidden: Vec<Linear>,
    /// Final layer to the class logits.
    output: Linear,
    /// Input means (a constant, not trained).
    mean: Tensor<1>,
    /// Inverse input standard deviations (a constant, not trained).
    inv_std: Tensor<1>,
    n_scales: usize,
    features_per_scale: usize,
    /// Dropout probability after each hidden layer, applied by [`Model::forward_train`] only.
    dropout: f64,
    leaky_slope: f64,
}

impl Model {
    /// Class logits `[n, 3]` for features `[n, n_scales * features_per_scale]` in evaluation
    /// mode (no dropout).
    pub fn forward(&self, features: Tensor<2>) -> Tensor<2> {
        self.forward_with(features, |x| x)
    }

    /// Training forward pass: dropout after every hidden layer, its masks drawn from `rng`
    /// (not from Burn's global generator, so that concurrent trainings stay reproducible).
    pub fn forward_train(&self, features: Tensor<2>, rng: &mut impl Rng) -> Tensor<2> {
        let keep = 1.0 - self.dropout;
        self.forward_with(features, |x| {
            if self.dropout == 0.0 {
                return x;
            }
            let (dims, device) = (x.dims(), x.device());
            let scale = (1.0 / keep) as f32;
            let mask: Vec<f32> = (0..dims[0] * dims[1])
                .map(|_| if rng.random_bool(keep) { scale } else { 0.0 })
                .collect();
            x * Tensor::<2>::from_data(TensorData::new(mask, dims), &device)
        })
    }

    fn forward_with(
        &self,
        features: Tensor<2>,
        mut dropout: impl FnMut(Tensor<2>) -> Tensor<2>,
    ) -> Tensor<2> {
        let x =
            (features - self.mean.clone().unsqueeze::<2>()) * self.inv_std.clone().unsqueeze::<2>();
        // leaky(x) = (1 - s) relu(x) + s x: Burn's autodiff has no leaky ReLU node and falls
        // back to a masked select, measurably slower in training than relu's own node.
        let slope = self.leaky_slope;
        let act = |t: Tensor<2>| relu(t.clone()) * (1.0 - slope) + t * slope;
        let mut layers = self.fusion.iter();
        let mut nodes: Vec<Tensor<2>> = (0..self.n_scales / 2)
            .zip(layers.by_ref())
            .map(|(pair, layer)| {
                let span = 2 * self.features_per_scale;
                act(layer.forward(x.clone().narrow(1, pair * span, span)))
            })
            .collect();
        while nodes.len() > 1 {
            nodes = nodes
                .chunks_exact(2)
                .zip(layers.by_ref())
                .map(|(pair, layer)| act(layer.forward(Tensor::cat(pair.to_vec(), 1))))
                .collect();
        }
        let mut x = nodes.remove(0);
        for layer in &self.hidden {
            x = dropout(act(layer.forward(x)));
        }
        self.output.forward(x)
    }

    /// The weights of every layer in [`ModelConfig::layer_shapes`] order.
    pub fn export_weights(&self) -> Result<Vec<LayerWeights>, NnError> {
        self.fusion
            .iter()
            .chain(&self.hidden)
            .chain(std::iter::once(&self.output))
            .map(LayerWeights::from_linear)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu_device;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    fn build(config: &ModelConfig) -> Model {
        let weights = config.random_weights(&mut StdRng::seed_from_u64(1));
        config
            .init(
                &Standardisation::identity(config.n_inputs()),
                &weights,
                &cpu_device(),
            )
            .unwrap()
    }

    #[test]
    fn default_config_has_1595_parameters() {
        // Fusion level 0: 2 pairs of 24 -> 12: 2 * (24*12 + 12) = 600.
        // Fusion level 1: 1 pair of 24 -> 16: 24*16 + 16 = 400.
        // Hidden 16 -> 16 twice: 2 * (16*16 + 16) = 544. Output 16 -> 3: 51.
        let config = ModelConfig::new(4, 12);
        assert_eq!(config.n_params(), 600 + 400 + 544 + 51);
        assert_eq!(build(&config).num_params(), 1595);
    }

    #[test]
    fn every_ablation_builds_and_maps_to_three_logits() {
        let device = cpu_device();
        for n_scales in [2, 4, 8, 16] {
            for fps in [12, 6, 8, 10] {
                let config = ModelConfig::new(n_scales, fps);
                let model = build(&config);
                assert_eq!(model.num_params(), config.n_params());
                let out = model.forward(Tensor::zeros([5, n_scales * fps], &device));
                assert_eq!(out.dims(), [5, 3], "{n_scales} scales x {fps}");
            }
        }
    }

    #[test]
    fn sixteen_scales_fuse_in_four_levels() {
        let levels = ModelConfig::new(16, 10).fusion_levels();
        assert_eq!(
            levels,
            vec![(8, 20, 12), (4, 24, 16), (2, 32, 16), (1, 32, 16)]
        );
    }

    #[test]
    fn invalid_configs_are_rejected() {
        assert!(ModelConfig::new(3, 12).validate().is_err());
        assert!(ModelConfig::new(1, 12).validate().is_err());
        assert!(ModelConfig::new(4, 0).validate().is_err());
        assert!(
            ModelConfig::new(4, 12)
                .with_dropout(1.0)
                .validate()
                .is_err()
        );
        assert!(
            ModelConfig::new(4, 12)
                .with_fusion_widths(vec![])
                .validate()
                .is_err()
        );
        // Widths up to the bound build; beyond it they are refused before any allocation.
        let wide = |fusion, hidden| {
            ModelConfig::new(4, 12)
                .with_fusion_widths(vec![fusion])
                .with_hidden_widths(vec![hidden])
                .validate()
        };
        assert!(wide(MAX_WIDTH, MAX_WIDTH).is_ok());
        for (fusion, hidden) in [(MAX_WIDTH + 1, 16), (16, 100_000_000), (1_000_000_000, 16)] {
            let e = wide(fusion, hidden).unwrap_err().to_string();
            assert!(e.contains("above the largest allowed, 4096"), "{e}");
        }
        let config = ModelConfig::new(4, 12);
        let weights = config.random_weights(&mut StdRng::seed_from_u64(0));
        let device = cpu_device();
        assert!(
            config
                .init(&Standardisation::identity(47), &weights, &device)
                .is_err()
        );
        let other = ModelConfig::new(4, 10).random_weights(&mut StdRng::seed_from_u64(0));
        assert!(
            config
                .init(&Standardisation::identity(48), &other, &device)
                .is_err()
        );
    }

    #[test]
    fn weights_survive_the_round_trip_through_burn() {
        let config = ModelConfig::new(4, 12);
        let weights = config.random_weights(&mut StdRng::seed_from_u64(5));
        let model = config
            .init(&Standardisation::identity(48), &weights, &cpu_device())
            .unwrap();
        assert_eq!(model.export_weights().unwrap(), weights);
    }

    #[test]
    fn forward_standardises_then_applies_the_layers() {
        // 2 scales x 1 feature, one fusion layer 2 -> 1, no hidden layer, output 1 -> 3.
        let config = ModelConfig::new(2, 1)
            .with_fusion_widths(vec![1])
            .with_hidden_widths(vec![]);
        let layer = |d_in, d_out, weight: Vec<f32>, bias: Vec<f32>| LayerWeights {
            d_in,
            d_out,
            weight,
            bias,
        };
        let weights = vec![
            layer(2, 1, vec![1.0, -2.0], vec![0.5]),
            layer(1, 3, vec![1.0, 2.0, -1.0], vec![0.0, 0.0, 1.0]),
        ];
        let standardisation = Standardisation {
            mean: vec![1.0, 0.0],
            std: vec![2.0, 1.0],
        };
        let device = cpu_device();
        let model = config.init(&standardisation, &weights, &device).unwrap();
        // Inputs (5, 1) -> standardised (2, 1) -> fusion 2 - 2 + 0.5 = 0.5 -> logits (0.5, 1, 0.5).
        // Inputs (1, 2) -> (0, 2) -> -4 + 0.5 = -3.5 -> leaky -0.035 -> logits (-0.035, -0.07, 1.035).
        let x = Tensor::<2>::from_data([[5.0, 1.0], [1.0, 2.0]], &device);
        let got = read_f32(model.forward(x)).unwrap();
        let want = [0.5, 1.0, 0.5, -0.035, -0.07, 1.035];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{got:?}");
        }
    }
}
