//! Materials: what the scene stores per material prim, turned into a [`Bsdf`] at a hit for
//! the path's wavelengths.
//!
//! Everything that does not depend on the wavelengths or the hit (albedo tables of rough
//! coats, diffuse Fresnel integrals, uplifted spectra) is computed once when the scene is
//! built; [`Material::bsdf`] only evaluates spectra and fills plain `Copy` data. The spectra
//! that do not depend on the hit are [`Material::constant_spectra`], which the integrators
//! take from a per-thread [`SpectraCache`] once per material and wavelength tuple
//! (`spectra.rs`) and pass to [`Material::bsdf_with`].
//!
//! **Dispersion.** A dielectric whose IOR varies with λ refracts each wavelength in its own
//! direction. [`Material::is_dispersive`] says so; the integrator then terminates the
//! secondary wavelengths (`SampledWavelengths::terminate_secondary`, pbrt-v4 semantics)
//! *before* asking for the BSDF, and the BSDF is built with the hero wavelength's IOR. With a
//! constant IOR (and for thin dielectrics, whose directions do not depend on λ) the
//! wavelengths are never collapsed. The material only reads `lambda`.
//!
//! **Textures.** Inputs read from a `UsdUVTexture` are evaluated at the hit's st, filtered
//! over its footprint ([`TexCoord`]; only computed when [`Material::is_textured`]), when the
//! BSDF is built: UsdPreviewSurface's in `preview.rs`, the colour reflectance and roughness of
//! the `spectral:*` materials through [`ColorInput`], [`FloatInput`] and [`AlphaTexture`]
//! (`inputs.rs`). Coat albedos that a textured roughness needs come from `coat_levels.rs`.
//!
//! **Normal maps.** [`Material::shading_normal`] perturbs the interpolated shading normal
//! (`normal_map.rs`); the scene calls it when it builds the `SurfaceHit`, so that the BSDF
//! frame and the integrators' cosines agree. [`Material::bsdf`] takes the final normal.
//!
//! **Opacity.** [`Material::opacity`] is the probability that the surface is there
//! (UsdPreviewSurface `opacity`, `opacityThreshold`); the integrator lets rays through the
//! rest of the time.

pub mod coat_levels;
pub mod inputs;
pub mod normal_map;
pub mod preview;
pub mod spectra;

use crate::bxdf::coat::ScalarFresnel;
use crate::bxdf::fresnel::diffuse_fresnel;
use crate::bxdf::{
    Bsdf, Bxdf, CoatAlbedo, CoatFresnel, ConductorBxdf, DielectricBxdf, DiffuseBxdf, OrenNayarBxdf,
    PlasticBase, PlasticBxdf, SpecularCoat, ThinDielectricBxdf, TrowbridgeReitz,
};
use crate::spectral::sellmeier::Sellmeier;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::{TexCoord, TextureInput};
use coat_levels::CoatLevels;
use glam::{Vec2, Vec3};
use std::sync::Arc;

pub use inputs::{AlphaTexture, ColorInput, FloatInput};
pub use preview::PreviewMaterial;
pub use spectra::{MaterialSpectra, SpectraCache};

