//! The BxDF behind UsdPreviewSurface: a clearcoat over a metallic blend of a metal and a
//! plastic. How the shader's inputs map onto it is in `material/preview.rs`.
//!
//! ```text
//! f = c f_cc + a(μo) a(μi) [ m f_metal + (1 − m) f_plastic ],   a(μ) = 1 − c E_cc(μ)
//! ```
//!
//! - f_cc: the clearcoat, a GGX (or mirror) dielectric reflection of IOR 1.5, weight c;
//!   E_cc its directional albedo. The albedo scaling a(μo) a(μi) passes what the coat does not
//!   reflect to the base (Kulla & Conty 2017, layering by albedo scaling): the total albedo is
//!   c E_cc(μo) + a(μo) · (base albedo ≤ 1) ≤ 1, and f stays symmetric.
//! - f_metal: GGX reflection with Schlick's Fresnel, F0 = the base colour (the "metallic"
//!   workflow of the UsdPreviewSurface specification and of Burley 2012).
//! - f_plastic: [`super::plastic`] — a dielectric specular coat over a Lambertian base.
//! - m blends the two linearly (metallic); both share the roughness.
//!
//! Sampling chooses one of the four lobes (clearcoat, metal, plastic coat, plastic diffuse)
//! with probabilities proportional to estimates of their albedos at ωo. Delta lobes (smooth
//! clearcoat, smooth metal, smooth plastic coat) share the mirror direction and are returned
//! together as one delta sample; the pdf of the others is the mixture of their pdfs.

use super::coat::{CoatAlbedo, SpecularCoat};
use super::plastic::PlasticBxdf;
use super::{mirror_z, BsdfSample, TransportMode};
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewBxdf {
    pub base: PlasticBxdf,
    /// GGX reflection with Schlick's Fresnel (F0 = base colour).
    pub metal: SpecularCoat,
    pub metallic: f32,
    pub clearcoat: SpecularCoat,
    pub clearcoat_albedo: CoatAlbedo,
    pub clearcoat_weight: f32,
}

/// The four lobes, in sampling order.
const CLEARCOAT: usize = 0;
const METAL: usize = 1;
const PLASTIC_COAT: usize = 2;
const PLASTIC_DIFFUSE: usize = 3;

/// What sampling needs to know at ωo: the lobes' selection weights (unnormalised).
struct Lobes {
    weights: [f32; 4],
    delta: [bool; 4],
    total: f32,
}

impl Lobes {
    fn delta_probability(&self) -> f32 {
        let d: f32 = (0..4)
            .filter(|&k| self.delta[k])
            .map(|k| self.weights[k])
            .sum();
        d / self.total
    }
}

impl PreviewBxdf {
    /// 1 − c E_cc(μ): the fraction the clearcoat lets through.
    #[inline]
    fn coat_attenuation(&self, mu: f32) -> f32 {
        1.0 - self.clearcoat_weight * self.clearcoat_albedo.eval(mu)
    }

    #[inline]
    pub fn is_specular(&self) -> bool {
        self.metallic >= 1.0
            && self.metal.is_delta()
            && (self.clearcoat_weight == 0.0 || self.clearcoat.is_delta())
    }

    fn lobes(&self, wo: Vec3) -> Lobes {
        let (c, m) = (self.clearcoat_weight, self.metallic);
        let a = self.coat_attenuation(wo.z);
        let pc = self.base.coat_probability(wo);
        let base = self.base.albedo.eval(wo.z)
            + self.base.albedo.transmittance(wo.z) * self.base.diffuse_albedo;
        // A lobe of weight 0 costs nothing (its albedo is not evaluated).
        let weights = [
            if c > 0.0 {
                c * self.clearcoat_albedo.eval(wo.z)
            } else {
                0.0
            },
            if m > 0.0 {
                a * m * self.metal.mirror_reflectance(wo).average()
            } else {
                0.0
            },
            a * (1.0 - m) * base * pc,
            a * (1.0 - m) * base * (1.0 - pc),
        ];
        Lobes {
            weights,
            delta: [
                self.clearcoat.is_delta(),
                self.metal.is_delta(),
                self.base.coat.is_delta(),
                false,
            ],
            total: weights.iter().sum(),
        }
    }

    /// The non-delta part of f, both directions in the upper hemisphere.
    fn f_upper(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let (c, m) = (self.clearcoat_weight, self.metallic);
        let a = self.coat_attenuation(wo.z) * self.coat_attenuation(wi.z);
        let mut base = SampledSpectrum::ZERO;
        if m > 0.0 {
            base += self.metal.f(wo, wi) * m;
        }
        if m < 1.0 {
            base += (self.base.coat.f(wo, wi) + self.base.f_diffuse(wo, wi)) * (1.0 - m);
        }
        let mut f = base * a;
        if c > 0.0 {
            f += self.clearcoat.f(wo, wi) * c;
        }
        f
    }

