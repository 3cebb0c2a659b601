//! The render loop: tiles over a rayon pool, samples in passes until the sample count or the
//! time budget is reached, a progress bar on a terminal, and the film turned into images.
//!
//! Light tracing and BDPT splat: each tile returns its splat list, merged in tile order after
//! the pass (or chunk of a pass), so images stay bit-identical for any thread count. Their
//! per-thread buffers (`bidir::Workspace`) live as long as a rayon job and are reused by every
//! sample of it.

use crate::integrator::bidir::strategies::{self, StrategyFilms, StrategyImage};
use crate::integrator::bidir::{BidirContext, Mis, TileAccumulator, Workspace};
use crate::integrator::{
    BdptIntegrator, IntegratorKind, LightTracer, MisHeuristic, PathIntegrator,
};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::sensor::film::{Film, Tile};
use crate::spectral::{color, xyz::sampled_to_xyz, SampledWavelengths};
use crate::texture::TextureFilter;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::time::Instant;

const TILE_SIZE: usize = 16;
/// Samples per chunk of a bidirectional pass (bounds the splat lists held at once: at most
/// max-depth + 1 splats of 16 bytes per sample).
const SPLAT_CHUNK_SAMPLES: u64 = 1 << 18;
/// Samples per pixel when neither a count nor a time budget is given.
pub const DEFAULT_SPP: u32 = 64;

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub spp: Option<u32>,
    /// Render until this many seconds have passed (then finish the current pass).
    pub time_budget: Option<f64>,
    pub seed: u64,
    pub threads: Option<usize>,
    pub max_depth: u32,
    pub integrator: IntegratorKind,
    /// MIS heuristic of BDPT.
    pub mis: MisHeuristic,
    /// Record the per-(s, t) decomposition (BDPT only).
    pub strategies: bool,
    pub progress: bool,
    /// Filter textures over the camera's pixel footprint (MIP-mapped, trilinear); false
    /// looks every texture up bilinearly at its finest level (pbrt-v4's
    /// `--disable-texture-filtering`; Mitsuba 3's bitmaps).
    pub filter_textures: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            spp: None,
            time_budget: None,
            seed: 0,
            threads: None,
            max_depth: 7,
            integrator: IntegratorKind::Path,
            mis: MisHeuristic::Power,
            strategies: false,
            progress: false,
            filter_textures: true,
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
}

pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<RenderOutput, String> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = opts.threads {
        builder = builder.num_threads(n.max(1));
    }
    let pool = builder
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    pool.install(|| render_in_pool(scene, opts))
}

