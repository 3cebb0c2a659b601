//! The light-meter driver: illuminance (lx) on a virtual surface and luminance (cd/m²) along
//! a ray, with a 95% confidence interval. Meters are sensors (`sensor::meter`), like
//! Mitsuba 3's `irradiancemeter` and `radiancemeter`; any integrator estimates them through
//! `Estimator::meter_sample` ([`MeterOptions::integrator`]: the path tracer's estimators of
//! `integrator::meter` by default, light tracing or BDPT with the meter as their sensor), and
//! nothing but the rays they need is traced — there is no film. Light tracing cannot estimate
//! luminance (`Integrator::check_meter`).
//!
//! A reading is the mean of independent per-sample estimates of the photometric quantity
//! (K_m ∫ E(λ) ȳ(λ) dλ from one set of hero wavelengths, `spectral::xyz::sampled_to_xyz`).
//! Sample `s` of meter `i` draws its random numbers from `Sampler::new(seed, i, s)`, and
//! samples are accumulated in blocks of [`BLOCK`] merged in sample order (`Stats`), so
//! readings are bit-identical for any number of threads (a `time_budget` aside, which stops
//! at a wall-clock moment).
//!
//! **Confidence interval.** ci95 = 1.96·s/√n, the normal approximation of the sample mean.
//! With [`Stop::RelError`] readings are refined in rounds (one per [`Progressive::step`]) until ci95/value is below the target
//! or a cap (samples per reading, wall time) is hit; every reading takes at least
//! [`MIN_SAMPLES_REL`] samples first so that s is not judged on a handful of samples. The
//! interval is checked for coverage on heavy-tailed cases in `tests/meters.rs`.
//!
//! **Rounds.** Under a sample count a round takes about [`PASS_SECONDS`] of work (the first
//! one block per reading), so that a progress observer or an interrupt is heard often; under
//! a relative error rounds are set by the targets alone, so that where a reading stops does
//! not depend on the machine's speed.
//!
//! **Iterations.** An estimator whose samples share per-iteration work (VCM: the light
//! vertices merged with) names its iteration size; blocks then end at iteration boundaries,
//! each iteration is prepared once per round before its blocks, and a reading's statistics
//! are over iteration means, its only independent observations (batch means), while
//! `samples` still counts samples. Such readings take at least [`MIN_ITERATIONS_REL`]
//! iterations before a relative-error target is judged.
//!
//! ```
//! use spectral_render::desc::*;
//! use spectral_render::scene::build;
//! use spectral_render::sensor::meter::Meter;
//! use spectral_render::session::{measure, MeterOptions, Stop};
//! use glam::{Mat4, Vec3};
//!
//! // A normalized distant light of 1000 lx shining straight down.
//! let mut desc = SceneDescription::default();
//! desc.lights.push(LightDesc {
//!     prim_path: "/Sun".into(),
//!     kind: LightKind::Distant { angle_deg: 0.0 },
//!     to_world: Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2),
//!     emission: EmissionDesc { intensity: 1000.0, normalize: true, ..Default::default() },
//!     shaping: None,
//!     shadows: true,
//! });
//! let scene = build(&desc, Some((1, 1))).unwrap();
//! let meter = Meter::illuminance(Vec3::ZERO, Vec3::Y).unwrap();
//! let opts = MeterOptions { stop: Stop::Samples(256), ..Default::default() };
//! let reading = measure(&scene, &[meter], &opts).unwrap().readings[0];
//! assert!((reading.value / 1000.0 - 1.0).abs() < 0.02);
//! ```

use super::auto::AutoReport;
use super::image::PASS_SECONDS;
use super::{pool, DepthCut, PassStats, Progressive};
use crate::error::Result;
use crate::integrator::cut::{depth_cap, CutSample};
use crate::integrator::{Estimator, Integrator, Iteration, Settings, Workspace};
use crate::math::ratio::RatioSums;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::sensor::meter::{Meter, MeterSensor, Stats};
use crate::spectral::{xyz::sampled_to_xyz, SampledWavelengths};
use crate::texture::TextureFilter;
use rayon::prelude::*;
use std::time::Instant;

