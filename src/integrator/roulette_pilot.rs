//! Where the path tracer's Russian roulette starts, chosen per scene by a pilot
//! (`--rr-depth auto`, the default of images rendered with the path tracer).
//!
//! Roulette trades variance for time: each path it ends saves the rays the path would have
//! traced and adds variance where the light it would have found was not negligible. The
//! start that does best depends on the scene (docs/design.md §8 "Variance per sample":
//! from the 4th bounce on the darker peers' box, from the 2nd in a bright room). The pilot
//! traces a few thousand paths without roulette (`PathIntegrator::pilot_walk`) and works out,
//! for each candidate start s, what roulette from s would make of those very paths in
//! expectation, so that the candidates are compared on common paths rather than on their own
//! noisy renders:
//!
//! - **Survival.** A path's contributions come in groups k = 0, 1, …, each decided by the
//!   roulette test after scattering event k (none before group 0). With pbrt-v4's rule
//!   (`roulette.rs`: survival p = max β·η² with the survivors' β carrying 1/p, so each test
//!   sees the throughput over the survival so far), the probability that group k is reached
//!   is P_k = min(1, min over s ≤ i ≤ k of b_i), b_i the max β·η² after event i without
//!   roulette.
//! - **Second moment.** The estimate is X = Σ_k c_k·1[k reached]/P_k; the indicators nest, so
//!   E[X²] = Σ_j Σ_k c_j c_k / P_min(j,k), and E[X] = Σ_k c_k whatever s (roulette is
//!   unbiased).
//! - **Variance.** A pixel's is E[X²] − m²; m² is estimated without bias by the product of
//!   two independent samples' X (the pilot takes two per pixel). The variance of s is the
//!   mean over the pilot's pixels: the expected squared error of the image, each pixel
//!   alike, as relRMSE and MSE weigh them.
//! - **Cost.** Ray queries, the renderer's deterministic measure of work (`scene::ray_count`,
//!   as `auto`'s pilot uses): Σ_k P_k r_k, r_k the queries of group k. The path tracer's CPU
//!   time is proportional to them across starts, with no fixed part to speak of (measured on
//!   two scenes: docs/design.md §8, "Where roulette starts, chosen per scene").
//!
//! The start with the highest efficiency 1/(variance × cost) wins (Rath et al. 2022,
//! "EARS: Efficiency-Aware Russian Roulette and Splitting", ACM TOG 41(4), §3, eq. (3): the
//! efficiency of an estimator, which EARS maximises per vertex; here one start per scene).
//! Contributions are luminance Y (`sampled_to_xyz`). The pilot draws independent numbers;
//! the image's low-discrepancy samples have less variance at every start, which the choice
//! does not model.
//!
//! Deterministic: the pilot's pixels and numbers depend on the image's size and the seed
//! only (not on a crop, the threads or a part), and its sums are taken in pixel order.

use super::path::PathIntegrator;
use super::roulette::DEFAULT_RR_DEPTH;
use crate::material::SpectraCache;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::spectral::xyz::sampled_to_xyz;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;
use rayon::prelude::*;

/// One group of a pilot path's contributions (`PathIntegrator::pilot_walk`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PilotGroup {
    /// The group's radiance at the path's wavelengths (relative to the sample's pdfs).
    pub l: SampledSpectrum,
    /// The max β·η² the roulette test before the group sees without roulette (1 for the
    /// first group, which no test precedes).
    pub b: f32,
    /// The ray queries the group made.
    pub rays: u32,
}

/// About how many pixels the pilot samples, two paths each, whatever the image's size.
pub const PILOT_PIXELS: u64 = 4096;
/// The deepest the pilot follows a path when the render's own cap is deeper or unlimited:
/// under every candidate the tail beyond survives with at most min b_i, which has decayed to
/// nothing in all but near-lossless scenes, where no candidate's roulette plays.
pub const PILOT_DEPTH: u32 = 32;
/// The latest start considered; with a depth cap D, start D + 1 means no roulette.
pub const LATEST_START: u32 = 8;
/// How many standard errors ahead of the default start another must be to be chosen: a
/// one-sided 97.7 % test, as `auto` asks bdpt to show itself ahead of vcm.
pub const SHOWN_SE: f64 = 2.0;
/// Salts the pilot's seed so that its numbers are not the image's first samples.
const PILOT_SALT: u64 = 0x7261_6f75_6c65_7474;

