//! A small 8-bit RGB raster for the illuminance map: filled rectangles, 1-pixel lines
//! (Bresenham 1965) and text in a built-in 5×7 bitmap font, so that legends need no font
//! files or extra crates.

/// Glyphs of the 5×7 font: 7 rows of 5 bits, most significant bit on the left. Only the
/// characters map and false-colour legends use (digits, a decimal point, signs, the words of
/// the summary and the unit cd/m2).
const FONT: &[(char, [u8; 7])] = &[
    ('0', [0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e]),
    ('1', [0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e]),
    ('2', [0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f]),
    ('3', [0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e]),
    ('4', [0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02]),
    ('5', [0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e]),
    ('6', [0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e]),
    ('7', [0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08]),
    ('8', [0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e]),
    ('9', [0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c]),
    ('.', [0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c]),
    ('-', [0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00]),
    ('+', [0x00, 0x04, 0x04, 0x1f, 0x04, 0x04, 0x00]),
    ('=', [0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00]),
    (':', [0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00]),
    ('e', [0x00, 0x00, 0x0e, 0x11, 0x1f, 0x10, 0x0e]),
    ('E', [0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f]),
    ('U', [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e]),
    ('/', [0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00]),
    ('a', [0x00, 0x00, 0x0e, 0x01, 0x0f, 0x11, 0x0f]),
    ('c', [0x00, 0x00, 0x0e, 0x10, 0x10, 0x11, 0x0e]),
    ('d', [0x01, 0x01, 0x0d, 0x13, 0x11, 0x11, 0x0f]),
    ('g', [0x00, 0x00, 0x0f, 0x11, 0x0f, 0x01, 0x0e]),
    ('i', [0x04, 0x00, 0x0c, 0x04, 0x04, 0x04, 0x0e]),
    ('l', [0x0c, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e]),
    ('m', [0x00, 0x00, 0x1a, 0x15, 0x15, 0x11, 0x11]),
    ('n', [0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11]),
    ('v', [0x00, 0x00, 0x11, 0x11, 0x11, 0x0a, 0x04]),
    ('x', [0x00, 0x00, 0x11, 0x0a, 0x04, 0x0a, 0x11]),
];

/// Glyph cell of the font at scale 1: 5 columns plus 1 of spacing, 7 rows.
pub const GLYPH_W: usize = 6;
pub const GLYPH_H: usize = 7;

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

    /// Draws `text` with its top-left corner at (x, y), each font pixel `scale`² pixels.
    /// Characters the font lacks are left blank.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: usize, c: [u8; 3]) {
        let s = scale as i64;
        for (k, ch) in text.chars().enumerate() {
            let Some((_, rows)) = FONT.iter().find(|(g, _)| *g == ch) else {
                continue;
            };
            let x0 = x + (k * GLYPH_W * scale) as i64;
            for (row, bits) in rows.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        self.fill_rect(x0 + col as i64 * s, y + row as i64 * s, s, s, c);
                    }
                }
            }
        }
    }

    /// Interleaved bytes for PNG encoding.
    pub fn bytes(&self) -> Vec<u8> {
        self.pixels.iter().flatten().copied().collect()
    }
}

/// Width in pixels of `text` drawn at `scale` (without the trailing spacing column).
pub fn text_width(text: &str, scale: usize) -> usize {
    (text.chars().count() * GLYPH_W).saturating_sub(1) * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_summary_character_has_a_glyph() {
        for ch in "0123456789.-+=: Emin Eavg Emax lx U0 e".chars() {
            assert!(ch == ' ' || FONT.iter().any(|(g, _)| *g == ch), "{ch}");
        }
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
