//! The pilot of `--integrator auto`: each candidate the scene analysis leaves
//! (`integrator::auto`) runs a short session, its efficiency is measured, and the most
//! efficient one's session goes on to the end.
//!
//! **Efficiency** is 1 / (variance × cost per sample), the efficiency ε = 1/(V·T) of PBR 3ed
//! §13.7 with a cost in place of the time T. For an image the variance is the sum over pixels
//! of the variance of the pixel's luminance (`PassStats::variance`, from the even and odd
//! halves of its samples), which is n times the expected squared error of the image after n
//! samples per pixel, the quantity `tools/equal_time.sh` compares; for meters it is the sum of
//! each reading's relative variance (its variance over the square of its value, averaged over
//! the candidates); where the camera sees specular surfaces on a small part of the image, the
//! pixels that see them are left out ([`counted_pixels`]). The cost is the number of ray queries the samples made
//! (`scene::ray_count`) times the integrator's [`cost_per_ray`], not their wall-clock time:
//! it is the same on every machine and under any load, so `auto` picks the same integrator
//! for a given seed, and with `--spp` the image is bit-identical to that of the integrator it
//! picked. A later candidate must be more than [`PREFERENCE`] times as efficient as an
//! earlier one to be chosen: the candidates come in order of simplicity (path before bdpt
//! before vcm), and the pilot's figures are estimates.
//!
//! **Pilot size.** Under `--spp N` each candidate takes max(2, N/32) samples per pixel in one
//! pass (`step_to`), the same for all, rounded up to whole chunks of the splatting ones (so
//! that the pass boundary leaves their image unchanged); meters max(256, N/32) samples per
//! reading, or under `--rel-error` the first round; under `--time T` each candidate runs for
//! T/32 (and at least 2 samples per pixel, the fewest that give a variance). The winner's
//! pilot samples are its first samples (same seed, same sample indices), so its session simply
//! continues: under `--spp` the result is exactly what the chosen integrator alone gives.
//! The losers' samples are discarded, which keeps every estimate unbiased. The pilot's time
//! counts towards `--time`.

use super::checkpoint::{self, Checkpoint};
use super::image::{ImageSession, RenderOptions, DEFAULT_SPP};
use super::meter::{MeterOptions, MeterSession, Reading, Stop, BLOCK};
use super::{PassStats, Progressive};
use crate::error::{Error, Result};
use crate::integrator::auto::{candidates, Candidates, Target, SDS_DECIDES};
use crate::integrator::Integrator;
use crate::scene::analysis::specular_pixels;
use crate::scene::Scene;
use crate::sensor::meter::Meter;
use std::time::Instant;

/// The pilot's share of the run, per candidate: 1/32 of the samples or of the time.
pub const PILOT_SHARE: f64 = 1.0 / 32.0;

/// How much more efficient than the simpler candidates before it a candidate must be to be
/// chosen: 10 %, the slack the issue allows `auto` against the best fixed integrator.
pub const PREFERENCE: f64 = 1.1;

/// The time a ray query of `integrator` costs relative to one of the path tracer, for the
/// shading, connection and merging work that comes with it. Measured as ns per ray query on
/// the stages of `scenes/` and the peers' Cornell box (`tools/bench_auto.sh`,
/// `examples/auto_pilot.rs`): bdpt 0.76–1.35, vcm 0.89–2.2 (its merges cost most in closed
/// diffuse rooms); the values are round figures within those ranges (docs/design.md §9).
pub fn cost_per_ray(integrator: &Integrator) -> f64 {
    match integrator {
        Integrator::Path | Integrator::Light | Integrator::Auto { .. } => 1.0,
        Integrator::Bdpt { .. } => 1.1,
        Integrator::Vcm(_) => 1.5,
    }
}

/// What one candidate did in the pilot.
#[derive(Clone, Debug, PartialEq)]
pub struct PilotFigures {
    pub integrator: Integrator,
    /// Samples per pixel, or per reading.
    pub samples: u64,
    /// Ray queries of all its samples.
    pub rays: u64,
    pub seconds: f64,
    /// Sum over pixels (those [`counted_pixels`] keeps) of the variance of the pixel's
    /// luminance (cd/m²)², or over readings of the relative variance, of the estimate after
    /// `samples`.
    pub variance: f64,
    /// 1 / (variance × rays × [`cost_per_ray`]): higher is better (`inf` for a noiseless
    /// estimate).
    pub efficiency: f64,
}

