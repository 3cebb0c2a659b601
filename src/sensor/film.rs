//! The film: per-pixel XYZ sums, filled by tiles, each term rounded once to a fixed grid and
//! summed as integers (`grid_sum`), so that the image depends on the samples only — not on
//! the passes, the threads, nor on whether the samples were rendered as parts and merged
//! ([`Film::merge`], `session::part`).
//!
//! Light tracing and BDPT also *splat*: a light path adds to whatever pixel it reaches. Each
//! splat is rounded to the grid and added ([`Film::add_splats`]). A splat is a contribution
//! per light path with the camera importance normalised over the whole image (see
//! `sensor::camera`); a pixel's value is its sample mean plus its splat sum divided by the
//! light paths traced per pixel (pbrt-v4's `RGBFilm::GetPixelRGB`, splatScale = 1/spp).
//!
//! **Variance.** The film also keeps the luminance Y of the odd-numbered samples apart (their
//! own-pixel values and their splats, in f64: they serve the variance estimate only). The even
//! and odd halves are two independent estimates a, b of the pixel, so
//! (a − b)² n_even n_odd / n² is an unbiased estimate of the variance of the pixel's mean over
//! all n samples, whatever the integrator ([`Film::variance_y`]).
//!
//! **Replicates.** An adaptive render's pixels take different numbers of even and odd
//! samples; its film keeps the odd samples' XYZ sums and counts apart too
//! (`sensor::replicates`), and such a pixel is the average of its two replicates' means.

use super::film_state::FilmState;
use super::grid_sum::{Fixed3, Grid};
use super::replicates::Replicates;
use crate::error::Reason;

/// Accumulated XYZ per pixel (Y in cd/m²), row-major, top row first.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    grid: Grid,
    /// Own-pixel sums of every sample, on the grid.
    sums: Vec<Fixed3>,
    samples: Vec<u64>,
    /// Splat sums on the grid (empty until something splats).
    splat: Vec<Fixed3>,
    /// Light paths traced over the whole image (each may splat anywhere).
    light_paths: u64,
    /// Y of the odd-numbered samples: own-pixel values and splats.
    odd_y: Vec<f64>,
    odd_splat_y: Vec<f64>,
    /// Terms clamped and sums saturated (`grid_sum`).
    clamped: u64,
    /// The odd samples' sums and counts, for pixels whose replicates' counts differ.
    replicates: Option<Replicates>,
}

/// One light-path contribution to a pixel (XYZ, before the 1/light-paths-per-pixel scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    pub pixel: u32,
    pub xyz: [f32; 3],
}

/// A rectangle of pixels rendered by one task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl Tile {
    pub fn pixel_count(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// Film indices of the tile's pixels, row by row.
    pub(crate) fn pixels(&self, width: usize) -> impl Iterator<Item = usize> + '_ {
        (self.y0..self.y1).flat_map(move |y| (self.x0..self.x1).map(move |x| y * width + x))
    }
}

impl Film {
    pub fn new(width: usize, height: usize, grid: Grid) -> Film {
        let n = width * height;
        Film {
            width,
            height,
            grid,
            sums: vec![[0; 3]; n],
            samples: vec![0; n],
            splat: Vec::new(),
            light_paths: 0,
            odd_y: vec![0.0; n],
            odd_splat_y: Vec::new(),
            clamped: 0,
            replicates: None,
        }
    }

    /// Keeps the odd samples' sums and counts apart from now on ([`Film::store_tile_counted`]),
    /// for pixels whose replicates take different sample counts; before any sample.
    pub fn keep_replicates(&mut self) {
        self.replicates = Some(Replicates::new(self.width * self.height));
    }

    /// Samples per pixel so far, row-major.
    pub fn sample_counts(&self) -> &[u64] {
        &self.samples
    }

    /// The grid the sums are held on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// Terms clamped and sums saturated so far (0 for any sane scene; reported when not).
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// The image split into tiles of `size` × `size` pixels, row by row.
    pub fn tiles(&self, size: usize) -> Vec<Tile> {
        let mut tiles = Vec::new();
        for y0 in (0..self.height).step_by(size) {
            for x0 in (0..self.width).step_by(size) {
                tiles.push(Tile {
                    x0,
                    y0,
                    x1: (x0 + size).min(self.width),
                    y1: (y0 + size).min(self.height),
                });
            }
        }
        tiles
    }

