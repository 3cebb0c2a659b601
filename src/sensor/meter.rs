//! Light meters: illuminance (lx) on a virtual surface and luminance (cd/m²) along a ray,
//! with a 95% confidence interval. They are sensors, like Mitsuba 3's `irradiancemeter` and
//! `radiancemeter`: the path tracer (`integrator::meter`, the default), light tracing or BDPT
//! (`integrator::meter_bidir`, with the meter as the sensor of `point.rs`) estimates them
//! ([`MeterOptions::integrator`]), and nothing but the rays they need is traced — there is no
//! film. Light tracing cannot estimate luminance ([`check_integrator`]).
//!
//! A reading is the mean of independent per-sample estimates of the photometric quantity
//! (K_m ∫ E(λ) ȳ(λ) dλ from one set of hero wavelengths, `spectral::xyz::sampled_to_xyz`).
//! Sample `s` of meter `i` draws its random numbers from `Sampler::new(seed, i, s)`, and
//! samples are accumulated in blocks of [`BLOCK`] merged in sample order ([`Stats`]), so
//! readings are bit-identical for any number of threads (a `time_budget` aside, which stops
//! at a wall-clock moment).
//!
//! **Confidence interval.** ci95 = 1.96·s/√n, the normal approximation of the sample mean.
//! With [`Stop::RelError`] readings are refined in rounds until ci95/value is below the target
//! or a cap (samples per reading, wall time) is hit; every reading takes at least
//! [`MIN_SAMPLES_REL`] samples first so that s is not judged on a handful of samples. The
//! interval is checked for coverage on heavy-tailed cases in `tests/meters.rs`.
//!
//! ```
//! use spectral_render::scene::{build, desc::*};
//! use spectral_render::sensor::meter::{measure, Meter, MeterOptions, Stop};
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
//! });
//! let scene = build(&desc, Some((1, 1))).unwrap();
//! let meter = Meter::illuminance(Vec3::ZERO, Vec3::Y).unwrap();
//! let opts = MeterOptions { stop: Stop::Samples(256), ..Default::default() };
//! let reading = measure(&scene, &[meter], &opts).unwrap().readings[0];
//! assert!((reading.value / 1000.0 - 1.0).abs() < 0.02);
//! ```

pub mod point;
pub mod stats;

pub use point::MeterSensor;
pub use stats::Stats;

use crate::integrator::bidir::Workspace;
use crate::integrator::meter::MeterIntegrator;
use crate::integrator::meter_bidir::BidirMeter;
use crate::integrator::{IntegratorKind, MisHeuristic, PathIntegrator};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::spectral::{xyz::sampled_to_xyz, SampledWavelengths};
use crate::texture::TextureFilter;
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// Samples per block of work (the unit of parallelism and of merging).
pub const BLOCK: u64 = 256;
/// Samples every reading takes before its interval is trusted under [`Stop::RelError`].
pub const MIN_SAMPLES_REL: u64 = 1024;
/// Samples per reading when neither a count nor a relative error is asked for.
pub const DEFAULT_SAMPLES: u64 = 4096;
/// Default cap on the samples of one reading under [`Stop::RelError`].
pub const DEFAULT_MAX_SAMPLES: u64 = 1 << 24;
/// Error bound given to a meter point, relative to the scene's extent (see [`origin_error`]):
/// 2⁻¹⁸ ≈ 3.8·10⁻⁶.
pub const ORIGIN_ERROR_REL: f32 = 1.0 / 262_144.0;

/// What a meter measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeterKind {
    /// Illuminance in lx on a surface with the meter's normal.
    Illuminance,
    /// Luminance in cd/m² arriving from the meter's direction.
    Luminance,
}

impl MeterKind {
    pub fn name(&self) -> &'static str {
        match self {
            MeterKind::Illuminance => "illuminance",
            MeterKind::Luminance => "luminance",
        }
    }

    pub fn unit(&self) -> &'static str {
        match self {
            MeterKind::Illuminance => "lx",
            MeterKind::Luminance => "cd/m2",
        }
    }
}

/// One meter in world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Meter {
    pub kind: MeterKind,
    pub p: Vec3,
    /// Unit normal of the receiving surface (illuminance) or the direction the meter looks
    /// along (luminance).
    pub dir: Vec3,
}

