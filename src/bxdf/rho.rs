//! The directional-hemispherical reflectance ρ_hd(ωo) = ∫ f(ωo, ωi) |cos θi| dωi of a BSDF
//! (PBR 4ed §4.3.1, Eq. 4.12), estimated as pbrt-v4's `BxDF::rho(wo, uc, u2)` does (PBR 4ed
//! §9.1.3): the mean of f |cos θi| / p over the BSDF's own samples, all its lobes, delta ones
//! included. The sample set is pbrt-v4's fixed 16-point set of `PathIntegrator::Li` (the
//! `ucRho` / `uRho` arrays its `VisibleSurface` albedo is estimated with), so the estimate is
//! deterministic: exact for a Lambertian lobe (every term is R), a 16-sample estimate for
//! glossy lobes.

use super::{Bsdf, TransportMode};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

/// pbrt-v4's `ucRho`: the lobe-selection samples (`src/pbrt/cpu/integrators.cpp`).
const UC_RHO: [f32; 16] = [
    0.757_416_4,
    0.378_708_2,
    0.708_348_7,
    0.189_354_1,
    0.914_936_3,
    0.354_174_35,
    0.599_085_8,
    0.094_677_03,
    0.857_872_5,
    0.457_468_12,
    0.686_759,
    0.177_087_16,
    0.967_451_8,
    0.299_542_9,
    0.508_320_1,
    0.047_338_516,
];

/// pbrt-v4's `uRho`: the direction samples, paired with [`UC_RHO`].
const U_RHO: [[f32; 2]; 16] = [
    [0.855_985, 0.570_367],
    [0.381_823, 0.851_844],
    [0.285_328, 0.764_262],
    [0.733_38, 0.114_073],
    [0.542_663, 0.344_465],
    [0.127_274, 0.414_848],
    [0.964_7, 0.947_162],
    [0.594_089, 0.643_463],
    [0.095_109, 0.170_369],
    [0.825_444, 0.263_359],
    [0.429_467, 0.454_469],
    [0.244_46, 0.816_459],
    [0.756_135, 0.731_258],
    [0.516_165, 0.152_852],
    [0.180_888, 0.214_174],
    [0.898_579, 0.503_897],
];

impl Bsdf {
    /// ρ_hd(`wo`) (world space, pointing away from the surface) per wavelength lane, from
    /// pbrt-v4's fixed samples; 0 for a grazing `wo`.
    pub fn rho(&self, wo: Vec3) -> SampledSpectrum {
        let n = self.frame.to_world(Vec3::Z);
        let mut r = SampledSpectrum::ZERO;
        for (uc, u) in UC_RHO.into_iter().zip(U_RHO) {
            // `sample_f` returns no sample for a zero pdf or a grazing `wo` (pbrt's checks).
            if let Some(bs) = self.sample_f(wo, uc, u, TransportMode::Radiance) {
                r += bs.f * (bs.wi.dot(n).abs() / bs.pdf_w);
            }
        }
        r * (1.0 / UC_RHO.len() as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bxdf::{Bxdf, DiffuseBxdf};
    use crate::testing::bxdf_examples::examples;
    use crate::testing::rng::Rng;

    #[test]
    fn a_lambertian_lobe_gives_its_reflectance_exactly() {
        let r = SampledSpectrum([0.1, 0.45, 0.8, 1.0]);
        let n = Vec3::new(0.3, 0.9, -0.2).normalize();
        let bsdf = Bsdf::new(Bxdf::Diffuse(DiffuseBxdf { r }), n);
        for wo in [n, (n + Vec3::X).normalize(), -n] {
            let rho = bsdf.rho(wo);
            for i in 0..4 {
                assert!((rho[i] - r[i]).abs() < 1e-6, "{wo}: {rho:?}");
            }
        }
    }

    #[test]
    fn the_fixed_samples_agree_with_a_long_estimate() {
        // Every model's 16-sample ρ against 2^16 independent samples of the same estimator
        // (PBR 4ed Eq. 4.12): the fixed set is a stratified subset, so within the spread of a
        // 16-sample mean of a term bounded by the model's largest term.
        let wo = Vec3::new(0.4, 0.1, 0.9).normalize();
        let mut rng = Rng::new(7);
        for ex in examples() {
            let bsdf = Bsdf::new(ex.bxdf, Vec3::Z);
            let fixed = bsdf.rho(wo);
            // Sums in f64: 2^16 terms near 1 in f32 would be off by ~1e-3.
            let (mut sum, mut sum2, n) = ([0.0f64; 4], [0.0f64; 4], 1 << 16);
            for _ in 0..n {
                let (uc, u) = (rng.f32(), [rng.f32(), rng.f32()]);
                if let Some(bs) = bsdf.sample_f(wo, uc, u, TransportMode::Radiance) {
                    let t = bs.f * (bs.wi.z.abs() / bs.pdf_w);
                    for (i, (s, s2)) in sum.iter_mut().zip(&mut sum2).enumerate() {
                        *s += f64::from(t[i]);
                        *s2 += f64::from(t[i]) * f64::from(t[i]);
                    }
                }
            }
            for (i, (s, s2)) in sum.iter().zip(&sum2).enumerate() {
                let mean = s / f64::from(n);
                let var = (s2 / f64::from(n) - mean * mean).max(0.0);
                // Five standard deviations of a 16-sample mean, plus 1e-3 for the long
                // estimate's own error where the terms hardly vary.
                let tol = 5.0 * (var / 16.0).sqrt() + 1e-3;
                assert!(
                    (f64::from(fixed[i]) - mean).abs() <= tol,
                    "{}: lane {i}: {} vs {mean} ± {tol}",
                    ex.name,
                    fixed[i],
                );
                assert!(fixed[i] >= 0.0, "{}", ex.name);
            }
        }
    }
}
