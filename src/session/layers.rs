//! The image's extra layers beside RGB and XYZ (`--spectral`, `--aov`): what a render is asked
//! for ([`LayerOptions`]), what a tile collects per sample ([`LayerTile`], allocated once per
//! tile and segment, never per sample) and the films that hold the sums ([`LayerFilms`]).
//! Every sum is on a fixed grid (`sensor::grid_sum`), so the layers, like the image, depend on
//! the seed and the sample count only.

use crate::error::{Error, Result};
use crate::integrator::bidir::record::SampleRecord;
use crate::integrator::Integrator;
use crate::sensor::film::Tile;
use crate::sensor::grid_sum::Grid;
use crate::sensor::spectral_film::{Binner, SpectralBins, SpectralFilm, SpectralImage};
use crate::spectral::SampledWavelengths;

/// The extra layers a render writes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerOptions {
    /// Spectral radiance in these bins (`sensor::spectral_film`).
    pub spectral: Option<SpectralBins>,
    /// The per-pixel variance of the mean luminance (`--aov variance`, from the film's even
    /// and odd halves, `sensor::film`).
    pub variance: bool,
}

impl LayerOptions {
    /// Whether any layer needs per-sample work.
    pub fn any(&self) -> bool {
        self.spectral.is_some()
    }

    /// Refuses layers the integrator cannot fill: the spectral film bins the sample's own
    /// pixel, so integrators that splat (light paths reaching any pixel) are refused.
    pub fn check(&self, integrator: &Integrator) -> Result<()> {
        if self.spectral.is_some() && integrator.capabilities().splats {
            return Err(Error::option(format!(
                "--spectral bins each sample's own pixel: integrator {} splats light paths \
                 over the image, which are not binned (use --integrator path)",
                integrator.name()
            )));
        }
        Ok(())
    }
}

/// What one tile collects for the layers over a segment.
#[derive(Clone, Debug, Default)]
pub struct LayerTile {
    binner: Option<Binner>,
    bins: usize,
    /// `spectral[k * bins + b]`, k the tile pixel.
    spectral: Vec<i128>,
    clamped: u64,
}

impl LayerTile {
    /// Empty sums for `tile` (nothing allocated when no layer is asked for).
    pub fn new(films: &LayerFilms, tile: &Tile) -> LayerTile {
        match &films.spectral {
            Some(f) => LayerTile {
                binner: Some(f.binner()),
                bins: f.bins().count,
                spectral: vec![0; tile.pixel_count() * f.bins().count],
                clamped: 0,
            },
            None => LayerTile::default(),
        }
    }

    /// Adds a finished sample of tile pixel `k` (its wavelengths final); `dropped`: the sample
    /// was non-finite and dropped from the image, so from the layers too.
    #[inline]
    pub fn add(
        &mut self,
        k: usize,
        rec: &SampleRecord,
        lambda: &SampledWavelengths,
        dropped: bool,
    ) {
        if dropped {
            return;
        }
        if let Some(binner) = &self.binner {
            let sums = &mut self.spectral[k * self.bins..(k + 1) * self.bins];
            self.clamped += binner.add(sums, rec.own(lambda), lambda);
        }
    }
}

/// The films of the layers asked for.
#[derive(Clone, Debug, Default)]
pub struct LayerFilms {
    pub spectral: Option<SpectralFilm>,
}

/// The layers of a rendered image.
#[derive(Clone, Debug, Default)]
pub struct LayerImages {
    pub spectral: Option<SpectralImage>,
    /// Per pixel, the estimated variance of the mean luminance in (cd/m²)² (× exposure²);
    /// −1 where a pixel has fewer than 2 samples (no estimate).
    pub variance: Option<Vec<f32>>,
}

impl LayerFilms {
    pub fn new(width: usize, height: usize, opts: &LayerOptions, grid: Grid) -> LayerFilms {
        LayerFilms {
            spectral: opts
                .spectral
                .map(|bins| SpectralFilm::new(width, height, bins, grid)),
        }
    }

    /// Adds a tile's sums of `samples` samples per pixel.
    pub fn store_tile(&mut self, tile: &Tile, t: &LayerTile, samples: u64) {
        if let Some(f) = &mut self.spectral {
            f.store_tile(tile, &t.spectral, samples, t.clamped);
        }
    }

    /// Terms clamped and sums saturated.
    pub fn clamped(&self) -> u64 {
        self.spectral.as_ref().map_or(0, SpectralFilm::clamped)
    }

    /// The layers times `scale` (the camera exposure).
    pub fn images(&self, scale: f64) -> LayerImages {
        LayerImages {
            spectral: self.spectral.as_ref().map(|f| SpectralImage {
                bins: f.bins(),
                images: f.images(scale),
            }),
            variance: None,
        }
    }
}