/// The integrator of a render with what it needs per sample.
enum Engine<'a> {
    Path(PathIntegrator),
    Light(LightTracer, BidirContext<'a>),
    Bdpt(BdptIntegrator, BidirContext<'a>),
}

impl<'a> Engine<'a> {
    fn new(scene: &'a Scene, opts: &RenderOptions) -> Engine<'a> {
        let max_depth = opts.max_depth;
        let filter = texture_filter(opts);
        let ctx = || BidirContext::new(scene, Mis::bdpt(opts.mis), max_depth).with_filter(filter);
        match opts.integrator {
            IntegratorKind::Path => Engine::Path(PathIntegrator { max_depth, filter }),
            IntegratorKind::Light => Engine::Light(LightTracer { max_depth }, ctx()),
            IntegratorKind::Bdpt => Engine::Bdpt(BdptIntegrator { max_depth }, ctx()),
        }
    }

    fn is_bidirectional(&self) -> bool {
        !matches!(self, Engine::Path(_))
    }
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

fn render_in_pool(scene: &Scene, opts: &RenderOptions) -> Result<RenderOutput, String> {
    let start = Instant::now();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut film = Film::new(w, h);
    let tiles = film.tiles(TILE_SIZE);
    let target = opts
        .spp
        .map(u64::from)
        .unwrap_or(if opts.time_budget.is_some() {
            u64::MAX
        } else {
            DEFAULT_SPP as u64
        });
    let engine = Engine::new(scene, opts);
    let strategy_count = strategy_count(opts)?;
    let mut strategy_films = (strategy_count > 0).then(|| StrategyFilms::new(w, h, opts.max_depth));
    // Splat lists of a whole pass could be large: bidirectional passes go in chunks.
    let chunk = if engine.is_bidirectional() {
        (SPLAT_CHUNK_SAMPLES / (w * h) as u64).max(1)
    } else {
        u64::MAX
    };
    let bar = progress_bar(opts, (w * h) as u64, target);
    let mut done = 0u64;
    let mut dropped = 0u64;
    while done < target {
        let elapsed = start.elapsed().as_secs_f64();
        let pass_end = done + pass_size(done, target, opts.time_budget, elapsed);
        while done < pass_end {
            let count = chunk.min(pass_end - done);
            let results: Vec<TileAccumulator> = tiles
                .par_iter()
                .map_init(
                    || Workspace::new(opts.max_depth, strategy_count),
                    |ws, tile| {
                        let task = TileTask {
                            tile,
                            first: done,
                            count,
                            seed: opts.seed,
                            strategy_count,
                        };
                        let r = render_tile(scene, &engine, &task, ws);
                        bar.inc(tile.pixel_count() as u64 * count);
                        r
                    },
                )
                .collect();
            for (tile, r) in tiles.iter().zip(results) {
                film.merge_tile(tile, &r.sums, count);
                film.add_splats(&r.splats);
                if let (Some(sf), Some(st)) = (&mut strategy_films, &r.strategies) {
                    sf.merge_tile(tile, st);
                }
                dropped += r.dropped;
            }
            if engine.is_bidirectional() {
                film.add_light_paths((w * h) as u64 * count);
            }
            if let Some(sf) = &mut strategy_films {
                sf.add_samples(count);
            }
            done += count;
        }
        if opts
            .time_budget
            .is_some_and(|t| start.elapsed().as_secs_f64() >= t)
        {
            break;
        }
    }
    bar.finish_and_clear();
    let exposure = scene.camera.exposure_scale as f64;
    let xyz = film.xyz(exposure);
    let rgb = xyz.iter().map(|p| xyz_to_rgb(*p)).collect();
    Ok(RenderOutput {
        width: w,
        height: h,
        xyz,
        rgb,
        spp: done,
        wall_time_s: start.elapsed().as_secs_f64(),
        dropped_samples: dropped,
        strategies: strategy_films.map(|sf| sf.images(exposure)),
    })
}

/// Linear Rec.709 RGB of an XYZ pixel.
pub fn xyz_to_rgb(p: [f32; 3]) -> [f32; 3] {
    color::xyz_to_rgb(p.map(f64::from)).map(|c| c as f32)
}

/// Strategies recorded: none unless asked for, and only for BDPT.
fn strategy_count(opts: &RenderOptions) -> Result<usize, String> {
    if !opts.strategies {
        return Ok(0);
    }
    if opts.integrator != IntegratorKind::Bdpt {
        return Err("strategy images need --integrator bdpt".into());
    }
    if opts.max_depth > strategies::MAX_DEPTH {
        return Err(format!(
            "strategy images need --max-depth {} or less",
            strategies::MAX_DEPTH
        ));
    }
    Ok(strategies::count(opts.max_depth))
}

/// Pass sizes: everything at once for a sample count; under a time budget, growing passes
/// (1, 1, 2, 4, … 64) so that the budget is checked often at first and cheaply later, each cut
/// to what the rate so far says still fits in the budget (at least 1), so that the render
/// ends close to the budget (equal-time comparisons rely on it).
fn pass_size(done: u64, target: u64, budget: Option<f64>, elapsed: f64) -> u64 {
    let remaining = target - done;
    let Some(budget) = budget else {
        return remaining;
    };
    let mut n = done.clamp(1, 64);
    if done > 0 && elapsed > 0.0 {
        let fits = (budget - elapsed) / (elapsed / done as f64);
        n = n.min((fits.max(1.0)) as u64);
    }
    n.min(remaining)
}

/// Samples [first, first + count) of every pixel of one tile.
struct TileTask<'a> {
    tile: &'a Tile,
    first: u64,
    count: u64,
    seed: u64,
    strategy_count: usize,
}

/// Renders a tile: per-pixel XYZ sums, splats (bidirectional integrators) and the number of
/// non-finite samples dropped.
fn render_tile(
    scene: &Scene,
    engine: &Engine,
    task: &TileTask,
    ws: &mut Workspace,
) -> TileAccumulator {
    let tile = task.tile;
    let mut acc = TileAccumulator::new(tile.pixel_count(), task.strategy_count);
    let width = scene.camera.width as u64;
    let mut k = 0;
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * width + x as u64;
            for s in task.first..task.first + task.count {
                let mut sampler = Sampler::new(task.seed, pixel, s);
                let mut lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                let [jx, jy] = sampler.get_2d();
                let u_lens = sampler.get_2d();
                let film = [x as f32 + jx, y as f32 + jy];
                match engine {
                    Engine::Path(pt) => {
                        let (ray, t_max) = scene.camera.generate_ray(film, u_lens);
                        let l = pt.li(scene, ray, t_max, &lambda, &mut sampler);
                        let xyz = sampled_to_xyz(l, &lambda);
                        if xyz.iter().all(|c| c.is_finite()) {
                            for (a, v) in acc.sums[k].iter_mut().zip(xyz) {
                                *a += v as f64;
                            }
                        } else {
                            acc.dropped += 1;
                        }
                        continue;
                    }
                    Engine::Light(lt, ctx) => {
                        ws.record.clear();
                        lt.sample(ctx, &mut lambda, &mut sampler, ws);
                    }
                    Engine::Bdpt(bdpt, ctx) => {
                        ws.record.clear();
                        bdpt.sample(ctx, film, u_lens, &mut lambda, &mut sampler, ws);
                    }
                }
                acc.add(k, &ws.record, &lambda);
            }
            k += 1;
        }
    }
    acc
}

/// A bar of samples with rate and ETA on a terminal; nothing when output is not a terminal.
fn progress_bar(opts: &RenderOptions, pixels: u64, target_spp: u64) -> ProgressBar {
    if !opts.progress || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = if target_spp == u64::MAX {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(pixels * target_spp)
    };
    bar.set_draw_target(ProgressDrawTarget::stderr());
    let template = if target_spp == u64::MAX {
        "{spinner} {elapsed_precise} {human_pos} samples  {per_sec}"
    } else {
        "{bar:40} {percent:>3}%  {human_pos}/{human_len} samples  {per_sec}  ETA {eta}"
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}
