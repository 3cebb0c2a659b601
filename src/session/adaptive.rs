//! Adaptive sampling (`--adaptive`): more samples where a pixel's noise is, the image unbiased
//! by construction (design.md §9, "Adaptive sampling").
//!
//! The even and the odd samples of a pixel are two independent replicates (`sampling/zsobol.rs`,
//! "Why two replicates"; the independent sampler's samples are independent anyway). Each
//! replicate first takes a pilot of n₁ samples in every pixel. Then each replicate's further
//! samples are allocated from the *other* replicate's pilot, so the count of a replicate's
//! samples does not depend on its own samples and its mean is unbiased; the pixel is the plain
//! average of the two replicates' means, with the fixed weights ½ (`sensor::replicates`).
//!
//! **Allocation.** With v the variance of one sample of a pixel (summed over the RGB channels
//! the output is judged in), the mean squared error Σ vᵢ/nᵢ of an image of N samples per pixel
//! on average is smallest for nᵢ ∝ √vᵢ (Neyman 1934, "On the two different aspects of the
//! representative method", optimum allocation). A pilot of a few samples estimates one pixel's
//! variance poorly (Monte Carlo samples are heavy-tailed), so the pilot's variances are
//! averaged over a (2r + 1)² box of pixels first. A sample's cost differs between pixels too
//! (paths from the lit walls are longer than those that leave through the open side): with
//! cᵢ the cost of one sample, the error at equal time is smallest for nᵢ ∝ √(vᵢ/cᵢ) (the same
//! optimum with a cost per unit, Cochran 1977, "Sampling Techniques", §5.5). The cost is the
//! pilot's ray queries per sample plus one (the camera and film's share, about one query's),
//! box-averaged like the variance. The counts are then water-filled,
//! nᵢ = clamp(k·σ̂ᵢ/√ĉᵢ, n₁, [`MAX_RATIO`]·N/2) with k such that their mean is N/2 per
//! replicate.
//! `tools/adaptive_gain.py` measured the scheme before it was built (design.md §8, "Adaptive
//! sampling: what it would buy").
//!
//! **Clipped moments.** The variance that sets the counts is that of the samples clipped per
//! channel at [`CLIP_MULTIPLE`] × the image's mean, found from the pilot's first sample of
//! each replicate (which the moments then leave out). Without the clip, the pixels that see a
//! light (their radiance a hundred times the walls', its noise too) and their neighbours in the
//! box take the largest counts, and on the peers' box a sixth of the budget went to pixels
//! whose error no display shows and the benchmark masks (design.md §9). The clip changes only
//! the allocation: the image sums the samples as they are.

use crate::sensor::film::Tile;
use crate::sensor::grid_sum::{Fixed3, Grid};
use crate::spectral::color;

/// The pilot's share of the sample budget.
pub const PILOT_FRACTION: f64 = 1.0 / 8.0;
/// The radius r of the (2r + 1)² box the pilot's variances are averaged over.
pub const BOX_RADIUS: usize = 2;
/// A replicate takes at most this many times the mean count in any pixel.
pub const MAX_RATIO: f64 = 16.0;
/// The fewest pilot samples per replicate (the first sets the clip; a variance needs 2 more).
pub const MIN_PILOT: u32 = 3;
/// The moments clip each channel at this multiple of the image's mean.
pub const CLIP_MULTIPLE: f64 = 8.0;

/// Sums of a replicate's samples in one pixel: the RGB values (linear Rec.709, before the
/// camera exposure), their squares summed over the channels, and the ray queries they made.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    pub n: u32,
    pub sum: [f64; 3],
    pub squares: f64,
    pub rays: u64,
}

impl Moments {
    /// Adds one sample of XYZ `xyz`, its RGB clipped at `clip`, which made `rays` ray queries.
    #[inline]
    pub fn add(&mut self, xyz: [f64; 3], clip: f64, rays: u64) {
        let rgb = color::xyz_to_rgb(xyz).map(|c| c.min(clip));
        self.n += 1;
        self.rays += rays;
        for (s, c) in self.sum.iter_mut().zip(rgb) {
            *s += c;
        }
        self.squares += rgb.iter().map(|c| c * c).sum::<f64>();
    }

