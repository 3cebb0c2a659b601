//! The render loop: tiles over a rayon pool, samples in passes until the sample count or the
//! time budget is reached, a progress bar on a terminal, and the film turned into images.

use crate::integrator::{IntegratorKind, PathIntegrator};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::sensor::film::{Film, Tile};
use crate::spectral::{color, xyz::sampled_to_xyz, SampledWavelengths};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::time::Instant;

const TILE_SIZE: usize = 16;
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
    pub progress: bool,
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
            progress: false,
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
    let bar = progress_bar(opts, (w * h) as u64, target);
    let integrator = PathIntegrator {
        max_depth: opts.max_depth,
    };
    let mut done = 0u64;
    let mut dropped = 0u64;
    while done < target {
        let pass = pass_size(done, target, opts.time_budget.is_some());
        let results: Vec<(Vec<[f64; 3]>, u64)> = tiles
            .par_iter()
            .map(|tile| {
                let r = render_tile(scene, &integrator, tile, done, pass, opts.seed);
                bar.inc(tile.pixel_count() as u64 * pass);
                r
            })
            .collect();
        for (tile, (sums, bad)) in tiles.iter().zip(results) {
            film.merge_tile(tile, &sums, pass);
            dropped += bad;
        }
        done += pass;
        if opts
            .time_budget
            .is_some_and(|t| start.elapsed().as_secs_f64() >= t)
        {
            break;
        }
    }
    bar.finish_and_clear();
    let xyz = film.xyz(scene.camera.exposure_scale as f64);
    let rgb = xyz
        .iter()
        .map(|p| color::xyz_to_rgb(p.map(f64::from)).map(|c| c as f32))
        .collect();
    Ok(RenderOutput {
        width: w,
        height: h,
        xyz,
        rgb,
        spp: done,
        wall_time_s: start.elapsed().as_secs_f64(),
        dropped_samples: dropped,
    })
}

/// Pass sizes: everything at once for a sample count; growing passes (1, 1, 2, 4, … 64) under
/// a time budget so that the budget is checked often at first and cheaply later.
fn pass_size(done: u64, target: u64, timed: bool) -> u64 {
    let remaining = target - done;
    if !timed {
        return remaining;
    }
    done.clamp(1, 64).min(remaining)
}

/// Renders samples [first, first + count) of every pixel in a tile; returns the XYZ sums
/// and the number of non-finite samples dropped.
fn render_tile(
    scene: &Scene,
    integrator: &PathIntegrator,
    tile: &Tile,
    first: u64,
    count: u64,
    seed: u64,
) -> (Vec<[f64; 3]>, u64) {
    let mut sums = vec![[0.0f64; 3]; tile.pixel_count()];
    let mut dropped = 0;
    let width = scene.camera.width as u64;
    let mut k = 0;
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * width + x as u64;
            for s in first..first + count {
                let mut sampler = Sampler::new(seed, pixel, s);
                let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                let [jx, jy] = sampler.get_2d();
                let u_lens = sampler.get_2d();
                let (ray, t_max) = scene
                    .camera
                    .generate_ray([x as f32 + jx, y as f32 + jy], u_lens);
                let l = integrator.li(scene, ray, t_max, &lambda, &mut sampler);
                let xyz = sampled_to_xyz(l, &lambda);
                if xyz.iter().all(|c| c.is_finite()) {
                    for (acc, v) in sums[k].iter_mut().zip(xyz) {
                        *acc += v as f64;
                    }
                } else {
                    dropped += 1;
                }
            }
            k += 1;
        }
    }
    (sums, dropped)
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