/// Samples per block of work (the unit of parallelism and of merging).
pub const BLOCK: u64 = 256;
/// Samples every reading takes before its interval is trusted under [`Stop::RelError`].
pub const MIN_SAMPLES_REL: u64 = 1024;
/// Iteration means every reading of an estimator with iterations (VCM) takes before its
/// interval is trusted under [`Stop::RelError`].
pub const MIN_ITERATIONS_REL: u64 = 32;
/// Samples per reading when neither a count nor a relative error is asked for.
pub const DEFAULT_SAMPLES: u64 = 4096;
/// Default cap on the samples of one reading under [`Stop::RelError`].
pub const DEFAULT_MAX_SAMPLES: u64 = 1 << 24;

/// When to stop sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// This many samples per reading.
    Samples(u64),
    /// Until ci95/value < the target for every reading (or a cap).
    RelError(f64),
}

#[derive(Clone, Debug)]
pub struct MeterOptions {
    pub stop: Stop,
    /// Cap on the samples of one reading under [`Stop::RelError`].
    pub max_samples: u64,
    /// Wall-clock cap in seconds (rounds stop once it is spent).
    pub time_budget: Option<f64>,
    pub seed: u64,
    /// Maximum scattering events; None: unlimited (as [`super::RenderOptions::max_depth`]).
    pub max_depth: Option<u32>,
    /// The path tracer's first bounce of Russian roulette (as
    /// [`super::RenderOptions::rr_depth`]).
    pub rr_depth: u32,
    pub threads: Option<usize>,
    /// The estimator: path tracing (default), light tracing or BDPT, with its settings.
    pub integrator: Integrator,
    /// Refuse to start when the estimated memory (`session::memory`) and what the process
    /// holds exceed this many bytes; None: the machine's available memory.
    pub max_memory: Option<u64>,
}

impl Default for MeterOptions {
    fn default() -> Self {
        MeterOptions {
            stop: Stop::Samples(DEFAULT_SAMPLES),
            max_samples: DEFAULT_MAX_SAMPLES,
            time_budget: None,
            seed: 0,
            max_depth: None,
            rr_depth: crate::integrator::roulette::DEFAULT_RR_DEPTH,
            threads: None,
            integrator: Integrator::Path,
            max_memory: None,
        }
    }
}

/// What stopped a reading before its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cap {
    /// `max_samples` under [`Stop::RelError`].
    Samples,
    /// The time budget.
    Time,
    /// The session was stopped from outside ([`MeterSession::interrupt`]: SIGINT, SIGTERM).
    Interrupted,
}

/// One meter's answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// Mean of the samples, in the kind's unit.
    pub value: f64,
    /// Half-width of the 95% confidence interval (infinite with fewer than two samples).
    pub ci95: f64,
    /// Samples averaged (finite ones; see `MeterRun::dropped`).
    pub samples: u64,
    /// Set when a cap stopped the reading short of its sample count or relative error.
    pub capped: Option<Cap>,
    /// What the depth cap cut of the reading, when a path reached it.
    pub depth_cut: Option<DepthCut>,
}

/// The readings of a run, in the order of the meters.
#[derive(Clone, Debug)]
pub struct MeterRun {
    pub readings: Vec<Reading>,
    /// Samples whose estimate was NaN or infinite and were dropped (should be 0).
    pub dropped: u64,
    pub wall_time_s: f64,
    /// The integrator's report on its settings and resources (`Estimator::report`).
    pub report: Option<String>,
    /// What `--integrator auto` chose and why (`session::auto`).
    pub auto: Option<AutoReport>,
}

/// Measures every meter to the end (sample count, relative error or time budget).
pub fn measure(scene: &Scene, meters: &[Meter], opts: &MeterOptions) -> Result<MeterRun> {
    let mut session = MeterSession::new(scene, meters, opts)?;
    super::run(&mut session, &mut super::quiet);
    Ok(session.readings())
}

/// Where one reading stands.
#[derive(Clone, Copy, Debug, Default)]
struct State {
    /// The reading's observations: its samples, or for an estimator with iterations (VCM),
    /// the mean of each iteration's samples — samples of one iteration share its light
    /// vertices, so only iteration means are independent and give an honest interval.
    stats: Stats,
    /// Finite samples averaged.
    samples: u64,
    /// Sample indices used so far (finite or not).
    taken: u64,
    finished: bool,
    capped: Option<Cap>,
    /// The observations' cut past the depth cap and total (`integrator::cut`).
    cut: BlockCut,
}

/// What a block's samples found past the depth cap: paired sums per sample (or, for an
/// estimator with iterations, the block's means as one pair), and the paths that reached it.
#[derive(Clone, Copy, Debug, Default)]
struct BlockCut {
    sums: RatioSums,
    capped: u64,
    limited: u64,
}

