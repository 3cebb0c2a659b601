//! A reference image rendered here, with its own noise measured.
//!
//! **Which integrator.** Without `--reference-integrator`, BDPT when it renders everything in
//! the scene (`Integrator::warnings`), else the path tracer. BDPT's MIS combination holds the
//! path tracer's and light tracing's techniques, so it is never far behind the better of
//! them and finds what either one misses (light through a door gap, caustics from small
//! lamps). A pilot run choosing by measured variance cannot see what an integrator never
//! finds: on scenes/gap.usda an 8 s pilot rated the path tracer most efficient because it had
//! not yet found the light's rare paths through the gap.
//!
//! **Its noise.** The reference is the mean of two independent halves A and B (different
//! seeds, the same sample count); (A − B)²/4 per pixel and channel is an unbiased estimate of
//! the variance of their mean, for R, G, B and Y alike, whatever the integrator. That is what
//! `metrics` subtracts. It is written with the reference (`variance.R`, … channels).

use super::metrics::{Reference, ReferenceVariance};
use super::{Clock, RunOptions};
use crate::error::Result;
use crate::integrator::Integrator;
use crate::sampling::SamplerKind;
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
    /// The sampler both halves drew from.
    pub sampler: Option<SamplerKind>,
    /// The path tracer's roulette start (`RenderOutput::rr_depth`), when both halves took
    /// the same.
    pub rr_depth: Option<u32>,
    /// The path tracer's split (`RenderOutput::split`), when both halves took the same.
    pub split: Option<u32>,
}

/// The integrator of a reference of `scene`'s image when none is named (module docs).
pub fn default_integrator(scene: &Scene) -> Integrator {
    let bdpt = Integrator::from_name("bdpt").unwrap_or_default();
    if bdpt.warnings(scene, true).is_empty() {
        bdpt
    } else {
        Integrator::Path
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
        sampler: opts.sampler,
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
        sampler: a.sampler,
        rr_depth: a.rr_depth.filter(|_| a.rr_depth == b.rr_depth),
        split: a.split.filter(|_| a.split == b.split),
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
