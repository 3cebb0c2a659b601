//! A thin dielectric slab (window pane, soap film without interference): PBR 4ed §9.5.3,
//! `ThinDielectricBxDF`.
//!
//! Light bounces between the two parallel interfaces; summing the geometric series gives
//! R' = R + T² R / (1 − R²) and T' = 1 − R' (PBR 4ed eq. 9.21), the transmitted ray leaves
//! parallel to the incident one (ωi = −ωo) and the reflected one is the mirror direction.
//! Both lobes are deltas. Because neither direction depends on λ, η is kept per wavelength
//! and a dispersive glass never needs the secondary wavelengths terminated. The lobe is
//! chosen with the mean R' over the wavelengths, so f/pdf = R'(λ)/mean R'.
//!
//! Scene use: `spectral:dielectric` with `bool inputs:thin = 1` (roughness is ignored).

use super::fresnel::fr_dielectric;
use super::{BsdfSample, TransportMode};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectricBxdf {
    /// η of the slab relative to the outside, per wavelength.
    pub eta: SampledSpectrum,
}

impl ThinDielectricBxdf {
    pub fn new(eta: SampledSpectrum) -> ThinDielectricBxdf {
        ThinDielectricBxdf { eta }
    }

    /// R' per wavelength for light at |cos θ| = `cos`.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> SampledSpectrum {
        self.eta.map(|eta| {
            let r = fr_dielectric(cos.abs(), eta);
            if r < 1.0 {
                let t = 1.0 - r;
                r + t * t * r / (1.0 - r * r)
            } else {
                r
            }
        })
    }

    #[inline]
    pub fn f(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        SampledSpectrum::ZERO
    }

    #[inline]
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> f32 {
        0.0
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        _u: [f32; 2],
        _mode: TransportMode,
    ) -> Option<BsdfSample> {
        let cos = wo.z.abs();
        if cos == 0.0 {
            return None;
        }
        let r = self.reflectance(cos);
        let pr = r.average();
        if uc < pr {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::reflection(r / cos, wi, pr, true));
        }
        let t = SampledSpectrum::ONE - r;
        Some(BsdfSample::transmission(t / cos, -wo, 1.0 - pr, true, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r_plus_t_is_one_and_unit_ior_is_invisible() {
        let b = ThinDielectricBxdf::new(SampledSpectrum([1.5, 1.52, 1.0, 2.0]));
        let wo = Vec3::new(0.5, 0.0, 0.5).normalize();
        let r = b
            .sample_f(wo, 0.0, [0.0; 2], TransportMode::Radiance)
            .unwrap();
        let t = b
            .sample_f(wo, 0.9999, [0.0; 2], TransportMode::Radiance)
            .unwrap();
        for i in 0..4 {
            let sum = r.f[i] * r.wi.z.abs() + t.f[i] * t.wi.z.abs();
            assert!((sum - 1.0).abs() < 1e-6);
        }
        assert_eq!(b.reflectance(0.7)[2], 0.0);
        assert_eq!(t.wi, -wo);
    }
}