/// One candidate start as the pilot rates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The first scattering event after which roulette may end a path (`--rr-depth`).
    pub start: u32,
    /// The mean variance of a pixel's luminance per sample (cd²/m⁴ before the exposure).
    pub variance: f64,
    /// The mean ray queries a sample.
    pub cost: f64,
    /// The standard error of `cost` (from the spread over the pilot's pixels).
    pub cost_se: f64,
    /// Shown ahead of [`DEFAULT_RR_DEPTH`]: its variance × cost is below the default's by more
    /// than [`SHOWN_SE`] standard errors of their difference over the pilot's pixels (the
    /// candidates are rated on the same paths, so the difference's error is small). True for
    /// the default itself.
    pub shown: bool,
}

impl Candidate {
    /// 1/(variance × cost), in the units above.
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.variance * self.cost)
    }
}

/// The pilot's verdict: the chosen start and every candidate's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    pub start: u32,
    pub candidates: Vec<Candidate>,
    /// Paths the pilot traced.
    pub paths: u64,
}

impl Choice {
    /// The chosen start's efficiency over `start`'s (None if `start` was not a candidate).
    pub fn gain_over(&self, start: u32) -> Option<f64> {
        let of = |s: u32| self.candidates.iter().find(|c| c.start == s);
        Some(of(self.start)?.efficiency() / of(start)?.efficiency())
    }

    /// One line for the log: the start and its gain over `default`.
    pub fn describe(&self, default: u32) -> String {
        let gain = self
            .gain_over(default)
            .map(|g| format!(", {g:.2}× the efficiency of start {default}"))
            .unwrap_or_default();
        format!(
            "Russian roulette from bounce {} (chosen by a pilot of {} paths{gain})",
            self.start, self.paths
        )
    }
}

/// The candidate starts for a depth cap `max_depth` (scattering events; `cut::SAFETY_DEPTH`
/// when unlimited): 1 to [`LATEST_START`], and no later than `max_depth` + 1 (no roulette).
pub fn candidates(max_depth: u32) -> std::ops::RangeInclusive<u32> {
    1..=LATEST_START.min(max_depth.saturating_add(1))
}

/// Runs the pilot on `scene` for a path tracer capped at `max_depth` with texture filter
/// `filter`, numbers from `seed`; None when no pilot path found any light (nothing to
/// choose by). Uses the current rayon pool.
pub fn choose(scene: &Scene, max_depth: u32, filter: TextureFilter, seed: u64) -> Option<Choice> {
    let pt = PathIntegrator {
        max_depth: max_depth.min(PILOT_DEPTH),
        rr_depth: u32::MAX,
        filter,
    };
    let starts: Vec<u32> = candidates(max_depth).collect();
    let pixels = pilot_pixels(scene.camera.width as u64, scene.camera.height as u64);
    let per_pixel: Vec<Vec<[f64; 2]>> = pixels
        .par_iter()
        .map_init(
            || (SpectraCache::default(), Vec::new()),
            |(spectra, groups), &(x, y)| {
                let index = y * scene.camera.width as u64 + x;
                let mut one = |sample| {
                    let mut sampler = Sampler::new(seed ^ PILOT_SALT, index, sample);
                    let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                    let film = [x as f32 + sampler.get_1d(), y as f32 + sampler.get_1d()];
                    let (ray, t_max) = scene.camera.generate_ray(film, sampler.get_2d());
                    groups.clear();
                    pt.pilot_walk(scene, ray, t_max, &lambda, &mut sampler, spectra, groups);
                    let c: Vec<f64> = groups
                        .iter()
                        .map(|g| f64::from(sampled_to_xyz(g.l, &lambda)[1]))
                        .collect();
                    (c, groups.clone())
                };
                let (a, b) = (one(0), one(1));
                let (xa, xb) = (a.0.iter().sum::<f64>(), b.0.iter().sum::<f64>());
                starts
                    .iter()
                    .map(|&s| {
                        let (ma, ca) = moments(&a.0, &a.1, s);
                        let (mb, cb) = moments(&b.0, &b.1, s);
                        [0.5 * (ma + mb) - xa * xb, 0.5 * (ca + cb)]
                    })
                    .collect()
            },
        )
        .collect();
    let candidates = rate(&starts, &per_pixel);
    let best = best(&candidates)?;
    Some(Choice {
        start: best.start,
        paths: 2 * pixels.len() as u64,
        candidates,
    })
}

