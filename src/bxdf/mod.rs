//! BxDFs: reflection models in a local shading frame where the normal is +Z.
//!
//! Conventions (docs/design.md §2): `f()` excludes the cosine; pdfs are per unit solid angle;
//! `wo` and `wi` point away from the surface. One model per file, dispatched through the
//! closed [`Bxdf`] enum; [`Bsdf`] adds the shading frame and is returned by value.
//!
//! | model | file | lobes |
//! |---|---|---|
//! | Lambertian | `diffuse.rs` | diffuse |
//! | Oren–Nayar | `oren_nayar.rs` | diffuse |
//! | conductor, smooth / rough | `conductor.rs` | mirror / GGX, complex Fresnel |
//! | dielectric, smooth / rough | `dielectric.rs` | mirror + refraction / GGX (Walter 2007) |
//! | thin dielectric | `thin_dielectric.rs` | mirror + straight transmission |
//! | plastic, smooth / rough | `plastic.rs` | coat (mirror / GGX) + coupled diffuse |
//! | UsdPreviewSurface | `preview.rs` | clearcoat + metal + plastic |
//!
//! Shared pieces: `fresnel.rs` (dielectric, complex and Schlick Fresnel, Snell),
//! `microfacet.rs` (Trowbridge–Reitz with visible-normal sampling), `coat.rs` (a specular
//! coat and its directional albedo, for the layered models), `rho.rs` (a BSDF's
//! directional-hemispherical reflectance, pbrt-v4's fixed-sample estimate: the albedo AOV).
//!
//! Delta lobes follow pbrt: `f` and `pdf` leave them out, `sample_f` returns them with
//! `specular: true`, f = reflectance/|cos θi| and pdf = the probability of choosing them.
//! Every model accepts ωo on either side of the surface.

mod at;
pub mod coat;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fresnel;
pub mod microfacet;
pub mod oren_nayar;
pub mod plastic;
pub mod preview;
mod rho;
pub mod thin_dielectric;

use crate::math::Frame;
use crate::spectral::SampledSpectrum;
use glam::Vec3;

pub use at::BsdfAt;
pub use coat::{CoatAlbedo, CoatFresnel, SpecularCoat};
pub use conductor::ConductorBxdf;
pub use dielectric::DielectricBxdf;
pub use diffuse::DiffuseBxdf;
pub use microfacet::TrowbridgeReitz;
pub use oren_nayar::OrenNayarBxdf;
pub use plastic::{PlasticBase, PlasticBxdf};
pub use preview::PreviewBxdf;
pub use thin_dielectric::ThinDielectricBxdf;

/// Whether radiance (camera paths) or importance (light paths) is being transported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// The result of sampling a BxDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub f: SampledSpectrum,
    /// Sampled direction (local in `Bxdf::sample_f`, world in `Bsdf::sample_f`).
    pub wi: Vec3,
    pub pdf_w: f32,
    /// True for a Dirac delta lobe (pdf and f are then relative to the delta).
    pub specular: bool,
    /// True when `wi` is on the other side of the surface than `wo`.
    pub transmission: bool,
    /// The relative IOR η' = ηt/ηi of a transmission (PBR 4ed §9.5), 1 for a reflection.
    pub eta: f32,
}

impl BsdfSample {
    #[inline]
    pub fn reflection(f: SampledSpectrum, wi: Vec3, pdf_w: f32, specular: bool) -> BsdfSample {
        BsdfSample {
            f,
            wi,
            pdf_w,
            specular,
            transmission: false,
            eta: 1.0,
        }
    }

    #[inline]
    pub fn transmission(
        f: SampledSpectrum,
        wi: Vec3,
        pdf_w: f32,
        specular: bool,
        eta: f32,
    ) -> BsdfSample {
        BsdfSample {
            f,
            wi,
            pdf_w,
            specular,
            transmission: true,
            eta,
        }
    }
}

/// f(ωo, ωi) with both densities of the pair: of sampling ωi from ωo (in the evaluated mode)
/// and of sampling ωo from ωi (in the other mode). A vertex merge needs all three at once
/// (Georgiev et al. 2012 tech. rep. (38), (39); SmallVCM's `BSDF::Evaluate` returns them
/// together): evaluated in one place, the models' shared terms (the local frame, the half
/// vector, D and Λ of a microfacet lobe, a coat's albedos) are computed once.
#[derive(Clone, Copy, Debug)]
pub struct BsdfEval {
    pub f: SampledSpectrum,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
}

