//! The image driver: tiles over the session's thread pool, samples in passes until the sample
//! count or the time budget is reached, and the film turned into images.
//!
//! **Passes.** Under `--spp` the first pass takes one chunk and later ones about
//! [`PASS_SECONDS`] of work each, so that observers (the progress bar) hear often; under a
//! time budget passes grow (1, 1, 2, 4, … 64 samples per pixel), each cut to what the
//! measured rate says still fits in the budget and in [`PASS_SECONDS`] (so that interrupts
//! and checkpoints are heard about once a second), and the session stops after the pass in
//! which the budget ran out (equal-time comparisons rely on it ending close to the budget).
//!
//! **Checkpoints.** [`ImageSession::checkpoint`] is the session's state between passes and
//! [`ImageSession::resume`] continues one (`session::checkpoint`); since an image depends on
//! the seed and the sample count only, a resumed render equals the uninterrupted one.
//!
//! **Sums.** Every sample's own-pixel value and every splat is rounded once to the film's
//! grid and summed as integers (`sensor::grid_sum`), so the image does not depend on the
//! order of the additions: not on threads, passes, chunks, nor on a render split into parts
//! ([`ImageSession::start_part`], `session::part`) and merged.
//!
//! **Chunks.** Light tracing and BDPT splat: each tile returns its splat list. Splat lists are
//! bounded by working in chunks of [`SPLAT_CHUNK_SAMPLES`] samples over the image, aligned at
//! multiples of the chunk size from sample 0; under `--spp` their passes are whole chunks.
//! The path tracer has one chunk for the whole render. Per-thread buffers (`Workspace`) live
//! as long as a rayon job and are reused by every sample of it.
//!
//! **Adaptive sampling** (`RenderOptions::adaptive`, `session::adaptive`): a pilot of a few
//! samples per pixel in both replicates, then each pixel's replicates take the counts the
//! allocation gives them, in passes over windows of sample indices as above (a pixel skips
//! the indices beyond its counts); the film keeps the replicates apart (`sensor::replicates`).
//!
//! **Iterations.** An estimator whose samples share per-iteration work (VCM: the light
//! vertices of the iteration and their hash grid) names its iteration size; segments then
//! also end at iteration boundaries, and each iteration is prepared (`begin_iteration`) on
//! the session's threads before its first sample.

use super::adaptive::{self, AdaptiveImage, AdaptiveRun, Plan, ReplicateTile};
use super::auto::AutoReport;
use super::checkpoint::{self, Checkpoint};
use super::crop::Crop;
use super::layers::{FirstHitSetup, LayerFilms, LayerImages, LayerOptions, LayerTile};
use super::roulette::{self, Roulette};
use super::{pool, DepthCut, PassStats, Progressive};
use crate::error::{Reason, Result};
use crate::integrator::bidir::strategies::{StrategyFilms, StrategyImage};
use crate::integrator::bidir::TileAccumulator;
use crate::integrator::cut::{depth_cap, BatchedRatio};
use crate::integrator::roulette::RrStart;
use crate::integrator::split::Split;
use crate::integrator::{Estimator, Integrator, Iteration, Settings, Workspace};
use crate::sampling::{dimensions, PixelSamplers, SamplerKind};
use crate::scene::{ray_count, Scene};
use crate::sensor::film::{Film, Tile};
use crate::sensor::grid_sum::{Fixed3, Grid};
use crate::spectral::{color, SampledWavelengths};
use crate::texture::TextureFilter;
use rayon::prelude::*;
use std::time::Instant;

const TILE_SIZE: usize = 16;
/// Samples per chunk of a splatting integrator at depth caps up to 7 (bounds the splat lists
/// held at once: at most max-depth + 1 splats of 16 bytes per sample).
pub const SPLAT_CHUNK_SAMPLES: u64 = 1 << 18;
/// Splats a chunk may hold at most (8 per sample of [`SPLAT_CHUNK_SAMPLES`]: 32 MiB): deeper
/// caps make chunks smaller ([`splat_chunk_samples`]), down to one sample per pixel.
pub const SPLATS_PER_CHUNK: u64 = SPLAT_CHUNK_SAMPLES * 8;

