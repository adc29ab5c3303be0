//! CPU training with Burn: Adam on seeded random batches, validation every few iterations,
//! the best weights by validation loss over several runs.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;
use std::time::Instant;

use burn::optim::{AdamConfig, GradientsParams};
use burn::prelude::*;
use rand::SeedableRng;
use rand::rngs::{SmallRng, StdRng};

use crate::backend::read_f32;
use crate::data::{BatchSampler, Dataset, Sampling, split_validation};
use crate::{FocalLoss, Model, ModelConfig, N_CLASSES, NnError, Standardisation, cpu_device};

/// Everything that decides a training run besides the data.
#[derive(Config, Debug, PartialEq)]
pub struct TrainConfig {
    /// The network to train.
    pub model: ModelConfig,
    /// The loss (focal, gamma 2, no alpha by default).
    #[config(default = "FocalLoss::new()")]
    pub loss: FocalLoss,
    /// Adam steps per run.
    #[config(default = 3000)]
    pub iterations: usize,
    /// Points per batch.
    #[config(default = 16384)]
    pub batch_size: usize,
    /// Adam learning rate.
    #[config(default = 1e-3)]
    pub learning_rate: f64,
    /// Adam beta 1.
    #[config(default = 0.9)]
    pub beta_1: f32,
    /// Adam beta 2.
    #[config(default = 0.999)]
    pub beta_2: f32,
    /// Adam epsilon (PyTorch's default, which the paper's implementation used).
    #[config(default = 1e-8)]
    pub epsilon: f32,
    /// How batches are drawn (uniform by default, see [`Sampling`]).
    #[config(default = "Sampling::Uniform")]
    pub sampling: Sampling,
    /// Validation points held out per class (the paper: 1000, 1000 and 100 for boundary).
    #[config(default = "[1000, 1000, 100]")]
    pub val_per_class: [usize; N_CLASSES],
    /// Validation loss is measured every this many iterations (and after the last one).
    #[config(default = 100)]
    pub val_every: usize,
    /// Independent runs; the weights with the lowest validation loss over all runs are kept.
    #[config(default = 5)]
    pub runs: usize,
    /// Seed of the validation split, the batches and the initial weights (run `r` uses
    /// `seed + r` for its batches and weights).
    #[config(default = 0)]
    pub seed: u64,
}

/// Progress of training, passed to the callback after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Current run, from 0.
    pub run: usize,
    /// Number of runs.
    pub runs: usize,
    /// Iterations done in this run (1-based).
    pub iteration: usize,
    /// Iterations per run.
    pub iterations: usize,
    /// Training loss of this iteration's batch.
    pub loss: f32,
    /// Validation loss, when it was measured at this iteration.
    pub val_loss: Option<f32>,
    /// Best validation loss so far over all runs.
    pub best_val_loss: Option<f32>,
    /// Training speed of the current run.
    pub iterations_per_second: f32,
}

/// The outcome of [`train`]: the best weights and where they came from.
#[derive(Debug)]
pub struct TrainedModel {
    /// The best model, in evaluation mode (no autodiff, no dropout).
    pub model: Model,
    /// The configuration it was trained with.
    pub config: TrainConfig,
    /// The input standardisation stored in the model.
    pub standardisation: Standardisation,
    /// Its validation loss.
    pub val_loss: f32,
    /// Run (from 0) and iteration at which it was taken.
    pub best_run: usize,
    /// Iteration of the best run at which it was taken.
    pub best_iteration: usize,
    /// Best validation loss of every run.
    pub run_val_losses: Vec<f32>,
    /// [`Dataset::fingerprint`] of the training data.
    pub data_hash: u64,
}

/// Trains `config.runs` models on `data` and returns the one with the lowest validation loss.
/// `progress` is called after every iteration of every run (for a progress bar), on the
/// calling thread.
///
/// The validation points are drawn per class from `data` with `config.seed` and excluded from
/// the batches; the standardisation is measured on all of `data`. Runs are reproducible for a
/// given seed up to the floating point order of Burn's kernels.
///
/// The runs are independent (run `r` seeds its weights, batches and dropout with `seed + r`),
/// so they run side by side on up to `rayon::current_num_threads()` threads: Flex spreads a
/// batch of this small network over one core only, and a run's result does not depend on
/// which thread ran it or when. The best weights are then chosen in run order, as one thread
/// running the runs one after another would choose them (a test holds the two equal).
pub fn train(
    data: &Dataset<'_>,
    config: &TrainConfig,
    progress: impl FnMut(&Progress),
) -> Result<TrainedModel, NnError> {
    train_on(data, config, rayon::current_num_threads(), progress)
}