    pub fn merge(&mut self, o: &Moments) {
        self.n += o.n;
        for (s, c) in self.sum.iter_mut().zip(o.sum) {
            *s += c;
        }
        self.squares += o.squares;
        self.rays += o.rays;
    }

    /// The cost of one sample: its mean ray queries plus one.
    pub fn cost(&self) -> f64 {
        1.0 + self.rays as f64 / f64::from(self.n.max(1))
    }

    /// The sample variance of one sample, summed over the channels (0 under 2 samples).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let n = f64::from(self.n);
        let mean_sq: f64 = self.sum.iter().map(|s| s * s).sum::<f64>() / n;
        ((self.squares - mean_sq) / (n - 1.0)).max(0.0)
    }
}

/// The plan of an adaptive render of `spp` samples per pixel on average.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    /// Pilot samples per replicate.
    pub pilot: u32,
    /// The mean samples per replicate of the whole render.
    pub mean: f64,
}

impl Plan {
    /// The plan for `spp`; an error when it is too few to adapt.
    pub fn new(spp: u32) -> Result<Plan, String> {
        if spp < 2 * MIN_PILOT {
            return Err(format!(
                "--adaptive needs --spp {} or more (a pilot of {MIN_PILOT} samples in each of \
                 a pixel's two replicates)",
                2 * MIN_PILOT
            ));
        }
        let pilot = ((f64::from(spp) * PILOT_FRACTION / 2.0).round() as u32).max(MIN_PILOT);
        Ok(Plan {
            pilot,
            mean: f64::from(spp) / 2.0,
        })
    }

    /// Samples per pixel of the pilot (both replicates).
    pub fn pilot_spp(&self) -> u64 {
        2 * u64::from(self.pilot)
    }
}

/// What one tile of an adaptive render collects per pixel over a segment: the odd samples'
/// grid sums, the samples per replicate, and, in the pilot, the replicates' [`Moments`].
#[derive(Clone, Debug, Default)]
pub struct ReplicateTile {
    pub odd: Vec<Fixed3>,
    pub counts: Vec<[u32; 2]>,
    /// Empty but in the pilot after its first samples.
    pub moments: Vec<[Moments; 2]>,
    /// The moments' clip.
    clip: f64,
}

impl ReplicateTile {
    /// A tile of `pixels` pixels, collecting moments clipped at `clip` when given.
    pub fn new(pixels: usize, clip: Option<f64>) -> ReplicateTile {
        ReplicateTile {
            odd: vec![[0; 3]; pixels],
            counts: vec![[0; 2]; pixels],
            moments: match clip {
                Some(_) => vec![[Moments::default(); 2]; pixels],
                None => Vec::new(),
            },
            clip: clip.unwrap_or(f64::INFINITY),
        }
    }

    /// Whether the tile collects the pilot's moments.
    pub fn collects(&self) -> bool {
        !self.moments.is_empty()
    }

    /// Sample `s` of tile pixel `k`: its own XYZ `xyz`, unless it is black its grid triple
    /// `t`, and the ray queries it made (counted while [`ReplicateTile::collects`]); true
    /// when the odd sum saturated.
    #[inline]
    pub fn add(&mut self, k: usize, s: u64, xyz: [f64; 3], t: Option<&Fixed3>, rays: u64) -> bool {
        let r = (s & 1) as usize;
        self.counts[k][r] += 1;
        if let Some(m) = self.moments.get_mut(k) {
            m[r].add(xyz, self.clip, rays);
        }
        match t {
            Some(t) if r == 1 => Grid::add3(&mut self.odd[k], t),
            _ => false,
        }
    }
}

