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

/// A spinner for a step of unknown length.
pub fn spinner(step: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_prefix(step.to_string());
    if let Ok(style) = ProgressStyle::with_template("{prefix:>10} {spinner} {elapsed} {msg}") {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// A progress display for the library's fit steps: a bar for features, one for training.
pub struct FitBars {
    bar: Option<(bool, ProgressBar)>,
}

impl FitBars {
    /// No bar yet.
    pub fn new() -> Self {
        Self { bar: None }
    }

    /// Shows `step`, starting a new bar when the step changes.
    pub fn show(&mut self, step: Step<'_>) {
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
    pub fn finish(&mut self) {
        if let Some((_, bar)) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
