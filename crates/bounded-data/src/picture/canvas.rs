//! A tiny RGB raster with discs, lines and a built-in 5x7 bitmap font, saved as PNG.
//!
//! Pictures (renders, plots) need no font files or graphics stack this way.

use crate::DataError;
use std::io::{BufWriter, Write};
use std::path::Path;

/// An RGB colour.
pub type Rgb = [u8; 3];

/// An RGB image, row-major, 3 bytes per pixel.
pub struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: usize, height: usize, background: Rgb) -> Self {
        let pixels = background.repeat(width * height);
        Self {
            width,
            height,
            pixels,
        }
    }

    /// The colour at (x, y).
    #[cfg(test)]
    pub(crate) fn get(&self, x: usize, y: usize) -> Rgb {
        let i = 3 * (y * self.width + x);
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }

    /// Sets (x, y) to `colour`; coordinates outside the canvas are ignored.
    pub fn set(&mut self, x: i64, y: i64, colour: Rgb) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = 3 * (y as usize * self.width + x as usize);
        self.pixels[i..i + 3].copy_from_slice(&colour);
    }

    /// A filled disc of radius `r` pixels.
    pub fn disc(&mut self, cx: i64, cy: i64, r: i64, colour: Rgb) {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy <= r * r {
                    self.set(cx + dx, cy + dy, colour);
                }
            }
        }
    }

    /// A one-pixel line (Bresenham).
    pub fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), colour: Rgb) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = ((x1 - x0).signum(), (y1 - y0).signum());
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        loop {
            self.set(x, y, colour);
            if x == x1 && y == y1 {
                return;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// Draws `text` with its top-left corner at (x, y), each font pixel `scale` pixels wide.
    ///
    /// Lower-case letters are drawn as capitals; characters the font lacks as `?`.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: i64, colour: Rgb) {
        for (n, ch) in text.chars().enumerate() {
            let rows = glyph(ch);
            let left = x + n as i64 * 6 * scale;
            for (row, bits) in rows.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        for sy in 0..scale {
                            for sx in 0..scale {
                                self.set(
                                    left + col * scale + sx,
                                    y + row as i64 * scale + sy,
                                    colour,
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// Width in pixels of `text` drawn at `scale`.
    pub fn text_width(text: &str, scale: i64) -> i64 {
        text.chars().count() as i64 * 6 * scale
    }

    /// Writes the canvas as an 8-bit RGB PNG, atomically: a failure leaves no file (and an
    /// existing one untouched).
    pub fn save_png(&self, path: &Path) -> Result<(), DataError> {
        check_png(path)?;
        let png = |source| DataError::Png {
            path: path.to_path_buf(),
            source,
        };
        bounded_geom::atomic::write_with(path, |file| {
            let mut out = BufWriter::new(file);
            let mut encoder = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            let mut writer = encoder.write_header().map_err(png)?;
            writer.write_image_data(&self.pixels).map_err(png)?;
            writer.finish().map_err(png)?;
            out.flush().map_err(|e| DataError::io(path, e))
        })
    }
}

/// Refuses an output path not ending in `.png` (any case): pictures are PNG only, and a
/// `.jpg` name on PNG bytes would mislead every viewer.
pub fn check_png(path: &Path) -> Result<(), DataError> {
    let png = (path.extension()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        return Ok(());
    }
    Err(DataError::InvalidOutput {
        path: path.to_path_buf(),
        what: "pictures are written as PNG: name the output .png".into(),
    })
}

/// The 5x7 bitmap of `ch`: seven rows, bit 4 is the leftmost column.
fn glyph(ch: char) -> [u8; 7] {
    match ch.to_ascii_uppercase() {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        ',' => [0, 0, 0, 0, 0x0C, 0x04, 0x08],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '+' => [0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0],
        '=' => [0, 0, 0x1F, 0, 0x1F, 0, 0],
        '_' => [0, 0, 0, 0, 0, 0, 0x1F],
        ' ' => [0; 7],
        _ => [0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_reaches_both_ends_and_disc_is_round() {
        let mut c = Canvas::new(20, 20, [255; 3]);
        c.line((2, 3), (15, 9), [0; 3]);
        assert_eq!(c.get(2, 3), [0; 3]);
        assert_eq!(c.get(15, 9), [0; 3]);
        c.disc(10, 10, 3, [1, 2, 3]);
        assert_eq!(c.get(13, 10), [1, 2, 3]);
        assert_eq!(
            c.get(13, 13),
            [255; 3],
            "corner of the box is outside the disc"
        );
    }

    #[test]
    fn text_draws_the_glyph_bits() {
        let mut c = Canvas::new(12, 7, [255; 3]);
        c.text(0, 0, "1-", 1, [0; 3]);
        // '1': row 0 is 0x04, the middle column.
        assert_eq!(c.get(2, 0), [0; 3]);
        assert_eq!(c.get(0, 0), [255; 3]);
        // '-': full row 3 of the second glyph, 6 pixels to the right.
        assert!((6..11).all(|x| c.get(x, 3) == [0; 3]));
        assert_eq!(Canvas::text_width("1-", 2), 24);
    }

    #[test]
    fn png_round_trips_and_a_failed_save_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let mut c = Canvas::new(3, 2, [10, 20, 30]);
        c.set(2, 1, [1, 2, 3]);
        let path = dir.path().join("c.png");
        c.save_png(&path).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(pixels, c.pixels);

        // The encoder refuses an empty picture: a named error, and no file at all.
        let empty = dir.path().join("empty.png");
        let e = Canvas::new(0, 4, [0; 3]).save_png(&empty).unwrap_err();
        assert!(matches!(e, DataError::Png { .. }), "{e}");
        assert!(
            e.to_string().starts_with(&empty.display().to_string()),
            "{e}"
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

        // Only .png names: a .jpg name on PNG bytes is refused before anything is written.
        let jpg = dir.path().join("c.jpg");
        let e = c.save_png(&jpg).unwrap_err().to_string();
        assert!(e.contains("pictures are written as PNG"), "{e}");
        assert!(!jpg.exists());
        c.save_png(&dir.path().join("C.PNG")).unwrap();
    }
}
