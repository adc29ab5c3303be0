//! Shaded splat rendering of a coloured point cloud, so a person can look at detections.
//!
//! Orthographic view from an azimuth / elevation; every point is a disc in a depth buffer,
//! and shading comes from the depth buffer's own gradient (no normals needed), which makes
//! creases and curvature readable.

use super::{Canvas, Rgb};
use crate::format::class_colour;
use bounded_geom::vec3::{cross, dot, normalize};
use bounded_geom::{Class, PointCloud};

/// Where the camera looks from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Rotation about the vertical (z) axis, degrees.
    pub azimuth: f64,
    /// Angle above the horizontal plane, degrees.
    pub elevation: f64,
}

impl Default for View {
    /// A three-quarter view from above, which shows three faces of a box.
    fn default() -> Self {
        Self {
            azimuth: 35.0,
            elevation: 30.0,
        }
    }
}

/// The picture of `cloud` with every point in the colour of its class (as
/// [`class_colour`] writes them), and a legend of the classes with their point counts in the
/// top left corner.
pub fn render_classes(
    cloud: &PointCloud,
    classes: &[Class],
    view: View,
    width: usize,
    height: usize,
) -> Canvas {
    let colours: Vec<Rgb> = classes.iter().map(|&c| class_colour(c)).collect();
    let mut canvas = render(cloud.points(), &colours, view, width, height);
    let counts = Class::counts(classes);
    let scale = if height >= 400 { 2 } else { 1 };
    let line = 10 * scale;
    for (row, class) in [Class::Sharp, Class::Boundary, Class::NonEdge]
        .into_iter()
        .enumerate()
    {
        let y = line / 2 + row as i64 * line;
        canvas.disc(line / 2 + 2, y + 3 * scale, 3 * scale, class_colour(class));
        let label = format!("{} {}", class.name(), counts[class as usize]);
        canvas.text(line + 4, y, &label, scale, [0, 0, 0]);
    }
    canvas
}