/// Samples over the image per chunk of a splatting integrator with depth cap `cap`.
pub fn splat_chunk_samples(cap: u32) -> u64 {
    (SPLATS_PER_CHUNK / (u64::from(cap) + 1)).clamp(1, SPLAT_CHUNK_SAMPLES)
}
/// Samples per pixel when neither a count nor a time budget is given.
pub const DEFAULT_SPP: u32 = 64;
/// The most samples per pixel a render takes (a time budget stops there too): the EXR
/// records the count as a 32-bit int.
pub const MAX_SPP: u64 = i32::MAX as u64;
/// Aimed-at duration of a pass under a sample count.
pub const PASS_SECONDS: f64 = 1.0;

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub spp: Option<u32>,
    /// Render until this many seconds have passed (then finish the current pass).
    pub time_budget: Option<f64>,
    pub seed: u64,
    pub threads: Option<usize>,
    /// Maximum scattering events (pbrt's maxdepth); None: unlimited — Russian roulette ends
    /// paths, behind the safety cap `SAFETY_DEPTH`. Whatever the cap, the output says what
    /// it cut when a path reached it ([`RenderOutput::depth_cut`]).
    pub max_depth: Option<u32>,
    /// Where the path tracer's Russian roulette starts (`--rr-depth`: `integrator::roulette`;
    /// auto, the default, by a pilot: `session::roulette`); the other integrators ignore it.
    pub rr_depth: RrStart,
    /// The continuations the path tracer's paths split into at their first vertex
    /// (`--split`: `integrator::split`; auto, the default, chosen with the roulette start);
    /// the other integrators ignore it.
    pub split: Split,
    /// The light-transport algorithm and its settings.
    pub integrator: Integrator,
    /// Record the per-(s, t) decomposition (`Capabilities::strategy_images`).
    pub strategies: bool,
    /// Filter textures over the camera's pixel footprint (MIP-mapped, trilinear); false
    /// looks every texture up bilinearly at its finest level (pbrt-v4's
    /// `--disable-texture-filtering`; Mitsuba 3's bitmaps).
    pub filter_textures: bool,
    /// Wavelengths each sample carries: 4 (a hero and 3 rotations, Wilkie et al. 2014) or 1
    /// (the hero alone: the secondaries are terminated before the sample starts and again
    /// after it, as a dispersive surface would, so every integrator, VCM's iteration tuples
    /// included, estimates with the hero only; `converge --wavelengths 1,4`).
    pub wavelengths: usize,
    /// Refuse to start when the estimated memory (`session::memory`) and what the process
    /// holds exceed this many bytes; None: the machine's available memory.
    pub max_memory: Option<u64>,
    /// The numbers the samples draw (`--sampler`): the low-discrepancy sequence for the
    /// integrators that keep its dimension layout (`Integrator::low_discrepancy`), else
    /// independent ones.
    pub sampler: SamplerKind,
    /// Extra layers: spectral radiance, AOVs (`session::layers`).
    pub layers: LayerOptions,
    /// Render only this window's pixels (`--crop`, or the stage's `dataWindowNDC`:
    /// `session::crop`); None: the whole image. Auto's pilot renders the same window.
    pub crop: Option<Crop>,
    /// Allocate the samples per pixel by a pilot's noise (`--adaptive`, `session::adaptive`):
    /// `spp` is then their mean. The path tracer only, under a sample count.
    pub adaptive: bool,
}

/// The wavelength counts [`RenderOptions::wavelengths`] may take.
pub const WAVELENGTH_COUNTS: [usize; 2] = [1, 4];

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            spp: None,
            time_budget: None,
            seed: 0,
            threads: None,
            max_depth: None,
            rr_depth: RrStart::Auto,
            split: Split::Auto,
            integrator: Integrator::Path,
            strategies: false,
            filter_textures: true,
            wavelengths: 4,
            max_memory: None,
            sampler: SamplerKind::ZSobol,
            layers: LayerOptions::default(),
            crop: None,
            adaptive: false,
        }
    }
}

/// The rendered image: absolute XYZ (Y in cd/m²) and linear Rec.709 RGB, camera exposure applied.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: usize,
    pub height: usize,
    pub xyz: Vec<[f32; 3]>,
    pub rgb: Vec<[f32; 3]>,
    pub spp: u64,
    pub wall_time_s: f64,
    /// Samples whose estimate was NaN or infinite and were dropped (should be 0).
    pub dropped_samples: u64,
    /// Per-(s, t) images when `RenderOptions::strategies` was set.
    pub strategies: Option<Vec<StrategyImage>>,
    /// The integrator's report on its settings and resources (`Estimator::report`).
    pub report: Option<String>,
    /// What `--integrator auto` chose and why (`session::auto`).
    pub auto: Option<AutoReport>,
    /// The path tracer's first bounce of Russian roulette (`session::roulette`); None for
    /// the other integrators.
    pub rr_depth: Option<u32>,
    /// The path tracer's split at the first vertex (`session::roulette`); None for the
    /// other integrators.
    pub split: Option<u32>,
    /// What the depth cap cut of the image's mean luminance, when a path reached it.
    pub depth_cut: Option<DepthCut>,
    /// Contributions clamped to the film's range (`sensor::grid_sum`; should be 0).
    pub clamped: u64,
    /// The window rendered (`--crop`), when not the whole image: `xyz` and `rgb` are the
    /// whole image's, meaningful inside the window only.
    pub crop: Option<Crop>,
    /// The extra layers asked for (`RenderOptions::layers`).
    pub layers: LayerImages,
    /// The sampler the samples drew from (`RenderOptions::sampler` where the integrator keeps
    /// the dimension layout, else independent); None when not known (a merge of parts that
    /// do not name it).
    pub sampler: Option<SamplerKind>,
}

/// Renders `scene` to the end (sample count or time budget) without an observer.
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<RenderOutput> {
    let mut session = ImageSession::new(scene, opts)?;
    super::run(&mut session, &mut super::quiet);
    Ok(session.output())
}

