//! The shape catalogue: every kind builds a mesh of size about 1 around the origin.
//!
//! Generated creases deviate from flat by at least [`MIN_CREASE_DEG`], well above the sharp
//! threshold, and smooth parts turn by at most [`ARC_STEP_DEG`](super::profile::ARC_STEP_DEG)
//! per edge, so no label hinges on rounding.

use super::mesh::Mesh;
use super::polyhedron::Polyhedron;
use super::profile::{P2, arc, extrude, revolve, round_corners, star_polygon};
use bounded_geom::vec3::{V3, segment_distance};
use rand::Rng;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Corners of random profiles turning less than this (degrees) are rounded into fillets.
const MIN_CREASE_DEG: f64 = 25.0;

/// Segments of a full revolution: 5 degrees per edge, far below the sharp threshold.
const ROUND_SEGMENTS: usize = 72;

/// One kind of generated shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ShapeKind {
    /// A box of random aspect (three-face corners, 90-degree creases).
    Box,
    /// A box with smaller boxes stuck on and dented into its faces, recursively.
    FractalCube,
    /// A staircase (alternating convex and concave creases).
    Stairs,
    /// An extruded random polygon (creases of many angles).
    Prism,
    /// A triangular prism whose apex angle is anywhere in 20..155 degrees (convex creases).
    Wedge,
    /// A block with a V-notch of random opening (a concave crease).
    Notch,
    /// A pyramid or frustum with a 3- to 8-gon base.
    Frustum,
    /// A revolved random profile mixing sharp and rounded (smooth) circles.
    Lathe,
    /// A capped cylinder (sharp rims, smooth side).
    Cylinder,
    /// A cone with its base (sharp rim, smooth side and apex).
    Cone,
    /// A sphere (smooth everywhere).
    Sphere,
    /// A torus (smooth everywhere).
    Torus,
    /// An extruded polygon with fillets of several radii along its vertical edges.
    RoundedPrism,
    /// An open sheet folded along one to three creases, some rounded (borders and creases).
    FoldedSheet,
    /// A flat disc or annulus (curved borders).
    Disc,
    /// A flat polygon, possibly with a hole (straight and curved borders).
    PolygonSheet,
    /// An open cylinder, full or partial (curved and straight borders).
    Tube,
    /// An open spherical cap (a curved border on a smooth surface).
    Bowl,
    /// A box without its top (a border on a sharp rim).
    OpenBox,
    /// A plate much thinner than the point spacing: boundary at its rim, as in the paper.
    ThinPlate,
    /// A box with 1..4 slices cut off by random planes (corners and creases of any angle).
    CutBlock,
    /// A turned part: a revolved profile of small steps, chamfers and grooves, so creases
    /// lie a few point spacings apart as on machined CAD parts.
    Turned,
    /// A thin-walled cup, round or polygonal, possibly with a flange: both sides of a wall
    /// and both creases of its rim fall into one neighbourhood.
    Cup,
    /// A block with narrow ribs and slots along its top (parallel creases close together).
    Ribbed,
    /// A block whose top folds along 1..4 shallow creases, each deviating 12..25 degrees
    /// from flat, convex or concave: the low ridges, valleys and slope changes that the
    /// other kinds (creases from 25 degrees) lack. Drawn only in sets that ask for it
    /// (`shallow=`, [`SetConfig::shallow`](super::SetConfig::shallow)).
    ShallowRidges,
}

impl ShapeKind {
    /// Every kind, in a fixed order.
    pub const ALL: [ShapeKind; 25] = [
        ShapeKind::Box,
        ShapeKind::FractalCube,
        ShapeKind::Stairs,
        ShapeKind::Prism,
        ShapeKind::Wedge,
        ShapeKind::Notch,
        ShapeKind::Frustum,
        ShapeKind::Lathe,
        ShapeKind::Cylinder,
        ShapeKind::Cone,
        ShapeKind::Sphere,
        ShapeKind::Torus,
        ShapeKind::RoundedPrism,
        ShapeKind::FoldedSheet,
        ShapeKind::Disc,
        ShapeKind::PolygonSheet,
        ShapeKind::Tube,
        ShapeKind::Bowl,
        ShapeKind::OpenBox,
        ShapeKind::ThinPlate,
        ShapeKind::CutBlock,
        ShapeKind::Turned,
        ShapeKind::Cup,
        ShapeKind::Ribbed,
        ShapeKind::ShallowRidges,
    ];