impl BlockCut {
    fn merge(&mut self, o: &BlockCut) {
        self.sums.merge(&o.sums);
        self.capped += o.capped;
        self.limited += o.limited;
    }
}

/// What one block returns: its statistics, its cut and the non-finite samples dropped.
#[derive(Clone, Copy, Debug, Default)]
struct BlockResult {
    stats: Stats,
    cut: BlockCut,
    dropped: u64,
}

/// Samples [first, end) of one meter.
#[derive(Clone, Copy, Debug)]
struct Block {
    meter: usize,
    first: u64,
    end: u64,
}

/// Light-meter readings refined progressively: one round of blocks per step.
pub struct MeterSession<'a> {
    opts: MeterOptions,
    pool: rayon::ThreadPool,
    estimator: Box<dyn Estimator + 'a>,
    sensors: Vec<MeterSensor>,
    states: Vec<State>,
    /// The index of the first meter in the whole study (0, or a part's first reading): meter
    /// i's samples are keyed by `first_meter + i`.
    first_meter: u64,
    auto: Option<AutoReport>,
    dropped: u64,
    passes: u32,
    start: Instant,
}

impl<'a> MeterSession<'a> {
    /// Refuses meters the integrator cannot estimate (`Integrator::check_meter`);
    /// `Integrator::Auto` is resolved first by its pilot (`session::auto`), whose winning
    /// session this then is.
    pub fn new(
        scene: &'a Scene,
        meters: &[Meter],
        opts: &MeterOptions,
    ) -> Result<MeterSession<'a>> {
        if let Integrator::Auto { .. } = opts.integrator {
            return super::auto::meters(scene, meters, opts);
        }
        for m in meters {
            opts.integrator.check_meter(m.kind)?;
        }
        let estimate = super::memory::meters(meters.len(), opts);
        super::memory::check("the measurement", &estimate, opts.max_memory)?;
        let settings = Settings {
            max_depth: depth_cap(opts.max_depth),
            rr_depth: opts.rr_depth,
            split: 1,
            filter: TextureFilter::Finest,
            meters: true,
        };
        Ok(MeterSession {
            pool: pool::new(opts.threads)?,
            estimator: opts.integrator.estimator(scene, settings)?,
            sensors: meters
                .iter()
                .map(|m| MeterSensor::new(m, scene.point_error(m.p)))
                .collect(),
            states: vec![State::default(); meters.len()],
            first_meter: 0,
            auto: None,
            dropped: 0,
            passes: 0,
            start: Instant::now(),
            opts: opts.clone(),
        })
    }

    /// Makes the session's meters readings `first`, `first + 1`, … of a larger study (a part
    /// of it, `meter --part`): each draws the random numbers it has in the whole study
    /// (`Sampler::new(seed, first + i, s)`), so its reading is the whole study's, bit for bit.
    /// Only before the first round.
    pub fn start_part(&mut self, first: u64) -> std::result::Result<(), String> {
        if self.passes > 0 {
            return Err("a meter session starts a part only before its first round".into());
        }
        self.first_meter = first;
        Ok(())
    }

    /// Marks the readings that have not reached their target as interrupted; the session
    /// takes no more samples.
    pub fn interrupt(&mut self) {
        for s in self.states.iter_mut().filter(|s| !s.finished) {
            s.finished = true;
            s.capped = Some(Cap::Interrupted);
        }
    }

    /// The readings so far, in the order of the meters.
    pub fn readings(&self) -> MeterRun {
        let depth = self.opts.max_depth;
        MeterRun {
            readings: self.states.iter().map(|s| reading(s, depth)).collect(),
            dropped: self.dropped,
            wall_time_s: self.start.elapsed().as_secs_f64(),
            report: self.estimator.report(),
            auto: self.auto.clone(),
        }
    }

    /// Samples per reading of the first round under a relative-error target: a pause there
    /// (`step_to`) leaves the rounds, and so the readings, as they would have been.
    pub(crate) fn first_round(&self) -> u64 {
        self.min_samples_rel().min(self.opts.max_samples)
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

    /// Ray queries the session's samples have made so far (`pool::ray_queries`).
    pub fn ray_queries(&self) -> u64 {
        pool::ray_queries(&self.pool)
    }

    /// The options the session runs with (the integrator `auto` chose, if it was asked for).
    pub fn options(&self) -> &MeterOptions {
        &self.opts
    }

    /// What `--integrator auto` chose and why, when it was asked for.
    pub fn auto(&self) -> Option<&AutoReport> {
        self.auto.as_ref()
    }
}