/// An image rendered progressively.
pub struct ImageSession<'a> {
    scene: &'a Scene,
    opts: RenderOptions,
    pool: rayon::ThreadPool,
    estimator: Box<dyn Estimator + 'a>,
    splats: bool,
    film: Film,
    layers: LayerFilms,
    tiles: Vec<Tile>,
    strategy_count: usize,
    strategy_films: Option<StrategyFilms>,
    /// Samples per pixel per chunk.
    chunk: u64,
    /// The effective depth cap.
    cap: u32,
    /// The samples' luminance within and past the cap, merged in tile order.
    cut: BatchedRatio,
    target: u64,
    /// The first sample of every pixel this session renders (0, or a part's start).
    first: u64,
    /// The window of pixels this session renders (`session::crop`), when not the whole.
    crop: Option<Crop>,
    done: u64,
    dropped: u64,
    passes: u32,
    start: Instant,
    /// Seconds spent before this session started (a resumed checkpoint's).
    prior_s: f64,
    auto: Option<AutoReport>,
    /// The path tracer's roulette (`session::roulette`), None for the other integrators.
    roulette: Option<Roulette>,
    /// Ray queries the roulette's pilot made, left out of [`ImageSession::ray_queries`].
    pilot_rays: u64,
    /// The samplers of every (pixel, sample).
    samplers: PixelSamplers,
    /// An adaptive render's state (`RenderOptions::adaptive`).
    adaptive: Option<AdaptiveRun>,
}

