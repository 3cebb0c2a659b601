//! Plastic: a Lambertian base under a smooth or rough dielectric coat.
//!
//! The model is Mitsuba's `plastic` / `roughplastic` (W. Jakob, Mitsuba 0.5 documentation
//! §8.2.9–8.2.10; Mitsuba 3 `plastic.cpp`), written once for both roughnesses:
//!
//! ```text
//! f(ωo, ωi) = f_coat(ωo, ωi) + ρ_eff / (π T̄) · t(μo) · t(μi)
//! t(μ) = 1 − E_coat(μ),   T̄ = ∫ t(μ) 2μ dμ,   ρ_eff = ρ (1 − F_dr,int) / (1 − ρ F_dr,int)
//! ```
//!
//! - f_coat is the coat's specular reflection (mirror, or GGX with the dielectric Fresnel);
//!   E_coat its directional albedo ([`super::coat`]).
//! - Light reaching the base is attenuated by t on the way in and out. Inside the coat the
//!   light that the base scatters back is reflected down again with probability F_dr,int, the
//!   interface's hemispherical reflectance seen from inside, and meets the base again: the
//!   series ρ Σ (ρ F_dr,int)ⁿ gives ρ_eff (Mitsuba's `nonlinear` internal-scattering term).
//! - Dividing by T̄ makes the diffuse part exactly energy-conserving: its albedo is
//!   ρ_eff · t(μo), so the total albedo E_coat(μo) + ρ_eff t(μo) ≤ 1, with equality for ρ = 1.
//!   For a smooth coat t = 1 − F and T̄ = 1 − F_dr,ext = η² (1 − F_dr,int), so the diffuse term is
//!   ρ / (1 − ρ F_dr,int) (1 − F(μo)) (1 − F(μi)) / (π η²), Mitsuba's smooth plastic exactly.
//!   (For a rough coat F_dr,int of the smooth interface is used, as an approximation.)
//!
//! f is symmetric in (ωo, ωi) (reciprocal) and two-sided. Sampling picks the coat with
//! probability E(μo) / (E(μo) + ρ̄_eff t(μo)), otherwise the cosine-weighted hemisphere.
//!
//! Scene use (`spectral:plastic`): `inputs:reflectance*` as for diffuse, `inputs:ior`
//! (default 1.5), `inputs:roughness` (GGX α of the coat; 0 is smooth).

use super::coat::{CoatAlbedo, CoatFresnel, SpecularCoat};
use super::fresnel::diffuse_fresnel;
use super::microfacet::TrowbridgeReitz;
use super::{mirror_z, BsdfEval, BsdfSample, TransportMode};
use crate::math::INV_PI;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticBxdf {
    pub coat: SpecularCoat,
    /// The coat's directional albedo E(μ) (precomputed by the material).
    pub albedo: CoatAlbedo,
    /// ρ_eff / (π T̄): the diffuse term before the coat's two transmittances.
    pub diffuse: SampledSpectrum,
    /// ρ_eff averaged over the wavelengths (for choosing a lobe).
    pub diffuse_albedo: f32,
}

/// The diffuse base of a plastic under its coat: what depends on ρ, F_dr,int and T̄ alone
/// (not on the hit), so that a material can compute it once per wavelength tuple.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlasticBase {
    /// ρ_eff / (π T̄).
    pub diffuse: SampledSpectrum,
    /// ρ_eff averaged over the wavelengths.
    pub diffuse_albedo: f32,
}

impl PlasticBase {
    /// ρ_eff = ρ (1 − F_dr,int) / (1 − ρ F_dr,int) of reflectance `r` (clamped to [0, 1])
    /// under a coat of internal diffuse reflectance `fdr_internal` and average transmittance
    /// `t_avg` (the module header).
    #[inline]
    pub fn new(r: SampledSpectrum, fdr_internal: f32, t_avg: f32) -> PlasticBase {
        let r_eff = if fdr_internal == 0.0 {
            // The series without internal reflection: ρ itself (the same bits as the
            // general form, whose factors are then exactly 1), without four divisions.
            r.map(|r| r.clamp(0.0, 1.0))
        } else {
            r.map(|r| {
                let r = r.clamp(0.0, 1.0);
                r * (1.0 - fdr_internal) / (1.0 - r * fdr_internal)
            })
        };
        let diffuse = if t_avg > 0.0 {
            r_eff * (INV_PI / t_avg)
        } else {
            SampledSpectrum::ZERO
        };
        PlasticBase {
            diffuse,
            diffuse_albedo: r_eff.average(),
        }
    }
}

