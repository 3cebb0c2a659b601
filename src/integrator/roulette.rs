//! The path tracer's Russian roulette (`--rr-depth`); where it starts by default is chosen
//! per scene by `roulette_pilot.rs`.
//!
//! After its `start`-th scattering event (and every later one) a path whose throughput has
//! dropped below 1 survives with probability p = max β·η² and carries 1/p from then on;
//! PBR 4ed §13.4.1 ("Russian roulette", the PathIntegrator's `rrBeta` test) with `start` 2,
//! Mitsuba 3's `path` plugin (`rr_depth`, default 5; `src/integrators/path.cpp`) from its
//! `rr_depth`-th. η² is the product of the squared relative IORs of the refractions so far
//! (pbrt-v4's `etaScale`, PBR 4ed §14.1.3): radiance scaled by 1/η² across an interface is
//! not absorbed, and roulette must not end it as if it were.
//!
//! Mitsuba also caps the survival probability at 0.95; ours is min(p, 1) as pbrt-v4's. The
//! cap only acts where max β·η² ≥ 0.95 after `start` bounces — near-lossless surroundings —
//! and there it multiplies each survivor's weight by 1/0.95 per bounce (more variance) to end
//! paths that the reflectances would carry on. Without it a lossless path (ρ = 1) runs to the
//! safety cap `cut::SAFETY_DEPTH`, which is reported with what it cut (docs/design.md §8
//! "Variance per sample").

use crate::sampling::Sampler;
use crate::spectral::SampledSpectrum;

/// pbrt-v4's first bounce of roulette (PBR 4ed §13.4.1): that of the bidirectional
/// integrators' subpaths (`bidir/subpath.rs`) and of the path tracer that continues their
/// camera subpaths past a cap (`cut.rs`).
pub const PBRT_RR_DEPTH: u32 = 2;

/// The first bounce at which roulette may end a path when no pilot chooses it: light
/// meters, and images whose pilot found no light (`roulette_pilot.rs`); pbrt-v4's.
pub const DEFAULT_RR_DEPTH: u32 = 2;

/// Where the path tracer's roulette starts (`--rr-depth`): chosen per scene by a pilot
/// (`roulette_pilot.rs`; the default), or a given scattering event (1 or later).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RrStart {
    #[default]
    Auto,
    At(u32),
}

impl RrStart {
    /// The start for a run that has no pilot (meters): the given one, or [`DEFAULT_RR_DEPTH`].
    pub fn or_default(self) -> u32 {
        match self {
            RrStart::Auto => DEFAULT_RR_DEPTH,
            RrStart::At(n) => n,
        }
    }
}

impl std::fmt::Display for RrStart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RrStart::Auto => f.write_str("auto"),
            RrStart::At(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for RrStart {
    type Err = String;

    /// `auto`, or a whole number of at least 1.
    fn from_str(s: &str) -> Result<RrStart, String> {
        if s == "auto" {
            return Ok(RrStart::Auto);
        }
        match s.parse::<u32>() {
            Ok(n) if n >= 1 => Ok(RrStart::At(n)),
            _ => Err(format!("'{s}': auto or a whole number of at least 1")),
        }
    }
}

/// Russian roulette after scattering event `depth` (1 for the first) of a path with
/// throughput `beta` and refraction scale `eta_scale`, for roulette from bounce `rr_depth`;
/// false when the path ends. Draws one number only when the test is played. Inlined into
/// the path tracer's walk (its one caller): −33 instructions a sample once `scatter` is
/// inlined there (design.md §8, eighth pass; the fifth pass measured −2 when it was not).
#[inline(always)]
pub fn survives(
    beta: &mut SampledSpectrum,
    eta_scale: f32,
    depth: u32,
    rr_depth: u32,
    sampler: &mut Sampler,
) -> bool {
    let m = beta.max_value() * eta_scale;
    if m < 1.0 && depth >= rr_depth {
        let q = (1.0 - m).max(0.0);
        if sampler.get_1d() < q {
            return false;
        }
        *beta = *beta / (1.0 - q);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler() -> Sampler<'static> {
        Sampler::new(7, 0, 0)
    }

    #[test]
    fn starts_parse_and_print() {
        for (text, start) in [
            ("auto", RrStart::Auto),
            ("1", RrStart::At(1)),
            ("5", RrStart::At(5)),
        ] {
            assert_eq!(text.parse::<RrStart>(), Ok(start));
            assert_eq!(start.to_string(), text);
        }
        for bad in ["0", "-2", "x", "", "Auto", "2.5"] {
            assert!(bad.parse::<RrStart>().is_err(), "{bad}");
        }
        assert_eq!(RrStart::Auto.or_default(), DEFAULT_RR_DEPTH);
        assert_eq!(RrStart::At(4).or_default(), 4);
    }

    #[test]
    fn before_its_start_roulette_neither_ends_nor_reweights_nor_draws() {
        let mut s = sampler();
        let mut reference = sampler();
        let mut beta = SampledSpectrum::splat(0.01);
        for depth in 1..5 {
            assert!(survives(&mut beta, 1.0, depth, 5, &mut s));
        }
        assert_eq!(beta, SampledSpectrum::splat(0.01));
        assert_eq!(s.get_1d(), reference.get_1d());
    }

    #[test]
    fn survivors_carry_the_inverse_probability_so_the_mean_is_kept() {
        // E[β'] = p · β/p = β: the mean of the survivors' weights over all trials is β, with
        // standard error β √((1 − p)/(p n)); held at 5 σ.
        let (b, n) = (0.3f32, 20_000u32);
        let mut s = sampler();
        let mut sum = 0.0f64;
        for _ in 0..n {
            let mut beta = SampledSpectrum::splat(b);
            if survives(&mut beta, 1.0, 5, 5, &mut s) {
                assert!((beta.max_value() - 1.0).abs() < 1e-6);
                sum += f64::from(beta.max_value());
            }
        }
        let mean = sum / f64::from(n);
        let se = f64::from(b) * ((1.0 - f64::from(b)) / (f64::from(b) * f64::from(n))).sqrt();
        assert!(
            (mean - f64::from(b)).abs() < 5.0 * se,
            "{mean} vs {b} ± {se}"
        );
    }

    #[test]
    fn a_throughput_of_one_or_more_always_survives_unchanged() {
        let mut s = sampler();
        for m in [1.0f32, 1.5, 40.0] {
            let mut beta = SampledSpectrum::splat(m);
            assert!(survives(&mut beta, 1.0, 9, 1, &mut s));
            assert_eq!(beta, SampledSpectrum::splat(m));
        }
        // Inside glass (η² = 2.25) a throughput of 0.5 is not absorption: 0.5 · 2.25 > 1.
        let mut beta = SampledSpectrum::splat(0.5);
        assert!(survives(&mut beta, 2.25, 9, 1, &mut s));
        assert_eq!(beta, SampledSpectrum::splat(0.5));
    }
}
