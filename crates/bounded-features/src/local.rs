//! The statistics of one point's nested neighbourhoods (SPEC.md, "Features").

use bounded_geom::{Sym3, dot};

use crate::FeatureConfig;

/// Values per scale with every group on (see `config::NAMES`).
pub(crate) const ALL_FEATURES: usize = 15;

/// Per-thread buffers, reused from point to point so the hot loop never allocates.
pub(crate) struct Scratch {
    /// Neighbours relative to the query point, in `f64`.
    local: Vec<[f64; 3]>,
    /// (squared distance to the centroid, rank) for the normal's half neighbourhood.
    near_centroid: Vec<(f64, u32)>,
}

impl Scratch {
    pub(crate) fn new(k0: usize) -> Self {
        Self {
            local: Vec::with_capacity(k0),
            near_centroid: Vec::with_capacity(k0),
        }
    }
}

/// A neighbourhood's normalised frame: centroid, scale factor and oriented normal.
struct Frame {
    mean: [f64; 3],
    /// `2 / (sqrt(s1) + sqrt(s2))`, or 1 when that is not finite (all points equal).
    scale: f64,
    /// Unit normal with `<p^_i, n> >= 0`.
    normal: [f64; 3],
    /// Eigenvalues of the covariance, descending, clamped at 0.
    variances: [f64; 3],
}

/// Writes the selected features of every scale for the point `neighbours[0]`, whose
/// `k0` sorted neighbours are `neighbours`, into `out` (scales x selected values).
pub(crate) fn point_features(
    points: &[[f32; 3]],
    neighbours: &[u32],
    config: &FeatureConfig,
    scratch: &mut Scratch,
    out: &mut [f32],
) {
    // Centre on the query point in f64: small, well-conditioned coordinates.
    let p = points[neighbours[0] as usize].map(f64::from);
    scratch.local.clear();
    scratch.local.extend(neighbours.iter().map(|&j| {
        let q = points[j as usize];
        [0, 1, 2].map(|a| f64::from(q[a]) - p[a])
    }));
    let k0 = neighbours.len();
    let mut largest: Option<Frame> = None;
    let per_scale = config.features_per_scale();
    for (&k, out) in config.scales.iter().zip(out.chunks_exact_mut(per_scale)) {
        let frame = frame(&scratch.local[..k], &mut scratch.near_centroid);
        let mut all = scale_features(&scratch.local[..k], &frame);
        if let Some(f0) = &largest {
            // c: this scale's centroid against the rest of the k0 neighbourhood,
            // in the k0 frame.
            let rest = mean(&scratch.local[k..k0]);
            let c = [0, 1, 2].map(|a| (frame.mean[a] - rest[a]) * f0.scale);
            [all[13], all[14]] = split(c, f0.normal);
        }
        for (o, i) in out.iter_mut().zip(config.groups.selected()) {
            *o = all[i] as f32;
        }
        largest.get_or_insert(frame);
    }
}

