//! The film: per-pixel XYZ sums in f64 (so millions of samples add up without loss), filled
//! by tiles, each pixel always in the same order (bit-identical images for any thread count).

/// Accumulated XYZ per pixel (Y in cd/m²), row-major, top row first.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    sum: Vec<[f64; 3]>,
    samples: Vec<u64>,
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

    /// Mean XYZ per pixel times `scale` (the camera exposure), as f32.
    pub fn xyz(&self, scale: f64) -> Vec<[f32; 3]> {
        self.sum
            .iter()
            .zip(&self.samples)
            .map(|(s, &n)| {
                let k = if n > 0 { scale / n as f64 } else { 0.0 };
                s.map(|c| (c * k) as f32)
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
}
