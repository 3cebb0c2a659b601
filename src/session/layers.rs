//! The image's extra layers beside RGB and XYZ (`--spectral`, `--aov`): what a render is asked
//! for ([`LayerOptions`]), what a tile collects per sample ([`LayerTile`], allocated once per
//! tile and segment, never per sample) and the films that hold the sums ([`LayerFilms`]).
//! The first-hit layers (position, normal, depth, albedo) follow pbrt-v4's GBufferFilm: each
//! sample's camera ray is traced again to the first surface it meets.
//! Every sum is on a fixed grid (`sensor::grid_sum`), so the layers, like the image, depend on
//! the seed and the sample count only.

use super::emission_layers::{EmissionFilms, EmissionImage, EmissionTile};
use crate::error::{Error, Result};
use crate::integrator::bidir::record::SampleRecord;
use crate::integrator::Integrator;
use crate::scene::{Hit, Scene, SurfaceHit};
use crate::sensor::film::Tile;
use crate::sensor::grid_sum::Grid;
use crate::sensor::spectral_film::{Binner, SpectralBins, SpectralFilm, SpectralImage};
use crate::spectral::{xyz, SampledWavelengths};
use crate::texture::TextureFilter;
use glam::{Mat4, Vec3};

/// Grid of the first-hit sums (`sensor::grid_sum`): 2^−40 m ≈ 1e−12 m for positions, and
/// normals and albedos to 1e−12; a term is clamped at 2^100 units, sums of 2^27 samples of
/// 2^60 m fit.
const FIRST_HIT_GRID: Grid = Grid { exponent: 40 };

/// The extra layers a render writes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerOptions {
    /// Spectral radiance in these bins (`sensor::spectral_film`).
    pub spectral: Option<SpectralBins>,
    /// The per-pixel variance of the mean luminance (`--aov variance`, from the film's even
    /// and odd halves, `sensor::film`).
    pub variance: bool,
    /// The first hit's position, normal and depth (`--aov position,normal,depth`).
    pub first_hit: bool,
    /// The first hit's directional-hemispherical reflectance (`--aov albedo`).
    pub albedo: bool,
}

impl LayerOptions {
    /// Whether any layer needs per-sample work.
    pub fn any(&self) -> bool {
        self.spectral.is_some() || self.first_hit || self.albedo
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
    /// What the first hits record, when they are traced.
    first_hit_setup: Option<FirstHitSetup>,
    /// Per tile pixel: the first hits' sums.
    first_hit: Vec<FirstHitSums>,
    /// The emission-weighted layers' sums (`session::emission_layers`).
    emission: EmissionTile,
}

/// A pixel's first-hit sums on [`FIRST_HIT_GRID`]: P.x, P.y, P.z, N.x, N.y, N.z over the
/// samples that hit something (`hits`), and the albedo's XYZ over all `samples`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FirstHitSums {
    pub sums: [i128; 6],
    pub hits: u64,
    pub albedo: [i128; 3],
    pub samples: u64,
}

/// What the first-hit layers need per sample: OpenEXR's world-to-camera matrix (as pbrt-v4's
/// GBufferFilm writes) and, for the albedo, the render's texture filter (`None`: no albedo).
#[derive(Clone, Copy, Debug)]
pub struct FirstHitSetup {
    pub to_camera: Mat4,
    pub albedo: Option<TextureFilter>,
}

impl LayerTile {
    /// Empty sums for `tile` (nothing allocated when no layer is asked for).
    pub fn new(films: &LayerFilms, tile: &Tile) -> LayerTile {
        let mut t = LayerTile {
            emission: films.emission.tile(tile),
            ..LayerTile::default()
        };
        if let Some(f) = &films.spectral {
            t.binner = Some(f.binner());
            t.bins = f.bins().count;
            t.spectral = vec![0; tile.pixel_count() * f.bins().count];
        }
        if let Some(fh) = &films.first_hit {
            t.first_hit_setup = Some(fh.setup);
            t.first_hit = vec![FirstHitSums::default(); tile.pixel_count()];
        }
        t
    }

    /// Traces the sample's camera ray (`film`, `u_lens` as the estimator had them) to its first
    /// hit and adds its camera-space position and geometric normal and, when asked, its
    /// albedo with the sample's final wavelengths `lambda` (pbrt-v4's GBufferFilm conventions:
    /// the surface the camera ray meets first, camera space; an escaped ray adds nothing, an
    /// albedo of 0).
    /// The test at the caller, the tracing out of line: most renders trace no first hits.
    #[inline(always)]
    pub fn add_first_hit(
        &mut self,
        k: usize,
        scene: &Scene,
        camera_sample: ([f32; 2], [f32; 2]),
        lambda: &SampledWavelengths,
    ) {
        if let Some(setup) = self.first_hit_setup {
            self.trace_first_hit(k, scene, setup, camera_sample, lambda);
        }
    }