/// Centroid, normalisation and oriented normal of `pts` (relative to the query point,
/// which is therefore the origin).
fn frame(pts: &[[f64; 3]], near_centroid: &mut Vec<(f64, u32)>) -> Frame {
    let m = mean(pts);
    let variances = covariance(pts.iter().copied(), m)
        .eigenvalues()
        .map(|v| v.max(0.0));
    let scale = 2.0 / (variances[0].sqrt() + variances[1].sqrt());
    let scale = if scale.is_finite() { scale } else { 1.0 };
    // Normal from the floor(k/2) points closest to the centroid: robust to outliers.
    let half = pts.len() / 2;
    near_centroid.clear();
    near_centroid.extend(pts.iter().zip(0u32..).map(|(q, j)| (dist2(*q, m), j)));
    let raw = if half == 0 {
        [0.0, 0.0, 1.0]
    } else {
        near_centroid
            .select_nth_unstable_by(half - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let near = &near_centroid[..half];
        let nm = mean_of(near.iter().map(|&(_, j)| pts[j as usize]), half);
        covariance(near.iter().map(|&(_, j)| pts[j as usize]), nm)
            .eigen()
            .smallest_vector
    };
    Frame {
        mean: m,
        scale,
        normal: orient(raw, m.map(|c| -c)),
        variances,
    }
}

/// Orients the unit normal `n` so that `<s, n> >= 0`, where `s = p_i - m` (the query
/// point's offset from the centroid, same direction as `p^_i`).
///
/// When `<s, n>` is exactly 0 the first non-zero component of `n` is made positive,
/// so the result never depends on the eigen solver's sign.
pub(crate) fn orient(n: [f64; 3], s: [f64; 3]) -> [f64; 3] {
    let t = dot(s, n);
    let tie = n.iter().copied().find(|&c| c != 0.0).unwrap_or(0.0);
    if t < 0.0 || (t == 0.0 && tie < 0.0) {
        n.map(|c| -c)
    } else {
        n
    }
}

/// The 15 values of one scale (all groups, `c` left at 0) in the normalised frame.
fn scale_features(pts: &[[f64; 3]], f: &Frame) -> [f64; ALL_FEATURES] {
    let mut all = [0.0; ALL_FEATURES];
    let s2 = f.scale * f.scale;
    all[..3].copy_from_slice(&f.variances.map(|v| v * s2));
    let normalised = pts
        .iter()
        .map(|q| [0, 1, 2].map(|a| (q[a] - f.mean[a]) * f.scale));
    let upper = |v: &[f64; 3]| dot(*v, f.normal) >= 0.0;
    // Two passes: means of U and L, then their covariances around those means.
    let (mut sum_u, mut sum_l, mut n_u) = ([0.0; 3], [0.0; 3], 0usize);
    for v in normalised.clone() {
        let (sum, up) = if upper(&v) {
            (&mut sum_u, true)
        } else {
            (&mut sum_l, false)
        };
        n_u += usize::from(up);
        for a in 0..3 {
            sum[a] += v[a];
        }
    }
    let n_l = pts.len() - n_u;
    let mean_u = sum_u.map(|c| c / n_u.max(1) as f64);
    let mean_l = sum_l.map(|c| c / n_l.max(1) as f64);
    if n_u >= 2 {
        let cov = covariance(normalised.clone().filter(upper), mean_u);
        all[3..6].copy_from_slice(&cov.eigenvalues().map(|v| v.max(0.0)));
    }
    if n_l >= 2 {
        let cov = covariance(normalised.clone().filter(|v| !upper(v)), mean_l);
        all[6..9].copy_from_slice(&cov.eigenvalues().map(|v| v.max(0.0)));
    }
    if n_u > 0 && n_l > 0 {
        [all[9], all[10]] = split([0, 1, 2].map(|a| mean_u[a] - mean_l[a]), f.normal);
    }
    // The query point is the origin of `pts`.
    [all[11], all[12]] = split(f.mean.map(|c| -c * f.scale), f.normal);
    all
}

/// Components of `v` along the unit vector `n` and the length of the rest.
fn split(v: [f64; 3], n: [f64; 3]) -> [f64; 2] {
    let along = dot(v, n);
    let rest = [0, 1, 2].map(|a| v[a] - along * n[a]);
    [along, dot(rest, rest).sqrt()]
}

fn mean(pts: &[[f64; 3]]) -> [f64; 3] {
    mean_of(pts.iter().copied(), pts.len())
}

/// Mean of `len` points (zero for none).
fn mean_of(pts: impl Iterator<Item = [f64; 3]>, len: usize) -> [f64; 3] {
    let mut s = [0.0; 3];
    for q in pts {
        for a in 0..3 {
            s[a] += q[a];
        }
    }
    s.map(|c| c / len.max(1) as f64)
}

/// Population covariance (divided by the count) of `pts` around `m`.
fn covariance(pts: impl Iterator<Item = [f64; 3]>, m: [f64; 3]) -> Sym3 {
    let mut c = Sym3::default();
    let mut n = 0usize;
    for q in pts {
        let d = [q[0] - m[0], q[1] - m[1], q[2] - m[2]];
        c.xx += d[0] * d[0];
        c.xy += d[0] * d[1];
        c.xz += d[0] * d[2];
        c.yy += d[1] * d[1];
        c.yz += d[1] * d[2];
        c.zz += d[2] * d[2];
        n += 1;
    }
    let inv = 1.0 / n.max(1) as f64;
    Sym3 {
        xx: c.xx * inv,
        xy: c.xy * inv,
        xz: c.xz * inv,
        yy: c.yy * inv,
        yz: c.yz * inv,
        zz: c.zz * inv,
    }
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    dot(d, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientation_ignores_the_solvers_sign() {
        let n = [0.6, 0.0, -0.8];
        for s in [[1.0, 2.0, 3.0], [-1.0, 0.5, 0.2], [0.8, 7.0, 0.6], [0.0; 3]] {
            let a = orient(n, s);
            assert_eq!(a, orient(n.map(|c| -c), s), "s = {s:?}");
            assert!(dot(a, s) >= 0.0);
        }
        // In-plane query point: the first non-zero component decides.
        assert_eq!(orient([0.0, -1.0, 0.0], [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
    }
}