/// Renders `points` with per-point `colours` into a `width` x `height` picture.
pub fn render(
    points: &[[f32; 3]],
    colours: &[Rgb],
    view: View,
    width: usize,
    height: usize,
) -> Canvas {
    let mut canvas = Canvas::new(width, height, [255, 255, 255]);
    if points.is_empty() {
        return canvas;
    }
    let (az, el) = (view.azimuth.to_radians(), view.elevation.to_radians());
    // Camera basis: right, up and towards-the-viewer, for a z-up world.
    let right = [az.cos(), -az.sin(), 0.0];
    let toward = [az.sin() * el.cos(), az.cos() * el.cos(), el.sin()];
    let up = cross(toward, right);
    let project = |p: &[f32; 3]| {
        let p = p.map(f64::from);
        (dot(p, right), dot(p, up), dot(p, toward))
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        let (x, y, _) = project(p);
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    let margin = 0.05;
    let extent = [(hi[0] - lo[0]).max(1e-12), (hi[1] - lo[1]).max(1e-12)];
    let scale = ((1.0 - 2.0 * margin) * width as f64 / extent[0])
        .min((1.0 - 2.0 * margin) * height as f64 / extent[1]);
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    // Splat radius: about the projected point spacing, so surfaces close up.
    let spacing = (extent[0] * extent[1] / points.len() as f64).sqrt() * scale;
    let radius = (0.8 * spacing).clamp(1.0, 6.0) as i64;

    let mut depth = vec![f64::NEG_INFINITY; width * height];
    let mut colour = vec![[255u8; 3]; width * height];
    for (p, c) in points.iter().zip(colours) {
        let (x, y, z) = project(p);
        let px = ((x - centre[0]) * scale + 0.5 * width as f64) as i64;
        let py = (0.5 * height as f64 - (y - centre[1]) * scale) as i64;
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let (sx, sy) = (px + dx, py + dy);
                if dx * dx + dy * dy > radius * radius
                    || sx < 0
                    || sy < 0
                    || sx >= width as i64
                    || sy >= height as i64
                {
                    continue;
                }
                let i = sy as usize * width + sx as usize;
                if z * scale > depth[i] {
                    depth[i] = z * scale;
                    colour[i] = *c;
                }
            }
        }
    }
    // Lambert shading from screen-space depth gradients, light from the upper left.
    let light = normalize([-0.4, 0.5, 1.0]);
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            if depth[i] == f64::NEG_INFINITY {
                continue;
            }
            let gradient = |a: Option<usize>, b: Option<usize>| match (a, b) {
                (Some(a), Some(b)) if depth[a].is_finite() && depth[b].is_finite() => {
                    (depth[b] - depth[a]) / 2.0
                }
                _ => 0.0,
            };
            let gx = gradient(
                x.checked_sub(1).map(|x| y * width + x),
                (x + 1 < width).then(|| i + 1),
            );
            let gy = gradient(
                (y + 1 < height).then(|| i + width),
                y.checked_sub(1).map(|y| y * width + x),
            );
            let normal = normalize([-gx, -gy, 1.0]);
            let shade = 0.35 + 0.65 * dot(normal, light).max(0.0);
            let [r, g, b] = colour[i];
            canvas.set(
                x as i64,
                y as i64,
                [r, g, b].map(|v| (f64::from(v) * shade).round() as u8),
            );
        }
    }
    canvas
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square in the z = 0 plane seen from straight above fills the middle of the picture
    /// with its colour (fully lit: the depth gradient is zero) and leaves the corners white.
    #[test]
    fn top_view_of_a_square() {
        let n = 60;
        let points: Vec<[f32; 3]> = (0..n * n)
            .map(|i| [(i % n) as f32 / n as f32, (i / n) as f32 / n as f32, 0.0])
            .collect();
        let colours = vec![[200, 0, 0]; points.len()];
        let view = View {
            azimuth: 0.0,
            elevation: 90.0,
        };
        let c = render(&points, &colours, view, 100, 100);
        let [r, g, b] = c.get(50, 50);
        let lit = 0.35 + 0.65 * normalize([-0.4, 0.5, 1.0])[2];
        assert_eq!(r, (200.0 * lit).round() as u8);
        assert_eq!((g, b), (0, 0));
        assert_eq!(c.get(1, 1), [255, 255, 255]);
    }

    /// The legend names each class beside a disc of its colour, top left, over the cloud.
    #[test]
    fn classes_come_with_a_legend() {
        let cloud = PointCloud::from_f64(&[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]).unwrap();
        let c = render_classes(&cloud, &[Class::Sharp; 2], View::default(), 100, 100);
        // Rows of 10 pixels from y = 5; each disc centred 3 pixels below its row's top.
        assert_eq!(c.get(7, 8), class_colour(Class::Sharp));
        assert_eq!(c.get(7, 18), class_colour(Class::Boundary));
        assert_eq!(c.get(7, 28), class_colour(Class::NonEdge));
        // "sharp 2" in black to the right of the first disc.
        let black = (14..60).flat_map(|x| (5..12).map(move |y| (x, y)));
        assert!(black.clone().any(|(x, y)| c.get(x, y) == [0, 0, 0]));
        let plain = render(
            cloud.points(),
            &[class_colour(Class::Sharp); 2],
            View::default(),
            100,
            100,
        );
        assert!(black.into_iter().all(|(x, y)| plain.get(x, y) != [0, 0, 0]));
    }

    /// The nearer of two overlapping points wins the depth test.
    #[test]
    fn nearer_point_is_drawn() {
        let points = [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        let colours = [[0, 0, 250], [250, 0, 0], [0; 3], [0; 3]];
        let view = View {
            azimuth: 0.0,
            elevation: 90.0,
        };
        let c = render(&points, &colours, view, 50, 50);
        assert!(c.get(25, 25)[2] > 0 && c.get(25, 25)[0] == 0);
    }
}
