//! Where the path tracer's Russian roulette starts and how many continuations its image paths
//! split into at their first vertex, chosen per scene by a pilot (`--rr-depth auto` and
//! `--split auto`, the defaults of images rendered with the path tracer).
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
//! **Splitting** (`--split auto`, `integrator::split`). The same pilot chooses n, the
//! continuations a path splits into at its first vertex, with the start: each pilot sample
//! takes its first vertex once and two continuations from it. With c₀ the first group (the
//! camera ray's vertex and next event estimation there), B₁, B₂ the continuations' sums and
//! M_c the second moment of the path through continuation c (above), the estimate
//! X_n = c₀ + (1/n) Σ B has E[X_n²] = (1/n) E[(c₀ + B)²] + (1 − 1/n) E[(c₀ + E[B | v₁])²], estimated
//! without bias by (1/n)(M₁ + M₂)/2 + (1 − 1/n)(c₀² + c₀(B₁ + B₂) + B₁B₂): B₁ and B₂ are
//! independent given the first vertex v₁, so B₁B₂ estimates E[B | v₁]² (the classic splitting
//! variance, Arvo and Kirk 1990, "Particle transport and image synthesis", §4). The cost of n
//! is r₀ + n·r_B, r₀ the first group's ray queries and r_B a continuation's expected ones: the
//! CPU time of split renders is proportional to their rays as it is across starts (measured
//! on six scenes: docs/design.md §8, "Splitting at the first vertex"). A split is held back
//! where the first vertex carries more than [`SPLIT_MAX_FIRST_SHARE`] of the unsplit variance:
//! there the image's low-discrepancy samples, which this model does not see, beat splitting.
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
#[derive(Clone, Copy, Debug, Default)]
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

/// The splits the pilot considers (`integrator::split`): powers of two.
pub const SPLITS: [u32; 4] = [1, 2, 4, 8];
/// The largest share of a sample's variance that its first vertex may carry for the pilot to
/// split (V_A / (V_A + V_B), from the unsplit and split-in-2 variances: 2V₂ − V₁ over V₁).
/// The pilot's independent numbers do not see how fast the low-discrepancy sampler shrinks
/// the first vertex's variance with more camera samples (its integrand is low-dimensional:
/// the pixel, the wavelengths, the first light sample); where that variance is more than a
/// few per cent, more samples beat splitting. Measured on six scenes (docs/design.md §8,
/// "Splitting at the first vertex"): the boxes' shares are 0.00–0.07 and splitting gains
/// there; open-office's are 0.10–0.33 and splitting loses 0.6× at n = 2.
pub const SPLIT_MAX_FIRST_SHARE: f64 = 0.1;

/// What the user fixed of the path tracer's roulette and splitting; None: the pilot chooses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Fixed {
    pub start: Option<u32>,
    pub split: Option<u32>,
}

impl Fixed {
    /// The candidate another must be shown ahead of: the given start and split, or the
    /// defaults (start [`DEFAULT_RR_DEPTH`], no split).
    pub fn reference(&self) -> (u32, u32) {
        (
            self.start.unwrap_or(DEFAULT_RR_DEPTH),
            self.split.unwrap_or(1),
        )
    }
}

/// One candidate (roulette start, split) as the pilot rates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub start: u32,
    pub split: u32,
    /// Mean over the pilot's pixels of one sample's variance (luminance²).
    pub variance: f64,
    /// Mean cost of one sample (ray queries) and its standard error over the pixels.
    pub cost: f64,
    pub cost_se: f64,
    /// Ahead of the reference (`Fixed::reference`) by [`SHOWN_SE`] standard errors of the
    /// per-pixel difference in variance × cost (always true for the reference itself).
    pub shown: bool,
}

impl Candidate {
    /// Efficiency, 1/(variance × cost) (Rath et al. 2022, §3).
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.variance * self.cost)
    }
}

/// The pilot's verdict: the chosen start and split and every candidate's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    pub start: u32,
    pub split: u32,
    pub candidates: Vec<Candidate>,
    /// Camera samples the pilot traced.
    pub paths: u64,
    pub fixed: Fixed,
}

