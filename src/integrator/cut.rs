//! What a depth cap cuts, estimated without touching the capped estimate.
//!
//! A depth cap (`--max-depth`, or the safety cap [`SAFETY_DEPTH`] when none is given) ends
//! every path that reaches it, and the light of the longer paths is lost: a bias. To say how
//! much, a random fraction [`Q`] of the capped paths is continued past the cap — on a
//! sampler stream of its own ([`continuation`], forked from the path's without advancing it,
//! so the capped estimate keeps its random numbers and its bits) — and what the continuation
//! finds, weighted 1/q, goes to a separate accumulator ([`CutSample::light`]). Its expectation
//! is the light of the paths longer than the cap (up to the continuation's own limit, the cap
//! plus [`SAFETY_DEPTH`]): Russian roulette with survival probability q (PBR 4ed §13.4.1,
//! "Russian roulette"), applied once, at the cap.
//!
//! The drivers report the fraction cut, cut / (capped + cut), as a ratio estimate
//! (`math::ratio`, Cochran 1977 §6.3–6.4) from paired sums: per sample for meters ([`RatioSums`]), per batch of
//! samples for images ([`BatchedRatio`]: a sample's pixel is not random, so the batches — all
//! pixels' samples of one residue of the sample index — are the independent observations).
//!
//! The path tracer continues its own path; BDPT and VCM continue their camera subpath with
//! the path tracer (every path longer than the cap has such a camera prefix), light tracing
//! its light subpath, connecting each further vertex to the sensor.

pub use crate::math::ratio::RatioSums;
use crate::sampling::Sampler;
use crate::spectral::SampledSpectrum;

/// The depth cap when none is given: Russian roulette ends paths long before it in any scene
/// whose reflectances stay below 1; reaching it is reported with what it cut.
pub const SAFETY_DEPTH: u32 = 1024;

/// The fraction of capped paths continued past the cap.
pub const Q: f32 = 0.125;

/// Offsets the continuation's sampler stream from the path's.
const STREAM: u64 = 0x4355_545f_5041_5354;

/// Batches of an image's samples for the interval of the fraction cut ([`BatchedRatio`]).
pub const BATCHES: usize = 16;

/// The effective depth cap of a run: the user's, or the safety cap.
#[inline]
pub fn depth_cap(max_depth: Option<u32>) -> u32 {
    max_depth.unwrap_or(SAFETY_DEPTH)
}

/// The limit of a continuation that starts at the cap `cap`.
#[inline]
pub fn continuation_limit(cap: u32) -> u32 {
    cap.saturating_add(SAFETY_DEPTH)
}

/// The sampler of a continuation past the cap, with probability [`Q`]: a stream derived from
/// the path's current state, which is left as it is.
#[inline]
pub fn continuation<'a>(sampler: &Sampler<'a>) -> Option<Sampler<'a>> {
    continuation_of(sampler, 0)
}

/// [`continuation`] of branch `b` of a path split at its first vertex (`integrator::path`):
/// the branches share the sampler's free stream, so each forks its own (branch 0 is the
/// unsplit path's).
#[inline]
pub fn continuation_of<'a>(sampler: &Sampler<'a>, b: u32) -> Option<Sampler<'a>> {
    let mut s = sampler.fork(STREAM.wrapping_add(u64::from(b)));
    (s.get_1d() < Q).then_some(s)
}

/// What one sample's continuations past the cap found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CutSample {
    /// The light beyond the cap, weighted 1/q, relative to the sample's final wavelengths
    /// (as its capped estimate).
    pub light: SampledSpectrum,
    /// Paths (or subpaths) of the sample that reached the cap.
    pub capped: u32,
    /// Continuations that reached their own limit: the light beyond it is not counted.
    pub limited: u32,
}

impl CutSample {
    /// Adds a continuation's light `l` (not yet weighted by 1/q) times `k`; `limited` when it
    /// reached its own limit.
    #[inline]
    pub fn add(&mut self, l: SampledSpectrum, k: f32, limited: bool) {
        self.light += l * (k / Q);
        self.limited += u32::from(limited);
    }
}

/// Sums of an image's samples in [`BATCHES`] batches by sample index (each batch holds every
/// pixel's samples of one residue), for the ratio of the cut to the whole image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BatchedRatio {
    /// Per batch: samples, Σ cut, Σ (capped + cut) of the samples' luminance.
    pub batches: [(u64, f64, f64); BATCHES],
    /// Paths that reached the cap and continuations that reached their own limit.
    pub capped: u64,
    pub limited: u64,
}

impl BatchedRatio {
    /// Adds a sample of index `s` whose capped estimate has luminance `main` and whose
    /// continuations (`cut`) found luminance `cut_y`.
    #[inline]
    pub fn push(&mut self, s: u64, main: f64, cut: &CutSample, cut_y: f64) {
        let b = &mut self.batches[(s % BATCHES as u64) as usize];
        b.0 += 1;
        b.1 += cut_y;
        b.2 += main + cut_y;
        self.capped += u64::from(cut.capped);
        self.limited += u64::from(cut.limited);
    }

    pub fn merge(&mut self, o: &BatchedRatio) {
        for (a, b) in self.batches.iter_mut().zip(&o.batches) {
            a.0 += b.0;
            a.1 += b.1;
            a.2 += b.2;
        }
        self.capped += o.capped;
        self.limited += o.limited;
    }

    /// The batches as observations of a ratio: the sums of each non-empty batch.
    pub fn sums(&self) -> RatioSums {
        let mut r = RatioSums::default();
        for &(n, c, t) in &self.batches {
            if n > 0 {
                r.push(c, t);
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_continuation_leaves_the_path_stream_alone_and_runs_a_fraction_q() {
        let mut hits = 0;
        let n = 80_000;
        for k in 0..n {
            let s = Sampler::new(3, k, 1);
            let before = s.clone().get_1d();
            if continuation(&s).is_some() {
                hits += 1;
            }
            assert_eq!(s.clone().get_1d(), before);
        }
        // Binomial(n, 1/8): σ = √(n q (1 − q)) ≈ 94.
        let expected = n as f64 * Q as f64;
        assert!((hits as f64 - expected).abs() < 5.0 * 94.0, "{hits}");
    }
}