/// What `auto` chose and why.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoReport {
    pub choice: Integrator,
    /// The analysis's reasons for the candidates.
    pub reasons: Vec<String>,
    /// Each candidate's pilot, in the order of the candidates (empty with one candidate).
    pub pilot: Vec<PilotFigures>,
    /// The pilot's size per candidate as a share of the run (samples or time).
    pub pilot_share: f64,
}

impl AutoReport {
    /// One line: `auto: bdpt (efficiency 3.1× path on a 3 % pilot)`, or the reason when
    /// there was a single candidate.
    pub fn summary(&self) -> String {
        let name = self.choice.name();
        let best = self.pilot.iter().find(|p| p.integrator == self.choice);
        let others: Vec<String> = self
            .pilot
            .iter()
            .filter(|p| p.integrator != self.choice)
            .map(|p| {
                let ratio = best.map_or(f64::NAN, |b| b.efficiency / p.efficiency);
                format!("{}× {}", ratio_text(ratio), p.integrator.name())
            })
            .collect();
        if others.is_empty() {
            return format!("auto: {name} ({})", self.reasons.join("; "));
        }
        if self.pilot.iter().any(|p| p.variance.is_infinite()) {
            return format!(
                "auto: {name} (a pilot found no light, so none was shown more efficient than \
                 the simplest on a {} % pilot)",
                percent(self.pilot_share)
            );
        }
        let behind = self.pilot.iter().any(|p| {
            best.is_some_and(|b| p.integrator != self.choice && p.efficiency > b.efficiency)
        });
        let kept = if behind {
            format!(
                ", kept as the simpler within {} %",
                percent(PREFERENCE - 1.0)
            )
        } else {
            String::new()
        };
        format!(
            "auto: {name} (efficiency {}{kept} on a {} % pilot)",
            others.join(", "),
            percent(self.pilot_share)
        )
    }
}

/// A ratio of efficiencies: two decimals near 1, where one would hide which is ahead.
fn ratio_text(r: f64) -> String {
    if !r.is_finite() {
        "∞".into()
    } else if (0.9..1.2).contains(&r) {
        format!("{r:.2}")
    } else if r < 100.0 {
        format!("{r:.1}")
    } else {
        format!("{r:.0}")
    }
}

fn percent(share: f64) -> String {
    let p = 100.0 * share;
    if p >= 10.0 || p == p.round() {
        format!("{p:.0}")
    } else {
        format!("{p:.1}")
    }
}

/// Resolves `opts.integrator` = auto for an image: the winner's session, which goes on from
/// where its pilot ended towards `opts`' target.
pub(super) fn image<'a>(scene: &'a Scene, opts: &RenderOptions) -> Result<ImageSession<'a>> {
    let Integrator::Auto { mis } = opts.integrator else {
        return ImageSession::new(scene, opts);
    };
    if opts.strategies {
        return Err(Error::option(format!(
            "strategy images need --integrator {}",
            Integrator::names_with(|c| c.strategy_images)
        )));
    }
    let clock = Instant::now();
    let Candidates {
        mut integrators,
        mut reasons,
    } = candidates(&scene.features, Target::Image, mis);
    let spp = opts.spp.map(u64::from).or(match opts.time_budget {
        Some(_) => None,
        None => Some(u64::from(DEFAULT_SPP)),
    });
    if spp == Some(1) && integrators.len() > 1 {
        integrators.truncate(1);
        reasons.push("one sample per pixel is too few to measure a variance: no pilot".into());
    }
    // Every candidate takes the same samples, whole chunks of every one.
    let quantum = integrators
        .iter()
        .map(|i| ImageSession::pause_quantum(i, scene, opts.max_depth))
        .max()
        .unwrap_or(1);
    let mut best: Option<ImageSession<'a>> = None;
    let mut best_efficiency = 0.0;
    // Whether a pilot so far found no light ([`found_light`]): then no later candidate is
    // chosen over the best so far.
    let mut blind = false;
    let mut pilot = Vec::new();
    let single = integrators.len() == 1;
    let counted = if single {
        Vec::new()
    } else {
        counted_pixels(scene)
    };
    for integrator in integrators {
        let mut o = RenderOptions {
            integrator,
            ..opts.clone()
        };
        if !single && spp.is_none() {
            o.time_budget = opts.time_budget.map(|t| t * PILOT_SHARE);
        }
        let mut session = ImageSession::new(scene, &o)?;
        if single {
            best = Some(session);
            break;
        }
        let start = Instant::now();
        let last = match spp {
            Some(n) => session.step_to(pilot_spp(n, quantum)),
            None => timed_pilot(&mut session),
        };
        let variance = found_light(
            &session,
            last.as_ref().map_or(f64::INFINITY, |s| {
                s.variance
                    .iter()
                    .zip(counted.iter().chain(std::iter::repeat(&true)))
                    .filter(|(_, c)| **c)
                    .map(|(v, _)| v)
                    .sum()
            }),
        );
        let figures = figures(
            integrator,
            session.samples(),
            session.ray_queries(),
            start.elapsed().as_secs_f64(),
            variance,
        );
        if best.is_none() || (!blind && figures.efficiency > best_efficiency * PREFERENCE) {
            best_efficiency = figures.efficiency;
            best = Some(session);
        }
        blind |= figures.variance.is_infinite();
        pilot.push(figures);
    }
    let mut session = best.ok_or_else(|| Error::option("auto found no candidate"))?;
    let report = AutoReport {
        choice: session.integrator(),
        reasons,
        pilot,
        pilot_share: PILOT_SHARE,
    };
    session.continue_after_pilot(opts.time_budget, clock, report);
    Ok(session)
}