impl<'a> ImageSession<'a> {
    /// A session of `opts.integrator`; `Integrator::Auto` is resolved first by its pilot
    /// (`session::auto`), whose winning session this then is.
    pub fn new(scene: &'a Scene, opts: &RenderOptions) -> Result<ImageSession<'a>> {
        let plan = check_adaptive(opts, !scene.emission_layers.is_empty())?;
        if let Integrator::Auto { .. } = opts.integrator {
            return super::auto::image(scene, opts);
        }
        if !WAVELENGTH_COUNTS.contains(&opts.wavelengths) {
            return Err(crate::error::Error::option(format!(
                "{} wavelengths per sample: 4 (hero sampling) or 1 (the hero alone)",
                opts.wavelengths
            )));
        }
        let strategy_count = if opts.strategies {
            opts.integrator.check_strategies(opts.max_depth)?
        } else {
            0
        };
        super::memory::check(
            "the render",
            &super::memory::image(scene, opts),
            opts.max_memory,
        )?;
        opts.layers.check(&opts.integrator)?;
        if !scene.emission_layers.is_empty() && opts.integrator != Integrator::Path {
            return Err(crate::error::Error::option(format!(
                "--illuminants and --light-groups weight each camera path by the layers' \
                 emission: integrator {} is not supported (use --integrator path)",
                opts.integrator.name()
            )));
        }
        let cap = depth_cap(opts.max_depth);
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let film = Film::new(w, h, Grid::for_scale(scene.camera.exposure_scale as f64));
        let first_hit = FirstHitSetup {
            to_camera: scene.camera.world_to_exr_camera(),
            albedo: Some(texture_filter(opts)),
        };
        let emission = scene.emission_layers.names();
        let layers = LayerFilms::new((w, h), &opts.layers, &emission, film.grid(), first_hit);
        let pool = pool::new(opts.threads)?;
        // The roulette's pilot is part of the render: its time counts.
        let start = Instant::now();
        let before = pool::ray_queries(&pool);
        let (integrator, rr, split) = (&opts.integrator, opts.rr_depth, opts.split);
        let roulette =
            pool.install(|| roulette::resolve(scene, integrator, (rr, split), cap, opts.seed));
        let pilot_rays = pool::ray_queries(&pool).wrapping_sub(before);
        let settings = Settings {
            max_depth: cap,
            rr_depth: roulette.as_ref().map_or(rr.or_default(), |r| r.start),
            split: roulette.as_ref().map_or(1, |r| r.split),
            filter: texture_filter(opts),
            meters: false,
        };
        let splats = opts.integrator.capabilities().splats;
        let mut session = ImageSession {
            scene,
            pool,
            estimator: opts.integrator.estimator(scene, settings)?,
            splats,
            tiles: film.tiles(TILE_SIZE),
            film,
            layers,
            strategy_count,
            strategy_films: (strategy_count > 0).then(|| StrategyFilms::new(w, h, cap)),
            chunk: if splats {
                splat_chunk(w * h, cap)
            } else {
                u64::MAX
            },
            cap,
            cut: BatchedRatio::default(),
            target: match (opts.spp, opts.time_budget) {
                (Some(n), _) => u64::from(n),
                (None, Some(_)) => MAX_SPP,
                (None, None) => u64::from(DEFAULT_SPP),
            },
            first: 0,
            crop: None,
            done: 0,
            dropped: 0,
            passes: 0,
            start,
            prior_s: 0.0,
            auto: None,
            roulette,
            pilot_rays,
            samplers: pixel_samplers(opts, w as u64),
            opts: opts.clone(),
            adaptive: plan.map(|p| AdaptiveRun::new(p, w * h, (w * h) as u64)),
        };
        if let Some(run) = &session.adaptive {
            session.film.keep_replicates();
            session.target = run.plan.pilot_spp();
        }
        if let Some(c) = opts.crop {
            session.start_crop(c).map_err(crate::error::Error::option)?;
        }
        Ok(session)
    }

    /// The samples per pixel a pause of a session of `integrator` on `scene` must be a
    /// multiple of for its image to stay what an unpaused session gives: a chunk for
    /// splatting integrators (their splats are summed pass by pass, so passes cover whole
    /// chunks), 1 otherwise (the open chunk continues across passes).
    pub(crate) fn pause_quantum(
        integrator: &Integrator,
        scene: &Scene,
        max_depth: Option<u32>,
    ) -> u64 {
        if integrator.capabilities().splats {
            let pixels = scene.camera.width as usize * scene.camera.height as usize;
            splat_chunk(pixels, depth_cap(max_depth))
        } else {
            1
        }
    }

    /// Goes on after `auto`'s pilot (`session::auto`) under `time_budget`, counted from
    /// `clock` (the pilot's start: its time counts), reporting `auto`.
    pub(crate) fn continue_after_pilot(
        &mut self,
        time_budget: Option<f64>,
        clock: Instant,
        auto: AutoReport,
    ) {
        self.opts.time_budget = time_budget;
        self.start = clock;
        self.auto = Some(auto);
    }

    /// The path tracer's roulette (`session::roulette`); None for the other integrators.
    pub fn roulette(&self) -> Option<&Roulette> {
        self.roulette.as_ref()
    }

    /// Ray queries the session's samples have made so far (`pool::ray_queries`).
    pub fn ray_queries(&self) -> u64 {
        pool::ray_queries(&self.pool).wrapping_sub(self.pilot_rays)
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u64 {
        self.done
    }

    /// Makes the session render samples [first, end) of every pixel (a part of the render,
    /// `session::part`) instead of [0, its target), before its first pass; the samples are
    /// the whole render's, with the same random numbers (the sampler is keyed by the sample
    /// index). A time budget has no fixed sample range and is refused.
    pub fn start_part(&mut self, first: u64, end: u64) -> Reason<()> {
        if self.done > 0 || self.first > 0 {
            return Err("a session starts a part only before its first pass".into());
        }
        if self.adaptive.is_some() {
            return Err(ADAPTIVE_WHOLE.into());
        }
        if !self.layers.emission.films.is_empty() {
            return Err(EMISSION_LAYERS_WHOLE.into());
        }
        if self.opts.time_budget.is_some() && self.opts.spp.is_none() {
            return Err("a part needs a sample count, not a time budget".into());
        }
        if first > end || end > self.target {
            return Err(format!(
                "samples {first}..{end} are not within the render's {}",
                self.target
            ));
        }
        self.first = first;
        self.done = first;
        self.target = end;
        Ok(())
    }

    /// Makes the session render only the pixels of `crop` (every sample of each, splats
    /// wherever they land: `session::crop`), before its first pass.
    pub fn start_crop(&mut self, crop: Crop) -> Reason<()> {
        if self.done > self.first || self.crop.is_some() {
            return Err("a session is cropped only before its first pass".into());
        }
        let (w, h) = (self.film.width, self.film.height);
        if crop.x1 > w || crop.y1 > h {
            return Err(format!(
                "the window {} is not within the {w}×{h} image",
                crop.label()
            ));
        }
        self.tiles = crop.clip(&self.tiles);
        self.crop = Some(crop);
        if let Some(run) = &mut self.adaptive {
            run.pixels = crop.pixel_count() as u64;
        }
        Ok(())
    }

    /// The image's width and height in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.film.width, self.film.height)
    }

    /// The film's raw state (a part's result, `session::part`).
    pub fn film_state(&self) -> crate::sensor::film_state::FilmState {
        self.film.state()
    }

    /// Samples dropped for a non-finite value so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// What the depth cap cut so far, as sums that merge (`integrator::cut`).
    pub fn depth_cut_sums(&self) -> BatchedRatio {
        self.cut
    }

    /// The integrator the session runs (the one `auto` chose, if it was asked for).
    pub fn integrator(&self) -> Integrator {
        self.opts.integrator
    }

    /// What `--integrator auto` chose and why, when it was asked for.
    pub fn auto(&self) -> Option<&AutoReport> {
        self.auto.as_ref()
    }

    /// The session's state under its run's identity (`session::checkpoint`).
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            identity: checkpoint::identity(self.scene, &self.opts),
            samples: self.done,
            dropped: self.dropped,
            wall_time_s: self.elapsed(),
            film: self.film.state(),
            strategies: self.strategy_films.as_ref().map(StrategyFilms::sums),
            depth_cut: self.cut,
        }
    }

    /// Continues from `c`, a checkpoint of the same run (identity checked), before any pass.
    pub fn resume(&mut self, c: Checkpoint) -> Reason<()> {
        c.check_identity(&checkpoint::identity(self.scene, &self.opts))?;
        if self.adaptive.is_some() {
            return Err("an adaptive render does not continue a checkpoint".into());
        }
        if self.done > 0 {
            return Err("a session resumes only before its first pass".into());
        }
        let film = Film::from_state(c.film)?;
        if (film.width, film.height) != (self.film.width, self.film.height) {
            return Err("the checkpoint's film has another size".into());
        }
        match (&mut self.strategy_films, c.strategies) {
            (Some(sf), Some(sums)) => sf.restore(sums)?,
            (None, None) => {}
            _ => return Err("the checkpoint's strategy images do not match".into()),
        }
        self.film = film;
        self.done = c.samples;
        self.dropped = c.dropped;
        self.cut = c.depth_cut;
        self.prior_s = c.wall_time_s;
        Ok(())
    }

    /// The integrator's report (`Estimator::report`) and the roulette pilot's, one line each.
    fn report(&self) -> Option<String> {
        let pilot = self.roulette.as_ref().and_then(|r| r.report.clone());
        match (self.estimator.report(), pilot) {
            (Some(a), Some(b)) => Some(format!("{a}\n{b}")),
            (a, b) => a.or(b),
        }
    }

    /// Wall-clock seconds of the render, a resumed checkpoint's included.
    fn elapsed(&self) -> f64 {
        self.prior_s + self.start.elapsed().as_secs_f64()
    }

    /// The image so far.
    pub fn output(&self) -> RenderOutput {
        let exposure = self.exposure();
        let xyz = self.film.xyz(exposure);
        let rgb = xyz.iter().map(|p| xyz_to_rgb(*p)).collect();
        RenderOutput {
            width: self.film.width,
            height: self.film.height,
            xyz,
            rgb,
            spp: match &self.adaptive {
                Some(run) => run.mean_spp().round() as u64,
                None => self.done - self.first,
            },
            wall_time_s: self.elapsed(),
            dropped_samples: self.dropped,
            strategies: self.strategy_films.as_ref().map(|sf| sf.images(exposure)),
            report: self.report(),
            auto: self.auto.clone(),
            rr_depth: self.roulette.as_ref().map(|r| r.start),
            split: self.roulette.as_ref().map(|r| r.split),
            depth_cut: DepthCut::new(
                self.opts.max_depth,
                &self.cut.sums(),
                self.cut.capped,
                self.cut.limited,
            ),
            clamped: self.film.clamped() + self.layers.clamped(),
            crop: self.crop,
            sampler: Some(sampler_kind(&self.opts)),
            layers: LayerImages {
                variance: self.opts.layers.variance.then(|| {
                    let v = self.film.variance_y(exposure);
                    v.iter()
                        .map(|&v| if v.is_finite() { v as f32 } else { -1.0 })
                        .collect()
                }),
                adaptive: self.adaptive.as_ref().map(|run| {
                    let (w, h) = (self.film.width, self.film.height);
                    let mask = adaptive::rendered(&self.tiles, w, h);
                    AdaptiveImage::new(run.plan, self.film.sample_counts(), &mask)
                }),
                ..self.layers.images(exposure)
            },
        }
    }

    fn exposure(&self) -> f64 {
        self.scene.camera.exposure_scale as f64
    }

    fn finished(&self) -> bool {
        self.done >= self.target || self.out_of_time()
    }

    fn out_of_time(&self) -> bool {
        let elapsed = self.elapsed();
        self.done > 0 && self.opts.time_budget.is_some_and(|t| elapsed >= t)
    }

    /// Samples per pixel of the next pass (see the module docs).
    fn pass_size(&self) -> u64 {
        let remaining = self.target - self.done;
        let elapsed = self.elapsed();
        let per_sample = elapsed / (self.done - self.first).max(1) as f64;
        let n = match self.opts.time_budget {
            Some(budget) => {
                let mut n = self.done.clamp(1, 64);
                if self.done > 0 && elapsed > 0.0 {
                    let left = (budget - elapsed).min(PASS_SECONDS);
                    n = n.min((left / per_sample).max(1.0) as u64);
                }
                n
            }
            None => {
                let quantum = if self.splats {
                    self.chunk.min(remaining)
                } else {
                    1
                };
                let wanted = if self.done == 0 || per_sample <= 0.0 {
                    1
                } else {
                    (PASS_SECONDS / per_sample).min(u32::MAX as f64) as u64
                };
                wanted.max(1).div_ceil(quantum).saturating_mul(quantum)
            }
        };
        match &self.adaptive {
            // After the pilot: about a pass's worth of samples at the rate so far.
            Some(run) if !run.in_pilot() && elapsed > 0.0 => {
                let rate = run.samples as f64 / elapsed;
                run.indices_for(self.done, rate * PASS_SECONDS)
                    .min(remaining)
            }
            // The pilot's first pass sets the clip (`session::adaptive`).
            Some(run) if run.clip.is_none() => n
                .min(remaining)
                .min(AdaptiveRun::FIRST.saturating_sub(self.done).max(1)),
            _ => n.min(remaining),
        }
    }

    /// The tiles of the segment [first, first + count): the session's, or after an adaptive
    /// render's pilot, the rows of those with a pixel whose samples reach into the segment
    /// (the last samples go to a few pixels: rows keep both threads busy on them).
    fn segment_tiles(&self, first: u64, count: u64) -> Vec<Tile> {
        let Some(alloc) = self.adaptive.as_ref().and_then(|r| r.allocation.as_deref()) else {
            return self.tiles.clone();
        };
        let w = self.film.width;
        let rows = self.tiles.iter().flat_map(|t| {
            (t.y0..t.y1).map(|y| Tile {
                y0: y,
                y1: y + 1,
                ..*t
            })
        });
        let reaches =
            |t: &Tile| count > 0 && t.pixels(w).any(|i| adaptive::end_of(alloc[i]) > first);
        rows.filter(reaches).collect()
    }

    /// Sets an adaptive render's clip once the pilot's first samples are in
    /// (`session::adaptive`).
    fn set_clip(&mut self) {
        let Some(run) = &mut self.adaptive else {
            return;
        };
        if run.clip.is_some() || self.done < AdaptiveRun::FIRST {
            return;
        }
        let mask = adaptive::rendered(&self.tiles, self.film.width, self.film.height);
        let xyz = self.film.xyz(1.0);
        let inside = xyz.iter().zip(&mask).filter(|(_, &m)| m);
        let sum: f64 = inside
            .map(|(p, _)| xyz_to_rgb(*p).iter().map(|&c| f64::from(c)).sum::<f64>())
            .sum();
        run.set_clip(sum / (3 * run.pixels.max(1)) as f64);
    }

    /// Ends an adaptive render's pilot, once done, by allocating its samples.
    fn allocate(&mut self) {
        let Some(run) = &mut self.adaptive else {
            return;
        };
        if run.in_pilot() && self.done >= self.target {
            let (w, h) = (self.film.width, self.film.height);
            let mask = adaptive::rendered(&self.tiles, w, h);
            self.target = run.allocate(&mask, w).max(self.done);
        }
    }

    /// Samples [first, first + count) of every pixel, all within one chunk.
    fn render_segment(&mut self, first: u64, count: u64) {
        let task = Segment {
            first,
            count,
            samplers: &self.samplers,
            strategy_count: self.strategy_count,
            hero_only: self.opts.wavelengths == 1,
            own_wavelengths: self.estimator.own_image_wavelengths(),
            grid: self.film.grid(),
            width: self.film.width,
            adaptive: self.adaptive.as_ref().map(|run| Adaptive {
                clip: run.moments_clip(),
                counts: run.allocation.as_deref(),
            }),
        };
        let estimator = &*self.estimator;
        let max_depth = self.cap;
        let layers = &self.layers;
        let scene = self.scene;
        let tiles = self.segment_tiles(first, count);
        let results: Vec<TileSums> = self.pool.install(|| {
            tiles
                .par_iter()
                .map_init(
                    || Workspace::new(max_depth, task.strategy_count),
                    |ws, tile| {
                        let acc = TileAccumulator::continuing(
                            vec![[0.0; 3]; tile.pixel_count()],
                            task.strategy_count,
                        );
                        let lt = LayerTile::new(layers, tile);
                        let reps = task
                            .adaptive
                            .map(|a| ReplicateTile::new(tile.pixel_count(), a.clip));
                        let sums = (acc, lt, reps);
                        if task.hero_only {
                            render_tile::<true>(estimator, scene, tile, &task, sums, ws)
                        } else {
                            render_tile::<false>(estimator, scene, tile, &task, sums, ws)
                        }
                    },
                )
                .collect()
        });
        for (tile, (r, fixed, clamped, lt, reps)) in tiles.iter().zip(results) {
            match (reps, &mut self.adaptive) {
                (Some(t), Some(run)) => {
                    let sums = (&fixed[..], &t.odd[..]);
                    self.film
                        .store_tile_counted(tile, sums, &r.odd_y, &t.counts, clamped);
                    run.add_tile(tile, self.film.width, &t);
                }
                _ => self.film.store_tile(tile, &fixed, &r.odd_y, count, clamped),
            }
            self.layers.store_tile(tile, &lt, count);
            self.film.add_splats(&r.splats, &r.odd_splats);
            if self.adaptive.as_ref().is_none_or(AdaptiveRun::in_pilot) {
                // An adaptive render's cut is its pilot's: its samples are alike in every
                // pixel, the later ones are not (design.md §9, "Adaptive sampling").
                self.cut.merge(&r.cut);
            }
            if let (Some(sf), Some(st)) = (&mut self.strategy_films, &r.strategies) {
                sf.merge_tile(tile, st);
            }
            self.dropped += r.dropped;
        }
        if self.splats {
            // One light path per camera sample rendered: a crop's pixels' only.
            let pixels = match self.crop {
                Some(c) => c.pixel_count(),
                None => self.film.width * self.film.height,
            };
            self.film.add_light_paths(pixels as u64 * count);
        }
        if let Some(sf) = &mut self.strategy_films {
            sf.add_samples(count);
        }
        self.done += count;
    }
}