    /// Snake-case name, used in generated cloud names.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Box => "box",
            ShapeKind::FractalCube => "fractal_cube",
            ShapeKind::Stairs => "stairs",
            ShapeKind::Prism => "prism",
            ShapeKind::Wedge => "wedge",
            ShapeKind::Notch => "notch",
            ShapeKind::Frustum => "frustum",
            ShapeKind::Lathe => "lathe",
            ShapeKind::Cylinder => "cylinder",
            ShapeKind::Cone => "cone",
            ShapeKind::Sphere => "sphere",
            ShapeKind::Torus => "torus",
            ShapeKind::RoundedPrism => "rounded_prism",
            ShapeKind::FoldedSheet => "folded_sheet",
            ShapeKind::Disc => "disc",
            ShapeKind::PolygonSheet => "polygon_sheet",
            ShapeKind::Tube => "tube",
            ShapeKind::Bowl => "bowl",
            ShapeKind::OpenBox => "open_box",
            ShapeKind::ThinPlate => "thin_plate",
            ShapeKind::CutBlock => "cut_block",
            ShapeKind::Turned => "turned",
            ShapeKind::Cup => "cup",
            ShapeKind::Ribbed => "ribbed",
            ShapeKind::ShallowRidges => "shallow_ridges",
        }
    }

    /// True for shapes with open borders (their points include the boundary class).
    pub fn is_open(self) -> bool {
        matches!(
            self,
            ShapeKind::FoldedSheet
                | ShapeKind::Disc
                | ShapeKind::PolygonSheet
                | ShapeKind::Tube
                | ShapeKind::Bowl
                | ShapeKind::OpenBox
                | ShapeKind::ThinPlate
        )
    }

    /// Builds a random instance (unwelded, untransformed).
    pub(crate) fn build(self, rng: &mut impl Rng) -> Mesh {
        match self {
            ShapeKind::Box => {
                let (a, b) = (rng.random_range(0.3..1.0), rng.random_range(0.3..1.0));
                let rect = [[0.0, 0.0], [a, 0.0], [a, b], [0.0, b]];
                extrude(&rect, rng.random_range(0.3..1.0), true, [true, true])
            }
            ShapeKind::FractalCube => {
                let mut m = Mesh::default();
                let depth = rng.random_range(1..=2);
                box_faces(&mut m, [0.0; 3], [0.5; 3], depth, None, rng);
                m
            }
            ShapeKind::Stairs => {
                extrude(&stairs(rng), rng.random_range(0.4..1.2), true, [true, true])
            }
            ShapeKind::Prism => {
                let corners = rng.random_range(3..=9);
                let poly = crease_safe(&star_polygon(rng, corners), true);
                extrude(&poly, rng.random_range(0.2..1.2), true, [true, true])
            }
            ShapeKind::Wedge => {
                let half = rng.random_range(20.0_f64..155.0).to_radians() / 2.0;
                let reach = rng.random_range(0.4..1.0);
                let tri = [
                    [0.0, 0.0],
                    [reach * half.cos(), reach * half.sin()],
                    [reach * half.cos(), -reach * half.sin()],
                ];
                extrude(&tri, rng.random_range(0.3..1.0), true, [true, true])
            }
            ShapeKind::Notch => {
                extrude(&notch(rng), rng.random_range(0.3..1.0), true, [true, true])
            }
            ShapeKind::Frustum => {
                let (r, h) = (rng.random_range(0.3..0.6), rng.random_range(0.3..1.0));
                let top = rng.random_range(0.0..0.9) * r;
                let profile: Vec<P2> = if top < 0.1 * r {
                    vec![[0.0, 0.0], [r, 0.0], [0.0, h]]
                } else {
                    vec![[0.0, 0.0], [r, 0.0], [top, h], [0.0, h]]
                };
                revolve(&profile, rng.random_range(3..=8), TAU, false)
            }
            ShapeKind::Lathe => revolve(&lathe_profile(rng), ROUND_SEGMENTS, TAU, false),
            ShapeKind::Cylinder => {
                let (r, h) = (rng.random_range(0.15..0.5), rng.random_range(0.3..1.0));
                revolve(
                    &[[0.0, 0.0], [r, 0.0], [r, h], [0.0, h]],
                    ROUND_SEGMENTS,
                    TAU,
                    false,
                )
            }
            ShapeKind::Cone => {
                let (r, h) = (rng.random_range(0.2..0.5), rng.random_range(0.3..1.0));
                revolve(
                    &[[0.0, 0.0], [r, 0.0], [0.0, h]],
                    ROUND_SEGMENTS,
                    TAU,
                    false,
                )
            }
            ShapeKind::Sphere => {
                let r = rng.random_range(0.3..0.6);
                revolve(
                    &arc([0.0, 0.0], r, -FRAC_PI_2, FRAC_PI_2),
                    ROUND_SEGMENTS,
                    TAU,
                    false,
                )
            }
            ShapeKind::Torus => {
                let big = rng.random_range(0.3..0.5);
                let small = rng.random_range(0.2..0.8) * big;
                let mut ring = arc([big, 0.0], small, 0.0, TAU);
                ring.pop(); // the arc repeats its start; the closed profile joins it instead
                revolve(&ring, ROUND_SEGMENTS, TAU, true)
            }
            ShapeKind::RoundedPrism => {
                let corners = rng.random_range(3..=7);
                let poly = star_polygon(rng, corners);
                let rounded = round_corners(&poly, true, |_| {
                    [0.03, 0.08, 0.15, 0.3][rng.random_range(0..4)]
                });
                extrude(&rounded, rng.random_range(0.2..1.0), true, [true, true])
            }
            ShapeKind::FoldedSheet => {
                let profile = folded_profile(rng);
                extrude(&profile, rng.random_range(0.4..1.2), false, [false, false])
            }
            ShapeKind::Disc => {
                let r = rng.random_range(0.3..0.6);
                let inner = if rng.random_bool(0.5) {
                    0.0
                } else {
                    rng.random_range(0.2..0.7) * r
                };
                revolve(&[[inner, 0.0], [r, 0.0]], ROUND_SEGMENTS, TAU, false)
            }
            ShapeKind::PolygonSheet => polygon_sheet(rng),
            ShapeKind::Tube => {
                let (r, h) = (rng.random_range(0.2..0.5), rng.random_range(0.3..1.0));
                let sweep = if rng.random_bool(0.5) {
                    TAU
                } else {
                    rng.random_range(0.5 * PI..1.7 * PI)
                };
                let segments = (ROUND_SEGMENTS as f64 * sweep / TAU).ceil() as usize;
                revolve(&[[r, 0.0], [r, h]], segments, sweep, false)
            }
            ShapeKind::Bowl => {
                let r = rng.random_range(0.3..0.6);
                let rim = rng.random_range(-0.3..0.6);
                revolve(
                    &arc([0.0, 0.0], r, -FRAC_PI_2, rim),
                    ROUND_SEGMENTS,
                    TAU,
                    false,
                )
            }
            ShapeKind::OpenBox => {
                let (a, b) = (rng.random_range(0.3..1.0), rng.random_range(0.3..1.0));
                let rect = [[0.0, 0.0], [a, 0.0], [a, b], [0.0, b]];
                extrude(&rect, rng.random_range(0.2..0.8), true, [true, false])
            }
            ShapeKind::CutBlock => {
                let size = [(); 3].map(|()| rng.random_range(0.4..1.0));
                let mut block = Polyhedron::cuboid(size);
                for _ in 0..rng.random_range(1..=4) {
                    block.cut_randomly(rng);
                }
                block.to_mesh()
            }
            ShapeKind::ThinPlate => {
                let mut m = polygon_sheet(rng);
                let thickness = rng.random_range(0.002..0.008);
                let mut other = m.clone();
                other.map(|[x, y, z]| [x, y, z + thickness]);
                m.append(&other);
                m
            }
            ShapeKind::Turned => revolve(&turned_profile(rng), ROUND_SEGMENTS, TAU, false),
            ShapeKind::Cup => {
                let segments = if rng.random_bool(0.7) {
                    ROUND_SEGMENTS
                } else {
                    rng.random_range(4..=8)
                };
                revolve(&cup_profile(rng), segments, TAU, false)
            }
            ShapeKind::ShallowRidges => extrude(
                &shallow_ridges(rng),
                rng.random_range(0.3..1.0),
                true,
                [true, true],
            ),
            ShapeKind::Ribbed => {
                extrude(&ribbed(rng), rng.random_range(0.3..1.0), true, [true, true])
            }
        }
    }
}