impl Choice {
    /// The chosen candidate's efficiency over that of (`start`, `split`), when both are
    /// candidates.
    pub fn gain_over(&self, (start, split): (u32, u32)) -> Option<f64> {
        let of = |s: u32, n: u32| {
            self.candidates
                .iter()
                .find(|c| c.start == s && c.split == n)
        };
        Some(of(self.start, self.split)?.efficiency() / of(start, split)?.efficiency())
    }

    /// One line for the log: what was chosen and by how much it beats the reference.
    pub fn describe(&self) -> String {
        let (s0, n0) = self.fixed.reference();
        let mut chosen = Vec::new();
        if self.fixed.start.is_none() {
            chosen.push(format!("Russian roulette from bounce {}", self.start));
        }
        if self.fixed.split.is_none() {
            chosen.push(match self.split {
                1 => "paths not split".to_string(),
                n => format!("paths split in {n} at their first vertex"),
            });
        }
        let reference = match (self.fixed.start.is_none(), self.fixed.split.is_none()) {
            (true, true) => format!("start {s0} unsplit"),
            (true, false) => format!("start {s0}"),
            _ => "no split".to_string(),
        };
        let gain = self
            .gain_over((s0, n0))
            .map(|g| format!(", {g:.2}× the efficiency of {reference}"))
            .unwrap_or_default();
        format!(
            "{} (chosen by a pilot of {} paths{gain})",
            chosen.join(", "),
            self.paths
        )
    }
}

/// The candidates (start, split) for a depth cap `max_depth` (scattering events;
/// `cut::SAFETY_DEPTH` when unlimited): starts 1 to [`LATEST_START`] and no later than
/// `max_depth` + 1 (no roulette), splits [`SPLITS`] (none with a cap of 0: no path
/// continues), each only the user's when fixed.
pub fn candidates(max_depth: u32, fixed: Fixed) -> Vec<(u32, u32)> {
    let starts: Vec<u32> = match fixed.start {
        Some(s) => vec![s],
        None => (1..=LATEST_START.min(max_depth.saturating_add(1))).collect(),
    };
    let splits: &[u32] = match fixed.split {
        Some(ref n) => std::slice::from_ref(n),
        None if max_depth == 0 => &[1],
        None => &SPLITS,
    };
    starts
        .iter()
        .flat_map(|&s| splits.iter().map(move |&n| (s, n)))
        .collect()
}

/// One pilot camera sample: its first group and its continuations (none, one when the first
/// vertex is specular, two when split), each as the whole path's luminance groups.
struct PilotSample {
    c0: f64,
    r0: f64,
    paths: Vec<(Vec<f64>, Vec<PilotGroup>)>,
}

impl PilotSample {
    /// The continuations' sums of luminance (B above).
    fn sums(&self) -> Vec<f64> {
        self.paths
            .iter()
            .map(|(c, _)| c[1..].iter().sum())
            .collect()
    }

    /// An unbiased estimate of the pixel's mean: c₀ + the mean of the continuations' sums.
    fn estimate(&self) -> f64 {
        let b = self.sums();
        self.c0 + b.iter().sum::<f64>() / (b.len().max(1) as f64)
    }

    /// [E[X²], cost] of this sample split in `n` with roulette from `start`, as the module's
    /// comment derives them.
    fn moments(&self, start: u32, n: u32) -> [f64; 2] {
        if self.paths.is_empty() {
            return [self.c0 * self.c0, self.r0];
        }
        let k = self.paths.len() as f64;
        let (mut m2, mut rays) = (0.0, 0.0);
        for (c, g) in &self.paths {
            let (m, r) = moments(c, g, start);
            (m2, rays) = (m2 + m / k, rays + r / k);
        }
        let b = self.sums();
        let n = if b.len() == 2 { f64::from(n) } else { 1.0 };
        if b.len() == 2 {
            let shared = self.c0 * self.c0 + self.c0 * (b[0] + b[1]) + b[0] * b[1];
            m2 = m2 / n + (1.0 - 1.0 / n) * shared;
        }
        [m2, self.r0 + n * (rays - self.r0)]
    }
}

