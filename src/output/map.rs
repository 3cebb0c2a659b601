//! Illuminance maps (`spectral-render meter --grid`): a rectangle of NU × NV cell centres
//! written as `BASE.csv`, `BASE.json` and a false-colour `BASE.png` with a lux legend and
//! isolux lines, plus the summary lighting designers check against EN 12464-1: E_min, E_avg,
//! E_max and the uniformity U0 = E_min / E_avg.
//!
//! Cell (i, j) is centred at origin + (i + ½)/NU · u + (j + ½)/NV · v (stage coordinates, as
//! given on the command line). In the image u runs to the right and v upwards, with axes in
//! metres from the origin (the lower-left corner, marked); the cell centres' lattice is
//! extended to the grid's edges by linear extrapolation (`to_edges`), the colours are
//! interpolated bilinearly on it and the isolines traced by marching squares on the same
//! lattice (`map/contour.rs`), so both reach the edges. On coarse grids each cell shows its
//! reading; `range` fixes the colour scale. The drawing stays on the hand-written canvas
//! (`map/canvas.rs`), see docs/design.md "Previews, working spaces and false colour". Each
//! file is replaced atomically (`output::atomic`); PNG encoding goes through `crate::imageio`.
//!
//! ```text
//! i,j,x,y,z,lux,ci95
//! 0,0,0.25,0.0,0.25,312.4,1.9
//! ```

pub(crate) mod canvas;
pub(crate) mod colormap;
pub(crate) mod contour;

use super::atomic::write_atomically;
use super::json;
use crate::error::{Error, Result};
use crate::imageio::encode_png_rgb8;
use crate::session::Reading;
use canvas::{text_width, Canvas, GLYPH_H};
use colormap::{is_light, viridis};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A measured grid, in stage coordinates.
#[derive(Clone, Debug)]
pub struct IlluminanceMap {
    pub origin: [f64; 3],
    pub u: [f64; 3],
    pub v: [f64; 3],
    pub nu: usize,
    pub nv: usize,
    pub normal: [f64; 3],
    /// One reading per cell, cell (i, j) at index j·NU + i.
    pub readings: Vec<Reading>,
    /// A fixed colour scale [min, max] in lx (`--range`); None: from the readings, widened
    /// to whole steps.
    pub range: Option<(f64, f64)>,
    /// Metres per stage unit (the stage's metersPerUnit), for the axes.
    pub meters_per_unit: f64,
}

/// EN 12464-1's figures for a calculation grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub e_min: f64,
    pub e_avg: f64,
    pub e_max: f64,
    /// E_min / E_avg (0 when E_avg is 0).
    pub u0: f64,
}

/// `BASE.json`: the grid, EN 12464-1's figures (at the top level and as `summary`), cells.
#[derive(Serialize)]
struct MapJson {
    kind: &'static str,
    unit: &'static str,
    grid: GridJson,
    #[serde(flatten)]
    figures: Figures,
    summary: Figures,
    cells: Vec<CellJson>,
}

#[derive(Serialize)]
struct GridJson {
    origin: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    n: [usize; 2],
    normal: [f64; 3],
}

#[derive(Clone, Copy, Serialize)]
struct Figures {
    #[serde(rename = "E_min")]
    e_min: f64,
    #[serde(rename = "E_avg")]
    e_avg: f64,
    #[serde(rename = "E_max")]
    e_max: f64,
    #[serde(rename = "U0")]
    u0: f64,
}

#[derive(Serialize)]
struct CellJson {
    i: usize,
    j: usize,
    at: [f64; 3],
    value: f64,
    ci95: f64,
    samples: u64,
}

impl IlluminanceMap {
    /// Centre of cell (i, j) in stage coordinates.
    pub fn cell_centre(
        origin: [f64; 3],
        u: [f64; 3],
        v: [f64; 3],
        (nu, nv): (usize, usize),
        (i, j): (usize, usize),
    ) -> [f64; 3] {
        let (a, b) = ((i as f64 + 0.5) / nu as f64, (j as f64 + 0.5) / nv as f64);
        std::array::from_fn(|k| origin[k] + a * u[k] + b * v[k])
    }