/// [`train`] with the runs spread over at most `threads` threads.
fn train_on(
    data: &Dataset<'_>,
    config: &TrainConfig,
    threads: usize,
    mut progress: impl FnMut(&Progress),
) -> Result<TrainedModel, NnError> {
    config.model.validate()?;
    check(config, data)?;
    let standardisation = Standardisation::fit(data.features(), data.n_inputs())?;
    let mut rng = StdRng::seed_from_u64(config.seed);
    let (pool, val_indices) = split_validation(data.labels(), config.val_per_class, &mut rng);
    if pool.is_empty() {
        return Err(NnError::Data(
            "no training points left after the validation split".into(),
        ));
    }
    let mut validation = (Vec::new(), Vec::new());
    data.gather(&val_indices, &mut validation.0, &mut validation.1);
    let shared = Shared {
        data,
        config,
        standardisation: &standardisation,
        pool: &pool,
        validation: &validation,
    };

    // Every step gets the best validation loss over all runs so far.
    let mut best_val_loss: Option<f32> = None;
    let mut report = |mut step: Progress| {
        if let Some(v) = step.val_loss
            && better(v, best_val_loss)
        {
            best_val_loss = Some(v);
        }
        step.best_val_loss = best_val_loss;
        progress(&step);
    };
    let next = AtomicUsize::new(0);
    let threads = threads.clamp(1, config.runs);
    let mut outcomes = if threads == 1 {
        // On the calling thread: no thread blocks waiting, even inside a one-thread rayon pool.
        shared.take_runs(&next, &mut report)
    } else {
        // Workers take the next run until none is left and send their progress here.
        let (sender, receiver) = mpsc::channel::<Progress>();
        thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|_| {
                    let (sender, next, shared) = (sender.clone(), &next, &shared);
                    scope.spawn(move || {
                        // The receiver lives until every worker is done: sending cannot fail.
                        shared.take_runs(next, &mut |step| {
                            let _ = sender.send(step);
                        })
                    })
                })
                .collect();
            drop(sender);
            receiver.into_iter().for_each(&mut report);
            workers
                .into_iter()
                .flat_map(|w| {
                    w.join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                })
                .collect::<Vec<_>>()
        })
    };
    outcomes.sort_by_key(|(run, _)| *run);

    let mut best: Option<(f32, Model, usize, usize)> = None;
    let mut run_val_losses = Vec::with_capacity(config.runs);
    for (run, outcome) in outcomes {
        let outcome = outcome?;
        run_val_losses.push(outcome.lowest);
        if let Some((val_loss, model, iteration)) = outcome.best
            && better(val_loss, best.as_ref().map(|b| b.0))
        {
            best = Some((val_loss, model, run, iteration));
        }
    }
    let (val_loss, model, best_run, best_iteration) =
        best.ok_or_else(|| NnError::InvalidConfig("training ran no iteration".into()))?;
    Ok(TrainedModel {
        model,
        config: config.clone(),
        standardisation,
        val_loss,
        best_run,
        best_iteration,
        run_val_losses,
        data_hash: data.fingerprint(),
    })
}

/// Whether a validation loss replaces the best so far: the first one, a lower one, or any
/// where the best so far is not a number (so that runs compared in order pick the first
/// lowest loss, and a diverged run never hides a later good one).
fn better(loss: f32, best: Option<f32>) -> bool {
    best.is_none_or(|b| b.is_nan() || loss < b)
}

/// What every run reads.
struct Shared<'a> {
    data: &'a Dataset<'a>,
    config: &'a TrainConfig,
    standardisation: &'a Standardisation,
    /// Indices of the training points (the validation points excluded).
    pool: &'a [u32],
    /// Features and labels of the validation points.
    validation: &'a (Vec<f32>, Vec<i64>),
}

/// One run's result.
struct RunOutcome {
    /// Its best weights in evaluation mode, their validation loss and iteration (the last
    /// weights of run 0 when there are no validation points, with a NaN loss).
    best: Option<(f32, Model, usize)>,
    /// Its lowest validation loss (infinite without validation points).
    lowest: f32,
}

