//! The spectral film (`--spectral`): per pixel, the spectral radiance averaged over each of N
//! wavelength bins, estimated from the same hero-wavelength samples as the XYZ film.
//!
//! **Estimator.** A sample carries wavelengths λ₁…λ₄ with pdfs p(λᵢ) (`SampledWavelengths`);
//! each λᵢ is, on its own, distributed with density p (the rotations of Wilkie et al. 2014,
//! "Hero Wavelength Spectral Sampling", §3, keep each lane's marginal). Lane i adds
//! L(λᵢ) / (4 p(λᵢ) Δ) to the bin b holding λᵢ, Δ the bin width, so that the expected sum
//! over the lanes is (1/Δ) ∫_b L(λ) dλ: the bin average of L, unbiased (the indicator of the
//! bin is the function estimated; Veach 1997 §2.4.1). A sample whose secondaries were
//! terminated has p₁…₃ = 0 and p₀ / 4 (`terminate_secondary`), so its hero lane alone adds
//! L(λ₀) / (p(λ₀) Δ), the same estimate. Integrating the bins against the CIE curves then
//! gives the XYZ layer up to the binning error (the curves' variation within a bin).
//!
//! **Exact sums.** Each lane's term is rounded once to a fixed grid and summed as `i128`
//! (`grid_sum`), like the XYZ film, so the bins do not depend on the threads or the passes.
//! The grid is [`EXTRA_BITS`] finer than the film's: a spectral radiance of white
//! (1 cd/m² over ~107 nm of ȳ at 683 lm/W) is ~1.4e-5 W·m⁻²·sr⁻¹·nm⁻¹, 2^−16 of the film's
//! unit. The per-sample work is four additions into the tile's slice: no allocation.

use super::film::Tile;
use super::grid_sum::Grid;
use crate::error::Reason;
use crate::spectral::{SampledSpectrum, SampledWavelengths, LAMBDA_MAX, LAMBDA_MIN, N_LAMBDA};

/// Bins written by `--spectral` without `--spectral-bins`.
pub const DEFAULT_BINS: usize = 32;
/// The narrowest bin, nm (narrower bins resolve nothing the 1 nm spectral tables hold).
pub const MIN_BIN_WIDTH: f32 = 1.0;
/// How much finer the spectral grid is than the film's (see the module docs).
pub const EXTRA_BITS: i32 = 16;

/// N equal wavelength bins over [min, max] nm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralBins {
    pub min: f32,
    pub max: f32,
    pub count: usize,
}

impl Default for SpectralBins {
    fn default() -> Self {
        SpectralBins {
            min: LAMBDA_MIN,
            max: LAMBDA_MAX,
            count: DEFAULT_BINS,
        }
    }
}

impl SpectralBins {
    /// `count` bins over [min, max], checked: within the simulated range, at least
    /// [`MIN_BIN_WIDTH`] wide.
    pub fn new(min: f32, max: f32, count: usize) -> Reason<SpectralBins> {
        if !(min.is_finite() && max.is_finite() && LAMBDA_MIN <= min && min < max)
            || max > LAMBDA_MAX
        {
            return Err(format!(
                "the spectral range {min}–{max} nm must be increasing and within \
                 {LAMBDA_MIN}–{LAMBDA_MAX} nm"
            ));
        }
        let most = ((max - min) / MIN_BIN_WIDTH).floor() as usize;
        if count == 0 || count > most {
            return Err(format!(
                "{count} spectral bins over {min}–{max} nm: between 1 and {most} \
                 (bins at least {MIN_BIN_WIDTH} nm wide)"
            ));
        }
        Ok(SpectralBins { min, max, count })
    }

    /// The width of a bin, nm.
    pub fn width(&self) -> f32 {
        (self.max - self.min) / self.count as f32
    }

    /// The bin holding `lambda` (the last bin includes `max`), or None outside the range.
    #[inline]
    pub fn index(&self, lambda: f32) -> Option<usize> {
        if !(self.min..=self.max).contains(&lambda) {
            return None;
        }
        let i = ((lambda - self.min) / (self.max - self.min) * self.count as f32) as usize;
        Some(i.min(self.count - 1))
    }

    /// Bin `i`'s edges, nm.
    pub fn edges(&self, i: usize) -> (f64, f64) {
        let (a, b) = (f64::from(self.min), f64::from(self.max));
        let w = (b - a) / self.count as f64;
        (a + w * i as f64, a + w * (i + 1) as f64)
    }

    /// Bin `i`'s centre, nm.
    pub fn centre(&self, i: usize) -> f64 {
        let (a, b) = self.edges(i);
        0.5 * (a + b)
    }
}

/// Bins a sample's spectrum into a pixel's sums (the per-sample step; plain Copy data).
#[derive(Clone, Copy, Debug)]
pub struct Binner {
    pub bins: SpectralBins,
    pub grid: Grid,
}