    fn centre(&self, i: usize, j: usize) -> [f64; 3] {
        Self::cell_centre(self.origin, self.u, self.v, (self.nu, self.nv), (i, j))
    }

    fn values(&self) -> Vec<f64> {
        self.readings.iter().map(|r| r.value).collect()
    }

    pub fn summary(&self) -> Summary {
        let v = self.values();
        let e_min = v.iter().copied().fold(f64::INFINITY, f64::min);
        let e_max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let e_avg = v.iter().sum::<f64>() / v.len().max(1) as f64;
        Summary {
            e_min,
            e_avg,
            e_max,
            u0: if e_avg > 0.0 { e_min / e_avg } else { 0.0 },
        }
    }

    /// One row per cell: i, j, x, y, z (stage coordinates), lux, ci95.
    pub fn csv(&self) -> String {
        let mut s = String::from("i,j,x,y,z,lux,ci95\n");
        for j in 0..self.nv {
            for i in 0..self.nu {
                let [x, y, z] = self.centre(i, j);
                let r = &self.readings[j * self.nu + i];
                s += &format!(
                    "{i},{j},{},{},{},{},{}\n",
                    num(x),
                    num(y),
                    num(z),
                    num(r.value),
                    num(r.ci95)
                );
            }
        }
        s
    }

    /// The grid, the summary (also at top level, for simple consumers) and every cell.
    pub fn json(&self) -> Result<String> {
        let sm = self.summary();
        let figures = Figures {
            e_min: sm.e_min,
            e_avg: sm.e_avg,
            e_max: sm.e_max,
            u0: sm.u0,
        };
        let mut cells = Vec::with_capacity(self.readings.len());
        for j in 0..self.nv {
            for i in 0..self.nu {
                let r = &self.readings[j * self.nu + i];
                cells.push(CellJson {
                    i,
                    j,
                    at: self.centre(i, j),
                    value: r.value,
                    ci95: r.ci95,
                    samples: r.samples,
                });
            }
        }
        json::pretty(&MapJson {
            kind: "illuminance_map",
            unit: "lx",
            grid: GridJson {
                origin: self.origin,
                u: self.u,
                v: self.v,
                n: [self.nu, self.nv],
                normal: self.normal,
            },
            figures,
            summary: figures,
            cells,
        })
    }

    /// Writes `BASE.csv`, `BASE.json` and `BASE.png`; returns their paths.
    pub fn write(&self, base: &Path) -> Result<[PathBuf; 3]> {
        let paths = files(base);
        let fail = |p: &Path, e: std::io::Error| Error::io(p, format!("cannot write: {e}"));
        let text = |p: &Path, s: String| {
            write_atomically(p, |f| f.write_all(s.as_bytes())).map_err(|e| fail(p, e))
        };
        text(&paths[0], self.csv())?;
        text(&paths[1], self.json()?)?;
        let img = self.image();
        let (w, h) = (img.width as u32, img.height as u32);
        write_atomically(&paths[2], |f| encode_png_rgb8(f, &img.bytes(), w, h))
            .map_err(|e| fail(&paths[2], e))?;
        Ok(paths)
    }

    /// The false-colour image: map, legend and summary line.
    pub fn image(&self) -> Canvas {
        let layout = Layout::new(self);
        let mut c = Canvas::new(layout.width, layout.height, WHITE);
        let values = self.values();
        let sm = self.summary();
        let (lo, hi, step) = match self.range {
            Some((lo, hi)) => (lo, hi, contour::nice_step(hi - lo, 6)),
            None => contour::scale(sm.e_min, sm.e_max),
        };
        let levels = contour::levels(sm.e_min.max(lo), sm.e_max.min(hi), step);
        self.paint_map(&mut c, &layout, &values, (lo, hi));
        self.paint_isolines(&mut c, &layout, &values, &levels, (lo, hi), step);
        paint_legend(&mut c, &layout, (lo, hi, step), &levels);
        self.paint_axes(&mut c, &layout);
        self.paint_cell_values(&mut c, &layout, &values, (lo, hi));
        c.text(MARGIN, layout.footer_y, &self.footer(), 2, INK);
        c
    }