/// The pixels whose pilot variance counts: all, or, where the camera sees specular surfaces
/// on under [`SDS_DECIDES`] of the image, those where it does not. Through such a surface a
/// camera path meets a small lamp (E S+ L) by hitting it, the one strategy for that path in
/// every integrator, of the same expected variance in all; a 2-spp pilot draws it or not, and
/// when it does the sum is 50–1500× larger (`scenes/caustic.usda`, the lamp seen through the
/// glass ball, 99.8 % of the summed variance in 0.1 % of the pixels), so that whichever
/// candidate drew it lost. The rest of the image decides, as the candidates' table says.
fn counted_pixels(scene: &Scene) -> Vec<bool> {
    let specular = specular_pixels(scene);
    let share = specular.iter().filter(|s| **s).count() as f32 / specular.len().max(1) as f32;
    if share < SDS_DECIDES {
        specular.iter().map(|s| !s).collect()
    } else {
        vec![true; specular.len()]
    }
}

/// The pilot's `variance`, or infinity when it is 0 because the pilot found no light at all
/// (a black image, as bdpt's 2-spp pilot on the prism gave before its roulette fix): such a
/// pilot measured nothing, and must not win as noiseless. Nor can a later candidate then be
/// shown more efficient than it: the efficiency 1/(V·T) (PBR 3ed §13.7) of a pilot that saw
/// no light is unknown, not 0, and [`PREFERENCE`] asks a later candidate to prove itself
/// ahead of the simpler ones. So after a black pilot the best so far is kept. On
/// `scenes/prism.usda` at 96×72 (a thin dispersed beam on a dark screen), path's 2-spp pilot
/// was black at 7 of 8 seeds and bdpt's at 5, and bdpt won "∞×" whenever its pilot drew a
/// few beam samples and path's did not (3 of 8), though path's mean MSE × CPU time over the
/// 8 seeds is 0.45× bdpt's.
fn found_light(session: &ImageSession, variance: f64) -> f64 {
    let black = variance == 0.0 && session.output().xyz.iter().all(|p| p[1] == 0.0);
    if black {
        f64::INFINITY
    } else {
        variance
    }
}

/// `opts` for continuing checkpoint `c`: with `--integrator auto`, the candidate the
/// checkpoint was rendered with (its identity names the integrator auto chose), so that a
/// resumed run takes no pilot and ends bit for bit where the uninterrupted one does. The
/// candidate whose run differs least from the checkpoint's is taken, so that
/// `ImageSession::resume` names any remaining difference. Otherwise `opts` as they are.
pub fn for_checkpoint(scene: &Scene, opts: &RenderOptions, c: &Checkpoint) -> RenderOptions {
    let Integrator::Auto { mis } = opts.integrator else {
        return opts.clone();
    };
    let Candidates { integrators, .. } = candidates(&scene.features, Target::Image, mis);
    let differences = |o: &RenderOptions| {
        let here = checkpoint::identity(scene, o);
        let there = |k: &String| c.identity.iter().find(|(key, _)| key == k).map(|p| &p.1);
        here.iter().filter(|(k, v)| there(k) != Some(v)).count()
    };
    integrators
        .into_iter()
        .map(|integrator| RenderOptions {
            integrator,
            ..opts.clone()
        })
        .min_by_key(differences)
        .unwrap_or_else(|| opts.clone())
}

