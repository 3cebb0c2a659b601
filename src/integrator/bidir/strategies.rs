//! The per-strategy decomposition of a BDPT image (`--strategies DIR`), as pbrt's
//! `visualizestrategies` / `visualizeweights`: for every (s, t) with s + t − 2 ≤ max depth, the
//! image of that technique's contributions with and without its MIS weight. The weighted
//! images sum to the BDPT image; each unweighted one is that technique's own (unbiased where
//! it can sample every path) estimate.
//!
//! Strategies are numbered by depth d = s + t − 2, then s: index = d(d + 3)/2 + s, for
//! s = 0 … d + 1 (t ≥ 1: no technique hits the lens).

use super::record::StrategyTile;
use crate::sensor::film::Tile;

/// Largest `max_depth` for which strategy images are written (the count grows quadratically).
pub const MAX_DEPTH: u32 = 15;

/// Strategies with s + t − 2 ≤ `max_depth`.
pub fn count(max_depth: u32) -> usize {
    let d = max_depth as usize;
    (d + 1) * (d + 4) / 2
}

/// The index of strategy (s, t), t ≥ 1.
#[inline]
pub fn index(s: u32, t: u32) -> usize {
    let d = (s + t - 2) as usize;
    d * (d + 3) / 2 + s as usize
}

/// (s, t) of a strategy index.
pub fn strategy(index: usize) -> (u32, u32) {
    let mut d = 0;
    while (d + 1) * (d + 4) / 2 <= index {
        d += 1;
    }
    let s = index - d * (d + 3) / 2;
    (s as u32, (d + 2 - s) as u32)
}

/// One strategy's images: mean XYZ per pixel, camera exposure applied.
#[derive(Clone, Debug)]
pub struct StrategyImage {
    pub s: u32,
    pub t: u32,
    pub weighted: Vec<[f32; 3]>,
    pub unweighted: Vec<[f32; 3]>,
}

/// Whole-image sums per strategy. Every pixel receives the same number of samples and of light
/// paths per pixel, so own-pixel sums and splats share one buffer and one divisor.
#[derive(Clone, Debug)]
pub struct StrategyFilms {
    width: usize,
    weighted: Vec<Vec<[f64; 3]>>,
    unweighted: Vec<Vec<[f64; 3]>>,
    samples_per_pixel: u64,
}

impl StrategyFilms {
    pub fn new(width: usize, height: usize, max_depth: u32) -> StrategyFilms {
        let n = count(max_depth);
        StrategyFilms {
            width,
            weighted: vec![vec![[0.0; 3]; width * height]; n],
            unweighted: vec![vec![[0.0; 3]; width * height]; n],
            samples_per_pixel: 0,
        }
    }

    /// Adds a tile's per-strategy sums and its strategy splats (tiles in tile order).
    pub fn merge_tile(&mut self, tile: &Tile, st: &StrategyTile) {
        let w = tile.x1 - tile.x0;
        for (i, (fw, fu)) in self
            .weighted
            .iter_mut()
            .zip(&mut self.unweighted)
            .enumerate()
        {
            for y in tile.y0..tile.y1 {
                for x in tile.x0..tile.x1 {
                    let k = i * st.pixels + (y - tile.y0) * w + (x - tile.x0);
                    let p = y * self.width + x;
                    add(&mut fw[p], st.weighted[k]);
                    add(&mut fu[p], st.unweighted[k]);
                }
            }
        }
        for s in &st.splats {
            let p = s.pixel as usize;
            add(
                &mut self.weighted[s.strategy as usize][p],
                s.weighted.map(f64::from),
            );
            add(
                &mut self.unweighted[s.strategy as usize][p],
                s.unweighted.map(f64::from),
            );
        }
    }

    /// Counts a pass of `n` samples per pixel (each with one light path).
    pub fn add_samples(&mut self, n: u64) {
        self.samples_per_pixel += n;
    }

    /// The images, scaled by `scale` (the camera exposure) over the samples per pixel.
    pub fn images(&self, scale: f64) -> Vec<StrategyImage> {
        let k = if self.samples_per_pixel > 0 {
            scale / self.samples_per_pixel as f64
        } else {
            0.0
        };
        let mean = |v: &Vec<[f64; 3]>| v.iter().map(|p| p.map(|c| (c * k) as f32)).collect();
        (0..self.weighted.len())
            .map(|i| {
                let (s, t) = strategy(i);
                StrategyImage {
                    s,
                    t,
                    weighted: mean(&self.weighted[i]),
                    unweighted: mean(&self.unweighted[i]),
                }
            })
            .collect()
    }
}

/// The raw sums of [`StrategyFilms`], to save them and continue later (checkpoints).
#[derive(Clone, Debug, PartialEq)]
pub struct StrategySums {
    pub weighted: Vec<Vec<[f64; 3]>>,
    pub unweighted: Vec<Vec<[f64; 3]>>,
    pub samples_per_pixel: u64,
}

impl StrategyFilms {
    pub fn sums(&self) -> StrategySums {
        StrategySums {
            weighted: self.weighted.clone(),
            unweighted: self.unweighted.clone(),
            samples_per_pixel: self.samples_per_pixel,
        }
    }

    /// Continues `sums` in place of these films' own, when their shapes agree.
    pub fn restore(&mut self, sums: StrategySums) -> Result<(), String> {
        let shape = |v: &Vec<Vec<[f64; 3]>>| v.iter().map(Vec::len).collect::<Vec<_>>();
        if shape(&sums.weighted) != shape(&self.weighted)
            || shape(&sums.unweighted) != shape(&self.unweighted)
        {
            return Err("the strategy images do not match this render's".into());
        }
        self.weighted = sums.weighted;
        self.unweighted = sums.unweighted;
        self.samples_per_pixel = sums.samples_per_pixel;
        Ok(())
    }
}

#[inline]
fn add(acc: &mut [f64; 3], v: [f64; 3]) {
    for (a, x) in acc.iter_mut().zip(v) {
        *a += x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_enumerate_every_strategy_once() {
        let max_depth = 6;
        let mut seen = vec![false; count(max_depth)];
        for d in 0..=max_depth {
            for s in 0..=d + 1 {
                let t = d + 2 - s;
                let i = index(s, t);
                assert!(!seen[i]);
                seen[i] = true;
                assert_eq!(strategy(i), (s, t));
            }
        }
        assert!(seen.iter().all(|&b| b));
    }
}