#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian reflection with a spectral reflectance in [0, 1].
    Diffuse {
        reflectance: ColorInput,
    },
    /// Oren–Nayar with slope deviation σ in radians.
    OrenNayar {
        reflectance: ColorInput,
        sigma: FloatInput,
    },
    /// A metal: complex IOR η + ik relative to air, GGX roughness (`roughness`: textured α,
    /// replacing `distrib`).
    Conductor {
        eta: Spectrum,
        k: Spectrum,
        distrib: TrowbridgeReitz,
        roughness: Option<AlphaTexture>,
    },
    /// A glass interface (outside: air; inside: the back of the geometric normal).
    Dielectric {
        ior: Sellmeier,
        distrib: TrowbridgeReitz,
        roughness: Option<AlphaTexture>,
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
    pub reflectance: ColorInput,
    /// A textured α, with the coat's albedo at roughness levels (replaces `distrib`,
    /// `albedo` and `t_avg`).
    pub roughness: Option<AlphaTexture>,
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
            reflectance: ColorInput::Constant(reflectance),
            roughness: None,
            eta,
            distrib,
            albedo,
            t_avg: albedo.average_transmittance(),
            fdr_internal: diffuse_fresnel(1.0 / eta),
        }
    }

    /// Reads α from `texture` (the coat's energy compensation from the nearest of the
    /// precomputed roughness levels, `coat_levels`).
    pub fn with_roughness_texture(self, texture: TextureInput) -> PlasticMaterial {
        let levels = CoatLevels::levels(ScalarFresnel::Dielectric { eta: self.eta });
        PlasticMaterial {
            roughness: Some(AlphaTexture {
                texture,
                coats: Some(Arc::new(levels)),
            }),
            ..self
        }
    }

    /// The coat's distribution, albedo and T̄ at `tc`.
    #[inline]
    fn coat(&self, tc: TexCoord) -> (TrowbridgeReitz, CoatAlbedo, f32) {
        match &self.roughness {
            Some(
                t @ AlphaTexture {
                    coats: Some(levels),
                    ..
                },
            ) => {
                let alpha = t.alpha(tc);
                let (albedo, t_avg) = levels.get(levels.level(alpha.sqrt()));
                (TrowbridgeReitz::isotropic(alpha), albedo, t_avg)
            }
            _ => (self.distrib, self.albedo, self.t_avg),
        }
    }

    /// The reflectance and, when ρ and the coat are both constant, the diffuse base
    /// ([`MaterialSpectra`]).
    #[inline]
    fn constant_spectra(&self, lambda: &SampledWavelengths) -> MaterialSpectra {
        let s0 = self.reflectance.constant(lambda);
        let base = if self.has_constant_base() {
            PlasticBase::new(s0, self.fdr_internal, self.t_avg)
        } else {
            PlasticBase::default()
        };
        MaterialSpectra {
            s0,
            base,
            ..MaterialSpectra::default()
        }
    }

    /// True when neither ρ nor the coat's roughness is textured.
    #[inline]
    fn has_constant_base(&self) -> bool {
        !self.reflectance.is_textured() && self.roughness.is_none()
    }

    #[inline]
    fn bxdf(&self, tc: TexCoord, lambda: &SampledWavelengths, c: &MaterialSpectra) -> PlasticBxdf {
        let (distrib, albedo, t_avg) = self.coat(tc);
        let coat = SpecularCoat::new(distrib, CoatFresnel::Dielectric { eta: self.eta });
        let base = if self.has_constant_base() {
            c.base
        } else {
            let r = self.reflectance.reflectance_with(tc, lambda, c.s0);
            PlasticBase::new(r, self.fdr_internal, t_avg)
        };
        PlasticBxdf::with_base(coat, albedo, base)
    }
}

impl Material {
    /// The BSDF at a surface point with texture coordinates `tc` (USD st and its footprint,
    /// [`Material::is_textured`]) and shading normal `ns`.
    #[inline]
    pub fn bsdf(&self, tc: TexCoord, ns: Vec3, lambda: &SampledWavelengths) -> Bsdf {
        self.bsdf_with(tc, ns, lambda, &self.constant_spectra(lambda))
    }

