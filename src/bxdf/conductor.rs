//! Conductors, smooth and rough (PBR 4ed §9.4 `ConductorBxDF`).
//!
//! The Fresnel term is the complex Fresnel equations with the metal's spectral η and k
//! (PBR 4ed §9.3.6), evaluated per wavelength. Smooth (α < 10⁻³): a mirror,
//! f = F(cos θ)/|cos θ| δ(ωi − reflect(ωo)). Rough: Torrance–Sparrow with the
//! Trowbridge–Reitz distribution, sampled by visible normals (PBR 4ed §9.6, eq. 9.33).
//! The model is two-sided: ωo below the surface sees the mirror image of the upper side.
//!
//! Scene use (`spectral:conductor`, docs/design.md §3):
//! ```text
//! def Shader "Gold" {
//!     uniform token info:id = "spectral:conductor"
//!     token inputs:metal = "Au"          # or inputs:eta:spectrum + inputs:k:spectrum
//!     float inputs:roughness = 0.1       # GGX α; 0 is a mirror
//! }
//! ```

use super::fresnel::fr_complex_spectrum;
use super::microfacet::TrowbridgeReitz;
use super::{BsdfSample, TransportMode};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorBxdf {
    pub distrib: TrowbridgeReitz,
    /// Real part of the complex index relative to the outside medium, per wavelength.
    pub eta: SampledSpectrum,
    /// Extinction coefficient, per wavelength.
    pub k: SampledSpectrum,
}

impl ConductorBxdf {
    pub fn new(distrib: TrowbridgeReitz, eta: SampledSpectrum, k: SampledSpectrum) -> Self {
        ConductorBxdf { distrib, eta, k }
    }

    #[inline]
    pub fn is_specular(&self) -> bool {
        self.distrib.effectively_smooth()
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        if self.is_specular() {
            return SampledSpectrum::ZERO;
        }
        match self.distrib.reflection_eval(wo, wi) {
            Some((wm, dg)) => fr_complex_spectrum(wo.dot(wm).abs(), self.eta, self.k) * dg,
            None => SampledSpectrum::ZERO,
        }
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        _uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.is_specular() {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let cos = wi.z.abs();
            let f = fr_complex_spectrum(cos, self.eta, self.k) / cos;
            return Some(BsdfSample::reflection(f, wi, 1.0, true));
        }
        let (wi, pdf_w, _) = self.distrib.sample_reflection(wo, u)?;
        Some(BsdfSample::reflection(
            self.f(wo, wi, mode),
            wi,
            pdf_w,
            false,
        ))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        if self.is_specular() {
            return 0.0;
        }
        self.distrib.reflection_pdf(wo, wi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    fn gold_like(alpha: f32) -> ConductorBxdf {
        ConductorBxdf::new(
            TrowbridgeReitz::isotropic(alpha),
            SampledSpectrum([0.2, 0.4, 1.0, 1.4]),
            SampledSpectrum([3.5, 2.8, 1.9, 1.7]),
        )
    }

    #[test]
    fn mirror_at_normal_incidence_reflects_the_tabulated_formula() {
        let b = gold_like(0.0);
        let s = b
            .sample_f(Vec3::Z, 0.5, [0.5, 0.5], TransportMode::Radiance)
            .unwrap();
        assert!(s.specular && (s.wi - Vec3::Z).length() < 1e-6);
        for i in 0..4 {
            let (n, k) = (b.eta[i], b.k[i]);
            let r = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            assert!((s.f[i] - r).abs() < 1e-5);
        }
    }

    #[test]
    fn rough_samples_agree_with_eval_and_pdf() {
        let b = gold_like(0.3);
        let mut s = Sampler::new(9, 0, 0);
        let wo = Vec3::new(0.3, 0.2, -0.9).normalize();
        for _ in 0..1000 {
            let Some(smp) = b.sample_f(wo, 0.5, s.get_2d(), TransportMode::Radiance) else {
                continue;
            };
            let f = b.f(wo, smp.wi, TransportMode::Radiance);
            let pdf = b.pdf(wo, smp.wi, TransportMode::Radiance);
            assert!(smp.wi.z < 0.0);
            assert!((pdf - smp.pdf_w).abs() <= 1e-3 * pdf.max(1.0));
            for i in 0..4 {
                assert!((f[i] - smp.f[i]).abs() <= 1e-3 * f[i].max(1.0));
            }
        }
    }
}