/// Where an adaptive render stands: its plan, the pilot's moments until the allocation is
/// made, then the allocation.
#[derive(Clone, Debug)]
pub struct AdaptiveRun {
    pub plan: Plan,
    /// Per film pixel, each replicate's pilot moments (emptied once allocated).
    pub moments: Vec<[Moments; 2]>,
    /// Per film pixel, the samples of each replicate, once the pilot is done.
    pub allocation: Option<Vec<[u32; 2]>>,
    /// Pixel samples rendered so far.
    pub samples: u64,
    /// Pixels rendered (the window's, under a crop).
    pub pixels: u64,
    /// The moments' clip, once the pilot's first samples are in.
    pub clip: Option<f64>,
    /// After the pilot, the pixels that take each sample index (to size the passes).
    takers: Vec<u64>,
}

impl AdaptiveRun {
    pub fn new(plan: Plan, film_pixels: usize, rendered_pixels: u64) -> AdaptiveRun {
        AdaptiveRun {
            plan,
            moments: vec![[Moments::default(); 2]; film_pixels],
            allocation: None,
            samples: 0,
            pixels: rendered_pixels,
            clip: None,
            takers: Vec::new(),
        }
    }

    /// Samples per pixel of the pilot's first pass (one per replicate), which sets the clip.
    pub const FIRST: u64 = 2;

    /// Sets the clip from the mean RGB value `mean` of the image so far (infinite for a
    /// black image).
    pub fn set_clip(&mut self, mean: f64) {
        let clip = CLIP_MULTIPLE * mean;
        self.clip = Some(if clip > 0.0 { clip } else { f64::INFINITY });
    }

    /// The clip of a segment's moments: in the pilot, once set.
    pub fn moments_clip(&self) -> Option<f64> {
        self.clip.filter(|_| self.in_pilot())
    }

    /// Whether the pilot is still under way.
    pub fn in_pilot(&self) -> bool {
        self.allocation.is_none()
    }

    /// Adds a pilot tile's moments and any tile's sample counts.
    pub fn add_tile(&mut self, tile: &Tile, width: usize, t: &ReplicateTile) {
        for (k, i) in tile.pixels(width).enumerate() {
            self.samples += u64::from(t.counts[k][0] + t.counts[k][1]);
            if let Some(m) = t.moments.get(k) {
                self.moments[i][0].merge(&m[0]);
                self.moments[i][1].merge(&m[1]);
            }
        }
    }

    /// Allocates the samples from the pilot (`mask`: the rendered pixels); the end of the
    /// sample indices the allocation reaches (2 × the largest count of a replicate).
    pub fn allocate(&mut self, mask: &[bool], width: usize) -> u64 {
        let a = allocate(&self.moments, mask, width, self.plan);
        self.moments = Vec::new();
        let end = a.iter().map(|c| end_of(*c)).max().unwrap_or(0);
        // takers[s]: the pixels whose counts reach index s, by a difference array.
        let mut ends = vec![0i64; end as usize + 1];
        for c in &a {
            for r in 0..2 {
                ends[0] += 1;
                ends[(2 * u64::from(c[r])).min(end) as usize] -= 1;
            }
        }
        let mut open = 0;
        self.takers = ends[..end as usize]
            .iter()
            .map(|d| {
                open += d;
                // Half the open replicates take an even index, half an odd one.
                open.max(0) as u64 / 2
            })
            .collect();
        self.allocation = Some(a);
        end
    }

    /// After the pilot, the sample indices from `done` that hold about `samples` pixel samples
    /// (at least 1).
    pub fn indices_for(&self, done: u64, samples: f64) -> u64 {
        let mut sum = 0.0;
        let mut m = 0;
        for &t in self.takers.iter().skip(done as usize) {
            sum += t as f64;
            m += 1;
            if sum >= samples {
                break;
            }
        }
        m.max(1)
    }

    /// Mean samples per pixel so far.
    pub fn mean_spp(&self) -> f64 {
        self.samples as f64 / self.pixels.max(1) as f64
    }
}

