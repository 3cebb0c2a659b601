//! `convergence.png`: error against wall time on log-log axes, one line per configuration
//! (our integrators solid with dots, peers dashed with squares), the fitted slope in each
//! legend entry, and the target errors as grey horizontal lines; and the text of the maps'
//! and false colour's rasters ([`draw_text`], `output/map/canvas.rs`). The only module naming
//! plotters; text is drawn with the DejaVu Sans font shipped in `assets/fonts/` (its licence
//! beside it), so no system font library is needed.

use super::atomic::write_atomically;
use crate::converge::fit::{self, TARGETS};
use crate::converge::{Row, SOURCE};
use crate::error::{Error, Result};
use crate::imageio;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::Path;
use std::sync::Once;

/// Plot size in pixels (small enough for a repository, large enough to read).
pub const SIZE: (u32, u32) = (900, 560);

const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Distinct colours (Okabe and Ito 2008, colour-blind safe) and black.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is ours and valid; a failure would only leave the labels out.
        let _ = register_font(FONT, FontStyle::Normal, FONT_BYTES);
    });
}

/// Draws `text` in DejaVu Sans of `px` pixels (the em) onto the RGB8 raster `pixels` of
/// `size`, the top of its line box at `at.1` and its left at `at.0`; what falls outside the
/// raster is clipped. Glyph edges are blended into what is beneath them.
pub fn draw_text(
    pixels: &mut [u8],
    size: (u32, u32),
    at: (i32, i32),
    text: &str,
    px: f64,
    color: [u8; 3],
) {
    register();
    let root = BitMapBackend::with_buffer(pixels, size).into_drawing_area();
    let style = (FONT, px)
        .into_font()
        .color(&RGBColor(color[0], color[1], color[2]));
    // The font is ours and valid: a failure could only leave this text out.
    let _ = root.draw_text(text, &style, at);
    let _ = root.present();
}

/// Width and height in pixels of `text` as [`draw_text`] draws it at `px`.
pub fn text_size(text: &str, px: f64) -> (u32, u32) {
    register();
    (FONT, px).into_font().box_size(text).unwrap_or((0, 0))
}

/// One curve of [`lines`]: its legend label, its points and whether it is dashed.
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub dashed: bool,
}

/// A linear-axes line plot of `series` into `path` (PNG), e.g. a pixel's spectrum beside the
/// CIE curves (`examples/spectral_pixel.rs`).
pub fn lines(
    path: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[Curve],
) -> Result<()> {
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw_lines(&mut buf, title, (x_label, y_label), series)
        .map_err(|e| Error::io(path, format!("cannot draw the plot: {e}")))?;
    write_atomically(path, |f| imageio::encode_png_rgb8(f, &buf, w, h))
        .map_err(|e| Error::io(path, format!("cannot write: {e}")))
}

fn draw_lines(
    buf: &mut [u8],
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[Curve],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    register();
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let y1 = all().fold(0.0f64, |m, p| m.max(p.1)) * 1.05;
    if !(x0 < x1 && y1 > 0.0) {
        return Err("nothing to plot".into());
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 20))
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, 0.0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for (i, c) in series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let style = colour.stroke_width(if c.dashed { 2 } else { 3 });
        let pts = c.points.iter().copied();
        if c.dashed {
            chart.draw_series(DashedLineSeries::new(pts, 8, 5, style))?;
        } else {
            chart.draw_series(LineSeries::new(pts, style))?;
        }
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(c.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
    }
    draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

/// The series' legend in a framed box at the upper right.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(180, 180, 180))
        .draw()
}

/// One line of the plot.
struct Series {
    label: String,
    peer: bool,
    points: Vec<(f64, f64)>,
}