    /// The summary line under the map, with the stage's unit when it is not the metre (the
    /// axes are in metres).
    fn footer(&self) -> String {
        let sm = self.summary();
        let mut line = format!(
            "Emin {}  Eavg {}  Emax {} lx  U0 {}",
            sig(sm.e_min),
            sig(sm.e_avg),
            sig(sm.e_max),
            sig(sm.u0)
        );
        if self.meters_per_unit != 1.0 {
            line += &format!("   (axes in m; stage unit {} m)", sig(self.meters_per_unit));
        }
        line
    }

    fn paint_map(&self, c: &mut Canvas, l: &Layout, values: &[f64], (lo, hi): (f64, f64)) {
        let (ext, _, _) = to_edges(values, self.nu, self.nv);
        for py in 0..l.map_h {
            for px in 0..l.map_w {
                let (gx, gy) = l.pixel_to_grid(px as f64 + 0.5, py as f64 + 0.5);
                let e = bilinear(
                    &ext,
                    self.nu + 2,
                    self.nv + 2,
                    to_ext(gx, self.nu),
                    to_ext(gy, self.nv),
                );
                let colour = viridis(((e - lo) / (hi - lo)) as f32);
                c.put(MAP_X + px as i64, l.top + py as i64, colour);
            }
        }
        let (w, h) = (l.map_w as i64, l.map_h as i64);
        let (x0, y0) = (MAP_X - 1, l.top - 1);
        c.line((x0, y0), (x0 + w + 1, y0), INK);
        c.line((x0, y0 + h + 1), (x0 + w + 1, y0 + h + 1), INK);
        c.line((x0, y0), (x0, y0 + h + 1), INK);
        c.line((x0 + w + 1, y0), (x0 + w + 1, y0 + h + 1), INK);
    }

    /// The u axis below the map and the v axis left of it, in metres from the grid's origin
    /// (its lower-left corner, marked with a square).
    fn paint_axes(&self, c: &mut Canvas, l: &Layout) {
        let len = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let (lu, lv) = (
            len(self.u) * self.meters_per_unit,
            len(self.v) * self.meters_per_unit,
        );
        let bottom = l.top + l.map_h as i64;
        let (w, h) = (l.map_w as f64, l.map_h as f64);
        for (length, along_u) in [(lu, true), (lv, false)] {
            if !(length.is_finite() && length > 0.0) {
                continue;
            }
            let step = contour::nice_step(length, 5);
            let mut k = 0.0;
            while k * step <= length * (1.0 + 1e-9) {
                let d = k * step;
                let text = tick_label(d, step);
                if along_u {
                    let x = MAP_X + (d / length * w).round() as i64;
                    c.line((x, bottom + 1), (x, bottom + 4), INK);
                    let tx = x - text_width(&text, 1) as i64 / 2;
                    c.text(tx, bottom + 7, &text, 1, INK);
                } else {
                    let y = bottom - (d / length * h).round() as i64;
                    c.line((MAP_X - 5, y), (MAP_X - 2, y), INK);
                    let tx = MAP_X - 8 - text_width(&text, 1) as i64;
                    c.text(tx, y - GLYPH_H as i64 / 2, &text, 1, INK);
                }
                k += 1.0;
            }
        }
        c.text(MAP_X + l.map_w as i64 + 6, bottom + 7, "m", 1, INK);
        c.text(
            MAP_X - 8 - text_width("m", 1) as i64,
            l.top - GLYPH_H as i64 - 4,
            "m",
            1,
            INK,
        );
        c.fill_rect(MAP_X - 4, bottom - 3, 7, 7, INK);
    }

    /// Each cell's reading at its centre, on grids coarse enough for the text to fit.
    fn paint_cell_values(&self, c: &mut Canvas, l: &Layout, values: &[f64], (lo, hi): (f64, f64)) {
        let cell_w = l.map_w as f64 / self.nu as f64;
        let cell_h = l.map_h as f64 / self.nv as f64;
        let widest = values
            .iter()
            .map(|v| text_width(&sig(*v), 1))
            .max()
            .unwrap_or(0);
        if cell_w < widest as f64 + 8.0 || cell_h < 2.0 * GLYPH_H as f64 + 4.0 {
            return;
        }
        for j in 0..self.nv {
            for i in 0..self.nu {
                let v = values[j * self.nu + i];
                let (x, y) = l.grid_to_pixel(i as f64, j as f64);
                let fill = viridis(((v - lo) / (hi - lo)) as f32);
                let ink = if is_light(fill) { INK } else { WHITE };
                let text = sig(v);
                let tx = x - text_width(&text, 1) as i64 / 2;
                c.text(tx, y - GLYPH_H as i64 / 2, &text, 1, ink);
            }
        }
    }

