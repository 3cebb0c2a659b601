//! BxDFs: reflection models in a local shading frame where the normal is +Z.
//!
//! Conventions (DESIGN.md §2): `f()` excludes the cosine; pdfs are per unit solid angle;
//! `wo` and `wi` point away from the surface. One model per file, dispatched through the
//! closed [`Bxdf`] enum; [`Bsdf`] adds the shading frame and is returned by value.

pub mod diffuse;

use crate::math::Frame;
use crate::spectral::SampledSpectrum;
use glam::Vec3;

pub use diffuse::DiffuseBxdf;

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
}

/// The closed set of reflection models.
#[derive(Clone, Copy, Debug)]
pub enum Bxdf {
    Diffuse(DiffuseBxdf),
}

impl Bxdf {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> SampledSpectrum {
        match self {
            Bxdf::Diffuse(b) => b.f(wo, wi, mode),
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
        match self {
            Bxdf::Diffuse(b) => b.sample_f(wo, uc, u, mode),
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        match self {
            Bxdf::Diffuse(b) => b.pdf(wo, wi, mode),
        }
    }

    /// True when every lobe is a delta (no point in light sampling).
    #[inline]
    pub fn is_specular(&self) -> bool {
        match self {
            Bxdf::Diffuse(_) => false,
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
        let wo_local = self.frame.to_local(wo);
        if wo_local.z == 0.0 {
            return None;
        }
        let s = self.bxdf.sample_f(wo_local, uc, u, mode)?;
        if s.pdf_w == 0.0 || s.f.is_black() || s.wi.z == 0.0 || !s.pdf_w.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: self.frame.to_world(s.wi),
            ..s
        })
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if wo.z == 0.0 {
            return 0.0;
        }
        self.bxdf.pdf(wo, wi, mode)
    }

    #[inline]
    pub fn is_specular(&self) -> bool {
        self.bxdf.is_specular()
    }
}

/// True when two local directions lie on the same side of the surface.
#[inline]
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}