/// The end of a pixel's sample indices under the counts `c` per replicate: replicate r's
/// samples are r, r + 2, …, r + 2(c_r − 1).
#[inline]
pub fn end_of(c: [u32; 2]) -> u64 {
    (2 * u64::from(c[0])).max(2 * u64::from(c[1]))
}

/// Whether sample `s` is among the counts `c` (replicate s mod 2, its sample ⌊s/2⌋).
#[inline]
pub fn takes(c: [u32; 2], s: u64) -> bool {
    s >> 1 < u64::from(c[(s & 1) as usize])
}

/// An adaptive render's samples per pixel (the EXR's `samples` channel) and a line of its
/// settings and counts (the `spectralRender:adaptive` attribute).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveImage {
    pub samples: Vec<f32>,
    pub summary: String,
}

impl AdaptiveImage {
    /// The image of `counts` (samples per film pixel) over the rendered pixels `mask`.
    pub fn new(plan: Plan, counts: &[u64], mask: &[bool]) -> AdaptiveImage {
        let inside = || counts.iter().zip(mask).filter(|(_, &m)| m).map(|(c, _)| *c);
        let (min, max) = (inside().min().unwrap_or(0), inside().max().unwrap_or(0));
        let n = inside().count().max(1) as f64;
        let mean = inside().sum::<u64>() as f64 / n;
        AdaptiveImage {
            samples: counts.iter().map(|&c| c as f32).collect(),
            summary: format!(
                "pilot {} spp, variance averaged over {}x{} pixels, at most {}x the mean; \
                 samples per pixel {min} to {max}, mean {mean:.3}",
                plan.pilot_spp(),
                2 * BOX_RADIUS + 1,
                2 * BOX_RADIUS + 1,
                MAX_RATIO
            ),
        }
    }
}

/// Which pixels of a `width` × `height` image the `tiles` cover.
pub fn rendered(tiles: &[Tile], width: usize, height: usize) -> Vec<bool> {
    let mut mask = vec![false; width * height];
    for t in tiles {
        for i in t.pixels(width) {
            mask[i] = true;
        }
    }
    mask
}

/// Each rendered pixel's counts per replicate [even, odd] from the pilot's `moments`
/// ([even, odd] per pixel, row-major, `width` wide; `mask` the rendered pixels): replicate 0's
/// from replicate 1's pilot and the other way round. Pixels outside `mask` get 0.
pub fn allocate(
    moments: &[[Moments; 2]],
    mask: &[bool],
    width: usize,
    plan: Plan,
) -> Vec<[u32; 2]> {
    let sigma = |r: usize| -> Vec<f64> {
        let v: Vec<f64> = moments.iter().map(|m| m[r].variance()).collect();
        let c: Vec<f64> = moments.iter().map(|m| m[r].cost()).collect();
        let v = box_average(&v, mask, width, BOX_RADIUS);
        let c = box_average(&c, mask, width, BOX_RADIUS);
        v.iter()
            .zip(c)
            .map(|(v, c)| (v / c.max(1.0)).sqrt())
            .collect()
    };
    let (from_odd, from_even) = (counts(&sigma(1), mask, plan), counts(&sigma(0), mask, plan));
    from_odd
        .into_iter()
        .zip(from_even)
        .map(|(a, b)| [a, b])
        .collect()
}

/// The average of `v` over the (2r + 1)² box around each pixel, over the pixels in `mask`
/// (0 outside it).
pub fn box_average(v: &[f64], mask: &[bool], width: usize, r: usize) -> Vec<f64> {
    let height = v.len() / width.max(1);
    let mut out = vec![0.0; v.len()];
    for y in 0..height {
        for x in 0..width {
            if !mask[y * width + x] {
                continue;
            }
            let (mut sum, mut n) = (0.0, 0u32);
            for yy in y.saturating_sub(r)..(y + r + 1).min(height) {
                for xx in x.saturating_sub(r)..(x + r + 1).min(width) {
                    let i = yy * width + xx;
                    if mask[i] {
                        sum += v[i];
                        n += 1;
                    }
                }
            }
            out[y * width + x] = sum / f64::from(n);
        }
    }
    out
}