    /// Adds a tile's grid sums (row-major over the tile), counting `samples_per_pixel` more
    /// samples, the odd samples' Y sums, and `clamped` terms the tile clamped.
    pub fn store_tile(
        &mut self,
        tile: &Tile,
        sums: &[Fixed3],
        odd_y: &[f64],
        samples: u64,
        clamped: u64,
    ) {
        for (k, i) in tile.pixels(self.width).enumerate() {
            self.clamped += u64::from(Grid::add3(&mut self.sums[i], &sums[k]));
            self.odd_y[i] += odd_y[k];
            self.samples[i] += samples;
        }
        self.clamped += clamped;
    }

    /// Adds a tile's grid sums as [`Film::store_tile`] does, each pixel with its own counts
    /// of even and odd samples (`counts[k]`) and the odd samples' grid sums `odd` apart (a film
    /// that keeps its replicates: [`Film::keep_replicates`]).
    pub fn store_tile_counted(
        &mut self,
        tile: &Tile,
        (sums, odd): (&[Fixed3], &[Fixed3]),
        odd_y: &[f64],
        counts: &[[u32; 2]],
        clamped: u64,
    ) {
        let reps = self
            .replicates
            .get_or_insert_with(|| Replicates::new(self.width * self.height));
        for (k, i) in tile.pixels(self.width).enumerate() {
            let [even, odd_n] = counts[k].map(u64::from);
            self.clamped += u64::from(Grid::add3(&mut self.sums[i], &sums[k]));
            self.clamped += u64::from(reps.add(i, &odd[k], odd_n));
            self.odd_y[i] += odd_y[k];
            self.samples[i] += even + odd_n;
        }
        self.clamped += clamped;
    }

    /// Adds splats (each rounded to the grid, so their order does not matter); `odd` holds
    /// the (pixel, Y) of the odd-numbered samples' splats among them.
    pub fn add_splats(&mut self, splats: &[Splat], odd: &[(u32, f32)]) {
        if splats.is_empty() {
            return;
        }
        self.ensure_splats();
        for s in splats {
            let (t, clamped) = self.grid.triple(s.xyz.map(f64::from));
            let saturated = Grid::add3(&mut self.splat[s.pixel as usize], &t);
            self.clamped += clamped + u64::from(saturated);
        }
        for &(pixel, y) in odd {
            self.odd_splat_y[pixel as usize] += y as f64;
        }
    }

    fn ensure_splats(&mut self) {
        if self.splat.is_empty() {
            self.splat = vec![[0; 3]; self.width * self.height];
            self.odd_splat_y = vec![0.0; self.width * self.height];
        }
    }

    /// Counts light paths traced (whether or not they splatted).
    pub fn add_light_paths(&mut self, n: u64) {
        self.light_paths += n;
    }

    /// Adds the film of another part of the same render (same size and grid): the result
    /// is the film that rendered both parts' samples, bit for bit in its sums and counts
    /// (the odd samples' Y, kept in f64 for the variance only, to round-off).
    pub fn merge(&mut self, other: &FilmState) -> Reason<()> {
        other.check()?;
        if (other.width, other.height) != (self.width, self.height) {
            return Err(format!(
                "a film of {}×{} pixels does not merge with one of {}×{}",
                other.width, other.height, self.width, self.height
            ));
        }
        if other.grid_exponent != self.grid.exponent {
            return Err("the films' grids differ (another camera exposure)".into());
        }
        for i in 0..self.sums.len() {
            self.clamped += u64::from(Grid::add3(&mut self.sums[i], &other.sums[i]));
            self.samples[i] += other.samples[i];
            self.odd_y[i] += other.odd_y[i];
        }
        if !other.splat.is_empty() {
            self.ensure_splats();
            for i in 0..self.splat.len() {
                self.clamped += u64::from(Grid::add3(&mut self.splat[i], &other.splat[i]));
                self.odd_splat_y[i] += other.odd_splat_y[i];
            }
        }
        self.light_paths += other.light_paths;
        self.clamped += other.clamped;
        Ok(())
    }

    /// The scale of splat sums: `scale` over the light paths per pixel (0 without any).
    fn splat_scale(&self, scale: f64) -> f64 {
        if self.light_paths > 0 {
            scale * (self.width * self.height) as f64 / self.light_paths as f64
        } else {
            0.0
        }
    }