impl Meter {
    /// An illuminance meter at `p` on a surface facing `normal` (any non-zero length).
    pub fn illuminance(p: Vec3, normal: Vec3) -> Result<Meter, String> {
        Meter::new(MeterKind::Illuminance, p, normal)
    }

    /// A luminance meter at `p` looking along `dir` (any non-zero length).
    pub fn luminance(p: Vec3, dir: Vec3) -> Result<Meter, String> {
        Meter::new(MeterKind::Luminance, p, dir)
    }

    fn new(kind: MeterKind, p: Vec3, dir: Vec3) -> Result<Meter, String> {
        if !p.is_finite() {
            return Err(format!("the meter position {p} is not finite"));
        }
        let unit = dir.normalize_or_zero();
        if unit == Vec3::ZERO || !unit.is_finite() {
            return Err(format!("the meter direction {dir} has no length"));
        }
        Ok(Meter { kind, p, dir: unit })
    }
}

/// A point given in stage coordinates (stage units, stage up axis), in world space.
pub fn stage_point(stage_to_world: &DMat4, p: DVec3) -> Vec3 {
    stage_to_world.transform_point3(p).as_vec3()
}

/// A direction given in stage coordinates, in world space (not normalised).
pub fn stage_vector(stage_to_world: &DMat4, v: DVec3) -> Vec3 {
    stage_to_world.transform_vector3(v).as_vec3()
}

/// A surface normal given in stage coordinates, in world space: transformed by the inverse
/// transpose (PBR 4ed §3.10.3), which for the stage's scale·rotation is the rotation.
pub fn stage_normal(stage_to_world: &DMat4, n: DVec3) -> Vec3 {
    stage_to_world
        .inverse()
        .transpose()
        .transform_vector3(n)
        .as_vec3()
}

/// The per-axis error bound given to a meter point, which has none of its own: the rays it
/// spawns leave from `p` moved along the normal (or view direction) by about this much
/// (`geometry::offset`). 2⁻¹⁸ of the scene's extent (bounding sphere or |p|, whichever is
/// larger) is 64 ulps of f32 at that magnitude: some 40 times the error bound of a ray hit on
/// the scene's largest triangles (PBR 4ed §6.8.3, γ₇·Σ|bᵢpᵢ|), so a meter typed on a floor,
/// a transformed wall or a surface converted from stage units starts above it, while the
/// change of geometry stays negligible (4 mm for a 1 km ground plane, 20 µm in a 5 m room).
/// The offset is along the meter's normal, so a meter lying on a surface must face away from
/// it (as a real sensor would); one lying in a floor with a sideways normal is ambiguous.
pub fn origin_error(scene: &Scene, p: Vec3) -> Vec3 {
    let extent = scene.center.abs().max_element() + scene.radius;
    Vec3::splat(ORIGIN_ERROR_REL * extent.max(p.abs().max_element()))
}

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
    pub max_depth: u32,
    pub threads: Option<usize>,
    /// The estimator: path tracing (default), light tracing or BDPT.
    pub integrator: IntegratorKind,
    /// The MIS heuristic of BDPT.
    pub mis: MisHeuristic,
}

impl Default for MeterOptions {
    fn default() -> Self {
        MeterOptions {
            stop: Stop::Samples(DEFAULT_SAMPLES),
            max_samples: DEFAULT_MAX_SAMPLES,
            time_budget: None,
            seed: 0,
            max_depth: 7,
            threads: None,
            integrator: IntegratorKind::Path,
            mis: MisHeuristic::Power,
        }
    }
}

/// Refuses what an integrator cannot estimate: a luminance meter is a delta sensor (one
/// point, one direction), which light tracing's connections (t = 1) reach with probability 0.
pub fn check_integrator(kind: MeterKind, integrator: IntegratorKind) -> Result<(), String> {
    if kind == MeterKind::Luminance && integrator == IntegratorKind::Light {
        return Err(
            "a luminance meter is a delta sensor (one point, one direction) that light \
                    tracing can never connect to; use --integrator path or bdpt"
                .into(),
        );
    }
    Ok(())
}

