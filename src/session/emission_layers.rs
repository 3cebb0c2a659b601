//! The films of the emission-weighted layers (`--illuminants`, `--light-groups`:
//! `light::emission_layers`). Each layer has a film of its own, filled exactly as the
//! image's: each sample's XYZ rounded once to the film's grid and summed as integers, a
//! non-finite sample dropped (from that layer), the odd samples' Y apart. A layer is then,
//! bit for bit, the image a render of the scene with that layer's emission gives from the
//! same seed (same light selection). With `--spectral`, each layer also has spectral bins.

use crate::integrator::bidir::record::SampleRecord;
use crate::sensor::film::{Film, Tile};
use crate::sensor::grid_sum::{Fixed3, Grid};
use crate::sensor::spectral_film::{Binner, SpectralBins, SpectralFilm, SpectralImage};
use crate::spectral::xyz::sampled_to_xyz;
use crate::spectral::SampledWavelengths;

/// One layer's film and, with `--spectral`, its bins.
#[derive(Clone, Debug)]
pub struct EmissionFilm {
    pub name: String,
    film: Film,
    spectral: Option<SpectralFilm>,
}

/// A layer's image: XYZ (Y in cd/m²) and linear Rec.709 RGB, × the camera exposure.
#[derive(Clone, Debug)]
pub struct EmissionImage {
    pub name: String,
    pub xyz: Vec<[f32; 3]>,
    pub rgb: Vec<[f32; 3]>,
    pub spectral: Option<SpectralImage>,
    /// Samples dropped from this layer as non-finite.
    pub dropped: u64,
}

/// What one tile collects for the layers over a segment, `[layer * pixels + k]`.
#[derive(Clone, Debug, Default)]
pub struct EmissionTile {
    pixels: usize,
    grid: Option<Grid>,
    fixed: Vec<Fixed3>,
    odd_y: Vec<f64>,
    clamped: u64,
    dropped: u64,
    binner: Option<Binner>,
    bins: usize,
    /// `spectral[(layer * pixels + k) * bins + b]`.
    spectral: Vec<i128>,
}

/// The films of all layers, their dropped samples.
#[derive(Clone, Debug, Default)]
pub struct EmissionFilms {
    pub films: Vec<EmissionFilm>,
    dropped: u64,
    /// Terms the tiles clamped.
    clamped: u64,
}

impl EmissionFilms {
    pub fn new(
        names: &[String],
        (width, height): (usize, usize),
        grid: Grid,
        bins: Option<SpectralBins>,
    ) -> EmissionFilms {
        let films = names
            .iter()
            .map(|name| EmissionFilm {
                name: name.clone(),
                film: Film::new(width, height, grid),
                spectral: bins.map(|b| SpectralFilm::new(width, height, b, grid)),
            })
            .collect();
        EmissionFilms {
            films,
            dropped: 0,
            clamped: 0,
        }
    }

    /// Empty sums for `tile` (nothing allocated without layers).
    pub fn tile(&self, tile: &Tile) -> EmissionTile {
        let Some(first) = self.films.first() else {
            return EmissionTile::default();
        };
        let (n, pixels) = (self.films.len(), tile.pixel_count());
        let binner = first.spectral.as_ref().map(SpectralFilm::binner);
        let bins = first.spectral.as_ref().map_or(0, |s| s.bins().count);
        EmissionTile {
            pixels,
            grid: Some(first.film.grid()),
            fixed: vec![[0; 3]; n * pixels],
            odd_y: vec![0.0; n * pixels],
            clamped: 0,
            dropped: 0,
            binner,
            bins,
            spectral: vec![0; n * pixels * bins],
        }
    }

    /// Adds a tile's sums of `samples` samples per pixel.
    pub fn store_tile(&mut self, tile: &Tile, t: &EmissionTile, samples: u64) {
        let p = t.pixels;
        for (j, f) in self.films.iter_mut().enumerate() {
            let range = j * p..(j + 1) * p;
            f.film
                .store_tile(tile, &t.fixed[range.clone()], &t.odd_y[range], samples, 0);
            if let Some(s) = &mut f.spectral {
                s.store_tile(
                    tile,
                    &t.spectral[j * p * t.bins..(j + 1) * p * t.bins],
                    samples,
                    0,
                );
            }
        }
        self.clamped += t.clamped;
        self.dropped += t.dropped;
    }

    /// Terms clamped and sums saturated.
    pub fn clamped(&self) -> u64 {
        self.clamped
            + self
                .films
                .iter()
                .map(|f| f.film.clamped() + f.spectral.as_ref().map_or(0, SpectralFilm::clamped))
                .sum::<u64>()
    }

    /// The layers' images × `scale` (the camera exposure).
    pub fn images(&self, scale: f64, xyz_to_rgb: fn([f32; 3]) -> [f32; 3]) -> Vec<EmissionImage> {
        self.films
            .iter()
            .map(|f| {
                let xyz = f.film.xyz(scale);
                EmissionImage {
                    name: f.name.clone(),
                    rgb: xyz.iter().map(|p| xyz_to_rgb(*p)).collect(),
                    xyz,
                    spectral: f.spectral.as_ref().map(|s| SpectralImage {
                        bins: s.bins(),
                        images: s.images(scale),
                    }),
                    dropped: self.dropped,
                }
            })
            .collect()
    }
}

impl EmissionTile {
    /// Adds sample `s` of tile pixel `k` (its wavelengths final): each layer's XYZ rounded
    /// to the grid as the image's own value is (`session::image`), a non-finite one dropped.
    /// True when the run has emission-weighted layers to sum.
    #[inline]
    pub fn is_on(&self) -> bool {
        self.grid.is_some()
    }

    #[inline]
    pub fn add(&mut self, k: usize, rec: &SampleRecord, lambda: &SampledWavelengths, s: u64) {
        let Some(grid) = self.grid else {
            return;
        };
        for (j, l) in rec.layers.iter().enumerate() {
            let xyz = sampled_to_xyz(*l, lambda);
            if !xyz.iter().all(|c| c.is_finite()) {
                self.dropped += 1;
                continue;
            }
            let i = j * self.pixels + k;
            let (t, c) = grid.triple(xyz.map(f64::from));
            self.clamped += c + u64::from(Grid::add3(&mut self.fixed[i], &t));
            if s % 2 == 1 {
                self.odd_y[i] += f64::from(xyz[1]);
            }
            if let Some(b) = &self.binner {
                let sums = &mut self.spectral[i * self.bins..(i + 1) * self.bins];
                self.clamped += b.add(sums, *l, lambda);
            }
        }
    }
}