impl Shared<'_> {
    /// Trains the next run not yet taken (counted by `next`) until none is left or one fails.
    fn take_runs(
        &self,
        next: &AtomicUsize,
        progress: &mut dyn FnMut(Progress),
    ) -> Vec<(usize, Result<RunOutcome, NnError>)> {
        let mut done = Vec::new();
        loop {
            let run = next.fetch_add(1, Ordering::Relaxed);
            if run >= self.config.runs {
                return done;
            }
            let outcome = self.run(run, progress);
            let failed = outcome.is_err();
            done.push((run, outcome));
            if failed {
                return done;
            }
        }
    }

    /// Trains run `run` from its own seed, passing progress on after every iteration.
    fn run(&self, run: usize, progress: &mut dyn FnMut(Progress)) -> Result<RunOutcome, NnError> {
        let (data, config) = (self.data, self.config);
        let run_seed = config.seed.wrapping_add(run as u64);
        let plain = cpu_device();
        let (val_x, val_y) = self.validation;
        let validation = (!val_y.is_empty()).then(|| {
            let n = val_y.len();
            (
                Tensor::<2>::from_data(
                    TensorData::new(val_x.clone(), [n, data.n_inputs()]),
                    &plain,
                ),
                Tensor::<1, Int>::from_data(TensorData::new(val_y.clone(), [n]), &plain),
            )
        });
        let device = plain.autodiff();
        let weights = config
            .model
            .random_weights(&mut StdRng::seed_from_u64(run_seed));
        let mut model = config.model.init(self.standardisation, &weights, &device)?;
        // Half a million dropout decisions per batch: a small fast generator, seeded per run.
        let mut dropout_rng = SmallRng::seed_from_u64(run_seed);
        let mut optim = AdamConfig::new()
            .with_beta_1(config.beta_1)
            .with_beta_2(config.beta_2)
            .with_epsilon(config.epsilon)
            .init();
        let mut sampler =
            BatchSampler::new(self.pool.to_vec(), data.labels(), config.sampling, run_seed);
        let (mut batch, mut xs, mut ys) = (Vec::new(), Vec::new(), Vec::new());
        let mut outcome = RunOutcome {
            best: None,
            lowest: f32::INFINITY,
        };
        let start = Instant::now();
        for iteration in 1..=config.iterations {
            sampler.sample(config.batch_size, &mut batch);
            data.gather(&batch, &mut xs, &mut ys);
            let n = batch.len();
            let x = Tensor::<2>::from_data(
                TensorData::new(std::mem::take(&mut xs), [n, data.n_inputs()]),
                &device,
            );
            let y =
                Tensor::<1, Int>::from_data(TensorData::new(std::mem::take(&mut ys), [n]), &device);
            let loss = config
                .loss
                .forward(model.forward_train(x, &mut dropout_rng), y);
            let grads = GradientsParams::from_grads(loss.backward(), &model);
            model = optim.step(config.learning_rate, model, grads);
            let loss = scalar(loss)?;

            let validate =
                iteration.is_multiple_of(config.val_every) || iteration == config.iterations;
            let val_loss = match (&validation, validate) {
                (Some((vx, vy)), true) => {
                    let eval = model.valid();
                    let val_loss =
                        scalar(config.loss.forward(eval.forward(vx.clone()), vy.clone()))?;
                    outcome.lowest = outcome.lowest.min(val_loss);
                    if better(val_loss, outcome.best.as_ref().map(|b| b.0)) {
                        outcome.best = Some((val_loss, eval, iteration));
                    }
                    Some(val_loss)
                }
                // Without validation points the last weights of the first run are kept.
                (None, true) if run == 0 && iteration == config.iterations => {
                    outcome.best = Some((f32::NAN, model.valid(), iteration));
                    None
                }
                _ => None,
            };
            progress(Progress {
                run,
                runs: config.runs,
                iteration,
                iterations: config.iterations,
                loss,
                val_loss,
                best_val_loss: None,
                iterations_per_second: iteration as f32 / start.elapsed().as_secs_f32(),
            });
        }
        Ok(outcome)
    }
}

fn check(config: &TrainConfig, data: &Dataset<'_>) -> Result<(), NnError> {
    if config.iterations == 0 || config.runs == 0 || config.batch_size == 0 || config.val_every == 0
    {
        return Err(NnError::InvalidConfig(
            "iterations, runs, batch_size and val_every must be positive".into(),
        ));
    }
    if data.n_inputs() != config.model.n_inputs() {
        return Err(NnError::Shape(format!(
            "data has {} inputs per point, the model {}",
            data.n_inputs(),
            config.model.n_inputs()
        )));
    }
    if data.is_empty() {
        return Err(NnError::Data("no training points".into()));
    }
    Ok(())
}

