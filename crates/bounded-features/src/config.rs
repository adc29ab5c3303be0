//! Which scales and which feature groups to compute.

use crate::{ContextSet, FeatureError};

/// The paper's default scales (neighbour counts), largest first.
pub const DEFAULT_SCALES: [usize; 4] = [128, 64, 32, 16];

/// Names of every feature of one scale, in output order, when all groups are on.
const NAMES: [&str; 16] = [
    "sigma_1", "sigma_2", "sigma_3", "sigma_u1", "sigma_u2", "sigma_u3", "sigma_l1", "sigma_l2",
    "sigma_l3", "d_perp", "d_par", "s_perp", "s_par", "c_perp", "c_par", "h",
];

/// Selection of feature groups, for the paper's feature ablation.
///
/// Output order within a scale is fixed: `sigma` (3), `sigma_u` (3), `sigma_l` (3),
/// `d` (perp, par), `s` (perp, par), `c` (perp, par), `h`, skipping unselected
/// groups. The default is BoundED's 12 features (everything but `sigma` and `h`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FeatureGroups {
    /// Eigenvalues of the whole normalised neighbourhood's covariance (3; off by default,
    /// only the paper's ablation uses them).
    pub sigma: bool,
    /// Eigenvalues of the upper set's covariance (3).
    pub sigma_u: bool,
    /// Eigenvalues of the lower set's covariance (3).
    pub sigma_l: bool,
    /// Difference of the upper and lower means, along and across the normal (2).
    pub d: bool,
    /// Offset of the query point from the centroid, along and across the normal (2).
    pub s: bool,
    /// Offset of this scale's centroid from the rest of the largest neighbourhood (2).
    pub c: bool,
    /// How far the query point lies inside the convex hull of its neighbours in the
    /// largest neighbourhood's tangent plane, over 32 directions (1; not in the paper): 0
    /// on a border. A mean such as `s` places a border of randomly sampled points only to
    /// about the neighbourhood's radius over `sqrt(k)`; the hull's edge runs through the
    /// outermost points themselves.
    pub h: bool,
}

impl FeatureGroups {
    /// BoundED's feature set: `sigma_u`, `sigma_l`, `d`, `s`, `c` (12 per scale).
    pub const BOUNDED: Self = Self {
        sigma: false,
        sigma_u: true,
        sigma_l: true,
        d: true,
        s: true,
        c: true,
        h: false,
    };

    /// No group: a base for selections such as `FeatureGroups { d: true, ..NONE }`.
    pub const NONE: Self = Self {
        sigma: false,
        sigma_u: false,
        sigma_l: false,
        d: false,
        s: false,
        c: false,
        h: false,
    };

    /// Every group: BoundED's, `sigma` and `h` (16 values per scale).
    pub const ALL: Self = Self {
        sigma: true,
        h: true,
        ..Self::BOUNDED
    };

    /// The paper's feature ablation, labelled: `sigma` alone, then `sigma_u` and `sigma_l`,
    /// adding `d`, `s` and `c` in turn up to BoundED's features.
    pub const ABLATION: [(&'static str, Self); 5] = {
        let ul = Self {
            sigma_u: true,
            sigma_l: true,
            ..Self::NONE
        };
        [
            (
                "sigma",
                Self {
                    sigma: true,
                    ..Self::NONE
                },
            ),
            ("sigma_U, sigma_L", ul),
            ("sigma_U/L, d", Self { d: true, ..ul }),
            (
                "sigma_U/L, d, s",
                Self {
                    d: true,
                    s: true,
                    ..ul
                },
            ),
            ("sigma_U/L, d, s, c (BoundED)", Self::BOUNDED),
        ]
    };

    /// Selection flags with the number of values of each group, in output order.
    fn flags(&self) -> [(bool, usize); 7] {
        [
            (self.sigma, 3),
            (self.sigma_u, 3),
            (self.sigma_l, 3),
            (self.d, 2),
            (self.s, 2),
            (self.c, 2),
            (self.h, 1),
        ]
    }

    /// Number of values per scale.
    pub fn count(&self) -> usize {
        self.flags().iter().filter(|f| f.0).map(|f| f.1).sum()
    }

    /// Names of the selected values of one scale, in output order.
    pub fn names(&self) -> Vec<&'static str> {
        self.selected().map(|i| NAMES[i]).collect()
    }

    /// Positions of the selected values within the full 15-value list of a scale.
    pub(crate) fn selected(&self) -> impl Iterator<Item = usize> + '_ {
        let mut start = 0;
        self.flags().into_iter().flat_map(move |(on, len)| {
            let range = start..start + len;
            start += len;
            range.filter(move |_| on)
        })
    }
}

impl Default for FeatureGroups {
    fn default() -> Self {
        Self::BOUNDED
    }
}

/// Scales, feature groups and context of an extraction.
///
/// Scales are neighbour counts (the point itself included), strictly descending:
/// the first is `k0`, whose frame and normal the `c` features use.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct FeatureConfig {
    /// Neighbour counts, largest first.
    pub scales: Vec<usize>,
    /// Feature groups computed at every scale.
    pub groups: FeatureGroups,
    /// The context values beside each scale's features, in an extraction in context.
    pub context: ContextSet,
}