    /// Mean XYZ per pixel times `scale` (the camera exposure), as f32: the sample mean plus
    /// the splat sum over light paths per pixel.
    pub fn xyz(&self, scale: f64) -> Vec<[f32; 3]> {
        let splat_k = self.splat_scale(scale);
        let g = self.grid;
        (0..self.sums.len())
            .map(|i| {
                let n = self.samples[i];
                let replicated = self.replicates.as_ref();
                if let Some(m) = replicated.and_then(|r| r.mean(i, &self.sums[i], n, g)) {
                    // An adaptive render does not splat (`session::adaptive`).
                    return m.map(|c| (c * scale) as f32);
                }
                let s = self.sums[i].map(|c| g.value(c));
                let k = if n > 0 { scale / n as f64 } else { 0.0 };
                match self.splat.get(i) {
                    Some(sp) if splat_k > 0.0 => {
                        std::array::from_fn(|c| (s[c] * k + g.value(sp[c]) * splat_k) as f32)
                    }
                    _ => s.map(|c| (c * k) as f32),
                }
            })
            .collect()
    }

    /// Per pixel, the estimated variance of the mean luminance Y (times `scale`²), from the
    /// difference of the even and odd samples' means; infinite with fewer than 2 samples.
    pub fn variance_y(&self, scale: f64) -> Vec<f64> {
        let pixels = (self.width * self.height) as f64;
        let g = self.grid;
        (0..self.sums.len())
            .map(|i| {
                let n = self.samples[i];
                let n_odd = match &self.replicates {
                    Some(r) => r.odd_samples(i),
                    None => n / 2,
                };
                if n_odd == 0 || n_odd == n {
                    return f64::INFINITY;
                }
                let (n_odd, n_even) = (n_odd as f64, (n - n_odd) as f64);
                let own = g.value(self.sums[i][1]);
                let (mut odd, mut even) = (self.odd_y[i], own - self.odd_y[i]);
                if let Some(sp) = self.splat.get(i) {
                    // Light paths per pixel = samples per pixel, split alike.
                    let lp = self.light_paths as f64 / pixels;
                    let k = n as f64 / lp;
                    odd += self.odd_splat_y[i] * k;
                    even += (g.value(sp[1]) - self.odd_splat_y[i]) * k;
                }
                let d = even / n_even - odd / n_odd;
                if n_even != n_odd && self.replicates.is_some() {
                    // The pixel is (a + b)/2 (`sensor::replicates`).
                    return scale * scale * d * d / 4.0;
                }
                scale * scale * d * d * n_even * n_odd / (n as f64 * n as f64)
            })
            .collect()
    }

    /// The film's raw state (`film_state`), to save it and continue it later.
    pub fn state(&self) -> FilmState {
        FilmState {
            width: self.width,
            height: self.height,
            grid_exponent: self.grid.exponent,
            sums: self.sums.clone(),
            samples: self.samples.clone(),
            odd_y: self.odd_y.clone(),
            splat: self.splat.clone(),
            odd_splat_y: self.odd_splat_y.clone(),
            light_paths: self.light_paths,
            clamped: self.clamped,
        }
    }

    /// A film that continues `state` (checked: one entry per pixel in every sequence).
    pub fn from_state(state: FilmState) -> Reason<Film> {
        state.check()?;
        Ok(Film {
            width: state.width,
            height: state.height,
            grid: Grid {
                exponent: state.grid_exponent,
            },
            sums: state.sums,
            samples: state.samples,
            splat: state.splat,
            light_paths: state.light_paths,
            odd_y: state.odd_y,
            odd_splat_y: state.odd_splat_y,
            clamped: state.clamped,
            replicates: None,
        })
    }