impl Binner {
    /// Adds the sample's own-pixel radiance `l` at wavelengths `lambda` to `sums` (one entry
    /// per bin); returns the terms clamped or sums saturated.
    #[inline]
    pub fn add(&self, sums: &mut [i128], l: SampledSpectrum, lambda: &SampledWavelengths) -> u64 {
        let scale = 1.0 / (N_LAMBDA as f64 * f64::from(self.bins.width()));
        let mut clamped = 0;
        for i in 0..N_LAMBDA {
            if lambda.pdf[i] == 0.0 || l[i] == 0.0 {
                continue;
            }
            let Some(b) = self.bins.index(lambda.lambda[i]) else {
                continue;
            };
            let v = f64::from(l[i]) / f64::from(lambda.pdf[i]) * scale;
            let (t, c) = self.grid.term(v);
            let (s, over) = sums[b].overflowing_add(t);
            sums[b] = if over { sums[b].saturating_add(t) } else { s };
            clamped += u64::from(c) + u64::from(over);
        }
        clamped
    }
}

/// Per pixel, the bins' sums on the grid and the samples they hold.
#[derive(Clone, Debug)]
pub struct SpectralFilm {
    pub width: usize,
    pub height: usize,
    binner: Binner,
    /// `sums[pixel * bins + b]`.
    sums: Vec<i128>,
    samples: Vec<u64>,
    clamped: u64,
}

impl SpectralFilm {
    /// A film of `bins` beside a film on `film_grid`.
    pub fn new(width: usize, height: usize, bins: SpectralBins, film_grid: Grid) -> SpectralFilm {
        SpectralFilm {
            width,
            height,
            binner: Binner {
                bins,
                grid: Grid {
                    exponent: film_grid.exponent + EXTRA_BITS,
                },
            },
            sums: vec![0; width * height * bins.count],
            samples: vec![0; width * height],
            clamped: 0,
        }
    }

    pub fn binner(&self) -> Binner {
        self.binner
    }

    pub fn bins(&self) -> SpectralBins {
        self.binner.bins
    }

    /// Terms clamped and sums saturated so far.
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// Adds a tile's sums (`tile.pixel_count() × bins`, row-major over the tile), counting
    /// `samples` more samples per pixel.
    pub fn store_tile(&mut self, tile: &Tile, sums: &[i128], samples: u64, clamped: u64) {
        let n = self.binner.bins.count;
        for (k, i) in tile.pixels(self.width).enumerate() {
            for b in 0..n {
                let acc = &mut self.sums[i * n + b];
                let (s, over) = acc.overflowing_add(sums[k * n + b]);
                *acc = if over {
                    acc.saturating_add(sums[k * n + b])
                } else {
                    s
                };
                self.clamped += u64::from(over);
            }
            self.samples[i] += samples;
        }
        self.clamped += clamped;
    }

    /// The bin-averaged spectral radiance (W·m⁻²·sr⁻¹·nm⁻¹) times `scale` (the camera
    /// exposure), one image per bin, row-major.
    pub fn images(&self, scale: f64) -> Vec<Vec<f32>> {
        let n = self.binner.bins.count;
        let g = self.binner.grid;
        (0..n)
            .map(|b| {
                (0..self.samples.len())
                    .map(|i| match self.samples[i] {
                        0 => 0.0,
                        s => (g.value(self.sums[i * n + b]) * scale / s as f64) as f32,
                    })
                    .collect()
            })
            .collect()
    }
}

/// A rendered spectral image: the bins and, per bin, its image.
#[derive(Clone, Debug)]
pub struct SpectralImage {
    pub bins: SpectralBins,
    pub images: Vec<Vec<f32>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_are_checked_and_cover_the_range() {
        let b = SpectralBins::default();
        assert_eq!(b.index(360.0), Some(0));
        assert_eq!(b.index(830.0), Some(31));
        assert_eq!(b.index(359.9), None);
        assert!((b.centre(0) - (360.0 + 470.0 / 64.0)).abs() < 1e-9);
        assert!(SpectralBins::new(400.0, 700.0, 300).is_ok());
        assert!(SpectralBins::new(400.0, 700.0, 301).is_err());
        assert!(SpectralBins::new(700.0, 400.0, 3).is_err());
        assert!(SpectralBins::new(350.0, 700.0, 3).is_err());
        assert!(SpectralBins::new(400.0, 700.0, 0).is_err());
    }

    #[test]
    fn a_constant_spectrum_bins_to_itself() {
        // L = 1 everywhere: every bin's mean tends to 1 (stratified hero samples).
        let bins = SpectralBins::new(400.0, 700.0, 10).unwrap();
        let mut film = SpectralFilm::new(1, 1, bins, Grid::for_scale(1.0));
        let binner = film.binner();
        let n = 40_000;
        let mut sums = vec![0i128; 10];
        for k in 0..n {
            let w = SampledWavelengths::sample_uniform((k as f32 + 0.5) / n as f32);
            binner.add(&mut sums, SampledSpectrum::ONE, &w);
        }
        let tile = Tile {
            x0: 0,
            y0: 0,
            x1: 1,
            y1: 1,
        };
        film.store_tile(&tile, &sums, n, 0);
        // Uniform over 360–830 nm: each 30 nm bin of 400–700 is hit by 30/470 of the lanes.
        for img in film.images(1.0) {
            assert!((img[0] - 1.0).abs() < 1e-3, "{}", img[0]);
        }
    }
}
