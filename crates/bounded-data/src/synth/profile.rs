//! 2D profiles and the two sweeps that turn them into meshes (extrusion and revolution).
//!
//! Most shapes are a profile swept one way or the other: boxes, prisms, stairs and wedges are
//! extruded polygons; cylinders, cones, spheres, tori, pyramids and lathe parts are revolved
//! profiles. Corners of a profile become creases (or fillets, when rounded first).

use super::mesh::Mesh;
use rand::Rng;
use std::f64::consts::TAU;

/// A 2D point: `(x, y)` for extrusion, `(radius, z)` for revolution.
pub(crate) type P2 = [f64; 2];

/// Arcs are split so consecutive segments turn by at most this (degrees): far below the
/// sharp threshold, so fillets and curved surfaces stay non-edge.
pub(crate) const ARC_STEP_DEG: f64 = 6.0;

fn sub2(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

fn len2(a: P2) -> f64 {
    a[0].hypot(a[1])
}

fn unit2(a: P2) -> P2 {
    let l = len2(a).max(f64::MIN_POSITIVE);
    [a[0] / l, a[1] / l]
}

/// Points of a circular arc around `centre` from angle `from` to `to` (radians), both ends included.
pub(crate) fn arc(centre: P2, radius: f64, from: f64, to: f64) -> Vec<P2> {
    let steps = ((to - from).abs() / ARC_STEP_DEG.to_radians())
        .ceil()
        .max(1.0) as usize;
    (0..=steps)
        .map(|i| {
            let t = from + (to - from) * i as f64 / steps as f64;
            [centre[0] + radius * t.cos(), centre[1] + radius * t.sin()]
        })
        .collect()
}

/// Replaces corners by tangent arcs: `radius(turn_degrees)` gives the fillet radius of each
/// corner (0 keeps it sharp). A radius too large for the adjacent edges is reduced.
pub(crate) fn round_corners(
    poly: &[P2],
    closed: bool,
    mut radius: impl FnMut(f64) -> f64,
) -> Vec<P2> {
    let n = poly.len();
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let interior = closed || (i > 0 && i + 1 < n);
        if !interior {
            out.push(poly[i]);
            continue;
        }
        let (prev, p, next) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        let (d0, d1) = (unit2(sub2(p, prev)), unit2(sub2(next, p)));
        let cross = d0[0] * d1[1] - d0[1] * d1[0];
        let turn = (d0[0] * d1[0] + d0[1] * d1[1]).clamp(-1.0, 1.0).acos();
        let r = radius(turn.to_degrees());
        if r <= 0.0 || turn < 1e-6 {
            out.push(p);
            continue;
        }
        let room = 0.45 * len2(sub2(p, prev)).min(len2(sub2(next, p)));
        let tangent = (r * (turn / 2.0).tan()).min(room);
        let r = tangent / (turn / 2.0).tan();
        let start = [p[0] - d0[0] * tangent, p[1] - d0[1] * tangent];
        // The centre lies on the inner side of the turn.
        let side = cross.signum();
        let normal = [-d0[1] * side, d0[0] * side];
        let centre = [start[0] + normal[0] * r, start[1] + normal[1] * r];
        let a0 = (start[1] - centre[1]).atan2(start[0] - centre[0]);
        out.extend(arc(centre, r, a0, a0 + side * turn));
    }
    out
}

/// A random star-shaped polygon around the origin with `corners` vertices, radii in
/// `[0.5, 1]`, counter-clockwise.
pub(crate) fn star_polygon(rng: &mut impl Rng, corners: usize) -> Vec<P2> {
    let step = TAU / corners as f64;
    (0..corners)
        .map(|k| {
            let t = step * (k as f64 + rng.random_range(-0.2..0.2));
            let r = rng.random_range(0.5..1.0);
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

/// Extrudes a profile along z from 0 to `height`: side walls, plus the caps asked for on a
/// closed profile (an open profile gives a folded or curved sheet).
pub(crate) fn extrude(profile: &[P2], height: f64, closed: bool, caps: [bool; 2]) -> Mesh {
    let mut m = Mesh::default();
    let bottom = m.vertices_of(profile.iter().map(|p| [p[0], p[1], 0.0]));
    let top = m.vertices_of(profile.iter().map(|p| [p[0], p[1], height]));
    m.strip(&bottom, &top, closed);
    if closed {
        if caps[0] {
            m.polygon(&bottom);
        }
        if caps[1] {
            m.polygon(&top);
        }
    }
    m
}

/// Revolves a `(radius, z)` profile around the z axis over `sweep` radians (a full turn
/// closes the surface) with `segments` steps; `closed_profile` joins the last profile point
/// to the first (a torus). Profile points on the axis collapse when the mesh is welded.
pub(crate) fn revolve(profile: &[P2], segments: usize, sweep: f64, closed_profile: bool) -> Mesh {
    let full = sweep >= TAU - 1e-9;
    let count = if full { segments } else { segments + 1 };
    let mut m = Mesh::default();
    let rings: Vec<Vec<u32>> = profile
        .iter()
        .map(|&[r, z]| {
            m.vertices_of((0..count).map(|j| {
                let t = sweep * j as f64 / segments as f64;
                [r * t.cos(), r * t.sin(), z]
            }))
        })
        .collect();
    for w in rings.windows(2) {
        m.strip(&w[0], &w[1], full);
    }
    if closed_profile && let (Some(last), Some(first)) = (rings.last(), rings.first()) {
        m.strip(last, first, full);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounded_square_keeps_straight_parts_and_has_quarter_arcs() {
        let square = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let r = round_corners(&square, true, |turn| {
            assert!((turn - 90.0).abs() < 1e-9);
            0.5
        });
        // Each arc of 90 degrees at 6 degree steps: 16 points.
        assert_eq!(r.len(), 4 * 16);
        // Every point is on the rounded square: distance 0.5 from the inner square [0.5, 1.5]^2.
        for p in &r {
            let dx = (p[0] - p[0].clamp(0.5, 1.5)).abs();
            let dy = (p[1] - p[1].clamp(0.5, 1.5)).abs();
            assert!((dx.hypot(dy) - 0.5).abs() < 1e-9, "{p:?}");
        }
    }

    #[test]
    fn capped_cylinder_welds_to_a_closed_surface() {
        let m = revolve(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]],
            64,
            TAU,
            false,
        )
        .welded();
        let f = m.features();
        assert!(f.border.is_empty());
        // Two sharp rim circles, each a closed loop of 64 points.
        assert_eq!(f.sharp.len(), 2);
        for line in &f.sharp {
            assert!(line.closed);
            assert!(
                (line.length() - 64.0 * 2.0 * (std::f64::consts::PI / 64.0).sin()).abs() < 1e-9
            );
        }
    }

    #[test]
    fn extruded_triangle_has_nine_sharp_edges() {
        let m = extrude(
            &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            1.0,
            true,
            [true, true],
        )
        .welded();
        let f = m.features();
        assert!(f.border.is_empty());
        assert_eq!(f.sharp.len(), 9);
    }
}
