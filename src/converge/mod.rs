//! Convergence: error against wall time per configuration (integrator × wavelengths), for
//! images and light meters (`spectral-render converge`, `cli/converge.rs`).
//!
//! A configuration runs one progressive session ([`crate::session`]) and takes a snapshot at
//! each sample count of the [`schedule`] (12 per decade) until its time budget is spent
//! (`RunOptions::time_s`, checked after each snapshot) or its sample cap is reached. Each
//! snapshot becomes a [`Row`]: samples, times and the errors against the reference
//! ([`metrics`] for images, relative error and ci95 for meters). [`fit`] turns a
//! configuration's rows into its slope, its times to the target errors and its efficiency.
//!
//! **Time.** `time_s` is measured wall time of the integrator alone: building the session
//! (the estimator and its setup, e.g. VCM's radius) and its passes up to the snapshot. The
//! metrics, the image conversion of a snapshot and any snapshot I/O run with the clock
//! stopped; `elapsed_s` is the wall time including them. Nothing is estimated.
//!
//! **Determinism.** Snapshot sample counts are fixed in advance and a session's image depends
//! only on the seed and the sample count, so for a fixed seed every row but its times is the
//! same on every run; the time budget only decides how many rows there are (`max_samples`
//! fixes that too).

pub mod fit;
pub mod mask;
pub mod meters;
pub mod metrics;
pub mod reference;
pub mod schedule;

use crate::error::Result;
use crate::integrator::Integrator;
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::session::{ImageSession, RenderOptions, RenderOutput};
use metrics::{image_errors, ImageErrors, Reference};
use serde::Serialize;
use std::time::{Duration, Instant};

/// What is compared: an integrator with its settings, carrying 1 or 4 wavelengths.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The configuration's name in the report ("bdpt", "path 1λ").
    pub label: String,
    pub integrator: Integrator,
    pub wavelengths: usize,
}

impl Config {
    /// `integrator` with `wavelengths`; the label names the wavelengths only when
    /// `name_wavelengths` (several counts are compared).
    pub fn new(integrator: Integrator, wavelengths: usize, name_wavelengths: bool) -> Config {
        let label = if name_wavelengths {
            format!("{} {}λ", integrator.name(), wavelengths)
        } else {
            integrator.name().to_string()
        };
        Config {
            label,
            integrator,
            wavelengths,
        }
    }
}

/// How every configuration runs.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Wall-time budget per configuration, seconds: no snapshot starts once it is spent.
    pub time_s: f64,
    /// Stop after the last snapshot at or below this many samples (per pixel or per reading).
    pub max_samples: Option<u64>,
    pub seed: u64,
    pub threads: Option<usize>,
    /// Maximum scattering events; None: unlimited (as `RenderOptions::max_depth`).
    pub max_depth: Option<u32>,
    pub filter_textures: bool,
    /// The samples' numbers (`RenderOptions::sampler`).
    pub sampler: SamplerKind,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            time_s: 60.0,
            max_samples: None,
            seed: 0,
            threads: None,
            max_depth: None,
            filter_textures: true,
            sampler: SamplerKind::ZSobol,
        }
    }
}

/// One snapshot of one configuration: the CSV and JSON row. Image rows leave the meter
/// fields empty and the other way round; errors are fractions.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Row {
    pub config: String,
    /// Who rendered it: "spectral-render", or a peer ("mitsuba 3.x llvm_ad_spectral").
    pub source: String,
    pub integrator: String,
    pub wavelengths: Option<u32>,
    pub samples: u64,
    /// Measured wall time of the integrator alone, seconds (module docs).
    pub time_s: f64,
    /// Measured wall time including metrics and snapshot I/O, seconds.
    pub elapsed_s: Option<f64>,
    /// Samples dropped for a non-finite value so far (should be 0).
    pub dropped: Option<u64>,
    pub rel_mse: Option<f64>,
    pub rel_rmse: Option<f64>,
    pub rel_rmse_masked: Option<f64>,
    pub rel_mse_corrected: Option<f64>,
    pub rel_rmse_corrected: Option<f64>,
    pub rel_rmse_masked_corrected: Option<f64>,
    pub bias_masked: Option<f64>,
    /// The 95 % upper bound of `bias_masked`.
    pub bias_masked_bound: Option<f64>,
    /// The error the configuration is judged by (`ImageErrors::primary`; a meter's relative
    /// error).
    pub error: Option<f64>,
    /// Meter rows: the meter's index in the order given.
    pub meter: Option<usize>,
    pub value: Option<f64>,
    pub ci95: Option<f64>,
    pub reference: Option<f64>,
    /// |value − reference| / |reference|.
    pub rel_error: Option<f64>,
    /// ci95 / |reference|.
    pub rel_ci95: Option<f64>,
    /// Whether value ± ci95 covers the reference.
    pub covered: Option<bool>,
    /// Peer rows: the snapshot's EXR (relative to the peers CSV).
    pub image: Option<String>,
}