/// Runs the pilot on `scene` for a path tracer capped at `max_depth` with texture filter
/// `filter`, numbers from `seed`, choosing what `fixed` leaves open; None when no pilot path
/// found any light (nothing to choose by). Uses the current rayon pool.
pub fn choose(
    scene: &Scene,
    max_depth: u32,
    filter: TextureFilter,
    seed: u64,
    fixed: Fixed,
) -> Option<Choice> {
    let pt = PathIntegrator {
        max_depth: max_depth.min(PILOT_DEPTH),
        rr_depth: u32::MAX,
        filter,
        split: 1,
    };
    let cands = candidates(max_depth, fixed);
    let pixels = pilot_pixels(scene.camera.width as u64, scene.camera.height as u64);
    let per_pixel: Vec<Vec<[f64; 2]>> = pixels
        .par_iter()
        .map_init(
            || (SpectraCache::default(), [Vec::new(), Vec::new()]),
            |(spectra, split), &(x, y)| {
                let index = y * scene.camera.width as u64 + x;
                let mut one = |sample| {
                    let mut sampler = Sampler::new(seed ^ PILOT_SALT, index, sample);
                    let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                    let film = [x as f32 + sampler.get_1d(), y as f32 + sampler.get_1d()];
                    let (ray, t_max) = scene.camera.generate_ray(film, sampler.get_2d());
                    let mut shared = PilotGroup::default();
                    let n = pt.pilot_walk(
                        scene,
                        ray,
                        t_max,
                        &lambda,
                        &mut sampler,
                        spectra,
                        (&mut shared, split),
                    );
                    let y = |g: &PilotGroup| f64::from(sampled_to_xyz(g.l, &lambda)[1]);
                    let c0 = y(&shared);
                    let paths = split[..n as usize]
                        .iter()
                        .map(|cont| {
                            let g: Vec<PilotGroup> = std::iter::once(shared)
                                .chain(cont.iter().copied())
                                .collect();
                            (g.iter().map(y).collect(), g)
                        })
                        .collect();
                    PilotSample {
                        c0,
                        r0: f64::from(shared.rays),
                        paths,
                    }
                };
                let (a, b) = (one(0), one(1));
                let mean2 = a.estimate() * b.estimate();
                cands
                    .iter()
                    .map(|&(s, n)| {
                        let (ma, mb) = (a.moments(s, n), b.moments(s, n));
                        [0.5 * (ma[0] + mb[0]) - mean2, 0.5 * (ma[1] + mb[1])]
                    })
                    .collect()
            },
        )
        .collect();
    let reference = cands.iter().position(|&c| c == fixed.reference());
    let mut rated = rate(&cands, reference, &per_pixel);
    if fixed.split.is_none() {
        hold_back_splits(&mut rated);
    }
    let best = best(&rated, reference)?;
    Some(Choice {
        start: best.start,
        split: best.split,
        paths: 2 * pixels.len() as u64,
        candidates: rated,
        fixed,
    })
}