/// Rounds the corners of a random profile that turn less than [`MIN_CREASE_DEG`], so every
/// remaining corner is an unambiguous crease.
fn crease_safe(poly: &[P2], closed: bool) -> Vec<P2> {
    round_corners(
        poly,
        closed,
        |turn| if turn < MIN_CREASE_DEG { 0.1 } else { 0.0 },
    )
}

/// A staircase profile of 2..6 steps of random tread and rise.
fn stairs(rng: &mut impl Rng) -> Vec<P2> {
    let steps = rng.random_range(2..=6);
    let mut profile = vec![[0.0, 0.0]];
    let (mut x, mut y) = (0.0, 0.0);
    for _ in 0..steps {
        y += rng.random_range(0.08..0.25);
        profile.push([x, y]);
        x += rng.random_range(0.1..0.3);
        profile.push([x, y]);
    }
    profile.push([x, 0.0]);
    profile
}

/// A size drawn log-uniformly from `lo..hi`: small details as often as large ones.
pub(crate) fn detail(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo.ln()..hi.ln()).exp()
}

/// A `(radius, z)` profile from the bottom pole to the top pole through 3..8 sections
/// whose radius changes by a square step or a 45-degree chamfer of 0.01..0.1.
fn turned_profile(rng: &mut impl Rng) -> Vec<P2> {
    let mut r = rng.random_range(0.2..0.45);
    let mut z = 0.0;
    let mut profile = vec![[0.0, 0.0], [r, 0.0]];
    for _ in 0..rng.random_range(3..=8) {
        z += detail(rng, 0.01, 0.2);
        profile.push([r, z]);
        let step = detail(rng, 0.01, 0.1);
        let next = if r + step > 0.5 || (r - step > 0.08 && rng.random_bool(0.5)) {
            r - step
        } else {
            r + step
        };
        if rng.random_bool(0.3) {
            z += step;
        }
        r = next;
        profile.push([r, z]);
    }
    z += detail(rng, 0.01, 0.2);
    profile.extend([[r, z], [0.0, z]]);
    profile
}

