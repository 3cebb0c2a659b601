//! The film: per-pixel XYZ sums in f64 (so millions of samples add up without loss), filled
//! by tiles, each pixel always in the same order (bit-identical images for any thread count).
//!
//! Samples are summed in *chunks* (`session::image`): a chunk's per-pixel sums start from
//! zero and are added to the film when the chunk closes. A render pass may end inside a chunk;
//! the chunk's partial sums are then kept open and the next pass continues them, so an image
//! depends only on the samples and the chunk size, not on how the samples were split into
//! passes.
//!
//! Light tracing and BDPT also *splat*: a light path adds to whatever pixel it reaches. Splats
//! are collected per tile as a list and merged in tile order ([`Film::add_splats`]), so their
//! sum is as deterministic as the tiles'. A splat is a contribution per light path with the
//! camera importance normalised over the whole image (see `sensor::camera`); a pixel's value
//! is its sample mean plus its splat sum divided by the light paths traced per pixel
//! (pbrt-v4's `RGBFilm::GetPixelRGB`, splatScale = 1/spp).
//!
//! **Variance.** The film also keeps the luminance Y of the odd-numbered samples apart (their
//! own-pixel values and their splats). The even and odd halves are two independent estimates
//! a, b of the pixel, so (a − b)² n_even n_odd / n² is an unbiased estimate of the variance
//! of the pixel's mean over all n samples, whatever the integrator ([`Film::variance_y`]).

use super::film_state::FilmState;
use crate::error::Reason;

/// Accumulated XYZ per pixel (Y in cd/m²), row-major, top row first.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    /// Sums of the closed chunks.
    closed: Vec<[f64; 3]>,
    /// Sums of the open chunk.
    open: Vec<[f64; 3]>,
    samples: Vec<u64>,
    splat: Vec<[f64; 3]>,
    /// Light paths traced over the whole image (each may splat anywhere).
    light_paths: u64,
    /// Y of the odd-numbered samples: own-pixel values and splats.
    odd_y: Vec<f64>,
    odd_splat_y: Vec<f64>,
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
    #[cfg(test)]
    pub fn pixel_count(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// Film indices of the tile's pixels, row by row.
    fn pixels(&self, width: usize) -> impl Iterator<Item = usize> + '_ {
        (self.y0..self.y1).flat_map(move |y| (self.x0..self.x1).map(move |x| y * width + x))
    }
}