    /// Isolux lines, each labelled once where its label fits clear of the others.
    fn paint_isolines(
        &self,
        c: &mut Canvas,
        l: &Layout,
        values: &[f64],
        levels: &[f64],
        (lo, hi): (f64, f64),
        step: f64,
    ) {
        let mut placed: Vec<[i64; 4]> = Vec::new();
        for &level in levels {
            let fill = viridis(((level - lo) / (hi - lo)) as f32);
            let ink = if is_light(fill) { INK } else { WHITE };
            let (ext, nx, ny) = to_edges(values, self.nu, self.nv);
            let segs = contour::isoline(&ext, nx, ny, level);
            let (nu, nv) = (self.nu, self.nv);
            let to_px = |g: [f64; 2]| l.grid_to_pixel(from_edges(g[0], nu), from_edges(g[1], nv));
            for (a, b) in &segs {
                c.line(to_px(*a), to_px(*b), ink);
            }
            let label = tick_label(level, step);
            let (tw, th) = (text_width(&label, 1) as i64 + 4, GLYPH_H as i64 + 4);
            let mut spots: Vec<(i64, i64)> = segs
                .iter()
                .map(|(a, b)| {
                    let (p, q) = (to_px(*a), to_px(*b));
                    ((p.0 + q.0) / 2, (p.1 + q.1) / 2)
                })
                .collect();
            // Prefer spots far from the map's edges.
            spots.sort_by_key(|&(x, y)| {
                let d = (x - MAP_X)
                    .min(MAP_X + l.map_w as i64 - x)
                    .min(y - l.top)
                    .min(l.top + l.map_h as i64 - y);
                (-d, x, y)
            });
            let fits = |r: &[i64; 4]| {
                r[0] >= MAP_X
                    && r[1] >= l.top
                    && r[0] + r[2] <= MAP_X + l.map_w as i64
                    && r[1] + r[3] <= l.top + l.map_h as i64
                    && placed.iter().all(|q| !overlaps(r, q))
            };
            if let Some(r) = spots
                .iter()
                .map(|&(x, y)| [x - tw / 2, y - th / 2, tw, th])
                .find(|r| fits(r))
            {
                c.fill_rect(r[0], r[1], r[2], r[3], fill);
                c.text(r[0] + 2, r[1] + 2, &label, 1, ink);
                placed.push(r);
            }
        }
    }
}

const WHITE: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [20, 20, 20];
/// Border around everything, in pixels.
const MARGIN: i64 = 12;
/// The map's left edge: the margin and the v axis's labels.
const MAP_X: i64 = MARGIN + 44;
/// Below the map: the u axis's ticks and labels.
const AXIS_H: i64 = GLYPH_H as i64 + 12;
/// The map's longer side, in pixels.
const MAP_LONG_SIDE: f64 = 480.0;
const BAR_W: i64 = 18;
const LEGEND_MIN_H: usize = 200;

/// Where the parts of the image go.
struct Layout {
    map_w: usize,
    map_h: usize,
    top: i64,
    bar_x: i64,
    bar_h: usize,
    footer_y: i64,
    width: usize,
    height: usize,
    nu: usize,
    nv: usize,
}