/// What stopped a reading before its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cap {
    /// `max_samples` under [`Stop::RelError`].
    Samples,
    /// The time budget.
    Time,
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
}

/// The readings of a run, in the order of the meters.
#[derive(Clone, Debug)]
pub struct MeterRun {
    pub readings: Vec<Reading>,
    /// Samples whose estimate was NaN or infinite and were dropped (should be 0).
    pub dropped: u64,
    pub wall_time_s: f64,
}

/// Measures every meter on a thread pool of `opts.threads` workers.
pub fn measure(scene: &Scene, meters: &[Meter], opts: &MeterOptions) -> Result<MeterRun, String> {
    for m in meters {
        check_integrator(m.kind, opts.integrator)?;
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = opts.threads {
        builder = builder.num_threads(n.max(1));
    }
    let pool = builder
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    Ok(pool.install(|| measure_in_pool(scene, meters, opts)))
}

/// Where one reading stands.
#[derive(Clone, Copy, Debug, Default)]
struct State {
    stats: Stats,
    /// Sample indices used so far (finite or not).
    taken: u64,
    finished: bool,
    capped: Option<Cap>,
}

/// Samples [first, end) of one meter.
#[derive(Clone, Copy, Debug)]
struct Block {
    meter: usize,
    first: u64,
    end: u64,
}

/// The per-sample estimator of a run.
#[derive(Clone, Copy)]
enum Estimator<'a> {
    Path(MeterIntegrator),
    Bidir(BidirMeter<'a>),
}

impl<'a> Estimator<'a> {
    fn new(scene: &'a Scene, opts: &MeterOptions) -> Estimator<'a> {
        let path = MeterIntegrator {
            path: PathIntegrator {
                max_depth: opts.max_depth,
                filter: TextureFilter::Finest,
            },
        };
        match BidirMeter::new(scene, opts.integrator, opts.mis, opts.max_depth) {
            Some(b) => Estimator::Bidir(b),
            None => Estimator::Path(path),
        }
    }

    /// One sample of meter `m`: its photometric Y (lx or cd/m²), which may be non-finite.
    fn sample(
        &self,
        scene: &Scene,
        m: &MeterSensor,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> f32 {
        let mut lambda = SampledWavelengths::sample_visible(sampler.get_1d());
        let l = match (self, m.kind) {
            (Estimator::Path(pt), MeterKind::Illuminance) => {
                pt.irradiance(scene, m.p, m.p_error, m.dir, &lambda, sampler)
            }
            (Estimator::Path(pt), MeterKind::Luminance) => {
                pt.radiance(scene, m.p, m.p_error, m.dir, &lambda, sampler)
            }
            (Estimator::Bidir(b), _) => b.sample(m, &mut lambda, sampler, ws),
        };
        // With the final wavelengths: a termination applies to the whole estimate.
        sampled_to_xyz(l, &lambda)[1]
    }
}

fn measure_in_pool(scene: &Scene, meters: &[Meter], opts: &MeterOptions) -> MeterRun {
    let start = Instant::now();
    let estimator = Estimator::new(scene, opts);
    let sensors: Vec<MeterSensor> = meters
        .iter()
        .map(|m| MeterSensor::new(m, origin_error(scene, m.p)))
        .collect();
    let mut states = vec![State::default(); meters.len()];
    let mut dropped = 0;
    loop {
        let mut targets: Vec<u64> = states.iter_mut().map(|s| next_target(s, opts)).collect();
        if !fit_time_budget(&mut states, &mut targets, opts, start) {
            break;
        }
        let blocks = blocks(&states, &targets);
        if blocks.is_empty() {
            break;
        }
        let results: Vec<(Stats, u64)> = blocks
            .par_iter()
            .map_init(
                || Workspace::new(opts.max_depth, 0),
                |ws, b| sample_block(scene, &estimator, &sensors[b.meter], b, opts.seed, ws),
            )
            .collect();
        for (b, (stats, bad)) in blocks.iter().zip(results) {
            let st = &mut states[b.meter];
            st.stats.merge(&stats);
            st.taken = b.end;
            dropped += bad;
        }
    }
    MeterRun {
        readings: states.iter().map(reading).collect(),
        dropped,
        wall_time_s: start.elapsed().as_secs_f64(),
    }
}

fn reading(s: &State) -> Reading {
    Reading {
        value: s.stats.mean,
        ci95: s.stats.ci95(),
        samples: s.stats.n,
        capped: s.capped,
    }
}

/// The sample count a reading should reach in the next round (its current count when it is
/// finished). Under a relative-error target the count needed is extrapolated from
/// ci95 ∝ 1/√n with 20% to spare, at most ×4 per round (the variance estimate of a
/// heavy-tailed estimator can be far off early), rounded to whole blocks.
fn next_target(s: &mut State, opts: &MeterOptions) -> u64 {
    if s.finished {
        return s.taken;
    }
    let timed = opts.time_budget.is_some();
    let target = match opts.stop {
        Stop::Samples(n) if s.taken >= n => None,
        // Under a time budget, growing rounds so that the budget is checked often.
        Stop::Samples(n) if timed => Some(n.min(round_up((2 * s.taken).max(BLOCK)))),
        Stop::Samples(n) => Some(n),
        Stop::RelError(_) if s.taken < MIN_SAMPLES_REL.min(opts.max_samples) => {
            Some(MIN_SAMPLES_REL.min(opts.max_samples))
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
    if (wanted as f64) <= affordable {
        return true;
    }
    let scale = affordable / wanted as f64;
    for (s, t) in states.iter().zip(targets.iter_mut()) {
        if *t > s.taken {
            let more = round_up((((*t - s.taken) as f64) * scale) as u64).max(BLOCK);
            *t = (*t).min(s.taken + more);
        }
    }
    true
}

/// The round's work: for each reading, the blocks from its current count to its target.
fn blocks(states: &[State], targets: &[u64]) -> Vec<Block> {
    let mut out = Vec::new();
    for (meter, (s, &target)) in states.iter().zip(targets).enumerate() {
        let mut first = s.taken;
        while first < target {
            let end = (first / BLOCK + 1).saturating_mul(BLOCK).min(target);
            out.push(Block { meter, first, end });
            first = end;
        }
    }
    out
}

/// The statistics of one block of samples and the number of non-finite ones dropped.
fn sample_block(
    scene: &Scene,
    estimator: &Estimator,
    m: &MeterSensor,
    b: &Block,
    seed: u64,
    ws: &mut Workspace,
) -> (Stats, u64) {
    let mut stats = Stats::default();
    let mut dropped = 0;
    for s in b.first..b.end {
        let mut sampler = Sampler::new(seed, b.meter as u64, s);
        let y = estimator.sample(scene, m, &mut sampler, ws);
        if y.is_finite() {
            stats.push(f64::from(y));
        } else {
            dropped += 1;
        }
    }
    (stats, dropped)
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
        let b = blocks(&states, &[700, 100]);
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
        assert_eq!(next_target(&mut s, &opts), MIN_SAMPLES_REL);
        // 1024 samples with a relative ci of 4%: needs ~16× more, grows by at most 4×.
        s.taken = 1024;
        s.stats = Stats {
            n: 1024,
            mean: 1.0,
            m2: (0.04 / 1.96 * 32.0f64).powi(2) * 1023.0,
        };
        assert_eq!(next_target(&mut s, &opts), 4096);
        s.stats.m2 = 0.0;
        assert_eq!(next_target(&mut s, &opts), 1024);
        assert!(s.finished && s.capped.is_none());
    }

    #[test]
    fn stage_conversion_of_a_z_up_centimetre_stage() {
        // S(0.01) · R where R takes (x, y, z) to (x, z, −y).
        let m = DMat4::from_scale(DVec3::splat(0.01))
            * DMat4::from_cols(
                glam::DVec4::X,
                glam::DVec4::NEG_Z,
                glam::DVec4::Y,
                glam::DVec4::W,
            );
        let p = stage_point(&m, DVec3::new(100.0, 200.0, 300.0));
        assert!((p - Vec3::new(1.0, 3.0, -2.0)).length() < 1e-6, "{p}");
        let n = stage_normal(&m, DVec3::Z).normalize();
        assert!((n - Vec3::Y).length() < 1e-6, "{n}");
    }
}