impl MeterSession<'_> {
    /// Samples a reading takes before its interval is trusted: [`MIN_SAMPLES_REL`], and for
    /// an estimator with iterations at least [`MIN_ITERATIONS_REL`] iteration means.
    fn min_samples_rel(&self) -> u64 {
        match self.estimator.iteration_samples() {
            Some(k) => MIN_SAMPLES_REL.max(MIN_ITERATIONS_REL * k),
            None => MIN_SAMPLES_REL,
        }
    }

    /// The statistics of `blocks`, in parallel, in their order.
    fn sample_blocks(&self, blocks: &[Block]) -> Vec<BlockResult> {
        let (estimator, sensors, seed) = (&*self.estimator, &self.sensors, self.opts.seed);
        let first = self.first_meter;
        let max_depth = depth_cap(self.opts.max_depth);
        let per_block = self.estimator.iteration_samples().is_some();
        self.pool.install(|| {
            blocks
                .par_iter()
                .map_init(
                    || Workspace::new(max_depth, 0),
                    |ws, b| {
                        let key = (seed, first + b.meter as u64);
                        sample_block(estimator, &sensors[b.meter], b, key, per_block, ws)
                    },
                )
                .collect()
        })
    }

    /// The statistics of `blocks` (each within one iteration of `k` samples), iteration by
    /// iteration in increasing order, each prepared first (`Estimator::begin_iteration`).
    fn sample_blocks_by_iteration(&mut self, blocks: &[Block], k: u64) -> Vec<BlockResult> {
        let mut results = vec![BlockResult::default(); blocks.len()];
        let mut iterations: Vec<u64> = blocks.iter().map(|b| b.first / k).collect();
        iterations.sort_unstable();
        iterations.dedup();
        for index in iterations {
            let it = Iteration {
                seed: self.opts.seed,
                index,
            };
            let estimator = &mut self.estimator;
            self.pool.install(|| estimator.begin_iteration(it));
            let picked: Vec<usize> = (0..blocks.len())
                .filter(|&i| blocks[i].first / k == index)
                .collect();
            let group: Vec<Block> = picked.iter().map(|&i| blocks[i]).collect();
            for (i, r) in picked.into_iter().zip(self.sample_blocks(&group)) {
                results[i] = r;
            }
        }
        results
    }
}

impl Progressive for MeterSession<'_> {
    fn step(&mut self) -> Option<PassStats> {
        let min_rel = self.min_samples_rel();
        let opts = &self.opts;
        let mut targets: Vec<u64> = self
            .states
            .iter_mut()
            .map(|s| next_target(s, opts, min_rel))
            .collect();
        if !fit_time_budget(&mut self.states, &mut targets, opts, self.start) {
            return None;
        }
        if matches!(opts.stop, Stop::Samples(_)) {
            fit_pass(&self.states, &mut targets, self.start);
        }
        self.round(&targets)
    }
}

impl MeterSession<'_> {
    /// Samples every reading on to exactly `n` samples in one round, whatever the session's
    /// own stop and time budget (snapshots at chosen counts: `converge`); None when every
    /// reading already has `n`. Blocks keep their fixed boundaries, so readings do not depend
    /// on where the rounds fell.
    pub fn step_to(&mut self, n: u64) -> Option<PassStats> {
        let targets: Vec<u64> = self.states.iter().map(|s| s.taken.max(n)).collect();
        self.round(&targets)
    }

    /// One round: every reading from its count to its target.
    fn round(&mut self, targets: &[u64]) -> Option<PassStats> {
        let iteration = self.estimator.iteration_samples();
        let blocks = blocks(&self.states, targets, iteration);
        if blocks.is_empty() {
            return None;
        }
        let results = match iteration {
            None => self.sample_blocks(&blocks),
            Some(k) => self.sample_blocks_by_iteration(&blocks, k),
        };
        for (b, r) in blocks.iter().zip(results) {
            let st = &mut self.states[b.meter];
            st.samples += r.stats.n;
            if iteration.is_some() && r.stats.n > 0 {
                st.stats.push(r.stats.mean);
            } else {
                st.stats.merge(&r.stats);
            }
            st.cut.merge(&r.cut);
            st.taken = b.end;
            self.dropped += r.dropped;
        }
        self.passes += 1;
        Some(PassStats {
            pass: self.passes,
            samples: self.states.iter().map(|s| s.taken).sum(),
            target: None,
            wall_time_s: self.start.elapsed().as_secs_f64(),
            dropped: self.dropped,
            variance: self
                .states
                .iter()
                .map(|s| s.stats.variance() / s.stats.n as f64)
                .collect(),
        })
    }
}