impl Layout {
    fn new(m: &IlluminanceMap) -> Layout {
        let len = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let (lu, lv) = (len(m.u), len(m.v));
        let k = MAP_LONG_SIDE / lu.max(lv);
        let map_w = ((lu * k).round() as usize).clamp(48, MAP_LONG_SIDE as usize);
        let map_h = ((lv * k).round() as usize).clamp(48, MAP_LONG_SIDE as usize);
        let top = MARGIN + 2 * GLYPH_H as i64 + 8;
        let bar_x = MAP_X + map_w as i64 + 24;
        let bar_h = map_h.max(LEGEND_MIN_H);
        let footer_y = top + bar_h.max(map_h + AXIS_H as usize) as i64 + 14;
        let legend_right = bar_x + BAR_W + 8 + text_width("0000000.00", 2) as i64 + MARGIN;
        let widest = text_width("Emin 00000  Eavg 00000  Emax 00000 lx  U0 0.000", 2);
        let footer_right = 2 * MARGIN + widest.max(text_width(&m.footer(), 2)) as i64;
        Layout {
            map_w,
            map_h,
            top,
            bar_x,
            bar_h,
            footer_y,
            width: legend_right.max(footer_right) as usize,
            height: (footer_y + 2 * GLYPH_H as i64 + MARGIN) as usize,
            nu: m.nu,
            nv: m.nv,
        }
    }

    /// Map pixel (from its top-left corner) to grid coordinates (column i, row j).
    fn pixel_to_grid(&self, px: f64, py: f64) -> (f64, f64) {
        let gx = px / self.map_w as f64 * self.nu as f64 - 0.5;
        let gy = (1.0 - py / self.map_h as f64) * self.nv as f64 - 0.5;
        (gx, gy)
    }

    /// Grid coordinates to a canvas pixel.
    fn grid_to_pixel(&self, gx: f64, gy: f64) -> (i64, i64) {
        let px = (gx + 0.5) / self.nu as f64 * self.map_w as f64;
        let py = (1.0 - (gy + 0.5) / self.nv as f64) * self.map_h as f64;
        (
            MAP_X + (px.floor() as i64).min(self.map_w as i64 - 1),
            self.top + (py.floor() as i64).min(self.map_h as i64 - 1),
        )
    }
}

/// The colour bar with its lux ticks, the isoline levels marked across it, and the unit.
fn paint_legend(c: &mut Canvas, l: &Layout, (lo, hi, step): (f64, f64, f64), levels: &[f64]) {
    let h = l.bar_h as f64;
    let y_of = |v: f64| l.top + ((hi - v) / (hi - lo) * h).round() as i64;
    for y in 0..l.bar_h {
        let v = hi - (y as f64 + 0.5) / h * (hi - lo);
        let colour = viridis(((v - lo) / (hi - lo)) as f32);
        c.fill_rect(l.bar_x, l.top + y as i64, BAR_W, 1, colour);
    }
    for &v in levels {
        let fill = viridis(((v - lo) / (hi - lo)) as f32);
        let ink = if is_light(fill) { INK } else { WHITE };
        c.line((l.bar_x, y_of(v)), (l.bar_x + BAR_W - 1, y_of(v)), ink);
    }
    // Multiples of the step within the scale (its ends, for a scale from the readings).
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    for k in first..=last {
        let v = k as f64 * step;
        let y = y_of(v);
        c.line((l.bar_x + BAR_W, y), (l.bar_x + BAR_W + 4, y), INK);
        c.text(
            l.bar_x + BAR_W + 8,
            y - GLYPH_H as i64,
            &tick_label(v, step),
            2,
            INK,
        );
    }
    c.text(l.bar_x, MARGIN, "lx", 2, INK);
}

fn overlaps(a: &[i64; 4], b: &[i64; 4]) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

/// The readings with a ring of values on the grid's edges, half a cell beyond the outer
/// centres, extrapolated linearly from the two nearest centres along each axis (a single
/// cell's value is kept): the colours and the isolines then reach the map's edges.
/// Returns the (NU + 2) × (NV + 2) lattice.
fn to_edges(values: &[f64], nu: usize, nv: usize) -> (Vec<f64>, usize, usize) {
    let (nx, ny) = (nu + 2, nv + 2);
    let clamp = |k: isize, n: usize| k.clamp(0, n as isize - 1) as usize;
    // Index into the readings, extrapolating beyond the border: k = −1 or n.
    let along = |get: &dyn Fn(usize) -> f64, k: isize, n: usize| -> f64 {
        if (0..n as isize).contains(&k) || n == 1 {
            get(clamp(k, n))
        } else if k < 0 {
            1.5 * get(0) - 0.5 * get(1)
        } else {
            1.5 * get(n - 1) - 0.5 * get(n - 2)
        }
    };
    let mut out = vec![0.0; nx * ny];
    for ey in 0..ny {
        for ex in 0..nx {
            let (i, j) = (ex as isize - 1, ey as isize - 1);
            let row = |j: usize| along(&|i| values[j * nu + i], i, nu);
            out[ey * nx + ex] = along(&row, j, nv);
        }
    }
    (out, nx, ny)
}

