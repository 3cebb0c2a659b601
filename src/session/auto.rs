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
//! earlier one to be chosen: the candidates come in the analysis's order of preference
//! (path before bdpt by simplicity; vcm before bdpt for point-like caustics, where it is the
//! robust one), and the pilot's figures are estimates. Where the first is the robust one
//! (`Candidates::proof`) a later one must be *shown* so: the lower end of the 95 % interval of
//! its efficiency ratio, from the pixel variances summed over blocks ([`efficiency_interval`]),
//! above [`PREFERENCE`].
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
use crate::math::ratio::RatioSums;
use crate::math::Z95;
use crate::scene::analysis::{emitter_pixels, specular_pixels};
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
    /// For an image's later candidate that must be shown ahead (`Candidates::proof`), the
    /// 95 % interval of its efficiency over that of the best candidate before it
    /// ([`efficiency_interval`]); otherwise `None`.
    pub interval: Option<[f64; 2]>,
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
    /// One line: `auto: bdpt (efficiency 3.1× path, 95 % interval 2.0–4.5× on a 3 % pilot)`,
    /// or the reason when there was a single candidate.
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
                 the first candidate on a {} % pilot)",
                percent(self.pilot_share)
            );
        }
        let ahead = self.pilot.iter().find(|p| {
            best.is_some_and(|b| p.integrator != self.choice && p.efficiency > b.efficiency)
        });
        let kept = match ahead.and_then(|p| p.interval) {
            Some([lo, hi]) => format!(
                ", kept: {}'s lead not shown, its 95 % interval {}–{}×",
                ahead.map_or("", |p| p.integrator.name()),
                ratio_text(lo),
                ratio_text(hi)
            ),
            _ if ahead.is_some() => format!(", kept within {} %", percent(PREFERENCE - 1.0)),
            _ => match best.and_then(|b| b.interval) {
                Some([lo, hi]) => format!(", 95 % interval {}–{}×", ratio_text(lo), ratio_text(hi)),
                None => String::new(),
            },
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
        proof,
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
    let mut best: Option<(ImageSession<'a>, Measured)> = None;
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
    let width = scene.camera.width as usize;
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
            best = Some((session, Measured::default()));
            break;
        }
        let start = Instant::now();
        let last = match spp {
            Some(n) => session.step_to(pilot_spp(n, quantum)),
            None => timed_pilot(&mut session),
        };
        let blocks = last
            .as_ref()
            .map_or_else(Vec::new, |s| block_sums(&s.variance, &counted, width));
        let variance = found_light(
            &session,
            last.as_ref().map_or(f64::INFINITY, |_| blocks.iter().sum()),
        );
        let mut figures = figures(
            integrator,
            session.samples(),
            session.ray_queries(),
            start.elapsed().as_secs_f64(),
            variance,
        );
        let measured = Measured {
            cost: session.ray_queries() as f64 * cost_per_ray(&integrator),
            blocks,
        };
        let wins = match &best {
            None => true,
            Some((_, b)) => !blind && challenge(b, &measured, &mut figures, proof),
        };
        if wins {
            best = Some((session, measured));
        }
        blind |= figures.variance.is_infinite();
        pilot.push(figures);
    }
    let mut session = best
        .map(|b| b.0)
        .ok_or_else(|| Error::option("auto found no candidate"))?;
    let report = AutoReport {
        choice: session.integrator(),
        reasons,
        pilot,
        pilot_share: PILOT_SHARE,
    };
    session.continue_after_pilot(opts.time_budget, clock, report);
    Ok(session)
}

/// Side of the square pixel blocks whose summed pilot variances are the sampling units of
/// [`efficiency_interval`]: 108 blocks at the benchmark's 96 × 72, 20 at 40 × 30. The
/// pixels' noise is independent, so any grouping estimates the same standard error; small
/// blocks give the interval more degrees of freedom, and 8 × 8 keeps them above a few even
/// on small images. A choice, not a derived value.
const BLOCK_SIDE: usize = 8;

/// What [`efficiency_interval`] needs of a candidate's image pilot.
#[derive(Clone, Debug, Default)]
struct Measured {
    /// Ray queries × [`cost_per_ray`].
    cost: f64,
    /// [`block_sums`] of its pilot's pixel variances.
    blocks: Vec<f64>,
}

impl Measured {
    fn variance(&self) -> f64 {
        self.blocks.iter().sum()
    }
}

/// The pilot variances `variance` of the pixels `counted` keeps (all where `counted` is
/// shorter), summed over blocks of [`BLOCK_SIDE`]² pixels of an image `width` wide, in a fixed
/// order; blocks without a counted pixel are left out, so that every candidate's blocks are
/// the same pixels.
fn block_sums(variance: &[f64], counted: &[bool], width: usize) -> Vec<f64> {
    let width = width.max(1);
    let across = width.div_ceil(BLOCK_SIDE);
    let rows = variance.len().div_ceil(width).div_ceil(BLOCK_SIDE);
    let mut sums = vec![0.0; across * rows];
    let mut used = vec![false; across * rows];
    for (i, v) in variance.iter().enumerate() {
        if !counted.get(i).copied().unwrap_or(true) {
            continue;
        }
        let b = (i / width / BLOCK_SIDE) * across + (i % width) / BLOCK_SIDE;
        sums[b] += v;
        used[b] = true;
    }
    sums.into_iter()
        .zip(used)
        .filter_map(|(s, u)| u.then_some(s))
        .collect()
}