impl PlasticBxdf {
    /// A plastic of base reflectance `r` under a coat of relative IOR `eta` and GGX `alpha`.
    /// Builds the coat's albedo table: call once per material, not per hit.
    pub fn new(r: SampledSpectrum, eta: f32, alpha: f32) -> PlasticBxdf {
        let coat = SpecularCoat::new(
            TrowbridgeReitz::isotropic(alpha),
            CoatFresnel::Dielectric { eta },
        );
        let albedo = coat.albedo();
        let t_avg = albedo.average_transmittance();
        PlasticBxdf::with_coat(coat, albedo, r, diffuse_fresnel(1.0 / eta), t_avg)
    }

    /// From a prepared coat, its average transmittance T̄ and the internal diffuse
    /// reflectance F_dr,int (0 to leave out the internal bounces). Cheap: per hit.
    #[inline]
    pub fn with_coat(
        coat: SpecularCoat,
        albedo: CoatAlbedo,
        r: SampledSpectrum,
        fdr_internal: f32,
        t_avg: f32,
    ) -> PlasticBxdf {
        PlasticBxdf::with_base(coat, albedo, PlasticBase::new(r, fdr_internal, t_avg))
    }

    /// From a prepared coat and the diffuse base under it ([`PlasticBase`], which a material
    /// whose ρ and coat are constant computes once per wavelength tuple).
    #[inline]
    pub fn with_base(coat: SpecularCoat, albedo: CoatAlbedo, base: PlasticBase) -> PlasticBxdf {
        PlasticBxdf {
            coat,
            albedo,
            diffuse: base.diffuse,
            diffuse_albedo: base.diffuse_albedo,
        }
    }

    /// The probability of sampling the coat at ωo (upper hemisphere).
    #[inline]
    pub fn coat_probability(&self, wo: Vec3) -> f32 {
        self.coat_probability_at(self.albedo.eval_and_transmittance(wo.z))
    }

    /// [`Self::coat_probability`] from the coat's (E(μo), t(μo)).
    #[inline]
    fn coat_probability_at(&self, (e, t): (f32, f32)) -> f32 {
        let d = t * self.diffuse_albedo;
        if e + d > 0.0 {
            e / (e + d)
        } else {
            1.0
        }
    }

    /// The diffuse part at (ωo, ωi), both in the upper hemisphere.
    #[inline]
    pub fn f_diffuse(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        self.diffuse * (self.albedo.transmittance(wo.z) * self.albedo.transmittance(wi.z))
    }

    /// Non-delta f with both directions mirrored into the upper hemisphere.
    #[inline]
    fn f_upper(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        self.coat.f(wo, wi) + self.f_diffuse(wo, wi)
    }

    #[inline]
    fn pdf_upper(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let pc = self.coat_probability(wo);
        pc * self.coat.pdf(wo, wi) + (1.0 - pc) * cosine_hemisphere_pdf(wi.z)
    }

    /// The terms of ωo alone ([`PlasticAt`]): what next event estimation's `f_pdf` and
    /// `sample_f` at one vertex share.
    #[inline(always)]
    pub fn at(&self, wo: Vec3) -> PlasticAt {
        let flip = wo.z < 0.0;
        let wo = mirror_z(wo, flip);
        let at_o = self.albedo.eval_and_transmittance(wo.z);
        PlasticAt {
            wo,
            flip,
            t_o: at_o.1,
            pc: self.coat_probability_at(at_o),
            s_o: self.coat.distrib.wo_term(wo),
        }
    }