/// Counts nᵢ = round(clamp(c·σᵢ, pilot, cap)) over the pixels in `mask`, with c such that the
/// unrounded counts' mean is `plan.mean` (uniform counts where every σ is 0).
fn counts(sigma: &[f64], mask: &[bool], plan: Plan) -> Vec<u32> {
    let lo = f64::from(plan.pilot);
    let hi = (MAX_RATIO * plan.mean).max(lo);
    let active: Vec<f64> = sigma
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(s, _)| if s.is_finite() { *s } else { 0.0 })
        .collect();
    let target = plan.mean * active.len() as f64;
    let total = |c: f64| -> f64 { active.iter().map(|s| (c * s).clamp(lo, hi)).sum() };
    let c = if active.iter().all(|&s| s <= 0.0) || plan.mean <= lo {
        None
    } else {
        Some(solve_scale(total, target))
    };
    sigma
        .iter()
        .zip(mask)
        .map(|(&s, &m)| match (m, c) {
            (false, _) => 0,
            (true, None) => plan.mean.max(lo).round() as u32,
            (true, Some(c)) => {
                let s = if s.is_finite() { s } else { 0.0 };
                (c * s).clamp(lo, hi).round() as u32
            }
        })
        .collect()
}

/// The c > 0 at which the non-decreasing `total(c)` reaches `target`, by bisection (to the
/// bisection's limit where `target` lies beyond the total's range).
fn solve_scale(total: impl Fn(f64) -> f64, target: f64) -> f64 {
    let mut hi = 1.0;
    while total(hi) < target && hi < 1e300 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if total(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(values: &[f64]) -> Moments {
        let mut m = Moments::default();
        for &v in values {
            // Y = v with x = z = 0 is not a grey; use the grey of luminance v.
            m.add(color::rgb_to_xyz([v, v, v]), f64::INFINITY, 3);
        }
        m
    }

    #[test]
    fn moments_give_the_sample_variance_summed_over_channels() {
        let m = moments(&[1.0, 3.0, 2.0, 6.0]);
        // Per channel: mean 3, Σ(x − 3)² = 4 + 0 + 1 + 9 = 14, / 3; three channels.
        assert!(
            (m.variance() - 3.0 * 14.0 / 3.0).abs() < 1e-9,
            "{}",
            m.variance()
        );
        assert_eq!(moments(&[5.0]).variance(), 0.0);
        let mut a = moments(&[1.0, 3.0]);
        a.merge(&moments(&[2.0, 6.0]));
        assert!((a.variance() - m.variance()).abs() < 1e-9);
    }

    #[test]
    fn the_plan_takes_an_eighth_as_its_pilot() {
        assert_eq!(Plan::new(256).unwrap().pilot, 16);
        assert_eq!(Plan::new(256).unwrap().pilot_spp(), 32);
        assert_eq!(Plan::new(16).unwrap().pilot, MIN_PILOT);
        assert_eq!(Plan::new(6).unwrap().pilot_spp(), 6);
        assert!(Plan::new(5).is_err());
    }

    #[test]
    fn the_box_averages_over_rendered_neighbours_only() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let mask = [true, true, false, true, true, true];
        let b = box_average(&v, &mask, 3, 1);
        assert_eq!(b[0], (1.0 + 2.0 + 4.0 + 5.0) / 4.0);
        assert_eq!(b[2], 0.0);
        assert_eq!(b[5], (2.0 + 5.0 + 6.0) / 3.0);
        assert_eq!(box_average(&v, &[true; 6], 3, 0), v.to_vec());
    }

    /// Pixels whose replicates' pilots differ: the left half noisy, the right half quiet.
    fn two_halves(noisy: f64) -> Vec<[Moments; 2]> {
        (0..64)
            .map(|i| {
                let a = if i % 8 < 4 { noisy } else { 1.0 };
                [
                    moments(&[0.0, a, 0.0, a]),
                    moments(&[0.0, 2.0 * a, 0.0, 2.0 * a]),
                ]
            })
            .collect()
    }

    #[test]
    fn counts_follow_the_other_replicates_noise_and_keep_the_mean() {
        let plan = Plan {
            pilot: 2,
            mean: 32.0,
        };
        let mask = vec![true; 64];
        let alloc = allocate(&two_halves(4.0), &mask, 8, plan);
        let mean = |r: usize| alloc.iter().map(|c| f64::from(c[r])).sum::<f64>() / 64.0;
        assert!((mean(0) - 32.0).abs() < 0.5 && (mean(1) - 32.0).abs() < 0.5);
        // Far from the edge between the halves (the box spreads it two pixels), the counts
        // are ∝ σ: 4 to 1.
        let (left, right) = (alloc[8 * 3], alloc[8 * 3 + 7]);
        let ratio = f64::from(left[0]) / f64::from(right[0]);
        assert!((ratio - 4.0).abs() < 0.2, "{left:?} {right:?}");
        assert!(alloc
            .iter()
            .all(|c| c[0] >= plan.pilot && c[1] >= plan.pilot));
        // Replicate 0 is allocated from replicate 1's pilot: make only replicate 1 vary.
        let mut m = two_halves(1.0);
        for (i, p) in m.iter_mut().enumerate() {
            if i % 8 < 4 {
                p[1] = moments(&[0.0, 8.0, 0.0, 8.0]);
            }
        }
        let alloc = allocate(&m, &mask, 8, plan);
        assert!(
            alloc[24][0] > 2 * alloc[31][0],
            "{:?} {:?}",
            alloc[24],
            alloc[31]
        );
        assert_eq!(alloc[24][1], alloc[31][1]);
    }

    #[test]
    fn black_pilots_and_unrendered_pixels() {
        let plan = Plan {
            pilot: 2,
            mean: 8.0,
        };
        let zero = vec![[Moments::default(); 2]; 16];
        let mut mask = vec![true; 16];
        mask[5] = false;
        let alloc = allocate(&zero, &mask, 4, plan);
        assert_eq!(alloc[5], [0, 0]);
        assert!(alloc
            .iter()
            .enumerate()
            .all(|(i, c)| i == 5 || *c == [8, 8]));
    }

    #[test]
    fn a_tile_counts_its_replicates_and_sums_the_odd_ones() {
        let mut t = ReplicateTile::new(2, Some(1.5));
        let g = Grid { exponent: 0 };
        let v = |x: f64| g.triple([x; 3]).0;
        t.add(1, 0, [1.0; 3], Some(&v(1.0)), 2);
        t.add(1, 1, [2.0; 3], Some(&v(2.0)), 4);
        t.add(1, 3, [0.0; 3], None, 1);
        assert_eq!(t.moments[1][1].cost(), 1.0 + 2.5);
        assert_eq!(t.counts, vec![[0, 0], [1, 2]]);
        assert_eq!(t.odd[1], v(2.0));
        assert_eq!((t.moments[1][0].n, t.moments[1][1].n), (1, 2));
        // Clipped at 1.5 per channel: 2 counts as 1.5.
        let rgb2 = t.moments[1][1].sum[0];
        assert!((rgb2 - 1.5).abs() < 1e-9, "{rgb2}");
        assert!(ReplicateTile::new(2, None).moments.is_empty());
        assert!(takes([2, 1], 2) && !takes([2, 1], 4) && takes([2, 1], 1) && !takes([2, 1], 3));
        assert_eq!(end_of([2, 1]), 4);
        assert_eq!(end_of([1, 3]), 6);
    }

    #[test]
    fn counts_are_capped_and_floored() {
        let plan = Plan {
            pilot: 3,
            mean: 4.0,
        };
        let mut sigma = vec![0.0; 100];
        sigma[0] = 1e6;
        let c = counts(&sigma, &[true; 100], plan);
        assert_eq!(c[0], (MAX_RATIO * 4.0) as u32);
        assert!(c[1..].iter().all(|&n| n >= 3));
    }
}
