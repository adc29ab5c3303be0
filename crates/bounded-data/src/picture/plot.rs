//! Precision-recall scatter plots, as in the paper's figure: one dot per model, one colour
//! per method.

use super::{Canvas, Rgb};

/// One method's points: (recall, precision) per model.
pub struct Series {
    /// Method name, shown in the legend.
    pub name: String,
    /// Dot colour.
    pub colour: Rgb,
    /// (recall, precision) pairs in [0, 1].
    pub points: Vec<(f64, f64)>,
}

/// Distinct colours for up to eight methods (then they repeat).
pub const PALETTE: [Rgb; 8] = [
    [214, 39, 40],
    [31, 119, 180],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];

const WIDTH: usize = 920;
const HEIGHT: usize = 560;
const LEFT: i64 = 70;
const TOP: i64 = 40;
const SIDE: i64 = 460;

/// Plots recall (x) against precision (y) for every series, with axes and a legend.
pub fn precision_recall(title: &str, series: &[Series]) -> Canvas {
    let mut c = Canvas::new(WIDTH, HEIGHT, [255; 3]);
    let grey = [200; 3];
    let black = [0; 3];
    let to_px = |recall: f64, precision: f64| {
        (
            LEFT + (recall.clamp(0.0, 1.0) * SIDE as f64).round() as i64,
            TOP + SIDE - (precision.clamp(0.0, 1.0) * SIDE as f64).round() as i64,
        )
    };
    for tick in 0..=10 {
        let v = f64::from(tick) / 10.0;
        let (x, _) = to_px(v, 0.0);
        let (_, y) = to_px(0.0, v);
        c.line((x, TOP), (x, TOP + SIDE), grey);
        c.line((LEFT, y), (LEFT + SIDE, y), grey);
        if tick % 2 == 0 {
            let label = format!("{v:.1}");
            c.text(
                x - Canvas::text_width(&label, 1) / 2,
                TOP + SIDE + 6,
                &label,
                1,
                black,
            );
            c.text(
                LEFT - 8 - Canvas::text_width(&label, 1),
                y - 3,
                &label,
                1,
                black,
            );
        }
    }
    c.line((LEFT, TOP + SIDE), (LEFT + SIDE, TOP + SIDE), black);
    c.line((LEFT, TOP), (LEFT, TOP + SIDE), black);
    c.text(LEFT + SIDE / 2 - 18, TOP + SIDE + 22, "RECALL", 1, black);
    c.text(8, TOP - 20, "PRECISION", 1, black);
    c.text(LEFT, 8, title, 2, black);
    for s in series {
        for &(r, p) in &s.points {
            let (x, y) = to_px(r, p);
            c.disc(x, y, 3, s.colour);
        }
    }
    for (row, s) in series.iter().enumerate() {
        let y = TOP + 10 + 22 * row as i64;
        c.disc(LEFT + SIDE + 30, y + 3, 5, s.colour);
        c.text(LEFT + SIDE + 42, y, &s.name, 1, black);
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dots_land_where_recall_and_precision_say() {
        let series = [Series {
            name: "X".into(),
            colour: [1, 2, 3],
            points: vec![(1.0, 1.0), (0.5, 0.25)],
        }];
        let c = precision_recall("T", &series);
        assert_eq!(c.get((LEFT + SIDE) as usize, TOP as usize), [1, 2, 3]);
        let (x, y) = (LEFT + SIDE / 2, TOP + SIDE - SIDE / 4);
        assert_eq!(c.get(x as usize, y as usize), [1, 2, 3]);
    }
}