/// The series of `rows`: (time, error) per configuration, with its slope in the label (a
/// peer's configuration names the renderer, e.g. "mitsuba llvm_ad_spectral").
fn series(rows: &[Row]) -> Vec<Series> {
    fit::groups(rows)
        .iter()
        .map(|g| {
            let pts = fit::points(g);
            let slope = fit::time_slope(&pts)
                .map(|f| format!(" (slope {:.2})", f.slope))
                .unwrap_or_default();
            let peer = g[0].source != SOURCE;
            let mut label = g[0].config.clone();
            if let Some(m) = g[0].meter {
                label += &format!(" meter {m}");
            }
            Series {
                label: label + &slope,
                peer,
                points: pts
                    .iter()
                    .filter(|p| p.error > 0.0 && p.time_s > 0.0)
                    .map(|p| (p.time_s, p.error))
                    .collect(),
            }
        })
        .filter(|s| !s.points.is_empty())
        .collect()
}

/// Powers of ten enclosing `lo..hi` (positive), at least one decade apart.
fn decades(lo: f64, hi: f64) -> (f64, f64) {
    let a = 10f64.powf(lo.log10().floor());
    let b = 10f64.powf(hi.log10().ceil());
    (a, if b <= a { a * 10.0 } else { b })
}

/// Draws the plot of `rows` titled `title` into `path` (PNG).
pub fn write(path: &Path, title: &str, y_label: &str, rows: &[Row]) -> Result<()> {
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw(&mut buf, title, y_label, &series(rows))
        .map_err(|e| Error::io(path, format!("cannot draw the plot: {e}")))?;
    write_atomically(path, |f| imageio::encode_png_rgb8(f, &buf, w, h))
        .map_err(|e| Error::io(path, format!("cannot write: {e}")))
}

fn draw(
    buf: &mut [u8],
    title: &str,
    y_label: &str,
    series: &[Series],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    register();
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let all = || series.iter().flat_map(|s| s.points.iter());
    let fold =
        |f: fn(f64, f64) -> f64, init: f64, k: fn(&(f64, f64)) -> f64| all().map(k).fold(init, f);
    let (t0, t1) = decades(
        fold(f64::min, f64::INFINITY, |p| p.0).min(1.0),
        fold(f64::max, 0.0, |p| p.0).max(1e-3),
    );
    let e_min = fold(f64::min, f64::INFINITY, |p| p.1).min(TARGETS[TARGETS.len() - 1]);
    let (e0, e1) = decades(
        e_min.max(1e-6),
        fold(f64::max, 0.0, |p| p.1).max(TARGETS[0]),
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("integrator wall time (s)")
        .y_desc(y_label)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    let grey = RGBColor(150, 150, 150);
    for t in TARGETS {
        chart.draw_series(LineSeries::new([(t0, t), (t1, t)], grey.stroke_width(1)))?;
        chart.draw_series(std::iter::once(Text::new(
            format!("{:.0} %", 100.0 * t),
            (t0 * 1.15, t * 1.04),
            (FONT, 13).into_font().color(&grey),
        )))?;
    }
    for (i, s) in series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let style = colour.stroke_width(if s.peer { 2 } else { 3 });
        if s.peer {
            chart.draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 5, style))?;
            let squares = s.points.iter().map(move |&p| {
                EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], colour.filled())
            });
            chart.draw_series(squares)?;
        } else {
            chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            let dots = s
                .points
                .iter()
                .map(move |&p| Circle::new(p, 2, colour.filled()));
            chart.draw_series(dots)?;
        }
        // The legend entry, drawn by an invisible series carrying the label.
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], colour.stroke_width(3))
            });
    }
    draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_plot_with_text() {
        let rows: Vec<Row> = (1..20)
            .map(|k| Row {
                config: "path".into(),
                source: SOURCE.into(),
                samples: k,
                time_s: 0.1 * k as f64,
                error: Some(0.3 / (k as f64).sqrt()),
                ..Row::default()
            })
            .collect();
        let (w, h) = SIZE;
        let mut buf = vec![255u8; (w * h * 3) as usize];
        draw(&mut buf, "test", "relRMSE", &series(&rows)).unwrap();
        // Something was drawn in the line's blue.
        assert!(buf.chunks(3).any(|p| p == [0, 114, 178]));
    }
}
