//! A small 8-bit RGB raster for the illuminance map and the false-colour legend: filled
//! rectangles and 1-pixel lines (Bresenham 1965), the numerics of the maps' pictures, and text
//! in DejaVu Sans drawn by plotters (`output::plot::draw_text`, the font shipped in
//! `assets/fonts/`). Text was once a hand-written 5×7 bitmap font with only the legends'
//! glyphs; the font gives every character (`cd/m²`, a stage's unit name) and anti-aliased
//! edges, and the layout keeps its sizes: a text of scale k is an em of `TEXT_PX`·k pixels whose
//! capital letters are about `GLYPH_H`·k pixels tall.

use crate::output::plot;

/// The em of scale-1 text, in pixels: DejaVu Sans's capitals are 0.73 em tall (its
/// `capHeight` 1493 of 2048 units), so 8 pixels, [`GLYPH_H`].
const TEXT_PX: f64 = 11.0;
/// The distance from the top plotters places a text at to the top of its capitals, in ems:
/// measured, the capitals start 0.15 em above it (`text_is_drawn_where…` checks it).
const CAP_GAP_EM: f64 = -0.15;

/// The height of scale-1 capitals (and digits) in pixels: the layouts' line unit.
pub const GLYPH_H: usize = 8;

/// An RGB8 image, row-major, top row first.
pub struct Canvas {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
}

impl Canvas {
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Canvas {
        Canvas {
            width,
            height,
            pixels: vec![background; width * height],
        }
    }

    /// Sets a pixel; coordinates outside the canvas are ignored.
    #[inline]
    pub fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            self.pixels[y as usize * self.width + x as usize] = c;
        }
    }

    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: [u8; 3]) {
        for yy in y..y + h {
            for xx in x..x + w {
                self.put(xx, yy, c);
            }
        }
    }

    /// A 1-pixel line between two points (Bresenham's algorithm, all octants).
    pub fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: [u8; 3]) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = ((x1 - x0).signum(), (y1 - y0).signum());
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        loop {
            self.put(x, y, c);
            if x == x1 && y == y1 {
                break;
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

    /// Draws `text` with the top-left corner of its capitals at (x, y), at `scale` (capitals
    /// `GLYPH_H`·scale pixels tall).
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: usize, c: [u8; 3]) {
        let px = TEXT_PX * scale as f64;
        let top = y - (CAP_GAP_EM * px).round() as i64;
        let clamp = |v: i64| v.clamp(i32::MIN as i64, i32::MAX as i64) as i32;
        let size = (self.width as u32, self.height as u32);
        let bytes = self.pixels.as_flattened_mut();
        plot::draw_text(bytes, size, (clamp(x), clamp(top)), text, px, c);
    }

    /// Interleaved bytes for PNG encoding.
    pub fn bytes(&self) -> Vec<u8> {
        self.pixels.iter().flatten().copied().collect()
    }
}

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: usize) -> usize {
    plot::text_size(text, TEXT_PX * scale as f64).0 as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_drawn_where_its_width_and_cap_height_say() {
        let ink = [0, 0, 0];
        for scale in [1, 2] {
            let mut c = Canvas::new(200, 40, [255; 3]);
            let (x, y) = (10, 12);
            c.text(x, y, "E 10 lx", scale, ink);
            let w = text_width("E 10 lx", scale) as i64;
            let dark = |p: &[u8; 3]| p[0] < 128;
            let (mut x0, mut x1, mut y0, mut y1) = (i64::MAX, 0, i64::MAX, 0);
            for (i, p) in c.pixels.iter().enumerate() {
                if dark(p) {
                    let (px, py) = ((i % 200) as i64, (i / 200) as i64);
                    (x0, x1, y0, y1) = (x0.min(px), x1.max(px), y0.min(py), y1.max(py));
                }
            }
            // The capital E's top within a pixel of y; the ink within the text's width; the
            // capitals GLYPH_H·scale tall (no descender in the text).
            let cap = (GLYPH_H * scale) as i64;
            assert!((y0 - y).abs() <= 1, "scale {scale}: top {y0}");
            assert!(
                x0 >= x && x0 <= x + 2 && x1 < x + w + 1,
                "scale {scale}: {x0}..{x1}, {w}"
            );
            assert!(
                (y1 + 1 - y - cap).abs() <= scale as i64 + 1,
                "scale {scale}: {y0}..{y1}"
            );
        }
        assert!(text_width("0000", 1) > text_width("00", 1));
        assert!(text_width("00", 2) > text_width("00", 1));
    }

    #[test]
    fn lines_reach_both_ends_and_clip() {
        let mut c = Canvas::new(10, 10, [0; 3]);
        c.line((-5, 2), (12, 7), [9; 3]);
        c.line((3, 0), (3, 9), [7; 3]);
        assert_eq!(c.pixels[3], [7; 3]);
        assert_eq!(c.pixels[9 * 10 + 3], [7; 3]);
        assert!(c.pixels.iter().filter(|p| **p == [9; 3]).count() >= 9);
    }
}