/// A `(radius, z)` profile of a cup with walls and bottom 0.015..0.08 thick, half of them
/// with an outward flange at the rim.
fn cup_profile(rng: &mut impl Rng) -> Vec<P2> {
    let (r, h) = (rng.random_range(0.2..0.45), rng.random_range(0.3..0.9));
    let (wall, bottom) = (detail(rng, 0.015, 0.08), detail(rng, 0.015, 0.1));
    let mut profile = vec![[0.0, 0.0], [r, 0.0]];
    if rng.random_bool(0.5) {
        let (reach, thick) = (detail(rng, 0.02, 0.15), detail(rng, 0.015, 0.06));
        profile.extend([[r, h - thick], [r + reach, h - thick], [r + reach, h]]);
    } else {
        profile.push([r, h]);
    }
    profile.extend([[r - wall, h], [r - wall, bottom], [0.0, bottom]]);
    profile
}

/// A block profile whose top carries ribs and slots 0.015..0.12 wide and 0.01..0.15 high,
/// 0.015..0.2 apart.
fn ribbed(rng: &mut impl Rng) -> Vec<P2> {
    let (w, h) = (rng.random_range(0.5..1.0), rng.random_range(0.2..0.5));
    let mut profile = vec![[0.0, 0.0], [w, 0.0], [w, h]];
    let mut x = w - detail(rng, 0.015, 0.2);
    while x > 0.05 {
        let width = detail(rng, 0.015, 0.12).min(x - 0.03);
        let height = detail(rng, 0.01, 0.15);
        let y = if rng.random_bool(0.5) {
            h + height
        } else {
            h - height.min(0.8 * h)
        };
        profile.extend([[x, h], [x, y], [x - width, y], [x - width, h]]);
        x -= width + detail(rng, 0.015, 0.2);
    }
    profile.push([0.0, h]);
    profile
}

