//! Hero-wavelength sampling (Wilkie et al. 2014, "Hero Wavelength Spectral Sampling").
//!
//! The hero wavelength is drawn from the visible-range pdf of Radziszewski et al. 2009
//! ("An Improved Technique for Full Spectral Rendering"), p(λ) ∝ sech²(0.0072 (λ − 538)),
//! the same importance function as pbrt-v4 (`SampleVisibleWavelengths`, PBR 4ed §5.4.2)
//! and Mitsuba 3 (`sample_rgb_spectrum`). The other three are rotations of the hero's primary
//! sample u by 1/4, 2/4, 3/4, so the four are stratified over [0, 1) (Mitsuba's
//! `sample_shifted`, pbrt-v4's `SampleVisible`).
//!
//! A sample calls no transcendental function: the inverse CDF's atanh is ½ ln((1 + y)/(1 − y)),
//! and the four logarithms are one branch-free polynomial pass over the four lanes (Cephes
//! `logf`, [`ln_lanes`]), within an ulp of the libm call the per-lane form makes
//! ([`sample_visible_wavelength_and_pdf`]). The pdf is the closed form 0.0039398 (1 − y²) of
//! the inverse CDF's own argument y rather than sech² of the wavelength: the same pdf.

use super::{SampledSpectrum, LAMBDA_MAX, LAMBDA_MIN, N_LAMBDA};

/// The wavelengths a path carries and their pdfs (per nm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    pub lambda: [f32; N_LAMBDA],
    pub pdf: [f32; N_LAMBDA],
}

