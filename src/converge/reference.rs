//! A reference image rendered here, with its own noise measured.
//!
//! **Which integrator.** Without `--reference-integrator`, a short pilot run of each
//! candidate (the unbiased integrators that render the scene completely, `Capabilities`)
//! measures its efficiency 1 / (V·t), V the mean relative variance of the pixels' luminance
//! over the unmasked pixels (the film's even/odd estimate, `sensor::film`), and the most
//! efficient one renders the reference. A variance-based choice cannot see what an
//! integrator misses entirely (a caustic path tracing never finds has no variance), so scenes
//! like that should name the integrator.
//!
//! **Its noise.** The reference is the mean of two independent halves A and B (different
//! seeds, the same sample count); (A − B)²/4 per pixel and channel is an unbiased estimate of
//! the variance of their mean, for R, G, B and Y alike, whatever the integrator. That is what
//! `metrics` subtracts. It is written with the reference (`variance.R`, … channels).

use super::metrics::{Reference, ReferenceVariance, REL_MSE_OFFSET};
use super::{Clock, RunOptions};
use crate::error::Result;
use crate::integrator::Integrator;
use crate::scene::Scene;
use crate::session::{ImageSession, Progressive, RenderOptions, RenderOutput};

/// Seeds of the reference's halves, far from the configurations' seeds.
const SEED_A: u64 = 0x5eed_0000_0000_000a;
const SEED_B: u64 = 0x5eed_0000_0000_000b;

/// How a reference was made.
#[derive(Clone, Debug)]
pub struct ReferenceInfo {
    pub integrator: Integrator,
    /// Samples per pixel of each half.
    pub spp_per_half: u64,
    /// Measured wall time of both halves, seconds.
    pub time_s: f64,
    /// The pilot's measured efficiency per candidate (name, 1/(V·t)), when there was one.
    pub pilot: Vec<(String, f64)>,
}

/// The candidates for a reference of `scene`'s image: unbiased integrators that render
/// everything in it (no `Integrator::warnings`).
pub fn candidates(scene: &Scene) -> Vec<Integrator> {
    Integrator::ALL
        .into_iter()
        .filter(|i| i.capabilities().unbiased && i.warnings(scene, true).is_empty())
        .collect()
}

/// The most efficient of `candidates` after `pilot_s` seconds each, with every candidate's
/// measured efficiency.
pub fn pilot(
    scene: &Scene,
    candidates: &[Integrator],
    pilot_s: f64,
    opts: &RunOptions,
    masked: &[bool],
) -> Result<(Integrator, Vec<(String, f64)>)> {
    let mut scores = Vec::new();
    for &integrator in candidates {
        let mut clock = Clock::default();
        let ro = RenderOptions {
            time_budget: Some(pilot_s),
            seed: opts.seed,
            threads: opts.threads,
            max_depth: opts.max_depth,
            integrator,
            filter_textures: opts.filter_textures,
            ..RenderOptions::default()
        };
        let mut session = clock.time(|| ImageSession::new(scene, &ro))?;
        let mut variance = Vec::new();
        while let Some(stats) = clock.time(|| session.step()) {
            variance = stats.variance;
        }
        let y: Vec<f32> = session.output().xyz.iter().map(|p| p[1]).collect();
        let v = relative_variance(&y, &variance, masked);
        scores.push((
            integrator,
            1.0 / (v * clock.seconds()).max(f64::MIN_POSITIVE),
        ));
    }
    let best = scores
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(Integrator::Path, |s| s.0);
    let named = scores
        .iter()
        .map(|(i, e)| (i.name().to_string(), *e))
        .collect();
    Ok((best, named))
}

/// Mean of var(Y)/(Y² + 0.01) over the unmasked pixels (all pixels when all are masked).
fn relative_variance(y: &[f32], variance: &[f64], masked: &[bool]) -> f64 {
    let keep = |i: usize| !masked[i] || masked.iter().all(|&m| m);
    let (sum, n) = (0..y.len())
        .filter(|&i| keep(i) && variance.get(i).is_some_and(|v| v.is_finite()))
        .fold((0.0, 0u64), |(s, n), i| {
            let r = f64::from(y[i]);
            (s + variance[i] / (r * r + REL_MSE_OFFSET), n + 1)
        });
    if n == 0 {
        f64::INFINITY
    } else {
        sum / n as f64
    }
}

/// Renders the reference with `integrator` in about `time_s` seconds: half A to half the
/// budget, half B to A's sample count.
pub fn render(
    scene: &Scene,
    integrator: Integrator,
    time_s: f64,
    opts: &RunOptions,
) -> Result<(Reference, ReferenceInfo)> {
    let mut clock = Clock::default();
    let ro = |seed| RenderOptions {
        time_budget: Some(time_s / 2.0),
        seed,
        threads: opts.threads,
        max_depth: opts.max_depth,
        integrator,
        filter_textures: opts.filter_textures,
        ..RenderOptions::default()
    };
    let mut a = clock.time(|| ImageSession::new(scene, &ro(SEED_A)))?;
    clock.time(|| while a.step().is_some() {});
    let a = a.output();
    let mut b = clock.time(|| ImageSession::new(scene, &ro(SEED_B)))?;
    clock.time(|| b.step_to(a.spp));
    let b = b.output();
    let info = ReferenceInfo {
        integrator,
        spp_per_half: a.spp,
        time_s: clock.seconds(),
        pilot: Vec::new(),
    };
    Ok((from_halves(&a, &b), info))
}

/// The mean of two independent renders and the variance of that mean, (a − b)²/4.
pub fn from_halves(a: &RenderOutput, b: &RenderOutput) -> Reference {
    let mean = |x: f32, y: f32| 0.5 * (x + y);
    let var = |x: f32, y: f32| 0.25 * (x - y) * (x - y);
    let zip3 = |f: &dyn Fn(f32, f32) -> f32, p: &[f32; 3], q: &[f32; 3]| {
        [f(p[0], q[0]), f(p[1], q[1]), f(p[2], q[2])]
    };
    let pairs = || a.rgb.iter().zip(&b.rgb);
    let y_pairs = || a.xyz.iter().zip(&b.xyz);
    Reference {
        width: a.width,
        height: a.height,
        rgb: pairs().map(|(p, q)| zip3(&mean, p, q)).collect(),
        y: y_pairs().map(|(p, q)| mean(p[1], q[1])).collect(),
        variance: Some(ReferenceVariance {
            rgb: pairs().map(|(p, q)| zip3(&var, p, q)).collect(),
            y: y_pairs().map(|(p, q)| var(p[1], q[1])).collect(),
        }),
    }
}