/// A block with a V-notch cut into its top; the notch's rim corners stay clear of the
/// sharp threshold (opening at most 130 degrees).
fn notch(rng: &mut impl Rng) -> Vec<P2> {
    let (w, h): (f64, f64) = (rng.random_range(0.6..1.0), rng.random_range(0.4..0.8));
    let half = rng.random_range(20.0_f64..130.0).to_radians() / 2.0;
    let depth = (0.6 * h).min(0.4 * w / half.tan());
    let spread = depth * half.tan();
    let mid = w / 2.0 + rng.random_range(-0.05..0.05) * w;
    vec![
        [0.0, 0.0],
        [w, 0.0],
        [w, h],
        [mid + spread, h],
        [mid, h - depth],
        [mid - spread, h],
        [0.0, h],
    ]
}

/// A `(radius, z)` profile from the bottom pole to the top pole through 2..5 random
/// radii; each corner is either kept sharp or filleted with a random radius.
fn lathe_profile(rng: &mut impl Rng) -> Vec<P2> {
    let knots = rng.random_range(2..=5);
    let mut profile = vec![[0.0, 0.0]];
    let mut z = 0.0;
    for i in 0..knots {
        if i > 0 {
            z += rng.random_range(0.1..0.4);
        }
        profile.push([rng.random_range(0.15..0.5), z]);
    }
    profile.push([0.0, z]);
    round_corners(&profile, false, |turn| {
        if turn < MIN_CREASE_DEG || rng.random_bool(0.4) {
            [0.02, 0.05, 0.1][rng.random_range(0..3)]
        } else {
            0.0
        }
    })
}

/// The least and the largest deviation from flat of a [`ShapeKind::ShallowRidges`] crease
/// (degrees): above the sharp threshold by more than the stretch of a shape can take away
/// (12 / 1.25 = 9.6 is the rare exception, labelled by its actual angle), below the 25 of
/// every other kind.
const SHALLOW_DEG: [f64; 2] = [12.0, 25.0];

/// The profile of a [`ShapeKind::ShallowRidges`] block: a bottom, two sides, and a top
/// from `x = w` back to `x = 0` whose slope turns by [`SHALLOW_DEG`] at each of 1..4
/// creases, up or down, within 30 degrees of level; the top is then raised so that its
/// lowest point lies a random height above the bottom.
fn shallow_ridges(rng: &mut impl Rng) -> Vec<P2> {
    let w: f64 = rng.random_range(0.6..1.2);
    let creases = rng.random_range(1..=4);
    // Crease positions, at least a tenth of the width apart and from the sides.
    let mut xs: Vec<f64> = Vec::new();
    while xs.len() < creases {
        let x = rng.random_range(0.1..0.9) * w;
        if xs.iter().all(|&o: &f64| (o - x).abs() > 0.1 * w) {
            xs.push(x);
        }
    }
    xs.sort_by(|a, b| b.total_cmp(a));
    xs.push(0.0);
    let limit = 30f64.to_radians();
    let mut slope: f64 = rng.random_range(-0.5 * limit..0.5 * limit);
    let mut top = vec![[w, 0.0]];
    for (i, &x) in xs.iter().enumerate() {
        let [x0, y0] = top[top.len() - 1];
        top.push([x, y0 + (x0 - x) * slope.tan()]);
        if i + 1 < xs.len() {
            // One of the two stays within the limit, as a turn is below it.
            let turn = rng
                .random_range(SHALLOW_DEG[0]..SHALLOW_DEG[1])
                .to_radians();
            let up = match (slope + turn <= limit, slope - turn >= -limit) {
                (true, true) => rng.random_bool(0.5),
                (up, _) => up,
            };
            slope += if up { turn } else { -turn };
        }
    }
    let lowest = top.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let rise = rng.random_range(0.3..0.7) - lowest;
    let mut profile = vec![[0.0, 0.0], [w, 0.0]];
    profile.extend(top.iter().map(|&[x, y]| [x, y + rise]));
    profile
}

