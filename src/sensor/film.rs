//! The film: per-pixel XYZ sums in f64 (so millions of samples add up without loss), filled
//! by tiles, each pixel always in the same order (bit-identical images for any thread count).
//!
//! Light tracing and BDPT also *splat*: a light path adds to whatever pixel it reaches. Splats
//! are collected per tile as a list and merged in tile order ([`Film::add_splats`]), so their
//! sum is as deterministic as the tiles'. A splat is a contribution per light path with the
//! camera importance normalised over the whole image (see `sensor::camera`); a pixel's value
//! is its sample mean plus its splat sum divided by the light paths traced per pixel
//! (pbrt-v4's `RGBFilm::GetPixelRGB`, splatScale = 1/spp).

/// Accumulated XYZ per pixel (Y in cd/m²), row-major, top row first.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    sum: Vec<[f64; 3]>,
    samples: Vec<u64>,
    splat: Vec<[f64; 3]>,
    /// Light paths traced over the whole image (each may splat anywhere).
    light_paths: u64,
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
}

impl Film {
    pub fn new(width: usize, height: usize) -> Film {
        Film {
            width,
            height,
            sum: vec![[0.0; 3]; width * height],
            samples: vec![0; width * height],
            splat: Vec::new(),
            light_paths: 0,
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

    /// Adds a tile's sums (row-major over the tile) and sample counts.
    pub fn merge_tile(&mut self, tile: &Tile, sums: &[[f64; 3]], samples_per_pixel: u64) {
        let w = tile.x1 - tile.x0;
        for y in tile.y0..tile.y1 {
            for x in tile.x0..tile.x1 {
                let i = y * self.width + x;
                let s = sums[(y - tile.y0) * w + (x - tile.x0)];
                for (acc, v) in self.sum[i].iter_mut().zip(s) {
                    *acc += v;
                }
                self.samples[i] += samples_per_pixel;
            }
        }
    }

    /// Adds splats in the order given (callers pass tiles in tile order).
    pub fn add_splats(&mut self, splats: &[Splat]) {
        if splats.is_empty() {
            return;
        }
        if self.splat.is_empty() {
            self.splat = vec![[0.0; 3]; self.width * self.height];
        }
        for s in splats {
            for (acc, v) in self.splat[s.pixel as usize].iter_mut().zip(s.xyz) {
                *acc += v as f64;
            }
        }
    }

    /// Counts light paths traced (whether or not they splatted).
    pub fn add_light_paths(&mut self, n: u64) {
        self.light_paths += n;
    }

    /// Mean XYZ per pixel times `scale` (the camera exposure), as f32: the sample mean plus
    /// the splat sum over light paths per pixel.
    pub fn xyz(&self, scale: f64) -> Vec<[f32; 3]> {
        let pixels = (self.width * self.height) as f64;
        let splat_k = if self.light_paths > 0 {
            scale * pixels / self.light_paths as f64
        } else {
            0.0
        };
        self.sum
            .iter()
            .zip(&self.samples)
            .enumerate()
            .map(|(i, (s, &n))| {
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

    /// Samples taken in the pixel with the fewest.
    pub fn min_samples(&self) -> u64 {
        self.samples.iter().copied().min().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        let f = Film::new(37, 20);
        let tiles = f.tiles(16);
        assert_eq!(tiles.iter().map(Tile::pixel_count).sum::<usize>(), 37 * 20);
    }

    #[test]
    fn merging_averages() {
        let mut f = Film::new(2, 1);
        let t = Tile {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 1,
        };
        f.merge_tile(&t, &[[2.0, 4.0, 6.0], [0.0; 3]], 2);
        f.merge_tile(&t, &[[2.0, 0.0, 0.0], [0.0; 3]], 2);
        assert_eq!(f.xyz(1.0)[0], [1.0, 1.0, 1.5]);
        assert_eq!(f.min_samples(), 4);
    }

    #[test]
    fn splats_are_divided_by_light_paths_per_pixel() {
        let mut f = Film::new(2, 1);
        let t = Tile {
            x0: 0,
            y0: 0,
            x1: 2,
            y1: 1,
        };
        f.merge_tile(&t, &[[1.0; 3], [0.0; 3]], 4);
        f.add_light_paths(8);
        let sp = |pixel, v| Splat { pixel, xyz: [v; 3] };
        f.add_splats(&[sp(1, 2.0), sp(1, 6.0), sp(0, 4.0)]);
        // 8 light paths over 2 pixels: 4 per pixel.
        assert_eq!(f.xyz(1.0), vec![[1.25; 3], [2.0; 3]]);
    }
}