fn reading(s: &State, max_depth: Option<u32>) -> Reading {
    Reading {
        value: s.stats.mean,
        ci95: s.stats.ci95(),
        samples: s.samples,
        capped: s.capped,
        depth_cut: DepthCut::new(max_depth, &s.cut.sums, s.cut.capped, s.cut.limited),
    }
}

/// The sample count a reading should reach in the next round (its current count when it is
/// finished). Under a relative-error target the count needed is extrapolated from
/// ci95 ∝ 1/√n with 20% to spare, at most ×4 per round (the variance estimate of a
/// heavy-tailed estimator can be far off early), rounded to whole blocks.
fn next_target(s: &mut State, opts: &MeterOptions, min_rel: u64) -> u64 {
    if s.finished {
        return s.taken;
    }
    let timed = opts.time_budget.is_some();
    let target = match opts.stop {
        Stop::Samples(n) if s.taken >= n => None,
        // Under a time budget, growing rounds so that the budget is checked often.
        Stop::Samples(n) if timed => Some(n.min(round_up((2 * s.taken).max(BLOCK)))),
        Stop::Samples(n) => Some(n),
        Stop::RelError(_) if s.taken < min_rel.min(opts.max_samples) => {
            Some(min_rel.min(opts.max_samples))
        }
        Stop::RelError(r) if s.stats.relative_ci95() < r => None,
        Stop::RelError(_) if s.taken >= opts.max_samples => {
            s.capped = Some(Cap::Samples);
            None
        }
        Stop::RelError(r) => {
            let rel = s.stats.relative_ci95();
            let need = s.taken as f64 * (rel / r).powi(2) * 1.2;
            // max/min rather than clamp: no panic on NaN or crossed bounds.
            let grow = need.max((s.taken + BLOCK) as f64).min(4.0 * s.taken as f64);
            Some(round_up(grow.min(u64::MAX as f64 / 2.0) as u64).min(opts.max_samples))
        }
    };
    match target {
        Some(t) => t,
        None => {
            s.finished = true;
            s.taken
        }
    }
}

fn round_up(n: u64) -> u64 {
    n.div_ceil(BLOCK) * BLOCK
}

/// Shrinks the next round so that it should end within the time budget, judging by the
/// sampling rate so far; when the budget is spent, marks the unfinished readings as capped
/// and returns false.
fn fit_time_budget(
    states: &mut [State],
    targets: &mut [u64],
    opts: &MeterOptions,
    start: Instant,
) -> bool {
    let Some(budget) = opts.time_budget else {
        return true;
    };
    let elapsed = start.elapsed().as_secs_f64();
    let taken: u64 = states.iter().map(|s| s.taken).sum();
    let wanted: u64 = states.iter().zip(&*targets).map(|(s, t)| t - s.taken).sum();
    if wanted == 0 {
        return true;
    }
    if elapsed >= budget {
        for s in states.iter_mut().filter(|s| !s.finished) {
            s.finished = true;
            s.capped = Some(Cap::Time);
        }
        return false;
    }
    if taken == 0 {
        return true;
    }
    let affordable = (budget - elapsed) * taken as f64 / elapsed.max(1e-9);
    shrink_round(states, targets, affordable);
    true
}

/// Under a sample count, cuts the round to about [`PASS_SECONDS`] of work at the rate so far
/// (the first round: one block per reading), so that observers and interrupts are heard
/// often. The readings do not change: blocks keep their boundaries.
fn fit_pass(states: &[State], targets: &mut [u64], start: Instant) {
    let taken: u64 = states.iter().map(|s| s.taken).sum();
    if taken == 0 {
        for (s, t) in states.iter().zip(targets.iter_mut()) {
            *t = (*t).min(s.taken + BLOCK);
        }
        return;
    }
    let elapsed = start.elapsed().as_secs_f64().max(1e-9);
    shrink_round(states, targets, PASS_SECONDS * taken as f64 / elapsed);
}

