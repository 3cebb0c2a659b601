//! Materials: what the scene stores per material prim, turned into a [`Bsdf`] at a hit for
//! the path's wavelengths.
//!
//! Everything that does not depend on the wavelengths or the hit (albedo tables of rough
//! coats, diffuse Fresnel integrals, uplifted spectra) is computed once when the scene is
//! built; [`Material::bsdf`] only evaluates spectra and fills plain `Copy` data.
//!
//! **Dispersion.** A dielectric whose IOR varies with λ refracts each wavelength in its own
//! direction. [`Material::is_dispersive`] says so; the integrator then terminates the
//! secondary wavelengths (`SampledWavelengths::terminate_secondary`, pbrt-v4 semantics)
//! *before* asking for the BSDF, and the BSDF is built with the hero wavelength's IOR. With a
//! constant IOR (and for thin dielectrics, whose directions do not depend on λ) the
//! wavelengths are never collapsed. The material only reads `lambda`.
//!
//! **Normal maps.** [`Material::shading_normal`] perturbs the interpolated shading normal
//! (`normal_map.rs`); the scene calls it when it builds the `SurfaceHit`, so that the BSDF
//! frame and the integrators' cosines agree. [`Material::bsdf`] takes the final normal.
//!
//! **Opacity.** [`Material::opacity`] is the probability that the surface is there
//! (UsdPreviewSurface `opacity`, `opacityThreshold`); the integrator lets rays through the
//! rest of the time.

pub mod coat_levels;
pub mod normal_map;
pub mod preview;

use crate::bxdf::fresnel::diffuse_fresnel;
use crate::bxdf::{
    Bsdf, Bxdf, CoatAlbedo, CoatFresnel, ConductorBxdf, DielectricBxdf, DiffuseBxdf, OrenNayarBxdf,
    PlasticBxdf, SpecularCoat, ThinDielectricBxdf, TrowbridgeReitz,
};
use crate::spectral::sellmeier::Sellmeier;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use glam::{Vec2, Vec3};

pub use preview::PreviewMaterial;

#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian reflection with a spectral reflectance in [0, 1].
    Diffuse {
        reflectance: Spectrum,
    },
    /// Oren–Nayar with slope deviation σ in radians.
    OrenNayar {
        reflectance: Spectrum,
        sigma: f32,
    },
    /// A metal: complex IOR η + ik relative to air, GGX roughness.
    Conductor {
        eta: Spectrum,
        k: Spectrum,
        distrib: TrowbridgeReitz,
    },
    /// A glass interface (outside: air; inside: the back of the geometric normal).
    Dielectric {
        ior: Sellmeier,
        distrib: TrowbridgeReitz,
    },
    /// A thin slab of glass.
    ThinDielectric {
        ior: Sellmeier,
    },
    Plastic(PlasticMaterial),
    Preview(Box<PreviewMaterial>),
}

/// A plastic with its coat's precomputed albedo.
#[derive(Clone, Debug)]
pub struct PlasticMaterial {
    pub reflectance: Spectrum,
    pub eta: f32,
    pub distrib: TrowbridgeReitz,
    pub albedo: CoatAlbedo,
    /// T̄ = ∫ (1 − E(μ)) 2μ dμ.
    pub t_avg: f32,
    /// F_dr of the coat seen from inside.
    pub fdr_internal: f32,
}

impl PlasticMaterial {
    /// Precomputes the coat of a plastic with IOR `eta` and GGX `alpha`.
    pub fn new(reflectance: Spectrum, eta: f32, alpha: f32) -> PlasticMaterial {
        let distrib = TrowbridgeReitz::isotropic(alpha);
        let albedo = SpecularCoat::new(distrib, CoatFresnel::Dielectric { eta }).albedo();
        PlasticMaterial {
            reflectance,
            eta,
            distrib,
            albedo,
            t_avg: albedo.average_transmittance(),
            fdr_internal: diffuse_fresnel(1.0 / eta),
        }
    }