impl Film {
    pub fn new(width: usize, height: usize) -> Film {
        let n = width * height;
        Film {
            width,
            height,
            closed: vec![[0.0; 3]; n],
            open: vec![[0.0; 3]; n],
            samples: vec![0; n],
            splat: Vec::new(),
            light_paths: 0,
            odd_y: vec![0.0; n],
            odd_splat_y: Vec::new(),
        }
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

    /// The open chunk's sums of a tile (row-major over the tile), to continue them.
    pub fn open_sums(&self, tile: &Tile) -> Vec<[f64; 3]> {
        tile.pixels(self.width).map(|i| self.open[i]).collect()
    }

    /// Replaces a tile's open-chunk sums by `sums` (which continued [`Film::open_sums`]),
    /// counting `samples_per_pixel` more samples, and adds the odd samples' Y sums.
    pub fn store_tile(&mut self, tile: &Tile, sums: &[[f64; 3]], odd_y: &[f64], samples: u64) {
        for (k, i) in tile.pixels(self.width).enumerate() {
            self.open[i] = sums[k];
            self.odd_y[i] += odd_y[k];
            self.samples[i] += samples;
        }
    }

    /// Closes the open chunk: its sums are added to the film's and it starts again at zero.
    pub fn close_chunk(&mut self) {
        for (c, o) in self.closed.iter_mut().zip(&mut self.open) {
            for (a, v) in c.iter_mut().zip(o.iter_mut()) {
                *a += *v;
                *v = 0.0;
            }
        }
    }

    /// Adds splats in the order given (callers pass tiles in tile order); `odd` holds the
    /// (pixel, Y) of the odd-numbered samples' splats among them.
    pub fn add_splats(&mut self, splats: &[Splat], odd: &[(u32, f32)]) {
        if splats.is_empty() {
            return;
        }
        if self.splat.is_empty() {
            self.splat = vec![[0.0; 3]; self.width * self.height];
            self.odd_splat_y = vec![0.0; self.width * self.height];
        }
        for s in splats {
            for (acc, v) in self.splat[s.pixel as usize].iter_mut().zip(s.xyz) {
                *acc += v as f64;
            }
        }
        for &(pixel, y) in odd {
            self.odd_splat_y[pixel as usize] += y as f64;
        }
    }

    /// Counts light paths traced (whether or not they splatted).
    pub fn add_light_paths(&mut self, n: u64) {
        self.light_paths += n;
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
        (0..self.closed.len())
            .map(|i| {
                let s: [f64; 3] = std::array::from_fn(|c| self.closed[i][c] + self.open[i][c]);
                let n = self.samples[i];
                let k = if n > 0 { scale / n as f64 } else { 0.0 };
                match self.splat.get(i) {
                    Some(sp) if splat_k > 0.0 => {
                        std::array::from_fn(|c| (s[c] * k + sp[c] * splat_k) as f32)
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
        (0..self.closed.len())
            .map(|i| {
                let n = self.samples[i];
                let (n_odd, n_even) = ((n / 2) as f64, (n - n / 2) as f64);
                if n < 2 {
                    return f64::INFINITY;
                }
                let own = self.closed[i][1] + self.open[i][1];
                let (mut odd, mut even) = (self.odd_y[i], own - self.odd_y[i]);
                if let Some(sp) = self.splat.get(i) {
                    // Light paths per pixel = samples per pixel, split alike.
                    let lp = self.light_paths as f64 / pixels;
                    let k = n as f64 / lp;
                    odd += self.odd_splat_y[i] * k;
                    even += (sp[1] - self.odd_splat_y[i]) * k;
                }
                let d = even / n_even - odd / n_odd;
                scale * scale * d * d * n_even * n_odd / (n as f64 * n as f64)
            })
            .collect()
    }

    /// The film's raw state (`film_state`), to save it and continue it later.
    pub fn state(&self) -> FilmState {
        FilmState {
            width: self.width,
            height: self.height,
            closed: self.closed.clone(),
            open: self.open.clone(),
            samples: self.samples.clone(),
            odd_y: self.odd_y.clone(),
            splat: self.splat.clone(),
            odd_splat_y: self.odd_splat_y.clone(),
            light_paths: self.light_paths,
        }
    }

    /// A film that continues `state` (checked: one entry per pixel in every sequence).
    pub fn from_state(state: FilmState) -> Reason<Film> {
        state.check()?;
        Ok(Film {
            width: state.width,
            height: state.height,
            closed: state.closed,
            open: state.open,
            samples: state.samples,
            splat: state.splat,
            light_paths: state.light_paths,
            odd_y: state.odd_y,
            odd_splat_y: state.odd_splat_y,
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

    #[test]
    fn tiles_cover_the_image_once() {
        let f = Film::new(37, 20);
        let tiles = f.tiles(16);
        assert_eq!(tiles.iter().map(Tile::pixel_count).sum::<usize>(), 37 * 20);
    }

    #[test]
    fn chunks_average() {
        let mut f = Film::new(2, 1);
        f.store_tile(&WHOLE, &[[2.0, 4.0, 6.0], [0.0; 3]], &[0.0; 2], 2);
        f.close_chunk();
        assert_eq!(f.open_sums(&WHOLE), vec![[0.0; 3]; 2]);
        f.store_tile(&WHOLE, &[[2.0, 0.0, 0.0], [0.0; 3]], &[0.0; 2], 2);
        assert_eq!(f.xyz(1.0)[0], [1.0, 1.0, 1.5]);
        assert_eq!(f.min_samples(), 4);
    }

    #[test]
    fn splats_are_divided_by_light_paths_per_pixel() {
        let mut f = Film::new(2, 1);
        f.store_tile(&WHOLE, &[[1.0; 3], [0.0; 3]], &[0.0; 2], 4);
        f.add_light_paths(8);
        let sp = |pixel, v| Splat { pixel, xyz: [v; 3] };
        f.add_splats(&[sp(1, 2.0), sp(1, 6.0), sp(0, 4.0)], &[]);
        // 8 light paths over 2 pixels: 4 per pixel.
        assert_eq!(f.xyz(1.0), vec![[1.25; 3], [2.0; 3]]);
    }

    #[test]
    fn variance_from_the_even_and_odd_halves() {
        // Pixel 0: samples Y = 1, 3, 1, 3 (odd ones 3 + 3): halves 1 and 3, variance of the
        // mean (3 − 1)² · 2 · 2 / 16 = 1. Pixel 1: all equal, variance 0.
        let mut f = Film::new(2, 1);
        f.store_tile(&WHOLE, &[[0.0, 8.0, 0.0], [0.0, 4.0, 0.0]], &[6.0, 2.0], 4);
        assert_eq!(f.variance_y(1.0), vec![1.0, 0.0]);
        assert_eq!(f.variance_y(2.0)[0], 4.0);
        // The same pixel values as splats of 4 light paths per pixel.
        let mut g = Film::new(2, 1);
        g.store_tile(&WHOLE, &[[0.0; 3]; 2], &[0.0; 2], 4);
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
        assert!(Film::new(1, 1).variance_y(1.0)[0].is_infinite());
    }
}
