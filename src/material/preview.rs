//! UsdPreviewSurface (the UsdPreviewSurface specification, OpenUSD 24) mapped onto
//! [`PreviewBxdf`]: a clearcoat over a metallic blend of a metal and a plastic.
//!
//! | input | mapping |
//! |---|---|
//! | `diffuseColor` | the Lambertian base ρ of the plastic, and the metal's Schlick F0 |
//! | `emissiveColor` | an emitter (handled by the scene builder, not here) |
//! | `useSpecularWorkflow` = 0 | metallic workflow: plastic coat = dielectric Fresnel with `ior`; metal weight = `metallic` |
//! | `useSpecularWorkflow` = 1 | plastic coat = Schlick with F0 = `specularColor`, F90 = 1; no metal lobe (`metallic` ignored, as the spec says) |
//! | `roughness` | GGX α = roughness² for metal and plastic coat |
//! | `clearcoat`, `clearcoatRoughness` | weight c of a GGX coat of IOR 1.5 (the spec's fixed clearcoat IOR), α = clearcoatRoughness² |
//! | `opacity`, `opacityThreshold` | threshold > 0: present where opacity ≥ threshold, a cutout elsewhere; threshold 0: present with probability `opacity` |
//! | `normal` | a constant tangent-space normal, applied in the frame built around the shading normal |
//!
//! **Textures.** `diffuseColor`, `metallic`, `clearcoat` and `opacity` may be connected to a
//! `UsdUVTexture` ([`PreviewTextures`]): they are looked up at the hit's st per BSDF, the colour
//! uplifted per lookup (`crate::texture`). Inputs whose value feeds precomputed coat albedos
//! (`roughness`, `clearcoatRoughness`, `specularColor`) and `emissiveColor` stay constant:
//! a texture there is rejected by the scene builder with a warning (the value default is used).
//!
//! Roughness is squared (α = r²) as in the specification's reference implementation and in
//! Burley 2012 (§5.4), where `roughness` is perceptually linear; `spectral:` materials take α
//! directly (DESIGN.md §3). The plastic coat uses the exact dielectric Fresnel of `ior`
//! rather than the reference shader's Schlick fit of it; the spec's F0 of `specularColor`
//! is Schlick by definition. Colours are uplifted with Jakob–Hanika 2019 and clamped to
//! [0, 1]. Without tangents on the meshes the tangent frame of `normal` is the orthonormal
//! basis of Duff et al. 2017 around the shading normal, so only the default (0, 0, 1) and
//! normals symmetric about +Z are portable between renderers.

use crate::bxdf::fresnel::diffuse_fresnel;
use crate::bxdf::{
    Bsdf, Bxdf, CoatAlbedo, CoatFresnel, PlasticBxdf, PreviewBxdf, SpecularCoat, TrowbridgeReitz,
};
use crate::math::Frame;
use crate::scene::desc::PreviewSurfaceDesc;
use crate::spectral::uplift::reflectance_lookup;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::TextureInput;
use glam::{Vec2, Vec3};

/// The fixed IOR of the clearcoat layer (UsdPreviewSurface specification).
pub const CLEARCOAT_IOR: f32 = 1.5;

#[derive(Clone, Debug)]
pub struct PreviewMaterial {
    /// `diffuseColor` as a reflectance.
    pub diffuse: Spectrum,
    /// `specularColor` as Schlick F0 in the specular workflow; `None` in the metallic one.
    pub specular: Option<Spectrum>,
    pub metallic: f32,
    pub ior: f32,
    pub distrib: TrowbridgeReitz,
    /// The plastic coat's albedo, its average transmittance and internal diffuse Fresnel.
    pub base_albedo: CoatAlbedo,
    pub base_t_avg: f32,
    pub base_fdr_internal: f32,
    pub clearcoat: f32,
    pub clearcoat_distrib: TrowbridgeReitz,
    pub clearcoat_albedo: CoatAlbedo,
    /// Probability that the surface is present.
    pub opacity: f32,
    /// Unit tangent-space normal; `Vec3::Z` leaves the shading normal unchanged.
    pub normal: Vec3,
    /// Inputs read from textures at the hit (override the constants above).
    pub textures: PreviewTextures,
}

/// The textured inputs of a UsdPreviewSurface; `None` where the input is a constant.
#[derive(Clone, Debug, Default)]
pub struct PreviewTextures {
    pub diffuse: Option<TextureInput>,
    pub metallic: Option<TextureInput>,
    pub clearcoat: Option<TextureInput>,
    pub opacity: Option<TextureInput>,
    /// `opacityThreshold`, applied to a textured opacity per lookup.
    pub opacity_threshold: f32,
}

impl PreviewTextures {
    /// True when no input is textured.
    pub fn is_empty(&self) -> bool {
        self.diffuse.is_none()
            && self.metallic.is_none()
            && self.clearcoat.is_none()
            && self.opacity.is_none()
    }
}

