//! Hand-checkable behaviour of the BoundED features.
//!
//! Index helpers name the 12 BoundED values of a scale: sigma_u 0..3, sigma_l 3..6,
//! d_perp 6, d_par 7, s_perp 8, s_par 9, c_perp 10, c_par 11.

mod common;

use bounded_features::{
    CONTEXT_PER_SCALE, ContextSet, FeatureConfig, FeatureError, FeatureGroups, Features, extract,
    extract_chunks, extract_chunks_staged, extract_in_context,
};
use bounded_geom::{GeomError, PointCloud};
use common::Rng;

const D_PERP: usize = 6;
const S_PERP: usize = 8;
const S_PAR: usize = 9;
const C_PERP: usize = 10;
const C_PAR: usize = 11;

fn config(scales: &[usize]) -> FeatureConfig {
    FeatureConfig {
        scales: scales.to_vec(),
        groups: FeatureGroups::BOUNDED,
        ..FeatureConfig::default()
    }
}

fn run(points: &[[f64; 3]], scales: &[usize]) -> Features {
    extract(&PointCloud::from_f64(points).unwrap(), &config(scales)).unwrap()
}

/// A jittered `n x n` grid of unit spacing on z = f(x, y), with z noise `noise`;
/// point `i` sits at grid cell (i % n, i / n), centred on the origin.
fn surface(n: usize, noise: f64, seed: u64, f: impl Fn(f64, f64) -> f64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed);
    let h = (n as f64 - 1.0) / 2.0;
    (0..n * n)
        .map(|i| {
            let x = (i % n) as f64 - h + rng.sym(0.1);
            let y = (i / n) as f64 - h + rng.sym(0.1);
            [x, y, f(x, y) + rng.sym(noise)]
        })
        .collect()
}

/// Index of the grid point at cell (cx, cy) of an `n x n` grid.
fn cell(n: usize, cx: usize, cy: usize) -> usize {
    cy * n + cx
}

#[test]
fn symmetric_grid_exact_values() {
    // 3x3 grid, k = 9 around the centre: centroid = query, s1 = s2 = 6/9, so the
    // normalised variances are exactly (1, 1, 0) (scale factor sqrt(3/2)). All points
    // lie in the split plane, so they join U by rank (centre 0, edge midpoints 1-4, then
    // corners 5-8, each in index order): ranks 0, 2, 4, 5, 7 go up, that is, offsets
    // (0,0), (-1,0), (0,1), (-1,-1), (-1,1): covariance [[0.24, 0.12], [0.12, 0.56]],
    // eigenvalues 0.6 and 0.2, normalised 0.9 and 0.3. L holds (0,-1), (1,0), (1,-1),
    // (1,1): [[0.1875, 0.1875], [0.1875, 0.6875]], eigenvalues 0.75 and 0.125,
    // normalised 1.125 and 0.1875. D = mean(U) - mean(L) = (-1.35, 0.45), in the plane:
    // d_par = sqrt(2.025 * 1.5).
    let pts: Vec<[f64; 3]> = (0..9)
        .map(|i| [(i % 3) as f64, (i / 3) as f64, 0.0])
        .collect();
    let cfg = FeatureConfig {
        scales: vec![9],
        groups: FeatureGroups {
            sigma: true,
            ..FeatureGroups::BOUNDED
        },
        ..FeatureConfig::default()
    };
    let f = extract(&PointCloud::from_f64(&pts).unwrap(), &cfg).unwrap();
    let x = f.point(4);
    let d_par = (2.025f32 * 1.5).sqrt();
    let want = [
        1.0, 1.0, 0.0, 0.9, 0.3, 0.0, 1.125, 0.1875, 0.0, 0.0, d_par, 0.0, 0.0, 0.0, 0.0,
    ];
    for (i, (g, w)) in x.iter().zip(want).enumerate() {
        assert!((g - w).abs() < 1e-6, "value {i}: {g} != {w} in {x:?}");
    }
}