impl ImageSession<'_> {
    /// Renders on to exactly `n` samples per pixel in one pass, whatever the session's own
    /// sample count or time budget (snapshots at chosen counts: `converge`); None when `n`
    /// samples are already done. The image at `n` is the same as after any other passes to
    /// `n` (chunks and iterations are aligned from sample 0).
    pub fn step_to(&mut self, n: u64) -> Option<PassStats> {
        (n > self.done).then(|| self.advance(n))
    }

    /// Renders samples [done, end) of every pixel, segment by segment (a segment ends at a
    /// chunk or iteration boundary), and returns the pass's statistics.
    fn advance(&mut self, end: u64) -> PassStats {
        let iteration = self.estimator.iteration_samples();
        while self.done < end {
            let mut segment_end = (self.done / self.chunk + 1).saturating_mul(self.chunk);
            if let Some(k) = iteration {
                if self.done.is_multiple_of(k) {
                    let it = Iteration {
                        seed: self.opts.seed,
                        index: self.done / k,
                    };
                    let estimator = &mut self.estimator;
                    self.pool.install(|| estimator.begin_iteration(it));
                }
                segment_end = segment_end.min((self.done / k + 1).saturating_mul(k));
            }
            self.render_segment(self.done, segment_end.min(end) - self.done);
        }
        self.passes += 1;
        PassStats {
            pass: self.passes,
            samples: match &self.adaptive {
                Some(run) => run.mean_spp() as u64,
                None => self.done,
            },
            target: (self.opts.time_budget.is_none() || self.opts.spp.is_some())
                .then_some(self.target),
            wall_time_s: self.elapsed(),
            dropped: self.dropped,
            variance: self.film.variance_y(self.exposure()),
        }
    }
}