impl TransportMode {
    /// The mode of the other subpath.
    #[inline]
    pub fn other(self) -> TransportMode {
        match self {
            TransportMode::Radiance => TransportMode::Importance,
            TransportMode::Importance => TransportMode::Radiance,
        }
    }
}

/// The closed set of reflection models.
#[derive(Clone, Copy, Debug)]
pub enum Bxdf {
    Diffuse(DiffuseBxdf),
    OrenNayar(OrenNayarBxdf),
    Conductor(ConductorBxdf),
    Dielectric(DielectricBxdf),
    ThinDielectric(ThinDielectricBxdf),
    Plastic(PlasticBxdf),
    Preview(PreviewBxdf),
}

/// Calls `$body` with `$b` bound to the model inside a [`Bxdf`].
macro_rules! dispatch {
    ($self:expr, $b:ident => $body:expr) => {
        match $self {
            Bxdf::Diffuse($b) => $body,
            Bxdf::OrenNayar($b) => $body,
            Bxdf::Conductor($b) => $body,
            Bxdf::Dielectric($b) => $body,
            Bxdf::ThinDielectric($b) => $body,
            Bxdf::Plastic($b) => $body,
            Bxdf::Preview($b) => $body,
        }
    };
}

impl Bxdf {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> SampledSpectrum {
        dispatch!(self, b => b.f(wo, wi, mode))
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        dispatch!(self, b => b.sample_f(wo, uc, u, mode))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        dispatch!(self, b => b.pdf(wo, wi, mode))
    }

    /// (`f(wo, wi, mode)`, `pdf(wo, wi, mode)`) bit for bit: next event estimation's pair.
    /// The plastic shares its terms; the other models evaluate the two.
    #[inline]
    pub fn f_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (SampledSpectrum, f32) {
        match self {
            Bxdf::Plastic(b) => b.f_pdf(wo, wi, mode),
            _ => dispatch!(self, b => (b.f(wo, wi, mode), b.pdf(wo, wi, mode))),
        }
    }

    /// [`BsdfEval`] in the local frame: the same values, bit for bit, as `f(wo, wi, mode)`,
    /// `pdf(wo, wi, mode)` and `pdf(wi, wo, mode.other())`; the plastic (the Cornell box's
    /// UsdPreviewSurface) shares its terms, the other models evaluate the three.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        match self {
            Bxdf::Plastic(b) => b.eval(wo, wi, mode),
            _ => dispatch!(self, b => BsdfEval {
                f: b.f(wo, wi, mode),
                pdf_fwd: b.pdf(wo, wi, mode),
                pdf_rev: b.pdf(wi, wo, mode.other()),
            }),
        }
    }

    /// True when every lobe is a delta (no point in light sampling).
    #[inline]
    pub fn is_specular(&self) -> bool {
        match self {
            Bxdf::Diffuse(_) | Bxdf::OrenNayar(_) | Bxdf::Plastic(_) => false,
            Bxdf::Conductor(b) => b.is_specular(),
            Bxdf::Dielectric(b) => b.is_specular(),
            Bxdf::ThinDielectric(_) => true,
            Bxdf::Preview(b) => b.is_specular(),
        }
    }

    /// The model's name (for test reports).
    pub fn name(&self) -> &'static str {
        match self {
            Bxdf::Diffuse(_) => "diffuse",
            Bxdf::OrenNayar(_) => "oren-nayar",
            Bxdf::Conductor(_) => "conductor",
            Bxdf::Dielectric(_) => "dielectric",
            Bxdf::ThinDielectric(_) => "thin-dielectric",
            Bxdf::Plastic(_) => "plastic",
            Bxdf::Preview(_) => "preview-surface",
        }
    }
}

/// A BxDF placed at a surface point: the shading frame plus the geometric normal.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    pub bxdf: Bxdf,
    pub frame: Frame,
}

impl Bsdf {
    pub fn new(bxdf: Bxdf, shading_normal: Vec3) -> Bsdf {
        Bsdf {
            bxdf,
            frame: Frame::from_normal(shading_normal),
        }
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> SampledSpectrum {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if wo.z == 0.0 {
            return SampledSpectrum::ZERO;
        }
        self.bxdf.f(wo, wi, mode)
    }

    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        self.at(wo).sample_f(uc, u, mode)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if wo.z == 0.0 {
            return 0.0;
        }
        self.bxdf.pdf(wo, wi, mode)
    }

