//! Hero-wavelength sampling (Wilkie et al. 2014, "Hero Wavelength Spectral Sampling").
//!
//! The hero wavelength is drawn from the visible-range pdf of Radziszewski et al. 2009
//! ("An Improved Technique for Full Spectral Rendering"), p(λ) ∝ sech²(0.0072 (λ − 538)),
//! the same importance function as pbrt-v4 (`SampleVisibleWavelengths`, PBR 4ed §5.4.2)
//! and Mitsuba 3 (`rgb_importance`). The other three are rotations of the hero's primary
//! sample u by 1/4, 2/4, 3/4, so the four are stratified over [0, 1).

use super::{SampledSpectrum, LAMBDA_MAX, LAMBDA_MIN, N_LAMBDA};

/// The wavelengths a path carries and their pdfs (per nm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    pub lambda: [f32; N_LAMBDA],
    pub pdf: [f32; N_LAMBDA],
}

impl SampledWavelengths {
    /// Stratified visible-range sampling from one uniform number.
    pub fn sample_visible(u: f32) -> SampledWavelengths {
        let mut lambda = [0.0; N_LAMBDA];
        let mut pdf = [0.0; N_LAMBDA];
        for i in 0..N_LAMBDA {
            let mut up = u + i as f32 / N_LAMBDA as f32;
            if up >= 1.0 {
                up -= 1.0;
            }
            lambda[i] = sample_visible_wavelength(up);
            pdf[i] = visible_wavelength_pdf(lambda[i]);
        }
        SampledWavelengths { lambda, pdf }
    }

    /// Uniform sampling over [LAMBDA_MIN, LAMBDA_MAX], stratified the same way.
    pub fn sample_uniform(u: f32) -> SampledWavelengths {
        let range = LAMBDA_MAX - LAMBDA_MIN;
        let lambda = std::array::from_fn(|i| {
            let up = (u + i as f32 / N_LAMBDA as f32).fract();
            LAMBDA_MIN + up * range
        });
        SampledWavelengths {
            lambda,
            pdf: [1.0 / range; N_LAMBDA],
        }
    }

    /// The pdfs as a spectrum (for dividing estimates).
    #[inline]
    pub fn pdf(&self) -> SampledSpectrum {
        SampledSpectrum(self.pdf)
    }

    /// Keeps only the hero wavelength (pbrt-v4 `TerminateSecondary`): the others get pdf 0
    /// and the hero's pdf is divided by N, so that estimates stay unbiased.
    pub fn terminate_secondary(&mut self) {
        if self.secondary_terminated() {
            return;
        }
        for i in 1..N_LAMBDA {
            self.pdf[i] = 0.0;
        }
        self.pdf[0] /= N_LAMBDA as f32;
    }

    pub fn secondary_terminated(&self) -> bool {
        self.pdf[1..].iter().all(|&p| p == 0.0)
    }

    /// An estimate `x` made with `later`, a copy of these wavelengths that may have terminated
    /// its secondaries since, re-expressed against these pdfs (× p(λ)/p'(λ) per lane: the
    /// hero lane × N, the others 0), so that converting it with these stays unbiased.
    #[inline]
    pub fn rebase(&self, x: SampledSpectrum, later: &SampledWavelengths) -> SampledSpectrum {
        if later.secondary_terminated() && !self.secondary_terminated() {
            x * self.pdf().safe_div(later.pdf())
        } else {
            x
        }
    }
}

/// Inverse CDF of p(λ) ∝ sech²(0.0072 (λ − 538)) on [360, 830] nm (Radziszewski et al. 2009).
#[inline]
pub fn sample_visible_wavelength(u: f32) -> f32 {
    let l = 538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh();
    l.clamp(LAMBDA_MIN, LAMBDA_MAX)
}

/// The normalised pdf of [`sample_visible_wavelength`], per nm.
#[inline]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let c = (0.0072 * (lambda - 538.0)).cosh();
    0.003_939_804 / (c * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pdf_integrates_to_one() {
        let n = 47_000;
        let h = (LAMBDA_MAX - LAMBDA_MIN) as f64 / n as f64;
        let sum: f64 = (0..n)
            .map(|i| {
                visible_wavelength_pdf(LAMBDA_MIN + (i as f64 + 0.5) as f32 * h as f32) as f64 * h
            })
            .sum();
        assert!((sum - 1.0).abs() < 1e-4, "{sum}");
    }

    #[test]
    fn inverse_cdf_matches_pdf() {
        // d(lambda)/du = 1/pdf(lambda), checked by finite differences.
        for &u in &[0.05f32, 0.3, 0.5, 0.7, 0.95] {
            let du = 1e-3;
            let dl = sample_visible_wavelength(u + du) - sample_visible_wavelength(u - du);
            let pdf = visible_wavelength_pdf(sample_visible_wavelength(u));
            assert!(((dl / (2.0 * du)) * pdf - 1.0).abs() < 2e-3, "u={u}");
        }
    }

    #[test]
    fn rotations_are_stratified() {
        let w = SampledWavelengths::sample_visible(0.9);
        assert!(w
            .lambda
            .iter()
            .all(|l| (LAMBDA_MIN..=LAMBDA_MAX).contains(l)));
        let mut sorted = w.lambda;
        sorted.sort_by(f32::total_cmp);
        assert!(sorted.windows(2).all(|p| p[1] > p[0]));
    }

    #[test]
    fn termination_keeps_the_estimate_unbiased() {
        let mut w = SampledWavelengths::sample_visible(0.2);
        let p0 = w.pdf[0];
        w.terminate_secondary();
        assert!(w.secondary_terminated());
        assert_eq!(w.pdf[0], p0 / 4.0);
        w.terminate_secondary();
        assert_eq!(w.pdf[0], p0 / 4.0);
    }
}