    #[inline(never)]
    fn trace_first_hit(
        &mut self,
        k: usize,
        scene: &Scene,
        setup: FirstHitSetup,
        (film, u_lens): ([f32; 2], [f32; 2]),
        lambda: &SampledWavelengths,
    ) {
        self.first_hit[k].samples += 1;
        let (ray, t_max) = scene.camera.generate_ray(film, u_lens);
        let (p, n) = match scene.intersect(&ray, t_max) {
            Some(Hit::Surface(si)) => {
                if let Some(filter) = setup.albedo {
                    let a = first_hit_albedo(scene, &si, -ray.d, filter, lambda);
                    self.add_albedo(k, a);
                }
                (si.p, si.ng)
            }
            // An analytic light's shape only emits: it reflects nothing.
            Some(Hit::Light { hit, .. }) => (hit.p, hit.n),
            None => return,
        };
        let m = setup.to_camera;
        let (pc, nc) = (
            m.transform_point3(p),
            m.transform_vector3(n).normalize_or_zero(),
        );
        let px = &mut self.first_hit[k];
        for (c, v) in [pc.x, pc.y, pc.z, nc.x, nc.y, nc.z].into_iter().enumerate() {
            let (t, clamped) = FIRST_HIT_GRID.term(f64::from(v));
            px.sums[c] = px.sums[c].saturating_add(t);
            self.clamped += u64::from(clamped);
        }
        px.hits += 1;
    }

    /// Adds an albedo's XYZ to tile pixel `k`.
    #[inline]
    fn add_albedo(&mut self, k: usize, a: [f32; 3]) {
        let px = &mut self.first_hit[k];
        for (c, v) in a.into_iter().enumerate() {
            let (t, clamped) = FIRST_HIT_GRID.term(f64::from(v));
            px.albedo[c] = px.albedo[c].saturating_add(t);
            self.clamped += u64::from(clamped);
        }
    }

    /// Adds the finished sample `s` of tile pixel `k` (its wavelengths final); `dropped`: the
    /// sample was non-finite and dropped from the image, so from the spectral layer too (an
    /// emission layer drops its own non-finite samples, as its own render would).
    /// The test at the caller, the sums out of line: most renders have no layers.
    #[inline(always)]
    pub fn add(
        &mut self,
        k: usize,
        rec: &SampleRecord,
        lambda: &SampledWavelengths,
        sample: (u64, bool),
    ) {
        if self.binner.is_some() || self.emission.is_on() {
            self.add_sums(k, rec, lambda, sample);
        }
    }

    #[inline(never)]
    fn add_sums(
        &mut self,
        k: usize,
        rec: &SampleRecord,
        lambda: &SampledWavelengths,
        (s, dropped): (u64, bool),
    ) {
        self.emission.add(k, rec, lambda, s);
        if dropped {
            return;
        }
        if let Some(binner) = &self.binner {
            let sums = &mut self.spectral[k * self.bins..(k + 1) * self.bins];
            self.clamped += binner.add(sums, rec.own(lambda), lambda);
        }
    }
}

/// The albedo of the surface `si` seen from `wo`, as XYZ with the sample's wavelengths:
/// pbrt-v4's `VisibleSurface` albedo, ρ_hd(ωo) of the BSDF at the first hit whatever its lobes
/// (`Bsdf::rho`, PBR 4ed §4.3.1 Eq. 4.12), converted like its GBufferFilm (the reflectance
/// under the working white at Y = 1: `xyz::reflectance_to_xyz`).
#[inline]
fn first_hit_albedo(
    scene: &Scene,
    si: &SurfaceHit,
    wo: Vec3,
    filter: TextureFilter,
    lambda: &SampledWavelengths,
) -> [f32; 3] {
    let material = &scene.materials[si.material as usize];
    let bsdf = material.bsdf(scene.tex_coord(si, filter), si.ns, lambda);
    xyz::reflectance_to_xyz(bsdf.rho(wo), lambda)
}

/// The films of the layers asked for.
#[derive(Clone, Debug, Default)]
pub struct LayerFilms {
    clamped: u64,
    pub spectral: Option<SpectralFilm>,
    pub first_hit: Option<FirstHitFilm>,
    pub emission: EmissionFilms,
}

/// Per pixel, the first hits' sums (`LayerTile::add_first_hit`).
#[derive(Clone, Debug)]
pub struct FirstHitFilm {
    setup: FirstHitSetup,
    /// Whether P, N and Z are written (`--aov position,normal,depth`).
    geometry: bool,
    pixels: Vec<FirstHitSums>,
    width: usize,
}