    fn bxdf(&self, lambda: &SampledWavelengths) -> PlasticBxdf {
        let coat = SpecularCoat::new(self.distrib, CoatFresnel::Dielectric { eta: self.eta });
        let r = self.reflectance.sample(lambda);
        PlasticBxdf::with_coat(coat, self.albedo, r, self.fdr_internal, self.t_avg)
    }
}

impl Material {
    /// The BSDF at a surface point with texture coordinates `uv` (USD st) and shading
    /// normal `ns`.
    #[inline]
    pub fn bsdf(&self, uv: Vec2, ns: Vec3, lambda: &SampledWavelengths) -> Bsdf {
        let bxdf = match self {
            Material::Diffuse { reflectance } => Bxdf::Diffuse(DiffuseBxdf {
                r: reflectance_at(reflectance, lambda),
            }),
            Material::OrenNayar { reflectance, sigma } => Bxdf::OrenNayar(OrenNayarBxdf::new(
                reflectance_at(reflectance, lambda),
                *sigma,
            )),
            Material::Conductor { eta, k, distrib } => Bxdf::Conductor(ConductorBxdf::new(
                *distrib,
                eta.sample(lambda),
                k.sample(lambda),
            )),
            Material::Dielectric { ior, distrib } => {
                Bxdf::Dielectric(DielectricBxdf::new(*distrib, ior.ior(lambda.lambda[0])))
            }
            Material::ThinDielectric { ior } => {
                Bxdf::ThinDielectric(ThinDielectricBxdf::new(SampledSpectrum::from_fn(|i| {
                    ior.ior(lambda.lambda[i])
                })))
            }
            Material::Plastic(p) => Bxdf::Plastic(p.bxdf(lambda)),
            Material::Preview(p) => return p.bsdf(uv, ns, lambda),
        };
        Bsdf::new(bxdf, ns)
    }

    /// True when the direction of a refracted ray depends on the wavelength: the integrator
    /// must then terminate the secondary wavelengths before calling [`Material::bsdf`].
    #[inline]
    pub fn is_dispersive(&self) -> bool {
        matches!(self, Material::Dielectric { ior, .. } if ior.is_dispersive())
    }

    /// The probability that the surface is present (1 for everything but a
    /// UsdPreviewSurface with opacity) at texture coordinates `uv`.
    #[inline]
    pub fn opacity(&self, uv: Vec2) -> f32 {
        match self {
            Material::Preview(p) => p.opacity(uv),
            _ => 1.0,
        }
    }

    /// True when the material perturbs the shading normal (UsdPreviewSurface `normal`): the
    /// scene then keeps tangent frames for the meshes it is bound to.
    pub fn perturbs_normal(&self) -> bool {
        matches!(self, Material::Preview(p) if p.perturbs_normal())
    }

    /// The shading normal at st = `uv` given the interpolated one `ns`, the geometric normal
    /// `ng` and the triangle's (∂p/∂u, ∂p/∂v) (`normal_map`); `ns` for every other material.
    #[inline]
    pub fn shading_normal(&self, uv: Vec2, ns: Vec3, ng: Vec3, dpduv: [Vec3; 2]) -> Vec3 {
        match self {
            Material::Preview(p) => p.shading_normal(uv, ns, ng, dpduv),
            _ => ns,
        }
    }

    /// True when the surface is present everywhere (opacity 1 and no opacity texture).
    #[inline]
    pub fn is_opaque(&self) -> bool {
        match self {
            Material::Preview(p) => p.is_opaque(),
            _ => true,
        }
    }
}

/// A reflectance spectrum at the path's wavelengths, clamped to [0, 1].
#[inline]
fn reflectance_at(s: &Spectrum, lambda: &SampledWavelengths) -> SampledSpectrum {
    s.sample(lambda).map(|v| v.clamp(0.0, 1.0))
}