    /// Bit for bit (`f(wo, wi, mode)`, `pdf(wo, wi, mode)`), one frame change and the
    /// model's shared terms ([`Bxdf::f_pdf`]; [`BsdfAt::f_pdf`] for several `wi`).
    #[inline]
    pub fn f_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (SampledSpectrum, f32) {
        self.at(wo).f_pdf(wi, mode)
    }

    /// [`BsdfEval`] of the pair: bit for bit `f(wo, wi, mode)`, `pdf(wo, wi, mode)` and
    /// `pdf(wi, wo, mode.other())`, at the cost of about one evaluation.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let e = self.bxdf.eval(wo, wi, mode);
        BsdfEval {
            f: if wo.z == 0.0 {
                SampledSpectrum::ZERO
            } else {
                e.f
            },
            pdf_fwd: if wo.z == 0.0 { 0.0 } else { e.pdf_fwd },
            pdf_rev: if wi.z == 0.0 { 0.0 } else { e.pdf_rev },
        }
    }

    #[inline]
    pub fn is_specular(&self) -> bool {
        self.bxdf.is_specular()
    }
}

/// `w` mirrored through the tangent plane when `flip` (two-sided models work above it).
#[inline]
pub(crate) fn mirror_z(w: Vec3, flip: bool) -> Vec3 {
    if flip {
        Vec3::new(w.x, w.y, -w.z)
    } else {
        w
    }
}

/// True when two local directions lie on the same side of the surface.
#[inline]
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::bxdf_examples::examples;
    use crate::testing::rng::Rng;

    #[test]
    fn eval_is_f_and_both_pdfs_bit_for_bit() {
        let mut rng = Rng::new(11);
        for ex in examples() {
            let bsdf = Bsdf::new(ex.bxdf, rng.unit_vector());
            for k in 0..400 {
                let (wo, wi) = (rng.unit_vector(), rng.unit_vector());
                // Pairs on one side, on both sides, and at the horizon.
                let wi = if k % 50 == 0 {
                    bsdf.frame.to_world(Vec3::X)
                } else {
                    wi
                };
                for mode in [TransportMode::Radiance, TransportMode::Importance] {
                    let e = bsdf.eval(wo, wi, mode);
                    let f = bsdf.f(wo, wi, mode);
                    let fwd = bsdf.pdf(wo, wi, mode);
                    let rev = bsdf.pdf(wi, wo, mode.other());
                    let bits = |s: SampledSpectrum| s.0.map(f32::to_bits);
                    assert_eq!(bits(e.f), bits(f), "{} f at {wo}, {wi}", ex.name);
                    assert_eq!(e.pdf_fwd.to_bits(), fwd.to_bits(), "{} pdf", ex.name);
                    assert_eq!(
                        e.pdf_rev.to_bits(),
                        rev.to_bits(),
                        "{} reverse pdf",
                        ex.name
                    );
                }
            }
        }
    }

    #[test]
    fn a_plastic_sample_carries_f_and_pdf_bit_for_bit() {
        // The plastic's non-delta samples' f and pdf (computed with shared terms in
        // `sample_f`) are its own `f` and `pdf` of the sampled pair.
        let mut rng = Rng::new(12);
        let mut checked = 0;
        for ex in examples() {
            if !matches!(ex.bxdf, Bxdf::Plastic(_)) {
                continue;
            }
            for _ in 0..400 {
                let wo = rng.unit_vector();
                let (uc, u) = (rng.f32(), [rng.f32(), rng.f32()]);
                let mode = TransportMode::Radiance;
                let Some(s) = ex.bxdf.sample_f(wo, uc, u, mode) else {
                    continue;
                };
                if s.specular {
                    continue;
                }
                let bits = |s: SampledSpectrum| s.0.map(f32::to_bits);
                let f = ex.bxdf.f(wo, s.wi, mode);
                assert_eq!(bits(s.f), bits(f), "{} f at {wo}, {}", ex.name, s.wi);
                let pdf = ex.bxdf.pdf(wo, s.wi, mode);
                assert_eq!(s.pdf_w.to_bits(), pdf.to_bits(), "{} pdf", ex.name);
                checked += 1;
            }
        }
        assert!(checked > 500, "{checked}");
    }
}