impl Progressive for ImageSession<'_> {
    fn step(&mut self) -> Option<PassStats> {
        if !self.out_of_time() {
            self.allocate();
        }
        if self.finished() {
            return None;
        }
        self.set_clip();
        let end = self.done + self.pass_size();
        Some(self.advance(end))
    }
}

/// Samples per pixel of a chunk of a splatting integrator on an image of `pixels` under the
/// depth cap `cap` ([`splat_chunk_samples`]).
fn splat_chunk(pixels: usize, cap: u32) -> u64 {
    (splat_chunk_samples(cap) / pixels.max(1) as u64).max(1)
}

/// The camera's texture footprint for the render's sample count (unknown under a time
/// budget: `TextureFilter::camera`).
fn texture_filter(opts: &RenderOptions) -> TextureFilter {
    if !opts.filter_textures {
        return TextureFilter::Finest;
    }
    let spp = match (opts.spp, opts.time_budget) {
        (Some(n), _) => Some(u64::from(n)),
        (None, Some(_)) => None,
        (None, None) => Some(u64::from(DEFAULT_SPP)),
    };
    TextureFilter::camera(spp)
}

/// The samplers of a run of `opts` on an image `width` wide: `opts.sampler` where the
/// integrator keeps the dimension layout, else independent.
fn pixel_samplers(opts: &RenderOptions, width: u64) -> PixelSamplers {
    let spp = opts.spp.map(u64::from).or(match opts.time_budget {
        Some(_) => None,
        None => Some(u64::from(DEFAULT_SPP)),
    });
    PixelSamplers::new(sampler_kind(opts), opts.seed, width, spp)
}

