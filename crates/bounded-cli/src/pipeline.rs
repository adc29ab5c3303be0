//! The detector of the command line's model options, run with a progress bar.

use crate::progress;
use anyhow::{Context, Result};
use bounded_geom::PointCloud;
use bounded_nn::{Detection, Detector};
use std::path::Path;

/// The model options of `detect` and `eval`.
#[derive(Debug, Clone, Copy, Default)]
pub struct ModelOptions<'a> {
    /// A model file (default: the embedded model).
    pub model: Option<&'a Path>,
    /// Scales replacing the model's.
    pub scales: Option<&'a [usize]>,
    /// The first stage alone.
    pub fast: bool,
    /// The decision threshold.
    pub sensitivity: Option<f32>,
}

/// The detector of `options`.
pub fn detector(options: ModelOptions<'_>) -> Result<Detector> {
    let ModelOptions {
        model,
        scales,
        fast,
        sensitivity,
    } = options;
    let mut detector = match model {
        Some(p) => {
            Detector::load(p).with_context(|| format!("cannot load model {}", p.display()))?
        }
        None => Detector::embedded().context("cannot load the embedded model")?,
    };
    if let Some(scales) = scales {
        detector = detector.with_scales(scales).context("--scales")?;
    }
    if fast {
        detector = detector.first_stage_only().context("--fast")?;
    }
    if let Some(s) = sensitivity {
        detector = detector.with_sensitivity(s).context("--sensitivity")?;
    }
    Ok(detector)
}

/// Classifies every point of `cloud`; `show_progress` draws a bar on stderr.
pub fn detect(detector: &Detector, cloud: &PointCloud, show_progress: bool) -> Result<Detection> {
    let bar = show_progress.then(|| progress::bar("detect", cloud.len() as u64, "points"));
    let detection = detector.detect_with_progress(cloud, &mut |done, _| {
        if let Some(bar) = &bar {
            bar.set_position(done as u64);
        }
    })?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    Ok(detection)
}