/// The 95 % interval of the efficiency of `challenger` over that of `best`, both image
/// pilots over the same blocks: (V_b C_b) / (V_c C_c) with V the summed variance and C the
/// cost. The costs are counted exactly; the uncertainty is in the ratio of the variance totals
/// R = Σ b_k / Σ c_k over the K blocks, whose standard error is that of the ratio estimator
/// of survey sampling (`math::ratio`, Cochran 1977 §6.4, with the blocks as the sampling
/// units), with Student's t at K − 1 degrees of freedom ([`t_95`]). Pairing the blocks removes
/// what the two images share (where the scene is bright, both are noisy); what remains is how
/// unevenly the variances are spread: where a few blocks carry most of either total (a
/// caustic's rare, enormous samples), the interval is wide. Infinite when the challenger's
/// variance is 0 (a noiseless estimate), (0, ∞) when there are fewer than 2 blocks.
fn efficiency_interval(best: &Measured, challenger: &Measured) -> (f64, f64) {
    let mut sums = RatioSums::default();
    (best.blocks.iter().zip(&challenger.blocks)).for_each(|(&b, &c)| sums.push(b, c));
    let (sb, sc) = (best.variance(), challenger.variance());
    if sc == 0.0 {
        return (f64::INFINITY, f64::INFINITY);
    }
    if sums.n < 2 || challenger.cost <= 0.0 || !(sb.is_finite() && sc.is_finite()) {
        return (0.0, f64::INFINITY);
    }
    let r = sb / sc;
    let half = t_95(sums.n as f64 - 1.0) * sums.standard_error();
    let costs = best.cost / challenger.cost;
    (costs * (r - half).max(0.0), costs * (r + half))
}

