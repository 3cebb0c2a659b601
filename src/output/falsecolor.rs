//! False-colour luminance images (`spectral-render falsecolor`), after Radiance's
//! `falsecolor`: luminance in cd/m² mapped to a colour scale with a legend on the left.
//!
//! - `scale` (Radiance's `-s`): the top of the legend, cd/m²; values above it saturate.
//! - `decades` (`-l`... in Radiance `-log`): a logarithmic scale over that many decades below
//!   `scale`; otherwise the scale is linear from 0.
//! - `divisions` (`-n`): the legend's intervals; `contours` (`-cl`): instead of filling the
//!   image with colour, draw its luminance in grey and the isolines at the division values in
//!   their colours (marching squares on the pixel lattice, `map/contour.rs`).
//!
//! The colours are viridis (`map/colormap.rs`), not Radiance's palette: perceptually uniform
//! and readable in grey. The legend is a continuous bar; tick k (k = 0..=divisions) sits at
//! value v_k = scale·k/n (linear) or scale·10^(−D + D·k/n) (log), on the bar's row whose
//! colour is that value's: the same colour a pixel of luminance v_k gets.

use super::map::canvas::{text_width, Canvas, GLYPH_H};
use super::map::colormap::{is_light, viridis};
use super::map::contour;
use super::map::sig;

/// What the image shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FalseColor {
    /// Top of the scale, cd/m².
    pub scale: f64,
    /// Decades of a log scale; None: linear.
    pub decades: Option<f64>,
    /// The legend's intervals.
    pub divisions: usize,
    /// Draw isolines at the division values over a grey image.
    pub contours: bool,
}

const WHITE: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [20, 20, 20];
const MARGIN: i64 = 12;
const BAR_W: i64 = 24;
const LEGEND_MIN_H: usize = 240;
/// From the bar to its labels: clear of the tick mark, so that it does not read as a minus.
const LABEL_GAP: i64 = 16;
/// The unit over the legend.
pub const UNIT: &str = "cd/m²";

/// Where the parts of the image are, in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    /// The luminance image's top-left corner.
    pub image_x: i64,
    pub top: i64,
    /// The legend bar's left edge and height (its top is `top`).
    pub bar_x: i64,
    pub bar_h: usize,
    pub width: usize,
    pub height: usize,
}

impl FalseColor {
    /// Position on the scale, 0 (bottom) to 1 (top), of luminance `y`.
    pub fn position(&self, y: f64) -> f64 {
        let t = match self.decades {
            None => y / self.scale,
            Some(d) if y > 0.0 => ((y / self.scale).log10() + d) / d,
            Some(_) => 0.0,
        };
        if t.is_nan() {
            0.0
        } else {
            t.clamp(0.0, 1.0)
        }
    }

    /// The luminance at position `t` of the scale.
    pub fn value(&self, t: f64) -> f64 {
        match self.decades {
            None => self.scale * t,
            Some(d) => self.scale * 10f64.powf(d * (t - 1.0)),
        }
    }

    /// The legend's tick values, bottom to top.
    pub fn ticks(&self) -> Vec<f64> {
        let n = self.divisions.max(1);
        (0..=n).map(|k| self.value(k as f64 / n as f64)).collect()
    }

    /// The colour of luminance `y`.
    pub fn colour(&self, y: f64) -> [u8; 3] {
        viridis(self.position(y) as f32)
    }

    pub fn layout(&self, width: usize, height: usize) -> Layout {
        let top = MARGIN + 2 * GLYPH_H as i64 + 12;
        let bar_x = MARGIN;
        let labels = self
            .ticks()
            .iter()
            .map(|v| text_width(&label(*v), 2))
            .max()
            .unwrap_or(0) as i64;
        let image_x = bar_x + BAR_W + LABEL_GAP + labels + 2 * MARGIN;
        let bar_h = height.max(LEGEND_MIN_H);
        Layout {
            image_x,
            top,
            bar_x,
            bar_h,
            width: (image_x + width as i64 + MARGIN) as usize,
            height: (top + bar_h as i64 + GLYPH_H as i64 + MARGIN) as usize,
        }
    }

    /// The row of the legend bar (canvas y) showing position `t`.
    pub fn bar_row(&self, l: &Layout, t: f64) -> i64 {
        let h = l.bar_h as f64;
        l.top + ((1.0 - t) * h - 0.5).round().clamp(0.0, h - 1.0) as i64
    }