/// Scales the round's new samples down to about `affordable` in all, at least one block for
/// every reading that goes on; rounds stay whole blocks.
fn shrink_round(states: &[State], targets: &mut [u64], affordable: f64) {
    let wanted: u64 = states.iter().zip(&*targets).map(|(s, t)| t - s.taken).sum();
    if (wanted as f64) <= affordable {
        return;
    }
    let scale = affordable / wanted as f64;
    for (s, t) in states.iter().zip(targets.iter_mut()) {
        if *t > s.taken {
            let more = round_up((((*t - s.taken) as f64) * scale) as u64).max(BLOCK);
            *t = (*t).min(s.taken + more);
        }
    }
}

/// The round's work: for each reading, the blocks from its current count to its target.
/// Blocks also end at multiples of `iteration` (the estimator's iteration size), so that a
/// block belongs to one iteration.
fn blocks(states: &[State], targets: &[u64], iteration: Option<u64>) -> Vec<Block> {
    let mut out = Vec::new();
    let next = |first: u64, unit: u64| (first / unit + 1).saturating_mul(unit);
    for (meter, (s, &target)) in states.iter().zip(targets).enumerate() {
        let mut first = s.taken;
        while first < target {
            let mut end = next(first, BLOCK).min(target);
            if let Some(k) = iteration {
                end = end.min(next(first, k));
            }
            out.push(Block { meter, first, end });
            first = end;
        }
    }
    out
}

/// The statistics of one block of samples, what they found past the depth cap, and the
/// number of non-finite ones dropped. Each sample's photometric Y (lx or cd/m²) uses the
/// final wavelengths, so a termination applies to the whole estimate. `per_block`: the cut's
/// observation is the block (its samples share an iteration) rather than each sample.
fn sample_block(
    estimator: &dyn Estimator,
    m: &MeterSensor,
    b: &Block,
    (seed, key): (u64, u64),
    per_block: bool,
    ws: &mut Workspace,
) -> BlockResult {
    let mut r = BlockResult::default();
    let mut block = RatioSums::default();
    for s in b.first..b.end {
        let mut sampler = Sampler::new(seed, key, s);
        let mut lambda = SampledWavelengths::sample_visible(sampler.get_1d());
        ws.record.cut = CutSample::default();
        let l = estimator.meter_sample(m, &mut lambda, &mut sampler, ws);
        let y = sampled_to_xyz(l, &lambda)[1];
        if !y.is_finite() {
            r.dropped += 1;
            continue;
        }
        r.stats.push(f64::from(y));
        let cut = ws.record.cut;
        r.cut.capped += u64::from(cut.capped);
        r.cut.limited += u64::from(cut.limited);
        // A non-finite continuation leaves the reading alone and counts as 0.
        let c = if cut.light.is_black() {
            0.0
        } else {
            f64::from(sampled_to_xyz(cut.light, &lambda)[1])
        };
        let c = if c.is_finite() { c } else { 0.0 };
        block.push(c, f64::from(y) + c);
    }
    if per_block && block.n > 0 {
        let n = block.n as f64;
        r.cut.sums.push(block.c / n, block.t / n);
    } else {
        r.cut.sums = block;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_follow_fixed_boundaries() {
        let states = [
            State {
                taken: 300,
                ..Default::default()
            },
            State::default(),
        ];
        let b = blocks(&states, &[700, 100], None);
        let spans: Vec<(usize, u64, u64)> = b.iter().map(|b| (b.meter, b.first, b.end)).collect();
        assert_eq!(spans, [(0, 300, 512), (0, 512, 700), (1, 0, 100)]);
    }

    #[test]
    fn relative_error_rounds_grow_and_stop() {
        let opts = MeterOptions {
            stop: Stop::RelError(0.01),
            max_samples: 1 << 20,
            ..Default::default()
        };
        let mut s = State::default();
        assert_eq!(next_target(&mut s, &opts, MIN_SAMPLES_REL), MIN_SAMPLES_REL);
        // 1024 samples with a relative ci of 4%: needs ~16× more, grows by at most 4×.
        s.taken = 1024;
        s.stats = Stats {
            n: 1024,
            mean: 1.0,
            m2: (0.04 / 1.96 * 32.0f64).powi(2) * 1023.0,
        };
        assert_eq!(next_target(&mut s, &opts, MIN_SAMPLES_REL), 4096);
        s.stats.m2 = 0.0;
        assert_eq!(next_target(&mut s, &opts, MIN_SAMPLES_REL), 1024);
        assert!(s.finished && s.capped.is_none());
    }
}