/// Each candidate's figures from the pilot's per-pixel [variance, cost]
/// (`per_pixel[pixel][i]` for `cands[i]`), shown or not against `cands[reference]`.
fn rate(
    cands: &[(u32, u32)],
    reference: Option<usize>,
    per_pixel: &[Vec<[f64; 2]>],
) -> Vec<Candidate> {
    let n = per_pixel.len() as f64;
    let mean = |f: &dyn Fn(&Vec<[f64; 2]>) -> f64| per_pixel.iter().map(f).sum::<f64>() / n;
    let spread = |f: &dyn Fn(&Vec<[f64; 2]>) -> f64, m: f64| {
        per_pixel.iter().map(|p| (f(p) - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)
    };
    let cost: Vec<f64> = (0..cands.len()).map(|i| mean(&|p| p[i][1])).collect();
    (0..cands.len())
        .map(|i| {
            let variance = mean(&|p| p[i][0]);
            let shown = match reference {
                Some(d) if d != i => {
                    let diff = |p: &Vec<[f64; 2]>| p[i][0] * cost[i] - p[d][0] * cost[d];
                    let m = mean(&diff);
                    m + SHOWN_SE * (spread(&diff, m) / n).sqrt() < 0.0
                }
                _ => true,
            };
            Candidate {
                start: cands[i].0,
                split: cands[i].1,
                variance,
                cost: cost[i],
                cost_se: (spread(&|p| p[i][1], cost[i]) / n).sqrt(),
                shown,
            }
        })
        .collect()
}

/// Marks the splits of every start whose first vertex carries more than
/// [`SPLIT_MAX_FIRST_SHARE`] of the unsplit variance as not shown.
fn hold_back_splits(rated: &mut [Candidate]) {
    let variance = |rated: &[Candidate], start, split| {
        rated
            .iter()
            .find(|c| c.start == start && c.split == split)
            .map(|c| c.variance)
    };
    for i in 0..rated.len() {
        let c = rated[i];
        if c.split == 1 {
            continue;
        }
        let share = match (variance(rated, c.start, 1), variance(rated, c.start, 2)) {
            (Some(v1), Some(v2)) => (2.0 * v2 - v1) / v1,
            _ => f64::INFINITY,
        };
        if share.is_nan() || share > SPLIT_MAX_FIRST_SHARE {
            rated[i].shown = false;
        }
    }
}

/// The most efficient candidate among those shown ahead of the reference (and the
/// reference itself): the reference unless another is strictly more efficient, the earliest
/// of equals otherwise (a scene whose paths roulette never reaches rates every start alike);
/// None when no candidate has a positive, finite variance.
fn best(candidates: &[Candidate], reference: Option<usize>) -> Option<&Candidate> {
    let valid = |c: &&Candidate| c.shown && c.variance > 0.0 && c.variance.is_finite();
    let first = reference.and_then(|r| candidates.get(r)).filter(valid);
    candidates
        .iter()
        .filter(valid)
        .fold(first, |best, c| match best {
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

    /// Equal candidates keep the reference; a strictly better one wins; invalid variances
    /// never do.
    #[test]
    fn ties_keep_the_reference() {
        let c = |start, variance| Candidate {
            start,
            split: 1,
            variance,
            cost: 2.0,
            cost_se: 0.0,
            shown: true,
        };
        let same = [c(1, 1.0), c(2, 1.0), c(3, 1.0)];
        assert_eq!(best(&same, Some(1)).unwrap().start, 2);
        let better = [c(1, 1.0), c(2, 1.0), c(3, 0.9), c(4, 0.9)];
        assert_eq!(best(&better, Some(1)).unwrap().start, 3);
        let broken = [c(1, f64::NAN), c(2, 0.0), c(3, -1.0)];
        assert!(best(&broken, Some(1)).is_none());
        assert_eq!(
            best(&[c(1, 0.5), c(2, f64::INFINITY)], Some(1))
                .unwrap()
                .start,
            1
        );
        let not_shown = Candidate {
            shown: false,
            ..c(3, 0.5)
        };
        assert_eq!(best(&[c(2, 1.0), not_shown], Some(0)).unwrap().start, 2);
    }

    /// A candidate is shown ahead of the reference only when its variance × cost is lower on
    /// the same pixels by more than the noise of the difference.
    #[test]
    fn a_candidate_must_show_itself_ahead_of_the_reference() {
        // Pixel values [variance, cost] for starts 2, 3 and 4: start 3 lower everywhere by
        // 10 % (shown), start 4 lower on average but as often higher (not shown).
        let per_pixel: Vec<Vec<[f64; 2]>> = (0..100)
            .map(|i| {
                let v = 1.0 + (i % 7) as f64;
                let noisy = if i % 2 == 0 { 0.5 * v } else { 1.4 * v };
                vec![[v, 1.0], [0.9 * v, 1.0], [noisy, 1.0]]
            })
            .collect();
        let rated = rate(&[(2, 1), (3, 1), (4, 1)], Some(0), &per_pixel);
        assert!(rated[0].shown && rated[1].shown, "{rated:?}");
        assert!(!rated[2].shown, "{rated:?}");
        assert_eq!(best(&rated, Some(0)).unwrap().start, 3);
    }

    /// Splits are held back where the first vertex carries more than the allowed share of
    /// the variance, and kept where it carries less.
    #[test]
    fn splits_need_a_small_first_vertex_share() {
        let c = |split, variance| Candidate {
            start: 2,
            split,
            variance,
            cost: 1.0,
            cost_se: 0.0,
            shown: true,
        };
        // V_A share 0.04: (2 · 0.52 − 1) / 1.
        let mut small = [c(1, 1.0), c(2, 0.52), c(4, 0.28)];
        hold_back_splits(&mut small);
        assert!(small.iter().all(|c| c.shown));
        // V_A share 0.2.
        let mut large = [c(1, 1.0), c(2, 0.6), c(4, 0.4)];
        hold_back_splits(&mut large);
        assert!(large[0].shown && !large[1].shown && !large[2].shown);
    }

    #[test]
    fn candidates_stop_at_no_roulette() {
        let starts = |d| {
            let c = candidates(d, Fixed::default());
            let mut s: Vec<u32> = c.iter().map(|&(s, _)| s).collect();
            s.dedup();
            s
        };
        assert_eq!(starts(7), (1..=8).collect::<Vec<_>>());
        assert_eq!(starts(3), (1..=4).collect::<Vec<_>>());
        assert_eq!(starts(u32::MAX), (1..=LATEST_START).collect::<Vec<_>>());
        assert_eq!(candidates(7, Fixed::default()).len(), 8 * SPLITS.len());
        // No split with a cap of 0; what the user fixes is the only candidate.
        assert_eq!(candidates(0, Fixed::default()), [(1, 1)]);
        let start = Fixed {
            start: Some(5),
            split: None,
        };
        assert_eq!(candidates(7, start), SPLITS.map(|n| (5, n)));
        let split = Fixed {
            start: None,
            split: Some(4),
        };
        assert!(candidates(7, split).iter().all(|&(_, n)| n == 4));
        assert_eq!(split.reference(), (DEFAULT_RR_DEPTH, 4));
    }

    /// The split's second moment: a first group c₀ = 1 and continuations that bring 0 or 2
    /// with probability ½ each, independently given the vertex, have E[X_n²] = (c₀ + E B)² +
    /// Var B / n = 4 + 1/n. The pilot's estimate from one pair of continuations, averaged
    /// over the four equally likely pairs, is that exactly; its cost counts the first vertex's
    /// rays once and n continuations'.
    #[test]
    fn the_split_moments_are_the_splitting_estimators() {
        let g = |b: f32, rays| PilotGroup {
            l: SampledSpectrum::ZERO,
            b,
            rays,
        };
        let sample = |b1: f64, b2: f64| PilotSample {
            c0: 1.0,
            r0: 2.0,
            paths: [b1, b2]
                .iter()
                .map(|&b| (vec![1.0, b], vec![g(1.0, 2), g(1.0, 3)]))
                .collect(),
        };
        for n in SPLITS {
            let pairs = [(0.0, 0.0), (0.0, 2.0), (2.0, 0.0), (2.0, 2.0)];
            let m2: f64 = pairs
                .iter()
                .map(|&(a, b)| sample(a, b).moments(9, n)[0] / 4.0)
                .sum();
            let want = 4.0 + 1.0 / f64::from(n);
            assert!((m2 - want).abs() < 1e-12, "n {n}: {m2} against {want}");
            let [_, cost] = sample(0.0, 2.0).moments(9, n);
            assert!((cost - (2.0 + 3.0 * f64::from(n))).abs() < 1e-12);
        }
        // Unsplit (one continuation: a specular first vertex), n changes nothing.
        let single = PilotSample {
            paths: sample(2.0, 0.0).paths[..1].to_vec(),
            ..sample(0.0, 0.0)
        };
        assert_eq!(single.moments(9, 1), single.moments(9, 8));
        assert_eq!(single.moments(9, 4)[0], 9.0);
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
