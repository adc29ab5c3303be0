//! Detection: features streamed block by block straight into the classifier, so memory stays
//! O(points + block) whatever the cloud's size. A two-stage model streams the features a
//! second time, beside the context of the first stage's probabilities, into its second
//! network (twice the time, 12 more bytes a point).

use crate::progress;
use anyhow::{Context, Result, bail};
use bounded_features::{
    CONTEXT_NAMES, DEFAULT_CHUNK_POINTS, FeatureBlock, FeatureConfig, FeatureError, FeatureGroups,
    extract_chunks, extract_chunks_in_context,
};
use bounded_geom::{Class, PointCloud};
use bounded_nn::{Classifier, N_CLASSES, argmax};
use indicatif::ProgressBar;
use std::time::{Duration, Instant};

/// Per-point results of a detection run.
pub struct Detection {
    /// Class probabilities (non-edge, sharp, boundary) per point, in input order.
    pub probabilities: Vec<[f32; N_CLASSES]>,
    /// The most probable class per point.
    pub classes: Vec<Class>,
    /// Wall time of the whole run (neighbour search, features and classification).
    pub elapsed: Duration,
    /// Wall time spent in the classifier alone.
    pub classification: Duration,
}

impl Detection {
    /// Points per class (non-edge, sharp, boundary).
    pub fn class_counts(&self) -> [usize; 3] {
        Class::counts(&self.classes)
    }

    /// The classes as their integer codes.
    pub fn codes(&self) -> Vec<u8> {
        Class::codes(&self.classes)
    }
}

/// The networks to run: all of `classifier`'s, or with `fast` its first stage alone (an
/// error for a one-stage model, where `--fast` would silently change nothing).
pub fn stages(classifier: Classifier, fast: bool) -> Result<Classifier> {
    match (fast, classifier.second_stage()) {
        (false, _) => Ok(classifier),
        (true, Some(_)) => Ok(Classifier::from_file(classifier.file().first_stage())?),
        (true, None) => {
            bail!("--fast leaves out a model's second stage, but this model has one stage")
        }
    }
}

/// The feature extraction a model was trained with, with its scales optionally replaced by
/// `scales` (same count).
pub fn feature_config(classifier: &Classifier, scales: Option<&[usize]>) -> Result<FeatureConfig> {
    let file = classifier.file();
    let groups = groups_named(&file.feature_names).with_context(|| {
        format!(
            "the model's features [{}] are not a feature set this build computes",
            file.feature_names.join(", ")
        )
    })?;
    if let Some(second) = &file.second_stage {
        let expected = file
            .feature_names
            .iter()
            .map(String::as_str)
            .chain(CONTEXT_NAMES);
        if !expected.eq(second.feature_names.iter().map(String::as_str)) {
            bail!(
                "the model's second stage reads [{}], not the first stage's features and the \
                 context this build computes",
                second.feature_names.join(", ")
            );
        }
    }
    let scales = match scales {
        Some(s) if s.len() != file.scales.len() => bail!(
            "--scales lists {} scales but the model was trained on {} ({:?})",
            s.len(),
            file.scales.len(),
            file.scales
        ),
        Some(s) => s.to_vec(),
        None => file.scales.clone(),
    };
    let config = FeatureConfig { scales, groups };
    config.validate()?;
    Ok(config)
}

/// The feature groups whose value names are exactly `names`.
fn groups_named(names: &[String]) -> Option<FeatureGroups> {
    (0u8..64)
        .map(|bits| FeatureGroups {
            sigma: bits & 1 != 0,
            sigma_u: bits & 2 != 0,
            sigma_l: bits & 4 != 0,
            d: bits & 8 != 0,
            s: bits & 16 != 0,
            c: bits & 32 != 0,
        })
        .find(|g| {
            g.names()
                .iter()
                .copied()
                .eq(names.iter().map(String::as_str))
        })
}

/// Classifies every point of `cloud`; `show_progress` draws a bar on stderr.
pub fn detect(
    cloud: &PointCloud,
    classifier: &Classifier,
    config: &FeatureConfig,
    show_progress: bool,
) -> Result<Detection> {
    let n = cloud.len();
    let k0 = config.largest_scale();
    if n < k0 {
        bail!(
            "the cloud has {n} points, fewer than the largest scale ({k0} neighbours); \
             choose smaller scales with --scales or use a denser cloud"
        );
    }
    let start = Instant::now();
    let stages = 1 + usize::from(classifier.second_stage().is_some());
    let bar = show_progress.then(|| progress::bar("detect", (stages * n) as u64, "points"));
    let mut classification = Duration::ZERO;
    let mut probabilities = vec![[0f32; N_CLASSES]; n];
    classify_stream(
        classifier,
        &mut probabilities,
        &mut classification,
        bar.as_ref(),
        |f| extract_chunks(cloud, config, DEFAULT_CHUNK_POINTS, f),
    )?;
    if let Some(second) = classifier.second_stage() {
        let first = std::mem::replace(&mut probabilities, vec![[0f32; N_CLASSES]; n]);
        classify_stream(
            second,
            &mut probabilities,
            &mut classification,
            bar.as_ref(),
            |f| extract_chunks_in_context(cloud, config, &first, DEFAULT_CHUNK_POINTS, f),
        )?;
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let classes = probabilities
        .iter()
        .map(|p| Class::from_code(argmax(p)).unwrap_or(Class::NonEdge))
        .collect();
    Ok(Detection {
        probabilities,
        classes,
        elapsed: start.elapsed(),
        classification,
    })
}

/// Classifies the feature blocks that `stream` hands out into `probabilities` (cloud order),
/// adding the classifier's time to `classification`.
fn classify_stream(
    classifier: &Classifier,
    probabilities: &mut [[f32; N_CLASSES]],
    classification: &mut Duration,
    bar: Option<&ProgressBar>,
    stream: impl FnOnce(&mut dyn FnMut(&FeatureBlock)) -> Result<(), FeatureError>,
) -> Result<()> {
    let mut block_out = Vec::new();
    let mut failure = None;
    stream(&mut |block| {
        if failure.is_some() {
            return;
        }
        let t = Instant::now();
        block_out.resize(block.len(), [0f32; N_CLASSES]);
        if let Err(e) = classifier.predict(block.values(), &mut block_out) {
            failure = Some(e);
            return;
        }
        for (&i, p) in block.points().iter().zip(&block_out) {
            probabilities[i as usize] = *p;
        }
        *classification += t.elapsed();
        if let Some(bar) = bar {
            bar.inc(block.len() as u64);
        }
    })?;
    match failure {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_groups_are_found_by_their_names() {
        let names: Vec<String> = FeatureGroups::BOUNDED
            .names()
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(groups_named(&names), Some(FeatureGroups::BOUNDED));
        assert_eq!(groups_named(&["nonsense".to_string()]), None);
    }
}
