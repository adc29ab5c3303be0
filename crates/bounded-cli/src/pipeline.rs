//! Detection: features streamed block by block straight into the classifier, so memory stays
//! O(points + block) whatever the cloud's size.

use crate::progress;
use anyhow::{Context, Result, bail};
use bounded_features::{DEFAULT_CHUNK_POINTS, FeatureConfig, FeatureGroups, extract_chunks};
use bounded_geom::{Class, PointCloud};
use bounded_nn::{Classifier, N_CLASSES, argmax};
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
    let bar = show_progress.then(|| progress::bar("detect", n as u64, "points"));
    let mut probabilities = vec![[0f32; N_CLASSES]; n];
    let mut block_out = Vec::new();
    let mut classification = Duration::ZERO;
    let mut failure = None;
    extract_chunks(cloud, config, DEFAULT_CHUNK_POINTS, |block| {
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
        classification += t.elapsed();
        if let Some(bar) = &bar {
            bar.inc(block.len() as u64);
        }
    })?;
    if let Some(e) = failure {
        return Err(e.into());
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