impl Row {
    /// The row's image errors filled in.
    pub fn with_errors(mut self, e: &ImageErrors) -> Row {
        self.rel_mse = Some(e.rel_mse);
        self.rel_rmse = Some(e.rel_rmse);
        self.rel_rmse_masked = e.rel_rmse_masked;
        self.rel_mse_corrected = e.rel_mse_corrected;
        self.rel_rmse_corrected = e.rel_rmse_corrected;
        self.rel_rmse_masked_corrected = e.rel_rmse_masked_corrected;
        self.bias_masked = e.bias_masked;
        self.bias_masked_bound = e.bias_masked_bound;
        self.error = Some(e.primary());
        self
    }
}

/// The source name of our own rows.
pub const SOURCE: &str = "spectral-render";

/// A stopwatch that runs only while the integrator works.
#[derive(Clone, Copy, Debug, Default)]
pub struct Clock {
    spent: Duration,
}

impl Clock {
    /// Runs `f` with the clock running.
    pub fn time<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.spent += start.elapsed();
        out
    }

    pub fn seconds(&self) -> f64 {
        self.spent.as_secs_f64()
    }
}

/// Runs `config` on `scene` to its budget, with a row per snapshot against `reference`
/// (`masked`: the emitter mask). `keep` sees every snapshot's image (for `--keep-images`),
/// with the clock stopped.
pub fn run_image(
    scene: &Scene,
    config: &Config,
    opts: &RunOptions,
    reference: &Reference,
    masked: &[bool],
    keep: &mut dyn FnMut(&Config, &RenderOutput) -> Result<()>,
) -> Result<Vec<Row>> {
    let start = Instant::now();
    let mut clock = Clock::default();
    let render_opts = render_options(config, opts);
    let mut session = clock.time(|| ImageSession::new(scene, &render_opts))?;
    let mut rows = Vec::new();
    for n in schedule::checkpoints(1) {
        if opts.max_samples.is_some_and(|m| n > m) {
            break;
        }
        let Some(stats) = clock.time(|| session.step_to(n)) else {
            continue;
        };
        let out = session.output();
        // The film's even/odd variance is the snapshot's own for every integrator: VCM's
        // even and odd iterations are independent replicates (`integrator::vcm::iteration_u`).
        let own_variance = Some(stats.variance.as_slice());
        let y: Vec<f32> = out.xyz.iter().map(|p| p[1]).collect();
        let errors = image_errors(&out.rgb, &y, own_variance, reference, masked);
        keep(config, &out)?;
        rows.push(
            Row {
                config: config.label.clone(),
                source: SOURCE.into(),
                integrator: config.integrator.name().into(),
                wavelengths: Some(config.wavelengths as u32),
                samples: n,
                time_s: clock.seconds(),
                elapsed_s: Some(start.elapsed().as_secs_f64()),
                dropped: Some(stats.dropped),
                ..Row::default()
            }
            .with_errors(&errors),
        );
        if clock.seconds() >= opts.time_s {
            break;
        }
    }
    Ok(rows)
}

/// The session options of a configuration: no sample count or budget of its own (snapshots
/// drive it with `step_to`); textures filtered for an unknown sample count, as under `--time`.
pub fn render_options(config: &Config, opts: &RunOptions) -> RenderOptions {
    RenderOptions {
        spp: None,
        time_budget: Some(opts.time_s),
        seed: opts.seed,
        threads: opts.threads,
        max_depth: opts.max_depth,
        integrator: config.integrator,
        filter_textures: opts.filter_textures,
        wavelengths: config.wavelengths,
        sampler: opts.sampler,
        ..RenderOptions::default()
    }
}