/// An open polyline with 1..3 folds whose deviation from flat is 25..165 degrees, either
/// sign; some folds are rounded into curved sheets.
fn folded_profile(rng: &mut impl Rng) -> Vec<P2> {
    let folds = rng.random_range(1..=3);
    let mut heading: f64 = 0.0;
    let mut p = [0.0, 0.0];
    let mut profile = vec![p];
    for i in 0..=folds {
        if i > 0 {
            let turn = rng.random_range(MIN_CREASE_DEG..165.0).to_radians();
            heading += if rng.random_bool(0.5) { turn } else { -turn };
        }
        let len = rng.random_range(0.3..0.8);
        p = [p[0] + len * heading.cos(), p[1] + len * heading.sin()];
        profile.push(p);
    }
    round_corners(&profile, false, |_| {
        if rng.random_bool(0.25) { 0.15 } else { 0.0 }
    })
}

/// A flat star polygon in the z = 0 plane, possibly with a round or polygonal hole.
fn polygon_sheet(rng: &mut impl Rng) -> Mesh {
    let corners = rng.random_range(3..=8);
    let outer = star_polygon(rng, corners);
    let outer = if rng.random_bool(0.3) {
        round_corners(&outer, true, |_| 0.1)
    } else {
        outer
    };
    let mut m = Mesh::default();
    let ring = m.vertices_of(outer.iter().map(|p| [p[0], p[1], 0.0]));
    if rng.random_bool(0.5) {
        let centre = m.vertex([0.0; 3]);
        m.fan(centre, &ring);
        return m;
    }
    // The hole follows the outer outline's angles, so the two rings pair up into quads; it
    // stays within the largest circle inside the outline (a square hole within its inscribed
    // square's diagonal).
    let inside = (0..outer.len())
        .map(|i| {
            let (a, b) = (outer[i], outer[(i + 1) % outer.len()]);
            segment_distance([0.0; 3], [a[0], a[1], 0.0], [b[0], b[1], 0.0])
        })
        .fold(f64::INFINITY, f64::min);
    let hole_radius = rng.random_range(0.2..0.6) * inside / std::f64::consts::SQRT_2;
    let square = rng.random_bool(0.5);
    let hole = m.vertices_of(outer.iter().map(|p| {
        let t = p[1].atan2(p[0]);
        let r = if square {
            // A square hole: radius of the square's outline along direction t.
            hole_radius / t.cos().abs().max(t.sin().abs())
        } else {
            hole_radius
        };
        [r * t.cos(), r * t.sin(), 0.0]
    }));
    m.strip(&ring, &hole, true);
    m
}