    /// `f_upper` and `pdf_upper` of one pair, bit for bit, with the coat's microfacet terms
    /// shared and the terms of ωo given (`at`; `wi` mirrored as ωo was).
    #[inline]
    fn f_pdf_upper(&self, at: &PlasticAt, wi: Vec3) -> (SampledSpectrum, f32) {
        let wo = at.wo;
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (SampledSpectrum::ZERO, 0.0);
        }
        let (coat_f, coat_pdf) = self.coat.f_pdf_at(wo, at.s_o, wi);
        let f = coat_f + self.diffuse * (at.t_o * self.albedo.transmittance(wi.z));
        let pc = at.pc;
        (f, pc * coat_pdf + (1.0 - pc) * cosine_hemisphere_pdf(wi.z))
    }

    /// Bit for bit (`f(wo, wi)`, `pdf(wo, wi)`) at about the cost of `f` alone.
    #[inline]
    pub fn f_pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> (SampledSpectrum, f32) {
        self.f_pdf_at(&self.at(wo), wi)
    }

    /// [`Self::f_pdf`] of (ωo, `wi`) given ωo's terms `at = self.at(wo)`.
    #[inline]
    pub fn f_pdf_at(&self, at: &PlasticAt, wi: Vec3) -> (SampledSpectrum, f32) {
        self.f_pdf_upper(at, mirror_z(wi, at.flip))
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SampledSpectrum {
        let flip = wo.z < 0.0;
        self.f_upper(mirror_z(wo, flip), mirror_z(wi, flip))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        let flip = wo.z < 0.0;
        self.pdf_upper(mirror_z(wo, flip), mirror_z(wi, flip))
    }

    /// f(ωo, ωi) with the pdfs of ωi from ωo and of ωo from ωi: bit for bit `f` and `pdf`
    /// both ways, the coat's microfacet terms and the albedo lookups shared.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> BsdfEval {
        let flip = wo.z < 0.0;
        let (wo, wi) = (mirror_z(wo, flip), mirror_z(wi, flip));
        // Otherwise ωi lies on ωo's side strictly, and `pdf(wi, wo)` mirrors as ωo does.
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return BsdfEval {
                f: SampledSpectrum::ZERO,
                pdf_fwd: 0.0,
                pdf_rev: 0.0,
            };
        }
        let (coat_f, coat_fwd, coat_rev) = self.coat.eval_pair(wo, wi);
        let (pc_o, pc_i) = (self.coat_probability(wo), self.coat_probability(wi));
        BsdfEval {
            f: coat_f + self.f_diffuse(wo, wi),
            pdf_fwd: pc_o * coat_fwd + (1.0 - pc_o) * cosine_hemisphere_pdf(wi.z),
            pdf_rev: pc_i * coat_rev + (1.0 - pc_i) * cosine_hemisphere_pdf(wo.z),
        }
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        _mode: TransportMode,
    ) -> Option<BsdfSample> {
        self.sample_f_at(&self.at(wo), uc, u)
    }

    /// [`Self::sample_f`] from ωo given its terms `at = self.at(wo)`. Inlined (into the path
    /// tracer's `scatter` through `BsdfAt::sample_f`): as a call it cost about 38 instructions
    /// a vertex in frame and copies (design.md §8, eighth pass).
    #[inline(always)]
    pub fn sample_f_at(&self, at: &PlasticAt, uc: f32, u: [f32; 2]) -> Option<BsdfSample> {
        let (wo, flip, pc) = (at.wo, at.flip, at.pc);
        if wo.z == 0.0 {
            return None;
        }
        let wi = if uc < pc {
            if self.coat.is_delta() {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                let f = self.coat.mirror_reflectance(wo) / wo.z;
                return Some(BsdfSample::reflection(f, mirror_z(wi, flip), pc, true));
            }
            self.coat.sample(wo, u)?
        } else {
            cosine_hemisphere(u)
        };
        let (f, pdf) = self.f_pdf_upper(at, wi);
        Some(BsdfSample::reflection(f, mirror_z(wi, flip), pdf, false))
    }
}

/// A plastic's terms of one ωo, which every pair (ωo, ωi) from it shares: ωo mirrored into
/// the upper hemisphere, the coat's transmittance t(μo) and sampling probability (from one
/// albedo lookup, `coat_probability`), and the microfacet term s(ωo)
/// ([`TrowbridgeReitz::wo_term`]). Computed once per vertex, they give next event
/// estimation's f and pdf and the BSDF sample the same bits as computing them per call.
#[derive(Clone, Copy, Debug)]
pub struct PlasticAt {
    wo: Vec3,
    flip: bool,
    t_o: f32,
    pc: f32,
    s_o: f32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    /// ∫ f cos dωi + the delta part, by sampling.
    fn albedo(b: &PlasticBxdf, wo: Vec3, n: usize) -> SampledSpectrum {
        let mut s = Sampler::new(5, 1, 0);
        let mut sum = SampledSpectrum::ZERO;
        for _ in 0..n {
            if let Some(x) = b.sample_f(wo, s.get_1d(), s.get_2d(), TransportMode::Radiance) {
                sum += x.f * (x.wi.z.abs() / x.pdf_w);
            }
        }
        sum / n as f32
    }

    #[test]
    fn white_smooth_plastic_reflects_everything() {
        let b = PlasticBxdf::new(SampledSpectrum::ONE, 1.5, 0.0);
        for cos in [1.0f32, 0.5, 0.1] {
            let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            let a = albedo(&b, wo, 200_000)[0];
            assert!((a - 1.0).abs() < 5e-3, "{cos}: {a}");
        }
    }
}