/// Each start's figures from the pilot's per-pixel [variance, cost] (`per_pixel[pixel][i]`
/// for `starts[i]`).
fn rate(starts: &[u32], per_pixel: &[Vec<[f64; 2]>]) -> Vec<Candidate> {
    let n = per_pixel.len() as f64;
    let mean = |f: &dyn Fn(&Vec<[f64; 2]>) -> f64| per_pixel.iter().map(f).sum::<f64>() / n;
    // The sample variance of the per-pixel values `f`, about their mean `m`.
    let spread = |f: &dyn Fn(&Vec<[f64; 2]>) -> f64, m: f64| {
        per_pixel.iter().map(|p| (f(p) - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)
    };
    let cost: Vec<f64> = (0..starts.len()).map(|i| mean(&|p| p[i][1])).collect();
    let default = starts.iter().position(|&s| s == DEFAULT_RR_DEPTH);
    (0..starts.len())
        .map(|i| {
            let variance = mean(&|p| p[i][0]);
            // variance × cost against the default's, pixel by pixel on the same paths.
            let shown = match default {
                Some(d) if d != i => {
                    let diff = |p: &Vec<[f64; 2]>| p[i][0] * cost[i] - p[d][0] * cost[d];
                    let m = mean(&diff);
                    m + SHOWN_SE * (spread(&diff, m) / n).sqrt() < 0.0
                }
                _ => true,
            };
            Candidate {
                start: starts[i],
                variance,
                cost: cost[i],
                cost_se: (spread(&|p| p[i][1], cost[i]) / n).sqrt(),
                shown,
            }
        })
        .collect()
}

/// The most efficient candidate among those shown ahead of [`DEFAULT_RR_DEPTH`] (and the
/// default itself): the default unless another is strictly more efficient, the earliest of
/// equals otherwise (a scene whose paths roulette never reaches rates every start alike);
/// None when no candidate has a positive, finite variance.
fn best(candidates: &[Candidate]) -> Option<&Candidate> {
    let valid = |c: &&Candidate| c.shown && c.variance > 0.0 && c.variance.is_finite();
    let default = candidates
        .iter()
        .filter(valid)
        .find(|c| c.start == DEFAULT_RR_DEPTH);
    candidates
        .iter()
        .filter(valid)
        .fold(default, |best, c| match best {
            Some(b) if b.efficiency() >= c.efficiency() => Some(b),
            _ => Some(c),
        })
}

/// The pilot's pixels: a regular grid of about [`PILOT_PIXELS`] over the whole image, each
/// at the middle of its cell.
fn pilot_pixels(w: u64, h: u64) -> Vec<(u64, u64)> {
    let stride = ((w * h) as f64 / PILOT_PIXELS as f64)
        .sqrt()
        .floor()
        .max(1.0) as u64;
    let (nx, ny) = (w / stride, h / stride);
    let mut out = Vec::with_capacity((nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            out.push((i * stride + stride / 2, j * stride + stride / 2));
        }
    }
    out
}

/// E[X²] and the expected ray queries of one pilot path (its groups' luminance `c` and
/// records `g`) under roulette from `start`, as the module's comment derives them.
fn moments(c: &[f64], g: &[PilotGroup], start: u32) -> (f64, f64) {
    let mut p = 1.0f64;
    let mut survival = Vec::with_capacity(g.len());
    for (k, group) in g.iter().enumerate() {
        if k as u32 >= start {
            p = p.min(f64::from(group.b));
        }
        survival.push(p.min(1.0));
    }
    // Σ_j (c_j / P_j)(c_j + 2 Σ_{k>j} c_k), the later sums accumulated backwards.
    let (mut m2, mut later, mut cost) = (0.0, 0.0, 0.0);
    for k in (0..c.len()).rev() {
        let pk = survival[k];
        if pk > 0.0 {
            m2 += c[k] / pk * (c[k] + 2.0 * later);
        }
        later += c[k];
        cost += pk * f64::from(g[k].rays);
    }
    (m2, cost)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn group(b: f32, rays: u32) -> PilotGroup {
        PilotGroup {
            l: SampledSpectrum::ZERO,
            b,
            rays,
        }
    }

    /// A path whose throughput never drops below 1 is never played: every start gives the
    /// square of its sum and all its rays.
    #[test]
    fn lossless_paths_are_untouched() {
        let g = [group(1.0, 2), group(1.0, 2), group(1.5, 2)];
        let c = [1.0, 2.0, 3.0];
        for s in 1..5 {
            let (m2, cost) = moments(&c, &g, s);
            assert!((m2 - 36.0).abs() < 1e-12, "start {s}: {m2}");
            assert_eq!(cost, 6.0);
        }
    }

    /// One test with survival p before the last group: E[X²] = (c0 + c1)² + c1²(1/p − 1) and
    /// the last group's rays count p times; a start after the test leaves the path whole.
    #[test]
    fn one_test_adds_its_variance_and_saves_its_rays() {
        let g = [group(1.0, 1), group(0.25, 2)];
        let c = [1.0, 2.0];
        let (m2, cost) = moments(&c, &g, 1);
        assert!((m2 - (9.0 + 4.0 * 3.0)).abs() < 1e-12, "{m2}");
        assert!((cost - 1.5).abs() < 1e-12);
        assert_eq!(moments(&c, &g, 2), (9.0, 3.0));
    }

    /// Nested tests: survival is the running minimum of the b's (pbrt-v4's β carries 1/p),
    /// checked against the definition E[X²] = Σ_j Σ_k c_j c_k / P_min(j,k).
    #[test]
    fn survival_is_the_running_minimum() {
        let b = [1.0f32, 0.8, 0.5, 0.6, 0.2];
        let g: Vec<PilotGroup> = b.iter().map(|&b| group(b, 1)).collect();
        let c = [0.3, 0.7, 0.2, 0.9, 0.4];
        for s in 1..6u32 {
            let p: Vec<f64> = (0..5)
                .map(|k| {
                    (0..=k)
                        .filter(|&i| i as u32 >= s)
                        .map(|i| f64::from(b[i]))
                        .fold(1.0, f64::min)
                })
                .collect();
            let mut want = 0.0;
            for j in 0..5 {
                for k in 0..5 {
                    want += c[j] * c[k] / p[j.min(k)];
                }
            }
            let (m2, cost) = moments(&c, &g, s);
            assert!((m2 - want).abs() < 1e-12, "start {s}: {m2} against {want}");
            assert!((cost - p.iter().sum::<f64>()).abs() < 1e-12);
        }
    }

    /// The moments against roulette itself (`roulette::survives`, pbrt-v4's rule with the
    /// survivors' β carrying 1/p) played on one path many times: E[X²] and the expected rays
    /// within 5 standard errors of the simulation's means, at every start.
    #[test]
    fn the_moments_are_those_of_the_roulette_it_models() {
        use crate::integrator::roulette::survives;
        let b = [1.0f32, 0.7, 0.9, 0.3, 0.5];
        let c = [0.5, 0.3, 0.4, 0.2, 0.6];
        let rays = [1, 2, 2, 1, 2];
        let g: Vec<PilotGroup> = (0..5).map(|k| group(b[k], rays[k])).collect();
        let trials = 200_000u64;
        for start in 1..6u32 {
            let mut sampler = Sampler::new(11, u64::from(start), 0);
            let [mut s2, mut s4, mut r1, mut r2] = [0.0f64; 4];
            for _ in 0..trials {
                let (mut x, mut w, mut r) = (c[0], 1.0f32, f64::from(rays[0]));
                for k in 1..5 {
                    // The throughput with roulette so far: the true one over the survival.
                    let mut beta = SampledSpectrum::splat(b[k] * w);
                    if !survives(&mut beta, 1.0, k as u32, start, &mut sampler) {
                        break;
                    }
                    w = beta[0] / b[k];
                    x += c[k] * f64::from(w);
                    r += f64::from(rays[k]);
                }
                (s2, s4, r1, r2) = (s2 + x * x, s4 + x.powi(4), r1 + r, r2 + r * r);
            }
            let n = trials as f64;
            let (m2, cost) = moments(&c, &g, start);
            let se_m2 = ((s4 / n - (s2 / n).powi(2)) / n).sqrt();
            let se_cost = ((r2 / n - (r1 / n).powi(2)) / n).sqrt();
            assert!(
                (s2 / n - m2).abs() < 5.0 * se_m2 + 1e-9,
                "start {start}: E[X²] {} vs {m2}",
                s2 / n
            );
            assert!(
                (r1 / n - cost).abs() < 5.0 * se_cost + 1e-9,
                "start {start}: rays {} vs {cost}",
                r1 / n
            );
        }
    }

    /// Equal candidates keep the default start; a strictly better one wins; invalid
    /// variances never do.
    #[test]
    fn ties_keep_the_default_start() {
        let c = |start, variance| Candidate {
            start,
            variance,
            cost: 2.0,
            cost_se: 0.0,
            shown: true,
        };
        let same = [c(1, 1.0), c(2, 1.0), c(3, 1.0)];
        assert_eq!(best(&same).unwrap().start, 2);
        let better = [c(1, 1.0), c(2, 1.0), c(3, 0.9), c(4, 0.9)];
        assert_eq!(best(&better).unwrap().start, 3);
        let broken = [c(1, f64::NAN), c(2, 0.0), c(3, -1.0)];
        assert!(best(&broken).is_none());
        assert_eq!(best(&[c(1, 0.5), c(2, f64::INFINITY)]).unwrap().start, 1);
        let not_shown = Candidate {
            shown: false,
            ..c(3, 0.5)
        };
        assert_eq!(best(&[c(2, 1.0), not_shown]).unwrap().start, 2);
    }

    /// A start is shown ahead of the default only when its variance × cost is lower on the
    /// same pixels by more than the noise of the difference.
    #[test]
    fn a_start_must_show_itself_ahead_of_the_default() {
        // Pixel values [variance, cost] for starts 2 and 3: start 3 lower everywhere by 10 %
        // (shown), start 4 lower on average but as often higher (not shown).
        let per_pixel: Vec<Vec<[f64; 2]>> = (0..100)
            .map(|i| {
                let v = 1.0 + (i % 7) as f64;
                let noisy = if i % 2 == 0 { 0.5 * v } else { 1.4 * v };
                vec![[v, 1.0], [0.9 * v, 1.0], [noisy, 1.0]]
            })
            .collect();
        let rated = rate(&[2, 3, 4], &per_pixel);
        assert!(rated[0].shown && rated[1].shown, "{rated:?}");
        assert!(!rated[2].shown, "{rated:?}");
        assert_eq!(best(&rated).unwrap().start, 3);
    }

    #[test]
    fn candidates_stop_at_no_roulette() {
        assert_eq!(candidates(7), 1..=8);
        assert_eq!(candidates(3), 1..=4);
        assert_eq!(candidates(u32::MAX), 1..=LATEST_START);
    }

    #[test]
    fn pilot_pixels_cover_the_image_on_a_grid() {
        let p = pilot_pixels(256, 256);
        assert_eq!(p.len(), 4096);
        assert_eq!(p[0], (2, 2));
        assert_eq!(*p.last().unwrap(), (254, 254));
        assert_eq!(pilot_pixels(10, 5).len(), 50);
        assert!(pilot_pixels(4000, 3000).len() as u64 <= 2 * PILOT_PIXELS);
    }
}
