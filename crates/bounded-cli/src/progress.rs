//! Progress bars on stderr (hidden automatically when stderr is not a terminal).

use bounded_nn::Step;
use indicatif::{ProgressBar, ProgressStyle};

/// A bar counting `len` units of `unit` (e.g. "points"), labelled `step`.
pub fn bar(step: &str, len: u64, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let template = format!(
        "{{prefix:>10}} [{{bar:32}}] {{human_pos}}/{{human_len}} {unit}, {{elapsed}} eta {{eta}} {{msg}}"
    );
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(step.to_string());
    bar
}

/// Runs `work`, a step of unknown length, under a spinner showing `step` and `message`.
pub fn spinning<T>(step: &str, message: &str, work: impl FnOnce() -> T) -> T {
    let bar = ProgressBar::new_spinner().with_prefix(step.to_string());
    if let Ok(style) = ProgressStyle::with_template("{prefix:>10} {spinner} {elapsed} {msg}") {
        bar.set_style(style);
    }
    bar.set_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let out = work();
    bar.finish_and_clear();
    out
}

/// A progress display for the library's fit steps: a bar for features, one for training.
pub struct FitBars {
    bar: Option<(bool, ProgressBar)>,
}

impl FitBars {
    /// Runs `work`, showing the steps it reports, and clears the bar after.
    pub fn around<T>(work: impl FnOnce(&mut dyn FnMut(Step<'_>)) -> T) -> T {
        let mut bars = Self { bar: None };
        let out = work(&mut |step| bars.show(step));
        bars.finish();
        out
    }

    /// Shows `step`, starting a new bar when the step changes.
    fn show(&mut self, step: Step<'_>) {
        let training = matches!(step, Step::Training(_));
        if self.bar.as_ref().is_some_and(|(t, _)| *t != training) {
            self.finish();
        }
        match step {
            Step::Features {
                done,
                total,
                context,
            } => {
                let (_, bar) = self.bar.get_or_insert_with(|| {
                    let name = if context { "context" } else { "features" };
                    (false, bar(name, total as u64, "points"))
                });
                bar.set_position(done as u64);
            }
            Step::Training(p) => {
                let (_, bar) = self.bar.get_or_insert_with(|| {
                    (true, bar("train", (p.iterations * p.runs) as u64, "its"))
                });
                bar.inc(1);
                if let Some(best) = p.best_val_loss {
                    bar.set_message(format!(
                        "run {}/{} loss {:.4} best val {best:.4}",
                        p.run + 1,
                        p.runs,
                        p.loss
                    ));
                }
            }
        }
    }

    /// Clears the current bar.
    fn finish(&mut self) {
        if let Some((_, bar)) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
