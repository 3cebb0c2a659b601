//! Dielectric interfaces, smooth and rough (PBR 4ed §9.5 and §9.7, `DielectricBxDF`).
//!
//! `eta` is η_inside/η_outside at the path's hero wavelength; the inside is −Z. ωo below the
//! surface means the path is inside and η is inverted by the Fresnel and Snell helpers.
//!
//! - Smooth (α < 10⁻³, or |η − 1| < 10⁻³): reflection with probability R = F(cos θo)
//!   (PBR 4ed eq. 9.4–9.6; R = 1 under total internal reflection), otherwise refraction by
//!   Snell's law (eq. 9.19) with f = T/|cos θi|, divided by η'² when radiance is transported
//!   (§9.5.2, eq. 9.20: radiance is compressed into the smaller solid angle).
//! - Rough: Walter et al. 2007 with the generalised half vector ωm ∝ η' ωi + ωo (PBR 4ed
//!   eq. 9.34), f_t = D G (1 − F) |ωi·ωm ωo·ωm| / (|cos θi cos θo| (ωi·ωm + ωo·ωm/η')²)
//!   (eq. 9.40) and the pdf D_ωo(ωm) |ωi·ωm| / (ωi·ωm + ωo·ωm/η')² (eq. 9.37), the visible
//!   normal chosen first and reflection vs transmission by R and T of that microfacet.
//! - η = 1 is invisible: R = 0 and ωi = −ωo exactly. For |η − 1| < 10⁻³ a rough interface is
//!   treated as smooth: its transmission lobe is narrower than α·10⁻³ rad and its
//!   reflectance below 3·10⁻⁷, while the generalised half vector would lose all precision.
//!
//! Scene use (`spectral:dielectric`, docs/design.md §3): `inputs:ior` (constant), `inputs:glass`
//! (`"BK7"`, `"fused_silica"`) or `inputs:sellmeierB`/`C` (dispersive), `inputs:roughness`
//! (GGX α), `inputs:thin` (see `thin_dielectric.rs`).

use super::fresnel::{fr_dielectric, refract};
use super::microfacet::TrowbridgeReitz;
use super::{BsdfSample, TransportMode};
use crate::math::reflect;
use crate::spectral::SampledSpectrum;
use glam::Vec3;

/// |η − 1| below which a rough interface is treated as smooth.
const NEAR_UNIT_ETA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricBxdf {
    pub distrib: TrowbridgeReitz,
    /// η_inside / η_outside.
    pub eta: f32,
}

impl DielectricBxdf {
    pub fn new(distrib: TrowbridgeReitz, eta: f32) -> DielectricBxdf {
        DielectricBxdf { distrib, eta }
    }