/// The two-sided 95 % point of Student's t at `nu` degrees of freedom, by the expansion of
/// Abramowitz & Stegun 26.7.5 about the normal point, to the ν⁻³ term (0.7 % below the table
/// at 3 degrees of freedom, 0.1 % at 5, less beyond).
fn t_95(nu: f64) -> f64 {
    let z = Z95;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    let g1 = (z3 + z) / 4.0;
    let g2 = (5.0 * z5 + 16.0 * z3 + 3.0 * z) / 96.0;
    let g3 = (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / 384.0;
    z + g1 / nu + g2 / (nu * nu) + g3 / (nu * nu * nu)
}

/// Whether a later candidate whose efficiency is `ratio` times the best before it, with a
/// 95 % interval from `low`, is chosen: with `proof` ([`Candidates::proof`]) when it is shown
/// more than [`PREFERENCE`] times as efficient (`low` above it: a one-sided test at 2.5 %),
/// otherwise when it is estimated so (`ratio` above it). Else the earlier one is kept, the
/// candidates' order being the static analysis's preference (`integrator::auto`).
fn shown_ahead(ratio: f64, low: f64, proof: bool) -> bool {
    if proof {
        low > PREFERENCE
    } else {
        ratio > PREFERENCE
    }
}

/// Whether a later candidate's image pilot (`measured`, `figures`) is chosen over the best
/// before it ([`shown_ahead`], with or without `proof`); its efficiency interval goes into
/// `figures`. A pilot that found no light (infinite variance) is never chosen.
fn challenge(
    best: &Measured,
    measured: &Measured,
    figures: &mut PilotFigures,
    proof: bool,
) -> bool {
    let (lo, hi) = efficiency_interval(best, measured);
    if proof {
        figures.interval = Some([lo, hi]);
    }
    let ratio = figures.efficiency * best.variance() * best.cost;
    figures.variance.is_finite() && shown_ahead(ratio, lo, proof)
}

/// The pixels whose pilot variance counts. Not those in or beside which the camera sees an
/// emitter (`scene::analysis::emitter_pixels`): their noise is mostly the pixel filter's over
/// the emitter's rim, which the render's low-discrepancy samples remove far faster than a
/// 2-spp pilot's variance says (on `scenes/cornell-box.usda` at 96 × 72 and 32 spp, path's
/// MSE is 6.9× lower with zsobol than with independent numbers on the whole image, 1.5×
/// without the lamp's pixels), and bdpt's light tracing renders without it; counted, they made
/// path's pilot variance 22× bdpt's where the two images' MSE differ by 3.8× (docs/design.md,
/// "The criterion in the `converge` report's measure"). The `converge` report's masked error
/// leaves them out too. And, where the camera sees specular surfaces on under
/// [`SDS_DECIDES`] of the image, not those that see them. Through such a surface a camera path
/// meets a small lamp (E S+ L) by hitting it, the one strategy for that path in every
/// integrator, of the same expected variance in all; a 2-spp pilot draws it or not, and when
/// it does the sum is 50–1500× larger (`scenes/caustic.usda`, the lamp seen through the glass
/// ball, 99.8 % of the summed variance in 0.1 % of the pixels), so that whichever candidate
/// drew it lost. The rest of the image decides, as the candidates' table says.
fn counted_pixels(scene: &Scene) -> Vec<bool> {
    let specular = specular_pixels(scene);
    let share = specular.iter().filter(|s| **s).count() as f32 / specular.len().max(1) as f32;
    let skip_specular = share < SDS_DECIDES;
    (specular.iter().zip(emitter_pixels(scene)))
        .map(|(s, e)| !(e || skip_specular && *s))
        .collect()
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
        interval: None,
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
        ..
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_sum_the_counted_pixels_of_each_square() {
        // 10 × 9 pixels: 2 × 2 blocks of 8 (the right and bottom ones partial).
        let variance: Vec<f64> = (0..90).map(|i| i as f64).collect();
        let all = block_sums(&variance, &[], 10);
        assert_eq!(all.len(), 4);
        assert_eq!(all.iter().sum::<f64>(), variance.iter().sum::<f64>());
        let top_left: f64 = (0..8)
            .flat_map(|y| (0..8).map(move |x| (y * 10 + x) as f64))
            .sum();
        assert_eq!(all[0], top_left);
        assert_eq!(all[3], 88.0 + 89.0);
        // Leaving out the bottom row leaves out the bottom blocks.
        let counted: Vec<bool> = (0..90).map(|i| i < 80).collect();
        assert_eq!(block_sums(&variance, &counted, 10), all[..2]);
    }

    #[test]
    fn t_matches_the_table() {
        // Student's t, two-sided 95 %: 3.182, 2.571, 2.228, 2.093 (any table).
        for (nu, t) in [(3.0, 3.1824), (5.0, 2.5706), (10.0, 2.2281), (19.0, 2.0930)] {
            assert!((t_95(nu) / t - 1.0).abs() < 0.008, "{nu}: {}", t_95(nu));
        }
        assert!((t_95(1e9) - Z95).abs() < 1e-6);
    }

    fn measured(cost: f64, blocks: &[f64]) -> Measured {
        Measured {
            cost,
            blocks: blocks.to_vec(),
        }
    }

    #[test]
    fn the_interval_is_narrow_for_even_variances_and_wide_for_a_few_large_ones() {
        // The challenger's variance is half the best's in every block, at equal cost: its
        // efficiency is 2×, and nothing varies from block to block.
        let best = measured(1.0, &[2.0; 100]);
        let even = measured(1.0, &[1.0; 100]);
        let (lo, hi) = efficiency_interval(&best, &even);
        assert!(
            (lo - 2.0).abs() < 1e-12 && (hi - 2.0).abs() < 1e-12,
            "{lo} {hi}"
        );
        assert!(shown_ahead(2.0, lo, true));
        // The cost enters as a plain factor.
        let dear = measured(4.0, &[1.0; 100]);
        let (lo, hi) = efficiency_interval(&best, &dear);
        assert!(
            (lo - 0.5).abs() < 1e-12 && (hi - 0.5).abs() < 1e-12,
            "{lo} {hi}"
        );
        // The same totals, the best's carried by one block of 100: 2× as efficient on the
        // point estimate, but a single block is no evidence.
        let mut spiky = vec![100.0 / 99.0; 100];
        spiky[37] = 100.0;
        let spiky = measured(1.0, &spiky);
        let r = spiky.variance() / even.variance();
        assert!((r - 2.0).abs() < 1e-3, "{r}");
        let (lo, hi) = efficiency_interval(&spiky, &even);
        assert!(lo < 1.0 && hi > 3.0, "{lo} {hi}");
        assert!(!shown_ahead(r, lo, true) && shown_ahead(r, lo, false));
        // Independent noise: 100 blocks of exponential spread (standard deviation = mean)
        // around 2 and 1: shown ahead (the interval's half-width is about 2 × 2 × 0.14).
        let mut rng = crate::testing::rng::Rng::new(7);
        let noisy = |mean: f64, rng: &mut crate::testing::rng::Rng| -> Vec<f64> {
            (0..100)
                .map(|_| -mean * (1.0 - f64::from(rng.f32())).ln())
                .collect()
        };
        let b = measured(1.0, &noisy(2.0, &mut rng));
        let c = measured(1.0, &noisy(1.0, &mut rng));
        let (lo, hi) = efficiency_interval(&b, &c);
        let r = b.variance() / c.variance();
        assert!(lo < r && r < hi && lo > 1.0, "{lo} {r} {hi}");
    }

    #[test]
    fn edge_cases_never_give_nan() {
        let best = measured(1.0, &[1.0, 2.0]);
        assert_eq!(
            efficiency_interval(&best, &measured(1.0, &[0.0, 0.0])),
            (f64::INFINITY, f64::INFINITY)
        );
        assert_eq!(
            efficiency_interval(&best, &measured(1.0, &[1.0])),
            (0.0, f64::INFINITY)
        );
        assert_eq!(
            efficiency_interval(&measured(1.0, &[]), &measured(1.0, &[])),
            (f64::INFINITY, f64::INFINITY)
        );
    }
}