/// The sampler a run of `opts` draws from: `opts.sampler` where the integrator keeps the
/// dimension layout, else independent.
pub(crate) fn sampler_kind(opts: &RenderOptions) -> SamplerKind {
    if opts.integrator.low_discrepancy() {
        opts.sampler
    } else {
        SamplerKind::Independent
    }
}

/// Why parts refuse adaptive sampling.
const ADAPTIVE_WHOLE: &str = "--adaptive allocates each pixel's samples from a pilot of the whole \
    render: it does not split into parts";

/// What adaptive sampling does not go with.
const ADAPTIVE_LAYERS: &str = "--spectral, --aov position/normal/depth/albedo, --illuminants \
    and --light-groups average each pixel's samples alike (--aov variance is supported)";

/// The plan of `opts`' adaptive render (None when not asked for), or why it cannot be;
/// `emission_layers`: the scene has emission layers (`--illuminants`, `--light-groups`).
pub fn check_adaptive(opts: &RenderOptions, emission_layers: bool) -> Result<Option<Plan>> {
    if !opts.adaptive {
        return Ok(None);
    }
    let refuse = |why: &str| Err(crate::error::Error::option(format!("--adaptive: {why}")));
    if opts.integrator != Integrator::Path {
        return refuse(&format!(
            "the samples are allocated per pixel, and integrator {} splats or chooses \
             (use --integrator path)",
            opts.integrator.name()
        ));
    }
    if opts.time_budget.is_some() && opts.spp.is_none() {
        return refuse("the allocation needs a sample count (--spp), not a time budget");
    }
    if opts.layers.any() || emission_layers {
        return refuse(ADAPTIVE_LAYERS);
    }
    let spp = opts.spp.unwrap_or(DEFAULT_SPP);
    Plan::new(spp)
        .map(Some)
        .map_err(crate::error::Error::option)
}

/// Why parts refuse emission layers (a window without a part, a stage's `dataWindowNDC`,
/// keeps them: they are cut to it like the image).
const EMISSION_LAYERS_WHOLE: &str = "--illuminants and --light-groups render all the samples in \
    one run: a part's saved state holds the image's film, not the layers' films";

/// Linear Rec.709 RGB of an XYZ pixel.
pub fn xyz_to_rgb(p: [f32; 3]) -> [f32; 3] {
    color::xyz_to_rgb(p.map(f64::from)).map(|c| c as f32)
}