    /// The spectra of this material that do not depend on the hit, at `lambda`:
    ///
    /// | model | `s0` | `s1` | `base` |
    /// |---|---|---|---|
    /// | diffuse, Oren–Nayar | constant ρ | – | – |
    /// | conductor | η | k | – |
    /// | dielectric | IOR at the hero (lane 0) | – | – |
    /// | thin dielectric | IOR per lane | – | – |
    /// | plastic | constant ρ | – | constant ρ and coat |
    /// | UsdPreviewSurface | constant `diffuseColor` | constant `specularColor` | constant ρ and base coat |
    ///
    /// (– and textured inputs: zero, unused.)
    #[inline]
    pub fn constant_spectra(&self, lambda: &SampledWavelengths) -> MaterialSpectra {
        let (s0, s1) = match self {
            Material::Diffuse { reflectance } | Material::OrenNayar { reflectance, .. } => {
                (reflectance.constant(lambda), SampledSpectrum::ZERO)
            }
            Material::Conductor { eta, k, .. } => (eta.sample(lambda), k.sample(lambda)),
            Material::Dielectric { ior, .. } => {
                let mut s0 = SampledSpectrum::ZERO;
                s0[0] = ior.ior(lambda.lambda[0]);
                (s0, SampledSpectrum::ZERO)
            }
            Material::ThinDielectric { ior } => (
                SampledSpectrum::from_fn(|i| ior.ior(lambda.lambda[i])),
                SampledSpectrum::ZERO,
            ),
            Material::Plastic(p) => return p.constant_spectra(lambda),
            Material::Preview(p) => return p.constant_spectra(lambda),
        };
        MaterialSpectra {
            s0,
            s1,
            base: PlasticBase::default(),
        }
    }

    /// [`Material::bsdf`] with this material's [`Material::constant_spectra`] at `lambda`
    /// given (from a [`SpectraCache`]): only textured inputs are evaluated here.
    #[inline]
    pub fn bsdf_with(
        &self,
        tc: TexCoord,
        ns: Vec3,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> Bsdf {
        // Each arm builds its Bsdf in place (as `PreviewMaterial::bsdf_with`): a match over a
        // Bxdf and then `Bsdf::new` copies the model twice more.
        match self {
            Material::Diffuse { reflectance } => Bsdf::new(
                Bxdf::Diffuse(DiffuseBxdf {
                    r: reflectance.reflectance_with(tc, lambda, c.s0),
                }),
                ns,
            ),
            Material::OrenNayar { reflectance, sigma } => Bsdf::new(
                Bxdf::OrenNayar(OrenNayarBxdf::new(
                    reflectance.reflectance_with(tc, lambda, c.s0),
                    sigma.eval(tc),
                )),
                ns,
            ),
            Material::Conductor {
                distrib, roughness, ..
            } => Bsdf::new(
                Bxdf::Conductor(ConductorBxdf::new(
                    AlphaTexture::distrib(roughness.as_ref(), *distrib, tc),
                    c.s0,
                    c.s1,
                )),
                ns,
            ),
            Material::Dielectric {
                distrib, roughness, ..
            } => Bsdf::new(
                Bxdf::Dielectric(DielectricBxdf::new(
                    AlphaTexture::distrib(roughness.as_ref(), *distrib, tc),
                    c.s0[0],
                )),
                ns,
            ),
            Material::ThinDielectric { .. } => {
                Bsdf::new(Bxdf::ThinDielectric(ThinDielectricBxdf::new(c.s0)), ns)
            }
            Material::Plastic(p) => Bsdf::new(Bxdf::Plastic(p.bxdf(tc, lambda, c)), ns),
            Material::Preview(p) => p.bsdf_with(tc, ns, lambda, c),
        }
    }

    /// True when the BSDF reads a texture: only then do the integrators compute the hit's
    /// footprint for [`Material::bsdf`] (an untextured material gets [`TexCoord::point`]).
    #[inline]
    pub fn is_textured(&self) -> bool {
        match self {
            Material::Diffuse { reflectance } => reflectance.is_textured(),
            Material::OrenNayar { reflectance, sigma } => {
                reflectance.is_textured() || sigma.is_textured()
            }
            Material::Conductor { roughness, .. } | Material::Dielectric { roughness, .. } => {
                roughness.is_some()
            }
            Material::ThinDielectric { .. } => false,
            Material::Plastic(p) => p.reflectance.is_textured() || p.roughness.is_some(),
            Material::Preview(p) => p.bsdf_is_textured(),
        }
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