/// Grid coordinate (centre k at k, edges at −½ and n − ½) → coordinate on the lattice of
/// [`to_edges`] (edges at 0 and n + 1, centre k at k + 1).
fn to_ext(g: f64, n: usize) -> f64 {
    let last = n as f64 - 1.0;
    if g < 0.0 {
        1.0 + 2.0 * g.max(-0.5)
    } else if g > last {
        n as f64 + 2.0 * (g - last).min(0.5)
    } else {
        g + 1.0
    }
}

/// The inverse of [`to_ext`].
fn from_edges(e: f64, n: usize) -> f64 {
    if e < 1.0 {
        -0.5 + 0.5 * e
    } else if e > n as f64 {
        n as f64 - 1.0 + 0.5 * (e - n as f64)
    } else {
        e - 1.0
    }
}

/// Bilinear interpolation between cell centres, clamped at the grid's border.
fn bilinear(values: &[f64], nx: usize, ny: usize, gx: f64, gy: f64) -> f64 {
    let gx = gx.clamp(0.0, (nx - 1) as f64);
    let gy = gy.clamp(0.0, (ny - 1) as f64);
    let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(nx - 1), (y0 + 1).min(ny - 1));
    let (fx, fy) = (gx - x0 as f64, gy - y0 as f64);
    let v = |x: usize, y: usize| values[y * nx + x];
    let a = v(x0, y0) + fx * (v(x1, y0) - v(x0, y0));
    let b = v(x0, y1) + fx * (v(x1, y1) - v(x0, y1));
    a + fy * (b - a)
}

/// A tick value with as many decimals as the step needs.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil() as usize
    };
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
        s[1..].to_string()
    } else {
        s
    }
}

/// Three significant digits, without exponent for everyday lux values.
pub fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (2 - v.abs().log10().floor() as i64).clamp(0, 6) as usize;
    format!("{v:.decimals$}")
}

/// A JSON/CSV number: shortest round-trip form; `null` for a non-finite value.
pub fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        "null".into()
    }
}

/// `[x, y, z]` of JSON numbers.
pub fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// `base` with `.ext` appended to its file name (`out/map` → `out/map.csv`).
/// The files [`IlluminanceMap::write`] writes for `base`: `BASE.csv`, `BASE.json`, `BASE.png`.
pub fn files(base: &Path) -> [PathBuf; 3] {
    ["csv", "json", "png"].map(|ext| with_suffix(base, ext))
}