    /// The pdf of the non-delta lobes, both directions in the upper hemisphere.
    fn pdf_upper(&self, wo: Vec3, wi: Vec3, lobes: &Lobes) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 || lobes.total <= 0.0 {
            return 0.0;
        }
        let w = &lobes.weights;
        let mut pdf = 0.0;
        if w[CLEARCOAT] > 0.0 {
            pdf += w[CLEARCOAT] * self.clearcoat.pdf(wo, wi);
        }
        if w[METAL] > 0.0 {
            pdf += w[METAL] * self.metal.pdf(wo, wi);
        }
        if w[PLASTIC_COAT] > 0.0 {
            pdf += w[PLASTIC_COAT] * self.base.coat.pdf(wo, wi);
        }
        pdf += w[PLASTIC_DIFFUSE] * cosine_hemisphere_pdf(wi.z);
        pdf / lobes.total
    }

    /// The sum of the delta lobes' reflectances in the mirror direction.
    fn delta_reflectance(&self, wo: Vec3) -> SampledSpectrum {
        let (c, m) = (self.clearcoat_weight, self.metallic);
        let mut base = SampledSpectrum::ZERO;
        if self.metal.is_delta() {
            base += self.metal.mirror_reflectance(wo) * m;
        }
        if self.base.coat.is_delta() {
            base += self.base.coat.mirror_reflectance(wo) * (1.0 - m);
        }
        let a = self.coat_attenuation(wo.z);
        let mut r = base * (a * a);
        if self.clearcoat.is_delta() {
            r += self.clearcoat.mirror_reflectance(wo) * c;
        }
        r
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        let flip = wo.z < 0.0;
        self.f_upper(mirror_z(wo, flip), mirror_z(wi, flip))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        let flip = wo.z < 0.0;
        let wo = mirror_z(wo, flip);
        self.pdf_upper(wo, mirror_z(wi, flip), &self.lobes(wo))
    }

    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        _mode: TransportMode,
    ) -> Option<BsdfSample> {
        let flip = wo.z < 0.0;
        let wo = mirror_z(wo, flip);
        if wo.z == 0.0 {
            return None;
        }
        let lobes = self.lobes(wo);
        if lobes.total.is_nan() || lobes.total <= 0.0 {
            return None;
        }
        let lobe = choose(&lobes.weights, uc * lobes.total);
        if lobes.delta[lobe] {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let f = self.delta_reflectance(wo) / wo.z;
            let pdf = lobes.delta_probability();
            return Some(BsdfSample::reflection(f, mirror_z(wi, flip), pdf, true));
        }
        let wi = match lobe {
            CLEARCOAT => self.clearcoat.sample(wo, u)?,
            METAL => self.metal.sample(wo, u)?,
            PLASTIC_COAT => self.base.coat.sample(wo, u)?,
            _ => cosine_hemisphere(u),
        };
        let f = self.f_upper(wo, wi);
        let pdf = self.pdf_upper(wo, wi, &lobes);
        Some(BsdfSample::reflection(f, mirror_z(wi, flip), pdf, false))
    }
}

/// The lobe whose cumulative weight interval contains `x` ∈ [0, Σ weights).
#[inline]
fn choose(weights: &[f32; 4], x: f32) -> usize {
    let mut acc = 0.0;
    let mut last = 0;
    for (k, &w) in weights.iter().enumerate() {
        if w <= 0.0 {
            continue;
        }
        acc += w;
        last = k;
        if x < acc {
            return k;
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bxdf::coat::CoatFresnel;
    use crate::bxdf::TrowbridgeReitz;
    use crate::sampling::warp::uniform_sphere;
    use crate::sampling::Sampler;

    fn preview(alpha: f32, metallic: f32, clearcoat: f32) -> PreviewBxdf {
        let rho = SampledSpectrum([0.2, 0.4, 0.6, 0.8]);
        let distrib = TrowbridgeReitz::isotropic(alpha);
        let cc = SpecularCoat::new(
            TrowbridgeReitz::isotropic(0.2),
            CoatFresnel::Dielectric { eta: 1.5 },
        );
        PreviewBxdf {
            base: PlasticBxdf::new(rho, 1.5, alpha),
            metal: SpecularCoat::new(distrib, CoatFresnel::Schlick { f0: rho }),
            metallic,
            clearcoat: cc,
            clearcoat_albedo: cc.albedo(),
            clearcoat_weight: clearcoat,
        }
    }

    #[test]
    fn without_metal_and_clearcoat_it_is_the_plastic() {
        let p = preview(0.3, 0.0, 0.0);
        let mut s = Sampler::new(1, 0, 0);
        let mode = TransportMode::Radiance;
        for _ in 0..500 {
            let (a, b) = (uniform_sphere(s.get_2d()), uniform_sphere(s.get_2d()));
            let (x, y) = (p.f(a, b, mode), p.base.f(a, b, mode));
            assert!((x - y)
                .0
                .iter()
                .all(|d| d.abs() <= 1e-6 * y.max_value().max(1.0)));
            let (pa, pb) = (p.pdf(a, b, mode), p.base.pdf(a, b, mode));
            assert!((pa - pb).abs() <= 1e-4 * pb.max(1e-3));
        }
    }

    #[test]
    fn smooth_metal_is_a_schlick_mirror() {
        let p = preview(0.0, 1.0, 0.0);
        assert!(p.is_specular());
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let x = p
            .sample_f(wo, 0.5, [0.5; 2], TransportMode::Radiance)
            .unwrap();
        assert!(x.specular && (x.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        let expected = p.metal.mirror_reflectance(wo);
        for i in 0..4 {
            assert!((x.f[i] * 0.8 / x.pdf_w - expected[i]).abs() < 1e-5);
        }
    }
}