/// Adds the faces of an axis-aligned box (except face `skip`) and, while `depth` lasts,
/// smaller boxes stuck on or dented into some faces.
///
/// Face `2 * axis + s` is the face on the `axis` side with sign `-1` (s = 0) or `+1`.
/// A face carrying a child is a ring of four quads around the child's footprint, so the
/// child's walls share its edges: the concave creases come out of the mesh like all others.
/// Footprints keep clear of the face border, so children of one box never intersect.
fn box_faces(
    m: &mut Mesh,
    centre: V3,
    half: V3,
    depth: u32,
    skip: Option<usize>,
    rng: &mut impl Rng,
) {
    const SQUARE: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    for face in 0..6 {
        if skip == Some(face) {
            continue;
        }
        let (axis, sign) = (face / 2, if face % 2 == 0 { -1.0 } else { 1.0 });
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let at = |du: f64, dv: f64, dn: f64| {
            let mut p = centre;
            p[axis] += sign * (half[axis] + dn);
            p[u] += du;
            p[v] += dv;
            p
        };
        let outer = m.vertices_of(SQUARE.map(|[a, b]| at(a * half[u], b * half[v], 0.0)));
        if depth == 0 || !rng.random_bool(0.6) {
            m.quad(outer[0], outer[1], outer[2], outer[3]);
            continue;
        }
        let dent = rng.random_bool(0.3);
        // Dents stay within 60% of the face so dents of neighbouring faces never meet
        // inside the box; bumps may use 90%.
        let reach = if dent { 0.6 } else { 0.9 };
        let hu = half[u] * rng.random_range(0.15..0.35);
        let hv = half[v] * rng.random_range(0.15..0.35);
        let ou = rng.random_range(-1.0..1.0) * (reach * half[u] - hu).max(0.0);
        let ov = rng.random_range(-1.0..1.0) * (reach * half[v] - hv).max(0.0);
        let hn = if dent {
            half[axis] * rng.random_range(0.1..0.3)
        } else {
            half[u].min(half[v]) * rng.random_range(0.15..0.35)
        };
        let inner = m.vertices_of(SQUARE.map(|[a, b]| at(ou + a * hu, ov + b * hv, 0.0)));
        m.strip(&outer, &inner, true);
        let mut child_half = [0.0; 3];
        child_half[axis] = hn;
        child_half[u] = hu;
        child_half[v] = hv;
        let out = if dent { -hn } else { hn };
        let toward_parent = 2 * axis + usize::from(sign < 0.0);
        let opening = 2 * axis + usize::from(sign > 0.0);
        let (child_skip, child_depth) = if dent {
            (opening, 0)
        } else {
            (toward_parent, depth - 1)
        };
        box_faces(
            m,
            at(ou, ov, out),
            child_half,
            child_depth,
            Some(child_skip),
            rng,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn every_kind_builds_a_mesh_with_the_expected_feature_classes() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for kind in ShapeKind::ALL {
            for _ in 0..5 {
                let m = kind.build(&mut rng).welded();
                assert!(!m.triangles.is_empty(), "{kind:?}");
                let f = m.features();
                assert_eq!(!f.border.is_empty(), kind.is_open(), "{kind:?} borders");
                let smooth = matches!(
                    kind,
                    ShapeKind::Sphere
                        | ShapeKind::Torus
                        | ShapeKind::Disc
                        | ShapeKind::Tube
                        | ShapeKind::Bowl
                        | ShapeKind::PolygonSheet
                        | ShapeKind::ThinPlate
                );
                if smooth {
                    assert!(f.sharp.is_empty(), "{kind:?} has sharp edges");
                } else if kind != ShapeKind::FoldedSheet {
                    assert!(!f.sharp.is_empty(), "{kind:?} has no sharp edge");
                }
            }
        }
    }

    #[test]
    fn shallow_ridges_turn_by_12_to_25_degrees_and_every_crease_is_sharp() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..50 {
            let profile = shallow_ridges(&mut rng);
            let n = profile.len();
            // Bottom, right side, 1..4 creases, the left end: 5..8 corners.
            assert!((5..=8).contains(&n), "{profile:?}");
            let turn = |i: usize| {
                let (a, b, c) = (profile[i - 1], profile[i], profile[(i + 1) % n]);
                let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
                let cos = (u[0] * v[0] + u[1] * v[1]) / (u[0].hypot(u[1]) * v[0].hypot(v[1]));
                cos.clamp(-1.0, 1.0).acos().to_degrees()
            };
            for i in 3..n - 1 {
                let t = turn(i);
                assert!(
                    (12.0..25.0).contains(&t),
                    "crease {i} turns {t}: {profile:?}"
                );
            }
            // The top stays above the bottom, the corners are steep.
            assert!(
                profile[2..].iter().all(|p| p[1] >= 0.3 - 1e-12),
                "{profile:?}"
            );
            assert!(turn(2) > 50.0 && turn(n - 1) > 50.0, "{profile:?}");
            // Extruded: every corner of the profile makes a sharp edge along the extrusion,
            // and both caps' rims are sharp: 3 n sharp edges, in polylines of n + 2 loops or
            // lines at most (corners turning more than 30 degrees split them).
            let m = extrude(&profile, 0.5, true, [true, true]).welded();
            let f = m.features();
            let segments: usize = (f.sharp.iter())
                .map(|l| l.points.len() - usize::from(!l.closed))
                .sum();
            assert_eq!(segments, 3 * n, "{profile:?}");
            assert!(f.border.is_empty());
        }
    }

    #[test]
    fn fractal_cube_is_closed() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20 {
            let m = ShapeKind::FractalCube.build(&mut rng).welded();
            assert!(m.features().border.is_empty());
        }
    }
}