/// Samples per pixel of each candidate's pilot under `--spp n`: max(2, n/32) rounded up to a
/// multiple of `quantum` (`ImageSession::pause_quantum` of every candidate), at most n.
fn pilot_spp(n: u64, quantum: u64) -> u64 {
    let k = ((n as f64 * PILOT_SHARE).ceil() as u64).max(2);
    k.div_ceil(quantum).saturating_mul(quantum).min(n)
}

/// The pilot of an image session whose time budget is the pilot's share: 2 samples per
/// pixel (the fewest that give a variance), then passes until the share is spent; its last
/// pass.
fn timed_pilot(session: &mut ImageSession) -> Option<PassStats> {
    let mut last = session.step_to(2);
    while let Some(s) = session.step() {
        last = Some(s);
    }
    last
}

fn figures(
    integrator: Integrator,
    samples: u64,
    rays: u64,
    seconds: f64,
    variance: f64,
) -> PilotFigures {
    let cost = variance * rays as f64 * cost_per_ray(&integrator);
    PilotFigures {
        integrator,
        samples,
        rays,
        seconds,
        variance,
        efficiency: if cost > 0.0 {
            1.0 / cost
        } else if cost == 0.0 {
            f64::INFINITY
        } else {
            0.0
        },
    }
}

/// Resolves `opts.integrator` = auto for light meters, as [`image`] does for an image.
pub(super) fn meters<'a>(
    scene: &'a Scene,
    meters: &[Meter],
    opts: &MeterOptions,
) -> Result<MeterSession<'a>> {
    let Integrator::Auto { mis } = opts.integrator else {
        return MeterSession::new(scene, meters, opts);
    };
    let clock = Instant::now();
    let Candidates {
        integrators,
        reasons,
    } = candidates(&scene.features, Target::Meters, mis);
    let single = integrators.len() == 1;
    let mut runs = Vec::new();
    for integrator in integrators {
        let o = MeterOptions {
            integrator,
            ..opts.clone()
        };
        let mut session = MeterSession::new(scene, meters, &o)?;
        let start = Instant::now();
        let last = if single {
            None
        } else {
            let pause = match opts.stop {
                Stop::Samples(n) => {
                    let k = ((n as f64 * PILOT_SHARE).ceil() as u64).div_ceil(BLOCK) * BLOCK;
                    k.max(BLOCK).min(n)
                }
                Stop::RelError(_) => session.first_round(),
            };
            session.step_to(pause)
        };
        let seconds = start.elapsed().as_secs_f64();
        runs.push((session, last, seconds));
    }
    let (winner, pilot) = pick_meters(&runs);
    let mut session = runs.swap_remove(winner).0;
    let report = AutoReport {
        choice: session.options().integrator,
        reasons,
        pilot,
        pilot_share: PILOT_SHARE,
    };
    session.continue_after_pilot(opts.time_budget, clock, report);
    Ok(session)
}

/// The most efficient of the meter pilots `runs` (session, last pass, seconds) and every
/// one's figures: the variance is the sum over readings of the reading's variance over the
/// square of its value averaged over the candidates (readings of 0 left out).
fn pick_meters(runs: &[(MeterSession, Option<PassStats>, f64)]) -> (usize, Vec<PilotFigures>) {
    let piloted: Vec<_> = runs
        .iter()
        .filter_map(|(s, last, t)| last.as_ref().map(|l| (s, l, *t)))
        .collect();
    if piloted.len() < runs.len() {
        return (0, Vec::new());
    }
    let readings: Vec<Vec<Reading>> = runs.iter().map(|r| r.0.readings().readings).collect();
    let reference: Vec<f64> = (0..readings[0].len())
        .map(|i| readings.iter().map(|r| r[i].value).sum::<f64>() / runs.len() as f64)
        .collect();
    let mut pilot = Vec::new();
    let mut best: Option<(usize, f64)> = None;
    for (k, (session, last, seconds)) in piloted.into_iter().enumerate() {
        let variance: f64 = last
            .variance
            .iter()
            .zip(&reference)
            .filter(|(_, r)| **r != 0.0)
            .map(|(v, r)| v / (r * r))
            .sum();
        let samples = readings[k].first().map_or(0, |r| r.samples);
        let f = figures(
            session.options().integrator,
            samples,
            session.ray_queries(),
            seconds,
            variance,
        );
        if best.is_none_or(|(_, e)| f.efficiency > e * PREFERENCE) {
            best = Some((k, f.efficiency));
        }
        pilot.push(f);
    }
    (best.map_or(0, |b| b.0), pilot)
}