#[test]
fn flat_disc() {
    // A noisy plane. At k0 = 128 the U / L split is by noise, so both halves span the
    // disc: normalised in-plane variances near 1 (a uniform disc of radius 2 has
    // variance 1 per axis). At small k the half-neighbourhood's normal tilts by about
    // the noise over the radius, which then decides the split, so sigma_U and sigma_L
    // are only compared at k0. At every scale the normal variance, d_perp and s_perp
    // vanish and the query sits near the centroid.
    let n = 24;
    let pts = surface(n, 0.01, 1, |_, _| 0.0);
    let f = run(&pts, &[128, 64, 32, 16]);
    let x = f.point(cell(n, 12, 12));
    let (su, sl) = (&x[0..3], &x[3..6]);
    assert!(
        su[0] > 0.7 && su[0] < 1.3 && sl[0] > 0.7 && sl[0] < 1.3,
        "{x:?}"
    );
    assert!(
        (su[0] - sl[0]).abs() < 0.25 && (su[1] - sl[1]).abs() < 0.25,
        "{x:?}"
    );
    for s in 0..4 {
        let v = &x[s * 12..(s + 1) * 12];
        assert!(v[2] < 0.01 && v[5] < 0.01, "{v:?}");
        assert!(v[D_PERP].abs() < 0.05, "d_perp {v:?}");
        assert!(v[S_PERP].abs() < 0.05 && v[S_PAR] < 0.3, "s {v:?}");
    }
}

#[test]
fn ridge_point_versus_flat_point() {
    // Roof z = -|y|: two planes meeting at 90 degrees along the x axis. On the ridge
    // the centroid sits 4R/(3 pi) ~ 0.42 R below the query and s1 ~ s2 ~ R^2/4 (R the
    // neighbourhood radius in xy), so s_perp ~ 0.85; the upper set (near the ridge) is
    // well above the lower set. Far from the ridge the surface is flat.
    let n = 40;
    let pts = surface(n, 0.005, 2, |_, y| -y.abs());
    // Rows are y; the ridge y = 0 runs between rows 19 and 20 of the jittered grid, so
    // use an exact ridge point by snapping one point onto it.
    let mut pts = pts;
    let ridge = cell(n, 20, 20);
    pts[ridge] = [pts[ridge][0], 0.0, 0.0];
    let far = cell(n, 20, 34);
    let f = run(&pts, &[64, 32, 16]);
    let (xr, xf) = (f.point(ridge), f.point(far));
    for s in 0..3 {
        let (r, q) = (&xr[s * 12..], &xf[s * 12..]);
        assert!(
            r[S_PERP] > 0.6 && r[S_PERP] < 1.1,
            "ridge s_perp {}",
            r[S_PERP]
        );
        assert!(q[S_PERP].abs() < 0.05, "flat s_perp {}", q[S_PERP]);
        assert!(r[D_PERP] > 0.3, "ridge d_perp {}", r[D_PERP]);
        assert!(q[D_PERP].abs() < 0.05, "flat d_perp {}", q[D_PERP]);
        // U is the band along the ridge, L the two slopes beyond: their second
        // variances (across the ridge) differ clearly.
        assert!(
            r[4] - r[1] > 0.3,
            "ridge sigma_u2 {} sigma_l2 {}",
            r[1],
            r[4]
        );
    }
}

