//! The detector of the command line's model options, run with a progress bar.

use crate::cli::ModelArgs;
use crate::progress;
use anyhow::{Context, Result};
use bounded_geom::PointCloud;
use bounded_nn::{Detection, Detector, EmbeddedModel};

/// The detector of the model options (the default ones: the embedded model as it is).
pub fn detector(options: &ModelArgs) -> Result<Detector> {
    let ModelArgs {
        model,
        embedded,
        scales,
        fast,
        sensitivity,
    } = options;
    let mut detector = match model {
        Some(p) => Detector::load(p).with_context(|| {
            let hint = EmbeddedModel::named_by(p).map_or(String::new(), |m| {
                format!(" (--embedded {m} names the embedded model)")
            });
            format!("cannot load model {}{hint}", p.display())
        })?,
        None => Detector::embedded_model(embedded.unwrap_or_default())
            .context("cannot load the embedded model")?,
    };
    if let Some(scales) = scales {
        detector = detector.with_scales(scales).context("--scales")?;
    }
    if *fast {
        detector = detector.first_stage_only().context("--fast")?;
    }
    if let Some(decision) = sensitivity {
        detector = detector.with_decision(*decision).context("--sensitivity")?;
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