impl Default for FeatureConfig {
    fn default() -> Self {
        Self {
            scales: DEFAULT_SCALES.to_vec(),
            groups: FeatureGroups::BOUNDED,
            context: ContextSet::Neighbourhood,
        }
    }
}

impl FeatureConfig {
    /// The paper's scale ablation: `count` scales of `2^i` neighbours, `i` evenly spaced
    /// over `(3, 7]` (`i = 3 + 4 j / count`, `j = count..1`), rounded to the nearest
    /// integer, halves away from zero. 2, 4, 8 and 16 scales reproduce the paper's lists,
    /// e.g. 8 scales: 128, 91, 64, 45, 32, 23, 16, 11.
    pub fn ablation(count: usize, groups: FeatureGroups) -> Result<Self, FeatureError> {
        let scales = (1..=count)
            .rev()
            .map(|j| 2f64.powf(3.0 + 4.0 * j as f64 / count as f64).round() as usize)
            .collect();
        let config = Self {
            scales,
            groups,
            context: ContextSet::Neighbourhood,
        };
        config.validate()?;
        Ok(config)
    }

    /// Values per scale.
    pub fn features_per_scale(&self) -> usize {
        self.groups.count()
    }

    /// Values per point: scales x values per scale.
    pub fn features_per_point(&self) -> usize {
        self.scales.len() * self.features_per_scale()
    }

    /// The largest scale `k0` (0 for an empty scale list, which [`validate`](Self::validate)
    /// rejects).
    pub fn largest_scale(&self) -> usize {
        self.scales.first().copied().unwrap_or(0)
    }

    /// Checks that scales are non-empty, positive and strictly descending, and that
    /// some feature group is selected.
    pub fn validate(&self) -> Result<(), FeatureError> {
        let bad = |reason| {
            Err(FeatureError::InvalidScales {
                scales: self.scales.clone(),
                reason,
            })
        };
        if self.scales.is_empty() {
            return bad("at least one scale is needed");
        }
        if self.scales.contains(&0) {
            return bad("every scale needs at least one neighbour");
        }
        if self.scales.windows(2).any(|w| w[0] <= w[1]) {
            return bad("scales must be strictly descending");
        }
        if self.groups.count() == 0 {
            return Err(FeatureError::NoFeatureGroups);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ablation_scales_match_the_paper() {
        let s = |n| {
            FeatureConfig::ablation(n, FeatureGroups::BOUNDED)
                .unwrap()
                .scales
        };
        assert_eq!(s(2), [128, 32]);
        assert_eq!(s(4), DEFAULT_SCALES);
        assert_eq!(s(8), [128, 91, 64, 45, 32, 23, 16, 11]);
        assert_eq!(
            s(16),
            [
                128, 108, 91, 76, 64, 54, 45, 38, 32, 27, 23, 19, 16, 13, 11, 10
            ]
        );
    }

    #[test]
    fn counts_and_names() {
        let c = FeatureConfig::default();
        assert_eq!((c.features_per_scale(), c.features_per_point()), (12, 48));
        assert_eq!(c.largest_scale(), 128);
        let g = FeatureGroups {
            sigma: true,
            sigma_u: false,
            sigma_l: false,
            d: false,
            s: true,
            c: false,
            h: true,
        };
        assert_eq!(g.count(), 6);
        assert_eq!(
            g.names(),
            ["sigma_1", "sigma_2", "sigma_3", "s_perp", "s_par", "h"]
        );
        assert_eq!(FeatureGroups::BOUNDED.names()[0], "sigma_u1");
        assert_eq!(FeatureGroups::BOUNDED.names()[11], "c_par");
    }

    #[test]
    fn the_feature_ablation_adds_groups_up_to_bounded() {
        let counts = FeatureGroups::ABLATION.map(|(_, g)| g.count());
        assert_eq!(counts, [3, 6, 8, 10, 12]);
        assert_eq!(FeatureGroups::ABLATION[4].1, FeatureGroups::BOUNDED);
        assert_eq!(
            (FeatureGroups::NONE.count(), FeatureGroups::ALL.count()),
            (0, 16)
        );
    }

    #[test]
    fn rejects_bad_configs() {
        let with = |scales: Vec<usize>| FeatureConfig {
            scales,
            groups: FeatureGroups::BOUNDED,
            ..FeatureConfig::default()
        };
        assert!(with(vec![]).validate().is_err());
        assert!(with(vec![16, 32]).validate().is_err());
        assert!(with(vec![32, 32]).validate().is_err());
        assert!(with(vec![4, 0]).validate().is_err());
        assert!(with(vec![4, 1]).validate().is_ok());
        let none = FeatureGroups {
            sigma_u: false,
            sigma_l: false,
            d: false,
            s: false,
            c: false,
            ..FeatureGroups::BOUNDED
        };
        assert_eq!(
            FeatureConfig::ablation(4, none),
            Err(FeatureError::NoFeatureGroups)
        );
    }
}