/// The first-hit layers: per pixel, the mean camera-space position and geometric normal of
/// the samples that hit a surface (0 where none did), and the depth Z = P.z.
#[derive(Clone, Debug)]
pub struct FirstHitImages {
    pub position: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
}

/// The layers of a rendered image.
#[derive(Clone, Debug, Default)]
pub struct LayerImages {
    pub spectral: Option<SpectralImage>,
    /// Per pixel, the estimated variance of the mean luminance in (cd/m²)² (× exposure²);
    /// −1 where a pixel has fewer than 2 samples (no estimate).
    pub variance: Option<Vec<f32>>,
    pub first_hit: Option<FirstHitImages>,
    /// Per pixel, the mean albedo over the pixel's samples (0 for those that escaped), as XYZ
    /// of the reflectance under the working white at Y = 1 (`--aov albedo`).
    pub albedo: Option<Vec<[f32; 3]>>,
    /// The emission-weighted layers (`--illuminants`, `--light-groups`), in order.
    pub emission: Vec<EmissionImage>,
    /// An adaptive render's samples per pixel and its settings (`session::adaptive`).
    pub adaptive: Option<super::adaptive::AdaptiveImage>,
}

impl LayerFilms {
    /// The films of `opts`' layers and of the emission layers named `emission`; `setup` for
    /// the first-hit layers (its albedo filter ignored unless `opts.albedo`).
    pub fn new(
        (width, height): (usize, usize),
        opts: &LayerOptions,
        emission: &[String],
        grid: Grid,
        setup: FirstHitSetup,
    ) -> LayerFilms {
        LayerFilms {
            clamped: 0,
            emission: EmissionFilms::new(emission, (width, height), grid, opts.spectral),
            spectral: opts
                .spectral
                .map(|bins| SpectralFilm::new(width, height, bins, grid)),
            first_hit: (opts.first_hit || opts.albedo).then(|| FirstHitFilm {
                setup: FirstHitSetup {
                    albedo: setup.albedo.filter(|_| opts.albedo),
                    ..setup
                },
                geometry: opts.first_hit,
                pixels: vec![FirstHitSums::default(); width * height],
                width,
            }),
        }
    }

    /// Adds a tile's sums of `samples` samples per pixel.
    pub fn store_tile(&mut self, tile: &Tile, t: &LayerTile, samples: u64) {
        if let Some(f) = &mut self.spectral {
            f.store_tile(tile, &t.spectral, samples, 0);
        }
        if let Some(f) = &mut self.first_hit {
            for (k, i) in tile.pixels(f.width).enumerate() {
                let (acc, add) = (&mut f.pixels[i], &t.first_hit[k]);
                for c in 0..6 {
                    acc.sums[c] = acc.sums[c].saturating_add(add.sums[c]);
                }
                for c in 0..3 {
                    acc.albedo[c] = acc.albedo[c].saturating_add(add.albedo[c]);
                }
                acc.hits += add.hits;
                acc.samples += add.samples;
            }
        }
        self.clamped += t.clamped;
        self.emission.store_tile(tile, &t.emission, samples);
    }

    /// Terms clamped and sums saturated.
    pub fn clamped(&self) -> u64 {
        self.clamped
            + self.spectral.as_ref().map_or(0, SpectralFilm::clamped)
            + self.emission.clamped()
    }

    /// The layers times `scale` (the camera exposure).
    pub fn images(&self, scale: f64) -> LayerImages {
        LayerImages {
            emission: self.emission.images(scale, super::image::xyz_to_rgb),
            spectral: self.spectral.as_ref().map(|f| SpectralImage {
                bins: f.bins(),
                images: f.images(scale),
            }),
            variance: None,
            adaptive: None,
            first_hit: self.first_hit.as_ref().filter(|f| f.geometry).map(|f| {
                let mean = |p: &FirstHitSums, c0: usize| -> [f32; 3] {
                    std::array::from_fn(|c| mean_of(p.sums[c0 + c], p.hits))
                };
                FirstHitImages {
                    position: f.pixels.iter().map(|p| mean(p, 0)).collect(),
                    normal: f.pixels.iter().map(|p| mean(p, 3)).collect(),
                }
            }),
            albedo: self
                .first_hit
                .as_ref()
                .filter(|f| f.setup.albedo.is_some())
                .map(|f| {
                    let mean = |p: &FirstHitSums| p.albedo.map(|s| mean_of(s, p.samples));
                    f.pixels.iter().map(mean).collect()
                }),
        }
    }
}

/// The mean of `n` terms summing to `sum` on [`FIRST_HIT_GRID`], 0 for none.
fn mean_of(sum: i128, n: u64) -> f32 {
    match n {
        0 => 0.0,
        n => (FIRST_HIT_GRID.value(sum) / n as f64) as f32,
    }
}
