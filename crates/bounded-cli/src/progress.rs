//! Progress bars on stderr (hidden automatically when stderr is not a terminal).

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