    /// The false-colour picture of `y` (luminance in cd/m², `width × height`, row-major).
    pub fn image(&self, y: &[f32], width: usize, height: usize) -> (Canvas, Layout) {
        let l = self.layout(width, height);
        let mut c = Canvas::new(l.width, l.height, WHITE);
        for (i, v) in y.iter().enumerate() {
            let colour = if self.contours {
                let g = (40.0 + 200.0 * self.position(f64::from(*v))).round() as u8;
                [g, g, g]
            } else {
                self.colour(f64::from(*v))
            };
            c.put(
                l.image_x + (i % width) as i64,
                l.top + (i / width) as i64,
                colour,
            );
        }
        if self.contours {
            self.paint_contours(&mut c, &l, y, width, height);
        }
        self.paint_legend(&mut c, &l);
        (c, l)
    }

    fn paint_contours(&self, c: &mut Canvas, l: &Layout, y: &[f32], width: usize, height: usize) {
        let t: Vec<f64> = y.iter().map(|v| self.position(f64::from(*v))).collect();
        let n = self.divisions.max(1);
        for k in 1..n {
            let level = k as f64 / n as f64;
            let colour = viridis(level as f32);
            for (a, b) in contour::isoline(&t, width, height, level) {
                // Pixel centres are at integer grid coordinates.
                let px =
                    |p: [f64; 2]| (l.image_x + p[0].round() as i64, l.top + p[1].round() as i64);
                c.line(px(a), px(b), colour);
            }
        }
    }

    fn paint_legend(&self, c: &mut Canvas, l: &Layout) {
        let h = l.bar_h as f64;
        for row in 0..l.bar_h {
            let t = 1.0 - (row as f64 + 0.5) / h;
            c.fill_rect(l.bar_x, l.top + row as i64, BAR_W, 1, viridis(t as f32));
        }
        let n = self.divisions.max(1);
        for (k, v) in self.ticks().iter().enumerate() {
            let y = self.bar_row(l, k as f64 / n as f64);
            let fill = viridis((k as f64 / n as f64) as f32);
            let ink = if is_light(fill) { INK } else { WHITE };
            if self.contours && k > 0 && k < n {
                c.line((l.bar_x, y), (l.bar_x + BAR_W - 1, y), ink);
            }
            c.line((l.bar_x + BAR_W, y), (l.bar_x + BAR_W + 4, y), INK);
            c.text(
                l.bar_x + BAR_W + LABEL_GAP,
                y - GLYPH_H as i64,
                &label(*v),
                2,
                INK,
            );
        }
        c.text(l.bar_x, MARGIN, UNIT, 2, INK);
    }
}

/// A legend value: three significant digits, no exponent for everyday luminances (the
/// maps' [`sig`]); "0" for a value that is not finite.
pub fn label(v: f64) -> String {
    if v.is_finite() {
        sig(v)
    } else {
        "0".into()
    }
}

/// A round top for the scale: the smallest 1, 2 or 5 × 10ᵏ at or above `max` (1 when the
/// image has no positive luminance).
pub fn default_scale(max: f64) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(max.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|f| f * mag)
        .find(|v| *v >= max * (1.0 - 1e-12))
        .unwrap_or(10.0 * mag)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear() -> FalseColor {
        FalseColor {
            scale: 800.0,
            decades: None,
            divisions: 8,
            contours: false,
        }
    }

    #[test]
    fn scales_and_ticks() {
        let f = linear();
        assert_eq!(
            f.ticks(),
            (0..=8).map(|k| 100.0 * k as f64).collect::<Vec<_>>()
        );
        assert_eq!(f.position(400.0), 0.5);
        assert_eq!(f.position(1e6), 1.0);
        let log = FalseColor {
            scale: 1000.0,
            decades: Some(3.0),
            divisions: 3,
            ..f
        };
        let ticks = log.ticks();
        for (t, want) in ticks.iter().zip([1.0, 10.0, 100.0, 1000.0]) {
            assert!((t - want).abs() < 1e-9 * want, "{ticks:?}");
        }
        assert_eq!(log.position(0.0), 0.0);
        assert!((log.position(10.0) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(default_scale(730.0), 1000.0);
        assert_eq!(default_scale(180.0), 200.0);
        assert_eq!(default_scale(0.0), 1.0);
        assert_eq!(label(0.125), "0.125");
        assert_eq!(label(1234.6), "1235");
    }

    #[test]
    fn contours_draw_lines_in_the_level_colours() {
        let f = FalseColor {
            contours: true,
            divisions: 4,
            ..linear()
        };
        let (w, h) = (80, 10);
        let y: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 10.0).collect();
        let (c, l) = f.image(&y, w, h);
        // The isoline at 400 cd/m² (level 2 of 4) runs down column 40.
        let at = |x: i64, y: i64| c.pixels[y as usize * c.width + x as usize];
        assert_eq!(at(l.image_x + 40, l.top + 5), viridis(0.5));
        let g = at(l.image_x + 30, l.top + 5);
        assert_eq!(g[0], g[1]);
    }
}