#[test]
fn half_plane_border_has_large_s_par() {
    // Half-disc neighbourhood: centroid 4R/(3 pi) from the border point, s1 = R^2/4,
    // s2 = R^2/4 - (4R/(3 pi))^2, so s_par ~ 0.42 * 2 / (0.5 + 0.265) ~ 1.1.
    let n = 30;
    let pts: Vec<[f64; 3]> = surface(n, 0.01, 3, |_, _| 0.0)
        .into_iter()
        .filter(|p| p[1] > 0.0)
        .collect();
    let cloud = PointCloud::from_f64(&pts).unwrap();
    let f = extract(&cloud, &config(&[64, 32])).unwrap();
    let nearest = |x: f64, y: f64| {
        (0..pts.len())
            .min_by(|&a, &b| {
                let d = |i: usize| (pts[i][0] - x).powi(2) + (pts[i][1] - y).powi(2);
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    let (border, inner) = (f.point(nearest(0.5, 0.5)), f.point(nearest(0.5, 7.5)));
    for s in 0..2 {
        let (b, i) = (&border[s * 12..], &inner[s * 12..]);
        assert!(
            b[S_PAR] > 0.8 && b[S_PAR] < 1.4,
            "border s_par {}",
            b[S_PAR]
        );
        assert!(i[S_PAR] < 0.3, "inner s_par {}", i[S_PAR]);
    }
}

#[test]
fn outlier_above_a_plane_has_large_s_perp() {
    // 16 neighbours on a unit grid span R ~ 2.3, so scale ~ 2 / R ~ 0.9; an outlier 3
    // above the plane has s_perp ~ 3 * 15/16 * 0.9 ~ 2.5, a plane point ~ 0.
    let n = 20;
    let mut pts = surface(n, 0.0, 4, |_, _| 0.0);
    pts.push([0.0, 0.0, 3.0]);
    let f = run(&pts, &[16]);
    let out = f.point(pts.len() - 1);
    let plane = f.point(cell(n, 3, 3));
    assert!(
        out[S_PERP] > 1.8 && out[S_PERP] < 3.5,
        "outlier s_perp {}",
        out[S_PERP]
    );
    assert!(plane[S_PERP].abs() < 0.01, "plane s_perp {}", plane[S_PERP]);
}

#[test]
fn c_detects_a_nearby_crease() {
    // A point 2.4 from the ridge: its 16 nearest (radius ~2.3) lie on its own slope, but the
    // 128 neighbourhood reaches over the ridge, so the small neighbourhood's centroid
    // is off the rest of the big one along the big one's normal. On a flat region c
    // stays in the plane; at k0 it is zero by definition.
    let n = 40;
    let pts = surface(n, 0.005, 5, |_, y| -y.abs());
    let f = run(&pts, &[128, 16]);
    let near = f.point(cell(n, 20, 22));
    let flat = {
        let flat_pts = surface(n, 0.005, 5, |_, y| -y);
        run(&flat_pts, &[128, 16]).point(cell(n, 20, 22)).to_vec()
    };
    assert_eq!((near[C_PERP], near[C_PAR]), (0.0, 0.0));
    let (cn, cf) = (near[12 + C_PERP], flat[12 + C_PERP]);
    assert!(cn.abs() > 0.1, "near crease c_perp {cn}");
    assert!(cf.abs() < 0.02, "flat c_perp {cf}");
    assert!(near[12 + C_PAR] > 0.0);
}

/// Number of points whose features differ by more than `tol` anywhere.
fn differing_points(a: &Features, b: &Features, tol: f32) -> usize {
    (0..a.len())
        .filter(|&i| {
            a.point(i)
                .iter()
                .zip(b.point(i))
                .any(|(x, y)| (x - y).abs() > tol)
        })
        .count()
}

#[test]
fn invariant_under_translation_rotation_and_scale() {
    // The clouds differ only by f32 rounding of the transformed coordinates (~1e-7
    // relative). Features are O(1) and continuous except where a neighbour lies on the
    // U / L split plane (within rounding, ~1 in 10^4 point-neighbour pairs here), which
    // moves it between the sets. So: at most 1% of the points may differ by more than
    // 1e-3.
    let n = 20;
    let pts = surface(n, 0.02, 6, |x, y| 0.05 * (x * x - 0.5 * y * y));
    let scales = [64, 32, 16];
    let base = run(&pts, &scales);
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let (c2, s2) = (1.1f64.cos(), 1.1f64.sin());
    type Transform = Box<dyn Fn([f64; 3]) -> [f64; 3]>;
    let transforms: [(&str, Transform); 3] = [
        (
            "translate",
            Box::new(|p| [p[0] + 5_403_150.25, p[1] - 77.5, p[2] + 1e3]),
        ),
        (
            "rotate",
            Box::new(move |p| {
                let q = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
                [q[0], c2 * q[1] - s2 * q[2], s2 * q[1] + c2 * q[2]]
            }),
        ),
        ("scale", Box::new(|p| p.map(|v| v * 1234.5))),
    ];
    // Context of arbitrary first-stage probabilities moves with the features.
    let mut rng = Rng(9);
    let probabilities: Vec<[f32; 3]> = (0..pts.len())
        .map(|_| {
            let (a, b) = (rng.next() as f32, rng.next() as f32);
            [(1.0 - a) * (1.0 - b), a, (1.0 - a) * b]
        })
        .collect();
    let in_context = |points: &[[f64; 3]]| {
        let cloud = PointCloud::from_f64(points).unwrap();
        extract_in_context(&cloud, &config(&scales), &probabilities).unwrap()
    };
    let base_context = in_context(&pts);
    for (name, t) in transforms {
        let moved: Vec<_> = pts.iter().map(|&p| t(p)).collect();
        let d = differing_points(&base, &run(&moved, &scales), 1e-3);
        assert!(d <= pts.len() / 100, "{name}: {d} points differ");
        let d = differing_points(&base_context, &in_context(&moved), 1e-3);
        assert!(
            d <= pts.len() / 100,
            "{name}, in context: {d} points differ"
        );
    }
    let tiny: Vec<_> = pts.iter().map(|p| p.map(|v| v * 1e-12)).collect();
    let d = differing_points(&base, &run(&tiny, &scales), 1e-3);
    assert!(d <= pts.len() / 100, "tiny coordinates: {d} points differ");
}

#[test]
fn a_plane_along_the_axes_splits_as_a_rotated_copy_does() {
    // Noise-free random points on z = 0: every offset from the split plane is exactly 0.
    // Rotated, the plane's points sit off it by rounding only, which splits them about in
    // halves; the axis-aligned copy must split alike (by rank), not put all in U. Compared
    // by medians over the inner points: the lower set's largest variance (about that of a
    // half disc, 1 at k0 and somewhat less at small k) and its share (about a half).
    let mut rng = Rng(5);
    let flat: Vec<[f64; 3]> = (0..3000)
        .map(|_| [rng.sym(10.0), rng.sym(10.0), 0.0])
        .collect();
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    let tilted: Vec<[f64; 3]> = flat
        .iter()
        .map(|p| [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]])
        .collect();
    let scales = [64, 16];
    let inner: Vec<usize> = (0..flat.len())
        .filter(|&i| flat[i][0].abs() < 7.0 && flat[i][1].abs() < 7.0)
        .collect();
    let median = |f: &Features, v: usize| {
        let mut x: Vec<f32> = inner.iter().map(|&i| f.point(i)[v]).collect();
        x.sort_by(f32::total_cmp);
        x[x.len() / 2]
    };
    let (along, rotated) = (run(&flat, &scales), run(&tilted, &scales));
    for s in 0..scales.len() {
        let sigma_l1 = s * 12 + 3;
        let (a, r) = (median(&along, sigma_l1), median(&rotated, sigma_l1));
        assert!(r > 0.4, "scale {s}: rotated sigma_l1 {r}");
        assert!(
            (a - r).abs() < 0.15 * r,
            "scale {s}: sigma_l1 {a} along the axes, {r} rotated"
        );
    }
}

#[test]
fn context_of_a_row_of_sharp_points_beside_the_features() {
    // An exact 12 x 12 grid of unit spacing; the first stage calls row y = 6 sharp. At
    // k = 5 a point has its 4 nearest grid neighbours, at k = 9 also the 4 diagonal ones.
    let n = 12;
    let pts: Vec<[f64; 3]> = (0..n * n)
        .map(|i| [(i % n) as f64, (i / n) as f64, 0.0])
        .collect();
    let probabilities: Vec<[f32; 3]> = (0..n * n)
        .map(|i| match i / n {
            6 => [0.0, 1.0, 0.0],
            _ => [1.0, 0.0, 0.0],
        })
        .collect();
    let cloud = PointCloud::from_f64(&pts).unwrap();
    let cfg = config(&[9, 5]);
    let plain = extract(&cloud, &cfg).unwrap();
    let with = extract_in_context(&cloud, &cfg, &probabilities).unwrap();
    let per_scale = 12 + CONTEXT_PER_SCALE;
    assert_eq!(with.per_point(), 2 * per_scale);
    for i in 0..n * n {
        for s in 0..2 {
            let own = &with.point(i)[s * per_scale..s * per_scale + 12];
            assert_eq!(own, &plain.point(i)[s * 12..s * 12 + 12], "point {i}");
        }
    }
    let context = |cx, cy, s: usize| {
        let start = s * per_scale + 12;
        with.point(cell(n, cx, cy))[start..start + CONTEXT_PER_SCALE].to_vec()
    };
    let third = 1.0 / 3.0;
    let cases = [
        // On the row: its two row neighbours are sharp, centred on the point.
        ((6, 6, 1), [0.6, 0.0, 0.0, 0.4]),
        ((6, 6, 0), [third, 0.0, 0.0, 1.0 - third]),
        // Beside it: one sharp neighbour straight up (offset = radius), then three
        // centred on the one above, at 1 of radius sqrt 2.
        ((6, 5, 1), [0.2, 0.0, 1.0, -0.2]),
        ((6, 5, 0), [third, 0.0, 0.5f32.sqrt(), -third]),
        // Far from it: no sharp probability, the rim value 1.
        ((6, 2, 0), [0.0, 0.0, 1.0, 0.0]),
    ];
    for ((cx, cy, s), expected) in cases {
        let got = context(cx, cy, s);
        for (g, e) in got.iter().zip(expected) {
            assert!(
                (g - e).abs() < 1e-6,
                "({cx}, {cy}) scale {s}: {got:?} vs {expected:?}"
            );
        }
    }
    let e = extract_in_context(&cloud, &cfg, &probabilities[1..]).unwrap_err();
    assert_eq!(
        e,
        FeatureError::ContextLength {
            points: n * n,
            probabilities: n * n - 1
        }
    );
}

#[test]
fn smaller_scales_are_prefixes_of_the_largest() {
    // A scale's sigma, d and s do not depend on which larger scales are computed.
    let n = 16;
    let pts = surface(n, 0.05, 7, |x, _| 0.1 * x * x);
    let both = run(&pts, &[64, 16]);
    let alone = run(&pts, &[16]);
    for i in 0..pts.len() {
        assert_eq!(
            &both.point(i)[12..12 + 10],
            &alone.point(i)[..10],
            "point {i}"
        );
    }
}

#[test]
fn identical_whatever_the_chunking_and_thread_count() {
    let n = 18;
    let pts = surface(n, 0.05, 8, |x, y| 0.2 * (x * y).sin());
    let cloud = PointCloud::from_f64(&pts).unwrap();
    let cfg = config(&[32, 8]);
    let reference = extract(&cloud, &cfg).unwrap();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for chunk in [1, 37, 100_000] {
            let mut got = vec![f32::NAN; reference.as_slice().len()];
            let mut seen = 0;
            pool.install(|| {
                extract_chunks(&cloud, &cfg, chunk, |b| {
                    assert!(b.len() <= chunk);
                    for (r, &i) in b.points().iter().enumerate() {
                        let i = i as usize;
                        got[i * 24..(i + 1) * 24].copy_from_slice(b.row(r));
                        seen += 1;
                    }
                })
            })
            .unwrap();
            assert_eq!(seen, pts.len());
            assert!(
                got.iter()
                    .zip(reference.as_slice())
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "threads {threads}, chunk {chunk}"
            );
        }
    }
}

#[test]
fn degenerate_clouds_give_finite_features() {
    let line: Vec<_> = (0..40)
        .map(|i| [i as f64, 2.0 * i as f64, -(i as f64)])
        .collect();
    let f = run(&line, &[32, 8]);
    assert!(f.as_slice().iter().all(|v| v.is_finite()));
    // A line is normalised by its only spread: variances along it are 4 (s2 = 0); every
    // point lies on the split plane, so U and L take about half of it each by rank, each
    // spread along it about as the whole.
    let x = f.point(20);
    assert!(
        (x[0] - 4.0).abs() < 1.0 && (x[3] - 4.0).abs() < 1.0,
        "{x:?}"
    );
    let dup: Vec<_> = (0..60)
        .map(|i| [(i % 3) as f64, 0.0, ((i / 3) % 2) as f64])
        .collect();
    assert!(run(&dup, &[6, 4]).as_slice().iter().all(|v| v.is_finite()));
}

#[test]
fn repeated_points_share_the_features_of_their_position() {
    // A crease (a roof ridge), then the same points again with every third one three times.
    let once = surface(16, 0.02, 9, |x, _| -x.abs());
    let mut repeated = once.clone();
    repeated.extend_from_slice(&once);
    repeated.extend(once.iter().step_by(3));
    let (a, b) = (run(&once, &[64, 16]), run(&repeated, &[64, 16]));
    let n = once.len();
    for (j, _) in repeated.iter().enumerate() {
        let i = if j < 2 * n { j % n } else { 3 * (j - 2 * n) };
        assert_eq!(b.point(j), a.point(i), "point {j}, a repeat of {i}");
    }
    // Fewer distinct positions than the largest scale: said as such.
    let same = PointCloud::from_f64(&[[3.0, -2.0, 1e6]; 40]).unwrap();
    let e = extract(&same, &config(&[32, 8])).unwrap_err();
    assert_eq!(
        e,
        FeatureError::TooFewDistinctPoints {
            points: 40,
            distinct: 1,
            k: 32
        }
    );
    assert!(e.to_string().contains("only 1 distinct positions"), "{e}");
}

#[test]
fn clear_errors() {
    assert!(matches!(
        PointCloud::from_f64(&[[0.0; 3], [f64::NAN, 1.0, 2.0]]),
        Err(GeomError::NonFinite { index: 1, .. })
    ));
    assert!(PointCloud::from_f64(&[[f64::INFINITY, 1.0, 2.0]]).is_err());
    let small = PointCloud::from_f64(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    let e = extract(&small, &FeatureConfig::default()).unwrap_err();
    assert_eq!(
        e,
        FeatureError::Geom(GeomError::TooFewPoints { points: 3, k: 128 })
    );
    assert!(e.to_string().contains("3 points") && e.to_string().contains("128"));
    assert!(matches!(
        extract(&small, &config(&[2, 3])),
        Err(FeatureError::InvalidScales { .. })
    ));
}

/// A stand-in first stage: probabilities from a row's first values, so that they vary from
/// point to point the way a classifier's would.
fn stand_in_first_stage(row: &[f32]) -> [f32; 3] {
    let (a, b) = (row[0].abs(), row[S_PERP].abs());
    let sum = 1.0 + a + b;
    [1.0 / sum, a / sum, b / sum]
}

#[test]
fn staged_equals_two_passes_whatever_the_chunking_and_thread_count() {
    // A crease with repeated points (each repeat's block row stands for its position).
    let mut pts = surface(30, 0.02, 11, |x, y| -x.abs() + 0.1 * (0.5 * y).sin());
    pts.extend(pts.clone().iter().step_by(5));
    let cloud = PointCloud::from_f64(&pts).unwrap();
    for (context, threads) in (ContextSet::ALL.into_iter()).flat_map(|c| [(c, 1), (c, 2), (c, 3)]) {
        let cfg = FeatureConfig {
            context,
            ..config(&[32, 8])
        };
        let plain = extract(&cloud, &cfg).unwrap();
        let first: Vec<[f32; 3]> = (0..plain.len())
            .map(|i| stand_in_first_stage(plain.point(i)))
            .collect();
        let reference = extract_in_context(&cloud, &cfg, &first).unwrap();
        let per_point = reference.per_point();
        assert_eq!(per_point, 2 * (12 + context.count()));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        // Chunks of 1 and 7 points wait for many later chunks: their halos get computed.
        for chunk in [1, 7, 60, 333, 100_000] {
            let mut got = vec![f32::NAN; reference.as_slice().len()];
            let mut seen = vec![0; pts.len()];
            let halo = pool
                .install(|| {
                    extract_chunks_staged(
                        &cloud,
                        &cfg,
                        chunk,
                        |block, out| {
                            for (r, p) in out.iter_mut().enumerate() {
                                *p = stand_in_first_stage(block.row(r));
                            }
                        },
                        |block| {
                            for (r, &i) in block.points().iter().enumerate() {
                                let i = i as usize;
                                got[i * per_point..(i + 1) * per_point]
                                    .copy_from_slice(block.row(r));
                                seen[i] += 1;
                            }
                        },
                    )
                })
                .unwrap();
            assert!(seen.iter().all(|&s| s == 1), "chunk {chunk}");
            assert!(
                got.iter()
                    .zip(reference.as_slice())
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{context:?}, threads {threads}, chunk {chunk}"
            );
            // Small chunks overflow the window of waiting chunks; one chunk never waits.
            if chunk <= 7 {
                assert!(halo > 0, "chunk {chunk}: no halo");
            }
            if chunk == 100_000 {
                assert_eq!(halo, 0);
            }
        }
    }
}

#[test]
fn reach_is_the_farthest_neighbour_and_for_the_context_its_neighbours_too() {
    // Ten points on a line, x = 0, 1, 2, 3, 5, ... (a gap of 2 after x = 3), a repeat of
    // x = 0 at the end; 3 neighbours (the point, then the two nearest).
    let xs = [0.0, 1.0, 2.0, 3.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 0.0];
    let points: Vec<[f64; 3]> = xs.iter().map(|&x| [x, 0.0, 0.0]).collect();
    let cloud = PointCloud::from_local(
        [0.0; 3],
        points.iter().map(|p| p.map(|c| c as f32)).collect(),
    )
    .unwrap();
    let cfg = config(&[3]);
    // Features: the distance of the third neighbour. x = 0: 2; x = 1, 2: 1; x = 3: 2 (2, 1);
    // x = 5: 2 (6, 7 or 3); x = 6..9: 1; x = 10: 2; the repeat shares x = 0's.
    let own = [2.0, 1.0, 1.0, 2.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0];
    let mut reach = vec![f32::NAN; xs.len()];
    extract_chunks(&cloud, &cfg, 4, |block| {
        for (&i, &r) in block.points().iter().zip(block.reach()) {
            reach[i as usize] = r;
        }
    })
    .unwrap();
    assert_eq!(reach, own);
    // The context reads the neighbours' first stage: the point's reach plus the largest of
    // its neighbours' (its own among them). x = 0 (neighbours 1, 2): 2 + 2; x = 2 (1, 3):
    // 1 + 2; x = 6 (5, 7): 1 + 2; x = 8 (7, 9): 1 + 1; x = 10 (9, 8): 2 + 2.
    let mut staged = vec![f32::NAN; xs.len()];
    extract_chunks_staged(
        &cloud,
        &cfg,
        4,
        |_, out| out.fill([1.0, 0.0, 0.0]),
        |block| {
            for (&i, &r) in block.points().iter().zip(block.reach()) {
                staged[i as usize] = r;
            }
        },
    )
    .unwrap();
    assert_eq!(
        staged,
        [4.0, 3.0, 3.0, 4.0, 4.0, 3.0, 2.0, 2.0, 3.0, 4.0, 4.0]
    );
}

#[test]
fn hull_inset_on_a_grid_by_hand() {
    // A 5 x 5 unit grid, x 0..4, y -2..2, z 0, one scale of all 25 points: centroid
    // (2, 0, 0), variances 2 and 2 (of 0..4), scale 2 / (2 sqrt 2) = 1 / sqrt 2. The hull
    // is the square's outline: (1, 0) lies 1 inside its edge x = 0, so h = 1 / sqrt 2;
    // the border point (0, 0) lies on it; the centre (2, 0) lies 2 inside every edge.
    let grid: Vec<[f64; 3]> = (0..25)
        .map(|i| [(i % 5) as f64, (i / 5) as f64 - 2.0, 0.0])
        .collect();
    let cfg = FeatureConfig {
        scales: vec![25],
        groups: FeatureGroups {
            h: true,
            s: true,
            ..FeatureGroups::NONE
        },
        ..FeatureConfig::default()
    };
    assert_eq!(cfg.groups.names(), ["s_perp", "s_par", "h"]);
    let f = extract(&PointCloud::from_f64(&grid).unwrap(), &cfg).unwrap();
    let e = |i: usize| f.point(i)[2];
    assert_eq!(
        (grid[11], grid[10], grid[12]),
        ([1.0, 0.0, 0.0], [0.0; 3], [2.0, 0.0, 0.0])
    );
    assert!((e(11) - 0.5f32.sqrt()).abs() < 1e-6, "{}", e(11));
    assert_eq!(e(10), 0.0);
    assert!((e(12) - 2.0 * 0.5f32.sqrt()).abs() < 1e-6, "{}", e(12));
}

#[test]
fn hull_inset_is_invariant_and_small_on_borders() {
    // A random half plane y >= 0: along the border h is small at every scale (the point
    // is on or next to its neighbours' hull), inside it is a good part of the radius
    // (about 1.1 for 16 random neighbours, near 2 for a full disc); moving, turning or
    // scaling the cloud keeps it (within the f32 rounding the other invariance test
    // allows).
    let mut rng = Rng(17);
    let pts: Vec<[f64; 3]> = (0..4000)
        .map(|_| [rng.next() * 60.0, rng.next() * 60.0, 0.0])
        .collect();
    let cfg = FeatureConfig {
        scales: vec![64, 16],
        groups: FeatureGroups {
            h: true,
            ..FeatureGroups::NONE
        },
        ..FeatureConfig::default()
    };
    let run_h = |p: &[[f64; 3]]| extract(&PointCloud::from_f64(p).unwrap(), &cfg).unwrap();
    let f = run_h(&pts);
    let at = &pts;
    let pick = |lo: f64, hi: f64| {
        (0..at.len()).filter(move |&i| {
            let p = at[i];
            p[1] >= lo && p[1] < hi && p[0] > 10.0 && p[0] < 50.0
        })
    };
    let median = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    for s in 0..2 {
        let mut border: Vec<f32> = pick(0.0, 0.15).map(|i| f.point(i)[s]).collect();
        let mut inside: Vec<f32> = pick(25.0, 35.0).map(|i| f.point(i)[s]).collect();
        let (b, i) = (median(&mut border), median(&mut inside));
        assert!(
            b < 0.2 && i > 0.9 && i < 2.5,
            "scale {s}: border {b}, inside {i}"
        );
    }
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let moved: Vec<_> = pts
        .iter()
        .map(|p| {
            [
                1e5 + 3.0 * (c * p[0] - s * p[2]),
                3.0 * p[1] - 7.0,
                3.0 * (s * p[0] + c * p[2]),
            ]
        })
        .collect();
    let d = differing_points(&f, &run_h(&moved), 1e-3);
    assert!(d <= pts.len() / 100, "{d} points differ");
}