    #[inline]
    pub fn is_specular(&self) -> bool {
        self.eta == 1.0
            || (self.eta - 1.0).abs() < NEAR_UNIT_ETA
            || self.distrib.effectively_smooth()
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> SampledSpectrum {
        if self.is_specular() {
            return SampledSpectrum::ZERO;
        }
        let Some((wm, etap)) = self.half_vector(wo, wi) else {
            return SampledSpectrum::ZERO;
        };
        let (cos_o, cos_i) = (wo.z, wi.z);
        let fr = self.fresnel(wo, wi, wm);
        let d = &self.distrib;
        let v = if cos_o * cos_i > 0.0 {
            d.d(wm) * d.g(wo, wi) * fr / (4.0 * cos_i * cos_o).abs()
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * cos_i * cos_o;
            let ft = d.d(wm) * (1.0 - fr) * d.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
            radiance_scale(ft, etap, mode)
        };
        SampledSpectrum::splat(v)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        if self.is_specular() {
            return 0.0;
        }
        let Some((wm, etap)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let r = self.fresnel(wo, wi, wm);
        let d = &self.distrib;
        if wo.z * wi.z > 0.0 {
            d.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * r
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            d.pdf(wo, wm) * wi.dot(wm).abs() / denom * (1.0 - r)
        }
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.is_specular() {
            self.sample_smooth(wo, uc, mode)
        } else {
            self.sample_rough(wo, uc, u, mode)
        }
    }

    fn sample_smooth(&self, wo: Vec3, uc: f32, mode: TransportMode) -> Option<BsdfSample> {
        let r = if self.eta == 1.0 {
            0.0
        } else {
            fr_dielectric(wo.z, self.eta)
        };
        if uc < r {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let f = SampledSpectrum::splat(r / wi.z.abs());
            return Some(BsdfSample::reflection(f, wi, r, true));
        }
        let (wi, etap) = if self.eta == 1.0 {
            (-wo, 1.0)
        } else {
            refract(wo, Vec3::Z, self.eta)?
        };
        let ft = radiance_scale((1.0 - r) / wi.z.abs(), etap, mode);
        Some(BsdfSample::transmission(
            SampledSpectrum::splat(ft),
            wi,
            1.0 - r,
            true,
            etap,
        ))
    }

    fn sample_rough(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let wm = self.distrib.sample_wm(wo, u);
        let r = fr_dielectric(wo.dot(wm), self.eta);
        let wi = if uc < r {
            reflect(wo, wm)
        } else {
            refract(wo, wm, self.eta)?.0
        };
        if uc < r && wo.z * wi.z <= 0.0 || uc >= r && wo.z * wi.z >= 0.0 {
            return None;
        }
        // f and pdf at the sampled direction, through the same generalised half vector as
        // `f` and `pdf` (PBR 4ed eq. 9.34–9.40), so the three always agree.
        let (f, pdf) = (self.f(wo, wi, mode), self.pdf(wo, wi, mode));
        Some(if uc < r {
            BsdfSample::reflection(f, wi, pdf, false)
        } else {
            let etap = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
            BsdfSample::transmission(f, wi, pdf, false, etap)
        })
    }

    /// F at the microfacet ωm, evaluated with whichever of ωo, ωi lies in the optically
    /// rarer medium: the same value by Snell's law, but well conditioned, while on the dense
    /// side F has a square-root singularity at the critical angle.
    #[inline]
    fn fresnel(&self, wo: Vec3, wi: Vec3, wm: Vec3) -> f32 {
        let transmission = wo.z * wi.z < 0.0;
        let wo_dense = (wo.z < 0.0) == (self.eta > 1.0);
        let w = if transmission && wo_dense { wi } else { wo };
        fr_dielectric(w.dot(wm), self.eta)
    }

    /// The generalised half vector of (ωo, ωi), facing +Z, and η' of the crossing (1 for a
    /// reflection); `None` for degenerate or back-facing configurations (PBR 4ed §9.7.4).
    #[inline]
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return None;
        }
        let etap = if cos_o * cos_i > 0.0 {
            1.0
        } else if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let wm = (wi * etap + wo).try_normalize()?;
        let wm = if wm.z < 0.0 { -wm } else { wm };
        // Microfacets seen from behind by either direction contribute nothing.
        if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
            return None;
        }
        Some((wm, etap))
    }
}

/// Radiance is divided by η'² across a refraction; importance is not (PBR 4ed §9.5.2).
#[inline]
fn radiance_scale(ft: f32, etap: f32, mode: TransportMode) -> f32 {
    match mode {
        TransportMode::Radiance => ft / (etap * etap),
        TransportMode::Importance => ft,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_r_plus_t_is_one_in_importance_mode() {
        let b = DielectricBxdf::new(TrowbridgeReitz::isotropic(0.0), 1.5);
        for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.6, -0.8)] {
            let mode = TransportMode::Importance;
            let r = b.sample_f(wo, 0.0, [0.5; 2], mode).unwrap();
            let t = b.sample_f(wo, 0.999_999, [0.5; 2], mode);
            let r_w = r.f[0] * r.wi.z.abs();
            let t_w = t.map_or(0.0, |t| t.f[0] * t.wi.z.abs());
            assert!((r_w + t_w - 1.0).abs() < 1e-5, "{wo}: {r_w} + {t_w}");
        }
    }

    #[test]
    fn total_internal_reflection_reflects_everything() {
        let b = DielectricBxdf::new(TrowbridgeReitz::isotropic(0.0), 1.5);
        let wo = Vec3::new(0.8, 0.0, -0.6); // inside, 53° > 41.8°
        for uc in [0.0, 0.5, 0.999] {
            let s = b
                .sample_f(wo, uc, [0.5; 2], TransportMode::Radiance)
                .unwrap();
            assert!(!s.transmission && s.wi.z < 0.0 && (s.f[0] * 0.6 - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn unit_ior_passes_straight_through() {
        for alpha in [0.0, 0.3] {
            let b = DielectricBxdf::new(TrowbridgeReitz::isotropic(alpha), 1.0);
            let wo = Vec3::new(0.3, -0.4, 0.5).normalize();
            let s = b
                .sample_f(wo, 0.3, [0.2, 0.7], TransportMode::Radiance)
                .unwrap();
            assert_eq!(s.wi, -wo);
            assert!(s.specular && s.pdf_w == 1.0 && (s.f[0] * s.wi.z.abs() - 1.0).abs() < 1e-6);
        }
    }
}