impl SampledWavelengths {
    /// Stratified visible-range sampling from one uniform number.
    /// The lanes' u are those of [`sample_visible_wavelength_and_pdf`]; the four atanh are
    /// evaluated together ([`ln_lanes`]).
    pub fn sample_visible(u: f32) -> SampledWavelengths {
        let y: [f32; N_LAMBDA] = std::array::from_fn(|i| {
            let up = u + i as f32 / N_LAMBDA as f32;
            visible_y(if up >= 1.0 { up - 1.0 } else { up })
        });
        let ln = ln_lanes(std::array::from_fn(|i| (1.0 + y[i]) / (1.0 - y[i])));
        SampledWavelengths {
            lambda: std::array::from_fn(|i| visible_lambda(0.5 * ln[i])),
            pdf: std::array::from_fn(|i| VISIBLE_PDF_PEAK * (1.0 - y[i] * y[i])),
        }
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
    sample_visible_wavelength_and_pdf(u).0
}

/// [`sample_visible_wavelength`] and its pdf [`visible_wavelength_pdf`] without a cosh: with
/// y = 0.8569 − 1.8275 u the inverse CDF is λ = 538 − (1/0.0072) atanh y, so
/// 0.0072 (λ − 538) = −atanh y and sech²(atanh y) = 1 − y² (cosh(atanh y) = 1/√(1 − y²)):
/// p(λ) = 0.0039398 (1 − y²), which is also 1 / (dλ/du) = 1 / (253.82 / (1 − y²)), the density
/// the inverse CDF actually produces. Equal to the sech² form up to round-off (tests: within
/// 10⁻⁵ relative over all u).
/// [`SampledWavelengths::sample_visible`] gives each lane this λ to an ulp of atanh and this
/// pdf exactly.
#[inline]
pub fn sample_visible_wavelength_and_pdf(u: f32) -> (f32, f32) {
    let y = visible_y(u);
    (visible_lambda(y.atanh()), VISIBLE_PDF_PEAK * (1.0 - y * y))
}

/// The inverse CDF's argument y = 0.8569 − 1.8275 u (Radziszewski et al. 2009).
#[inline]
fn visible_y(u: f32) -> f32 {
    0.856_910_6 - 1.827_502 * u
}

/// λ = 538 − (1/0.0072) atanh y, clamped to the range.
#[inline]
fn visible_lambda(atanh_y: f32) -> f32 {
    (538.0 - 138.888_89 * atanh_y).clamp(LAMBDA_MIN, LAMBDA_MAX)
}

/// Natural logarithms of positive normal floats, lane by lane with no branch or call, so the
/// compiler can keep the four lanes in one vector: x = m 2^e with m in [√½, √2), ln x =
/// e ln 2 + ln m, ln m by Cephes `logf`'s polynomial in m − 1 and its two-part ln 2 (Moshier
/// 1989, "Methods and Programs for Mathematical Functions", §4.2; relative error below
/// 2·10⁻⁷ over the inverse CDF's range, tested against f64).
#[inline]
fn ln_lanes(x: [f32; N_LAMBDA]) -> [f32; N_LAMBDA] {
    std::array::from_fn(|i| {
        let bits = x[i].to_bits();
        // m in [½, 1) and x = m 2^e.
        let mut e = ((bits >> 23) & 0xff) as i32 - 126;
        let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
        let low = m < std::f32::consts::FRAC_1_SQRT_2;
        e -= low as i32;
        let t = if low { m + m - 1.0 } else { m - 1.0 };
        let e = e as f32;
        let z = t * t;
        let p = ((((((((7.037_683_6e-2 * t - 1.151_461e-1) * t + 1.167_699_9e-1) * t
            - 1.242_014_1e-1)
            * t
            + 1.424_932_3e-1)
            * t
            - 1.666_805_8e-1)
            * t
            + 2.000_071_4e-1)
            * t
            - 2.499_999_4e-1)
            * t
            + 3.333_333e-1)
            * t
            * z;
        let r = p - 2.121_944_4e-4 * e - 0.5 * z;
        t + r + 0.693_359_4 * e
    })
}

/// The visible-range pdf at its peak λ = 538 nm, per nm: 0.0072 / (tanh(0.0072 · 292) +
/// tanh(0.0072 · 178)), the normalisation over [360, 830] nm (Radziszewski et al. 2009;
/// pbrt-v4 `VisibleWavelengthsPDF`).
const VISIBLE_PDF_PEAK: f32 = 0.003_939_804;

/// The normalised pdf of [`sample_visible_wavelength`], per nm.
#[inline]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let c = (0.0072 * (lambda - 538.0)).cosh();
    VISIBLE_PDF_PEAK / (c * c)
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
    fn closed_form_pdf_is_the_sech2_pdf_to_round_off() {
        // Over the whole unit interval (the rotations reach all of it), including its ends.
        let n = 100_000;
        for i in 0..=n {
            let u = (i as f32 / n as f32).min(1.0 - f32::EPSILON / 2.0);
            let (l, p) = sample_visible_wavelength_and_pdf(u);
            let q = visible_wavelength_pdf(l);
            assert!((p - q).abs() <= 1e-5 * q, "u={u} λ={l}: {p} vs {q}");
        }
    }

    #[test]
    fn lane_logarithm_is_within_round_off() {
        // Over the ratios (1 + y)/(1 − y) the sampler takes, and a decade beyond each end.
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = (1e-3f64 * (2e5f64).powf(i as f64 / 200_000.0)) as f32;
            let got = ln_lanes([x; N_LAMBDA])[0] as f64;
            let want = (x as f64).ln();
            worst = worst.max((got - want).abs() / want.abs().max(1e-3));
        }
        assert!(worst < 2e-7, "relative error {worst}");
    }

    #[test]
    fn lanes_are_the_per_lane_inverse_to_an_ulp() {
        // Every lane against sample_visible_wavelength_and_pdf (libm's atanh): λ within
        // 2 · 10⁻⁴ nm (a few ulp at 830 nm), the pdf bit for bit.
        let n = 100_000;
        for i in 0..n {
            let u = i as f32 / n as f32;
            let w = SampledWavelengths::sample_visible(u);
            for k in 0..N_LAMBDA {
                let mut up = u + k as f32 / N_LAMBDA as f32;
                if up >= 1.0 {
                    up -= 1.0;
                }
                let (l, p) = sample_visible_wavelength_and_pdf(up);
                assert!(
                    (w.lambda[k] - l).abs() <= 2e-4,
                    "u={up}: {} vs {l}",
                    w.lambda[k]
                );
                assert_eq!(w.pdf[k], p, "u={up}");
            }
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