impl PreviewMaterial {
    /// Precomputes the material; `diffuse` and `specular` are the uplifted colours.
    pub fn new(d: &PreviewSurfaceDesc, diffuse: Spectrum, specular: Spectrum) -> PreviewMaterial {
        let distrib = TrowbridgeReitz::isotropic(d.roughness.clamp(0.0, 1.0).powi(2));
        let specular = d.use_specular_workflow.then_some(specular);
        let (fresnel, fdr) = match &specular {
            Some(s) => {
                let f0 = s.to_dense().max_value().clamp(0.0, 1.0);
                (
                    CoatFresnel::Schlick {
                        f0: SampledSpectrum::splat(f0),
                    },
                    0.0,
                )
            }
            None => (
                CoatFresnel::Dielectric { eta: d.ior },
                diffuse_fresnel(1.0 / d.ior),
            ),
        };
        let base_albedo = SpecularCoat::new(distrib, fresnel).albedo();
        let clearcoat_distrib =
            TrowbridgeReitz::isotropic(d.clearcoat_roughness.clamp(0.0, 1.0).powi(2));
        let clearcoat_albedo = SpecularCoat::new(
            clearcoat_distrib,
            CoatFresnel::Dielectric { eta: CLEARCOAT_IOR },
        )
        .albedo();
        PreviewMaterial {
            diffuse,
            metallic: if specular.is_some() {
                0.0
            } else {
                d.metallic.clamp(0.0, 1.0)
            },
            specular,
            ior: d.ior,
            distrib,
            base_albedo,
            base_t_avg: base_albedo.average_transmittance(),
            base_fdr_internal: fdr,
            clearcoat: d.clearcoat.clamp(0.0, 1.0),
            clearcoat_distrib,
            clearcoat_albedo,
            opacity: presence(d.opacity, d.opacity_threshold),
            normal: tangent_normal(d.normal),
            textures: PreviewTextures {
                opacity_threshold: d.opacity_threshold,
                ..PreviewTextures::default()
            },
        }
    }

    /// The probability that the surface is present at st = `uv`.
    #[inline]
    pub fn opacity(&self, uv: Vec2) -> f32 {
        match &self.textures.opacity {
            Some(t) => presence(t.float(uv), self.textures.opacity_threshold),
            None => self.opacity,
        }
    }

    /// True when the surface is present everywhere.
    pub fn is_opaque(&self) -> bool {
        self.textures.opacity.is_none() && self.opacity >= 1.0
    }

    /// The diffuse reflectance at st = `uv`, clamped to [0, 1].
    #[inline]
    fn rho(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let s = match &self.textures.diffuse {
            Some(t) => {
                let sigmoid = reflectance_lookup(t.rgb(uv));
                SampledSpectrum::from_fn(|i| sigmoid.eval(lambda.lambda[i]))
            }
            None => self.diffuse.sample(lambda),
        };
        s.map(|v| v.clamp(0.0, 1.0))
    }

    /// A scalar input: the texture's float output at `uv` or the constant, clamped to [0, 1].
    #[inline]
    fn scalar(t: &Option<TextureInput>, constant: f32, uv: Vec2) -> f32 {
        match t {
            Some(t) => {
                let v = t.float(uv);
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            }
            None => constant,
        }
    }

    /// The BSDF at a hit with st = `uv` and shading normal `ns`.
    #[inline]
    pub fn bsdf(&self, uv: Vec2, ns: Vec3, lambda: &SampledWavelengths) -> Bsdf {
        let clamp01 = |s: &Spectrum| s.sample(lambda).map(|v| v.clamp(0.0, 1.0));
        let rho = self.rho(uv, lambda);
        let metallic = if self.specular.is_some() {
            0.0
        } else {
            Self::scalar(&self.textures.metallic, self.metallic, uv)
        };
        let clearcoat = Self::scalar(&self.textures.clearcoat, self.clearcoat, uv);
        let fresnel = match &self.specular {
            Some(s) => CoatFresnel::Schlick { f0: clamp01(s) },
            None => CoatFresnel::Dielectric { eta: self.ior },
        };
        let base = PlasticBxdf::with_coat(
            SpecularCoat::new(self.distrib, fresnel),
            self.base_albedo,
            rho,
            self.base_fdr_internal,
            self.base_t_avg,
        );
        let bxdf = PreviewBxdf {
            base,
            metal: SpecularCoat::new(self.distrib, CoatFresnel::Schlick { f0: rho }),
            metallic,
            clearcoat: SpecularCoat::new(
                self.clearcoat_distrib,
                CoatFresnel::Dielectric { eta: CLEARCOAT_IOR },
            ),
            clearcoat_albedo: self.clearcoat_albedo,
            clearcoat_weight: clearcoat,
        };
        let n = if self.normal == Vec3::Z {
            ns
        } else {
            Frame::from_normal(ns).to_world(self.normal).normalize()
        };
        Bsdf::new(Bxdf::Preview(bxdf), n)
    }
}

/// The probability that the surface is there: a cutout mask when `threshold` > 0.
fn presence(opacity: f32, threshold: f32) -> f32 {
    let opacity = opacity.clamp(0.0, 1.0);
    if threshold > 0.0 {
        if opacity >= threshold {
            1.0
        } else {
            0.0
        }
    } else {
        opacity
    }
}

/// The authored normal made unit; (0, 0, 1) when it is degenerate or points below.
fn tangent_normal(n: [f32; 3]) -> Vec3 {
    match Vec3::from_array(n).try_normalize() {
        Some(v) if v.z > 0.0 => v,
        _ => Vec3::Z,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cutouts_and_partial_opacity() {
        assert_eq!(presence(0.3, 0.5), 0.0);
        assert_eq!(presence(0.5, 0.5), 1.0);
        assert_eq!(presence(0.3, 0.0), 0.3);
        assert_eq!(presence(1.0, 0.0), 1.0);
        assert_eq!(tangent_normal([0.0, 0.0, -1.0]), Vec3::Z);
        assert_eq!(tangent_normal([0.0, 0.0, 2.0]), Vec3::Z);
    }
}