/// Samples [first, first + count) of every pixel of a tile.
#[derive(Clone, Copy)]
struct Segment<'a> {
    first: u64,
    count: u64,
    samplers: &'a PixelSamplers,
    strategy_count: usize,
    /// Terminate the secondary wavelengths (`RenderOptions::wavelengths` = 1).
    hero_only: bool,
    /// The estimator replaces each sample's wavelengths (`Estimator::own_image_wavelengths`).
    own_wavelengths: bool,
    /// The film's grid (`sensor::grid_sum`).
    grid: Grid,
    /// The film's width (a pixel's index in `adaptive`'s counts).
    width: usize,
    /// An adaptive render's segment.
    adaptive: Option<Adaptive<'a>>,
}

/// A segment of an adaptive render: the pilot's, or each pixel's counts per replicate.
#[derive(Clone, Copy)]
struct Adaptive<'a> {
    /// Collect the pilot's moments, clipped here.
    clip: Option<f64>,
    counts: Option<&'a [[u32; 2]]>,
}

/// A tile's accumulator (its own-pixel sums emptied), its own-pixel sums on the grid, the
/// terms it clamped, its layers' sums and an adaptive render's replicates.
type TileSums = (
    TileAccumulator,
    Vec<Fixed3>,
    u64,
    LayerTile,
    Option<ReplicateTile>,
);

/// Renders a tile's samples into `acc`: per-pixel XYZ sums, splats and the number of
/// non-finite samples dropped. `HERO_ONLY`: every sample carries its hero wavelength alone
/// (a constant, so the 4-wavelength loop has no per-sample test).
fn render_tile<const HERO_ONLY: bool>(
    estimator: &dyn Estimator,
    scene: &Scene,
    tile: &Tile,
    task: &Segment,
    (mut acc, mut layers, mut reps): (TileAccumulator, LayerTile, Option<ReplicateTile>),
    ws: &mut Workspace,
) -> TileSums {
    let mut fixed = vec![[0; 3]; tile.pixel_count()];
    let mut clamped = 0;
    let mut k = 0;
    // What an estimator that brings its own wavelengths is handed (it replaces them first).
    let unset = SampledWavelengths::sample_visible(0.5);
    // A pinhole's path tracer does not read the lens sample (`Estimator::reads_lens`); the
    // layers' first hit (`add_first_hit`) goes through the same camera.
    let lens_read = estimator.reads_lens();
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = task.samplers.pixel(x as u32, y as u32);
            let counts = task
                .adaptive
                .and_then(|a| a.counts)
                .map(|c| c[y * task.width + x]);
            let end = match counts {
                Some(c) => (task.first + task.count).min(adaptive::end_of(c)),
                None => task.first + task.count,
            };
            for s in task.first..end {
                if counts.is_some_and(|c| !adaptive::takes(c, s)) {
                    continue;
                }
                let rays = match &reps {
                    Some(r) if r.collects() => ray_count::on_this_thread(),
                    _ => 0,
                };
                let mut sampler = pixel.sampler(s);
                sampler.set_dimension(dimensions::WAVELENGTH);
                // Drawn either way: the independent sampler's later numbers follow it.
                let u = sampler.get_1d();
                let mut lambda = if task.own_wavelengths {
                    unset
                } else {
                    SampledWavelengths::sample_visible(u)
                };
                if HERO_ONLY {
                    lambda.terminate_secondary();
                }
                sampler.set_dimension(dimensions::FILM);
                let [jx, jy] = sampler.get_2d();
                sampler.set_dimension(dimensions::LENS);
                let u_lens = sampler.get_2d_if(lens_read);
                let film = [x as f32 + jx, y as f32 + jy];
                ws.record.clear();
                estimator.image_sample(film, u_lens, &mut lambda, &mut sampler, ws);
                if HERO_ONLY {
                    // VCM replaces the sample's wavelengths by its iteration's tuple.
                    lambda.terminate_secondary();
                }
                let dropped = acc.dropped;
                acc.add(k, &ws.record, &lambda, s);
                layers.add(k, &ws.record, &lambda, (s, acc.dropped != dropped));
                layers.add_first_hit(k, scene, (film, u_lens), &lambda);
                // The sample's own value (0 when it was dropped), rounded to the grid; zero
                // (a black sample, about one in six on the peers' box) rounds to 0 unclamped
                // and adds nothing, so it is skipped (design.md §8, "The per-sample cost,
                // seventh pass").
                let own = std::mem::replace(&mut acc.sums[k], [0.0; 3]);
                let mut on_grid = None;
                if own != [0.0; 3] {
                    let (t, c) = task.grid.triple(own);
                    clamped += c + u64::from(Grid::add3(&mut fixed[k], &t));
                    on_grid = Some(t);
                }
                if let Some(r) = &mut reps {
                    let rays = ray_count::on_this_thread().wrapping_sub(rays);
                    clamped += u64::from(r.add(k, s, own, on_grid.as_ref(), rays));
                }
            }
            k += 1;
        }
    }
    (acc, fixed, clamped, layers, reps)
}