/// Reads a one-element tensor back.
fn scalar(t: Tensor<1>) -> Result<f32, NnError> {
    read_f32(t)?
        .first()
        .copied()
        .ok_or_else(|| NnError::Tensor("empty loss tensor".into()))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::Rng;

    /// 4 inputs (2 scales x 2 features); class 0 when x0 < 0, else 1 when x1 < 0, else 2.
    pub(crate) fn toy_set(n: usize, seed: u64) -> (Vec<f32>, Vec<u8>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut features = Vec::with_capacity(n * 4);
        let mut labels = Vec::with_capacity(n);
        for _ in 0..n {
            let x: [f32; 4] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            labels.push(if x[0] < 0.0 {
                0
            } else if x[1] < 0.0 {
                1
            } else {
                2
            });
            features.extend_from_slice(&x);
        }
        (features, labels)
    }

    pub(crate) fn toy_config() -> TrainConfig {
        let model = ModelConfig::new(2, 2)
            .with_fusion_widths(vec![8])
            .with_hidden_widths(vec![8])
            .with_dropout(0.1);
        TrainConfig::new(model)
            .with_iterations(300)
            .with_batch_size(256)
            .with_learning_rate(1e-2)
            .with_val_per_class([50, 50, 50])
            .with_val_every(50)
            .with_runs(2)
    }

    fn accuracy(model: &Model, features: &[f32], labels: &[u8]) -> f32 {
        let device = cpu_device();
        let x = Tensor::<2>::from_data(
            TensorData::new(features.to_vec(), [labels.len(), 4]),
            &device,
        );
        let predicted = model
            .forward(x)
            .argmax(1)
            .into_data()
            .try_into_vec_as::<i64>()
            .unwrap();
        let correct = predicted
            .iter()
            .zip(labels)
            .filter(|(p, l)| **p == i64::from(**l))
            .count();
        correct as f32 / labels.len() as f32
    }

    #[test]
    fn separable_toy_set_is_learned_and_loss_falls() {
        let (features, labels) = toy_set(3000, 1);
        let data = Dataset::new(&features, &labels, 4).unwrap();
        let mut losses = Vec::new();
        let trained = train(&data, &toy_config(), |p| {
            if p.run == 0 {
                losses.push(p.loss)
            }
        })
        .unwrap();
        assert_eq!(losses.len(), 300);
        let mean = |s: &[f32]| s.iter().sum::<f32>() / s.len() as f32;
        let (first, last) = (mean(&losses[..10]), mean(&losses[290..]));
        assert!(last < 0.3 * first, "loss {first} -> {last}");
        let (test_x, test_y) = toy_set(2000, 2);
        let acc = accuracy(&trained.model, &test_x, &test_y);
        assert!(acc > 0.95, "accuracy {acc}");
        assert_eq!(trained.run_val_losses.len(), 2);
        let min_run = trained
            .run_val_losses
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min);
        assert_eq!(trained.val_loss, min_run);
        assert_eq!(trained.val_loss, trained.run_val_losses[trained.best_run]);
        assert_eq!(trained.data_hash, data.fingerprint());
    }

    #[test]
    fn same_seed_same_result() {
        let (features, labels) = toy_set(500, 3);
        let data = Dataset::new(&features, &labels, 4).unwrap();
        let config = toy_config()
            .with_iterations(20)
            .with_runs(1)
            .with_val_every(10);
        let a = train(&data, &config, |_| {}).unwrap();
        let b = train(&data, &config, |_| {}).unwrap();
        assert_eq!(a.val_loss, b.val_loss);
        let c = train(&data, &config.with_seed(9), |_| {}).unwrap();
        assert_ne!(a.val_loss, c.val_loss);
    }

    #[test]
    fn runs_side_by_side_give_the_sequential_result_bit_for_bit() {
        let (features, labels) = toy_set(800, 4);
        let data = Dataset::new(&features, &labels, 4).unwrap();
        let config = toy_config()
            .with_iterations(60)
            .with_runs(3)
            .with_val_every(10);
        let run = |threads| {
            let mut steps = vec![0; 3];
            let trained = train_on(&data, &config, threads, |p| steps[p.run] += 1).unwrap();
            assert_eq!(steps, [60, 60, 60]);
            trained
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one.run_val_losses, two.run_val_losses);
        assert_eq!(
            (one.val_loss, one.best_run, one.best_iteration),
            (two.val_loss, two.best_run, two.best_iteration)
        );
        assert_eq!(
            one.model.export_weights().unwrap(),
            two.model.export_weights().unwrap()
        );
        // The runs differ, so the choice among them is tested too.
        assert_ne!(one.run_val_losses[0], one.run_val_losses[1]);
    }

    #[test]
    fn a_lower_loss_or_one_after_nan_is_better() {
        assert!(better(0.5, None));
        assert!(better(0.4, Some(0.5)));
        assert!(!better(0.5, Some(0.5)));
        assert!(!better(0.6, Some(0.5)));
        assert!(better(0.6, Some(f32::NAN)));
        assert!(!better(f32::NAN, Some(0.5)));
    }

    #[test]
    fn mismatched_inputs_are_rejected() {
        let (features, labels) = toy_set(100, 3);
        let data = Dataset::new(&features, &labels, 4).unwrap();
        let config = TrainConfig::new(ModelConfig::new(4, 2));
        assert!(matches!(
            train(&data, &config, |_| {}),
            Err(NnError::Shape(_))
        ));
        let config = toy_config().with_iterations(0);
        assert!(matches!(
            train(&data, &config, |_| {}),
            Err(NnError::InvalidConfig(_))
        ));
    }
}