    /// Samples taken in the pixel with the fewest.
    #[cfg(test)]
    pub fn min_samples(&self) -> u64 {
        self.samples.iter().copied().min().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHOLE: Tile = Tile {
        x0: 0,
        y0: 0,
        x1: 2,
        y1: 1,
    };
    const UNIT: Grid = Grid {
        exponent: super::super::grid_sum::GRID_BITS,
    };

    fn fixed(v: [f64; 3]) -> Fixed3 {
        v.map(|c| UNIT.term(c).0)
    }

    #[test]
    fn tiles_cover_the_image_once() {
        let f = Film::new(37, 20, UNIT);
        let tiles = f.tiles(16);
        assert_eq!(tiles.iter().map(Tile::pixel_count).sum::<usize>(), 37 * 20);
    }

    #[test]
    fn sums_average() {
        let mut f = Film::new(2, 1, UNIT);
        f.store_tile(&WHOLE, &[fixed([2.0, 4.0, 6.0]), [0; 3]], &[0.0; 2], 2, 0);
        f.store_tile(&WHOLE, &[fixed([2.0, 0.0, 0.0]), [0; 3]], &[0.0; 2], 2, 0);
        assert_eq!(f.xyz(1.0)[0], [1.0, 1.0, 1.5]);
        assert_eq!(f.min_samples(), 4);
    }

    #[test]
    fn splats_are_divided_by_light_paths_per_pixel() {
        let mut f = Film::new(2, 1, UNIT);
        f.store_tile(&WHOLE, &[fixed([1.0; 3]), [0; 3]], &[0.0; 2], 4, 0);
        f.add_light_paths(8);
        let sp = |pixel, v| Splat { pixel, xyz: [v; 3] };
        f.add_splats(&[sp(1, 2.0), sp(1, 6.0), sp(0, 4.0)], &[]);
        // 8 light paths over 2 pixels: 4 per pixel.
        assert_eq!(f.xyz(1.0), vec![[1.25; 3], [2.0; 3]]);
    }

    #[test]
    fn merged_halves_equal_the_whole_bit_for_bit() {
        let sp = |pixel, v: f32| Splat {
            pixel,
            xyz: [v, 0.1 * v, 3.0],
        };
        let tiles: Vec<(Fixed3, Vec<Splat>)> = (0..6)
            .map(|s| {
                let v = 1.0 / (s as f64 + 3.0);
                (fixed([v, 1e-7 * v, 1e5 * v]), vec![sp(s % 2, v as f32)])
            })
            .collect();
        let render = |range: std::ops::Range<usize>| {
            let mut f = Film::new(2, 1, UNIT);
            for (own, splats) in &tiles[range] {
                f.store_tile(&WHOLE, &[*own, *own], &[0.5; 2], 1, 0);
                f.add_splats(splats, &[]);
                f.add_light_paths(2);
            }
            f
        };
        let whole = render(0..6);
        let mut merged = render(0..2);
        merged.merge(&render(2..5).state()).unwrap();
        merged.merge(&render(5..6).state()).unwrap();
        assert_eq!(merged.state(), whole.state());
        assert_eq!(merged.xyz(0.7), whole.xyz(0.7));
        let other = Film::new(1, 1, UNIT);
        assert!(merged.merge(&other.state()).is_err());
    }

    #[test]
    fn variance_from_the_even_and_odd_halves() {
        // Pixel 0: samples Y = 1, 3, 1, 3 (odd ones 3 + 3): halves 1 and 3, variance of the
        // mean (3 − 1)² · 2 · 2 / 16 = 1. Pixel 1: all equal, variance 0.
        let mut f = Film::new(2, 1, UNIT);
        let own = [fixed([0.0, 8.0, 0.0]), fixed([0.0, 4.0, 0.0])];
        f.store_tile(&WHOLE, &own, &[6.0, 2.0], 4, 0);
        assert_eq!(f.variance_y(1.0), vec![1.0, 0.0]);
        assert_eq!(f.variance_y(2.0)[0], 4.0);
        // The same pixel values as splats of 4 light paths per pixel.
        let mut g = Film::new(2, 1, UNIT);
        g.store_tile(&WHOLE, &[[0; 3]; 2], &[0.0; 2], 4, 0);
        g.add_light_paths(8);
        let sp = |pixel, y| Splat {
            pixel,
            xyz: [0.0, y, 0.0],
        };
        g.add_splats(
            &[sp(0, 1.0), sp(0, 3.0), sp(0, 1.0), sp(0, 3.0)],
            &[(0, 3.0), (0, 3.0)],
        );
        assert_eq!(g.variance_y(1.0)[0], 1.0);
        assert!(Film::new(1, 1, UNIT).variance_y(1.0)[0].is_infinite());
    }
}