fn with_suffix(base: &Path, ext: &str) -> PathBuf {
    let mut name = base.file_name().unwrap_or_default().to_os_string();
    name.push(".");
    name.push(ext);
    base.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(value: f64) -> Reading {
        Reading {
            value,
            ci95: 0.01 * value,
            samples: 64,
            capped: None,
            depth_cut: None,
        }
    }

    fn ramp(nu: usize, nv: usize) -> IlluminanceMap {
        IlluminanceMap {
            origin: [0.0, 0.0, 0.0],
            u: [2.0, 0.0, 0.0],
            v: [0.0, 0.0, 1.0],
            nu,
            nv,
            normal: [0.0, 1.0, 0.0],
            readings: (0..nu * nv)
                .map(|k| reading(100.0 + 10.0 * (k % nu) as f64 + (k / nu) as f64))
                .collect(),
            range: None,
            meters_per_unit: 1.0,
        }
    }

    #[test]
    fn a_fixed_range_sets_the_colours() {
        let mut m = ramp(4, 3);
        m.range = Some((0.0, 400.0));
        let l = Layout::new(&m);
        let c = m.image();
        // Beside cell (0, 0)'s value label: about 100 lx, a quarter of the way up.
        let (x, y) = l.grid_to_pixel(0.0, 0.0);
        let p = c.pixels[(y - GLYPH_H as i64) as usize * c.width + x as usize];
        let want = viridis(0.25);
        assert!(
            (0..3).all(|k| (p[k] as i32 - want[k] as i32).abs() <= 3),
            "{p:?} {want:?}"
        );
    }

    #[test]
    fn summary_and_text_outputs() {
        let m = ramp(4, 3);
        let s = m.summary();
        assert_eq!((s.e_min, s.e_max), (100.0, 132.0));
        assert!((s.e_avg - 116.0).abs() < 1e-12);
        assert!((s.u0 - 100.0 / 116.0).abs() < 1e-12);
        let csv = m.csv();
        assert_eq!(csv.lines().count(), 13);
        assert_eq!(
            csv.lines().nth(2).unwrap(),
            "1,0,0.75,0.0,0.16666666666666666,110.0,1.1"
        );
        let json: serde_json::Value = serde_json::from_str(&m.json().unwrap()).unwrap();
        assert_eq!(json["summary"]["E_min"], 100.0);
        assert_eq!(json["U0"], json["summary"]["U0"]);
        assert_eq!(json["grid"]["n"], serde_json::json!([4, 3]));
        assert_eq!(json["cells"].as_array().unwrap().len(), 12);
        assert_eq!(json["cells"][1]["value"], 110.0);
    }

    #[test]
    fn image_has_the_map_legend_and_isolines() {
        let m = ramp(20, 10);
        let img = m.image();
        assert!(img.width > 480 && img.height > 200);
        // The map's lower-left pixel shows the minimum, its upper-right the maximum.
        let l = Layout::new(&m);
        let at = |x: i64, y: i64| img.pixels[y as usize * img.width + x as usize];
        let (lo, hi, _) = contour::scale(100.0, 219.0);
        let low = viridis(((100.0 - lo) / (hi - lo)) as f32);
        // (Beside the origin's mark.)
        let p = at(MAP_X + 5, l.top + l.map_h as i64 - 1);
        assert!(
            (0..3).all(|k| (p[k] as i32 - low[k] as i32).abs() <= 3),
            "{p:?} vs {low:?}"
        );
        let mut isoline_pixels = 0;
        for y in l.top..l.top + l.map_h as i64 {
            for x in MAP_X..MAP_X + l.map_w as i64 {
                isoline_pixels += [INK, WHITE].contains(&at(x, y)) as usize;
            }
        }
        assert!(isoline_pixels > 100, "{isoline_pixels}");
    }

    #[test]
    fn edges_extrapolate_the_readings_linearly() {
        // A ramp in u: 100, 110, 120, 130 → edges 95 and 135; constant in v.
        let values: Vec<f64> = (0..8).map(|k| 100.0 + 10.0 * (k % 4) as f64).collect();
        let (ext, nx, ny) = to_edges(&values, 4, 2);
        assert_eq!((nx, ny), (6, 4));
        assert_eq!(&ext[0..6], &[95.0, 100.0, 110.0, 120.0, 130.0, 135.0]);
        assert_eq!(&ext[18..24], &ext[0..6]);
        for g in [-0.5, -0.2, 0.0, 1.5, 3.0, 3.25, 3.5] {
            assert!((from_edges(to_ext(g, 4), 4) - g).abs() < 1e-12, "{g}");
        }
        // Isolines reach the edge: the 97.5 lx line lies between the edge and centre 0.
        let segs = contour::isoline(&ext, nx, ny, 97.5);
        assert!(!segs.is_empty());
        for (a, _) in segs {
            assert!((from_edges(a[0], 4) - (-0.25)).abs() < 1e-9, "{a:?}");
        }
    }

    #[test]
    fn labels_and_numbers() {
        assert_eq!(tick_label(250.0, 50.0), "250");
        assert_eq!(tick_label(0.15, 0.05), "0.15");
        assert_eq!(tick_label(-0.0, 0.5), "0.0");
        assert_eq!(sig(1234.4), "1234");
        assert_eq!(sig(0.4567), "0.457");
        assert_eq!(num(f64::NAN), "null");
        assert_eq!(
            with_suffix(Path::new("out/map"), "png"),
            Path::new("out/map.png")
        );
    }
}
