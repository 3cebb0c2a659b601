//! Lambertian reflection: f = R/π on the side of `wo` (PBR 4ed §9.2), sampled by the
//! cosine-weighted hemisphere (pdf = |cos θi|/π).

use super::{same_hemisphere, BsdfSample, TransportMode};
use crate::math::INV_PI;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct DiffuseBxdf {
    pub r: SampledSpectrum,
}

impl DiffuseBxdf {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        if !same_hemisphere(wo, wi) {
            return SampledSpectrum::ZERO;
        }
        self.r * INV_PI
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        _uc: f32,
        u: [f32; 2],
        _mode: TransportMode,
    ) -> Option<BsdfSample> {
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf_w = cosine_hemisphere_pdf(wi.z.abs());
        Some(BsdfSample::reflection(self.r * INV_PI, wi, pdf_w, false))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi.z.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn albedo_equals_reflectance() {
        // ∫ f cos = R: the estimator f cos / pdf is exactly R for every sample.
        let b = DiffuseBxdf {
            r: SampledSpectrum::splat(0.8),
        };
        let mut s = Sampler::new(1, 0, 0);
        for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.6, -0.8)] {
            for _ in 0..100 {
                let smp = b
                    .sample_f(wo, 0.5, s.get_2d(), TransportMode::Radiance)
                    .unwrap();
                let est = smp.f * smp.wi.z.abs() / smp.pdf_w;
                assert!((est[0] - 0.8).abs() < 1e-5);
                assert!((b.pdf(wo, smp.wi, TransportMode::Radiance) - smp.pdf_w).abs() < 1e-6);
                assert!(same_hemisphere(wo, smp.wi));
            }
        }
    }
}
