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
//! | `normal` | a tangent-space normal (constant or a normal map), applied to the shading normal in the tangent frame of st by the scene (`normal_map.rs`) |
//!
//! **Textures.** `diffuseColor`, `metallic`, `roughness`, `clearcoat`, `opacity` and `normal`
//! may be connected to a `UsdUVTexture` ([`PreviewTextures`]): they are looked up at the hit's st per
//! BSDF, the colour uplifted per lookup (`crate::texture`). A textured `roughness` sets the GGX
//! α exactly; the plastic coat's energy compensation (albedo E(μ), T̄) is taken from the
//! nearest of 33 roughness levels precomputed at build time. `clearcoatRoughness`,
//! `specularColor` (which feed precomputed albedos) and `emissiveColor` stay constant: a
//! texture there is warned about by the scene builder and the spec default is used.
//!
//! Roughness is squared (α = r²) as in the specification's reference implementation and in
//! Burley 2012 (§5.4), where `roughness` is perceptually linear; `spectral:` materials take α
//! directly (DESIGN.md §3). The plastic coat uses the exact dielectric Fresnel of `ior`
//! rather than the reference shader's Schlick fit of it; the spec's F0 of `specularColor`
//! is Schlick by definition. Colours are uplifted with Jakob–Hanika 2019 and clamped to
//! [0, 1]. The tangent frame of `normal` is ∂p/∂u (Gram–Schmidt against the shading normal)
//! and ±n × t on the side of ∂p/∂v; on a mesh without st (or where st is degenerate) it is the
//! arbitrary basis of Duff et al. 2017 around the shading normal, so there only the default
//! (0, 0, 1) and normals symmetric about +Z are portable between renderers.

use super::normal_map;
use crate::bxdf::fresnel::diffuse_fresnel;
use crate::bxdf::{
    Bsdf, Bxdf, CoatAlbedo, CoatFresnel, PlasticBxdf, PreviewBxdf, SpecularCoat, TrowbridgeReitz,
};
use crate::scene::desc::PreviewSurfaceDesc;
use crate::spectral::uplift::reflectance_lookup;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::TextureInput;
use glam::{Vec2, Vec3};
use std::sync::Arc;

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
    pub roughness: Option<TextureInput>,
    /// A tangent-space normal map (`normal`, usually raw with scale 2 and bias −1).
    pub normal: Option<TextureInput>,
    /// Precomputed with the roughness texture ([`PreviewMaterial::set_roughness_texture`]).
    pub roughness_coats: Option<Arc<RoughnessCoats>>,
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
            && self.roughness.is_none()
            && self.normal.is_none()
    }
}

impl PreviewMaterial {
    /// Precomputes the material; `diffuse` and `specular` are the uplifted colours.
    pub fn new(d: &PreviewSurfaceDesc, diffuse: Spectrum, specular: Spectrum) -> PreviewMaterial {
        let distrib = TrowbridgeReitz::isotropic(d.roughness.clamp(0.0, 1.0).powi(2));
        let specular = d.use_specular_workflow.then_some(specular);
        let fresnel = albedo_fresnel(specular.as_ref(), d.ior);
        let fdr = match &specular {
            Some(_) => 0.0,
            None => diffuse_fresnel(1.0 / d.ior),
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

    /// Reads `roughness` from `t`: the GGX α is exact per lookup, the base coat's energy
    /// compensation (albedo, average transmittance) comes from the nearest of
    /// [`ROUGHNESS_LEVELS`] precomputed roughnesses (Δr = 1/32).
    pub fn set_roughness_texture(&mut self, t: TextureInput) {
        let fresnel = albedo_fresnel(self.specular.as_ref(), self.ior);
        let albedo: [CoatAlbedo; ROUGHNESS_LEVELS] = std::array::from_fn(|k| {
            let r = k as f32 / (ROUGHNESS_LEVELS - 1) as f32;
            SpecularCoat::new(TrowbridgeReitz::isotropic(r * r), fresnel).albedo()
        });
        let t_avg = albedo.map(|a| a.average_transmittance());
        self.textures.roughness = Some(t);
        self.textures.roughness_coats = Some(Arc::new(RoughnessCoats { albedo, t_avg }));
    }

    /// The base GGX distribution, its coat albedo and average transmittance at st = `uv`.
    #[inline]
    fn base_coat(&self, uv: Vec2) -> (TrowbridgeReitz, CoatAlbedo, f32) {
        match (&self.textures.roughness, &self.textures.roughness_coats) {
            (Some(t), Some(coats)) => {
                let r = Self::scalar(Some(t), 0.0, uv);
                let k = (r * (ROUGHNESS_LEVELS - 1) as f32).round() as usize;
                let k = k.min(ROUGHNESS_LEVELS - 1);
                let distrib = TrowbridgeReitz::isotropic(r * r);
                (distrib, coats.albedo[k], coats.t_avg[k])
            }
            _ => (self.distrib, self.base_albedo, self.base_t_avg),
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
    fn scalar(t: Option<&TextureInput>, constant: f32, uv: Vec2) -> f32 {
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
            Self::scalar(self.textures.metallic.as_ref(), self.metallic, uv)
        };
        let clearcoat = Self::scalar(self.textures.clearcoat.as_ref(), self.clearcoat, uv);
        let fresnel = match &self.specular {
            Some(s) => CoatFresnel::Schlick { f0: clamp01(s) },
            None => CoatFresnel::Dielectric { eta: self.ior },
        };
        let (distrib, albedo, t_avg) = self.base_coat(uv);
        let base = PlasticBxdf::with_coat(
            SpecularCoat::new(distrib, fresnel),
            albedo,
            rho,
            self.base_fdr_internal,
            t_avg,
        );
        let bxdf = PreviewBxdf {
            base,
            metal: SpecularCoat::new(distrib, CoatFresnel::Schlick { f0: rho }),
            metallic,
            clearcoat: SpecularCoat::new(
                self.clearcoat_distrib,
                CoatFresnel::Dielectric { eta: CLEARCOAT_IOR },
            ),
            clearcoat_albedo: self.clearcoat_albedo,
            clearcoat_weight: clearcoat,
        };
        Bsdf::new(Bxdf::Preview(bxdf), ns)
    }

    /// True when `normal` (constant or textured) perturbs the shading normal.
    pub fn perturbs_normal(&self) -> bool {
        self.textures.normal.is_some() || self.normal != Vec3::Z
    }

    /// The shading normal perturbed by `normal` at st = `uv`, in the tangent frame `dpduv`
    /// (`material::normal_map`).
    #[inline]
    pub fn shading_normal(&self, uv: Vec2, ns: Vec3, ng: Vec3, dpduv: [Vec3; 2]) -> Vec3 {
        let n_t = match &self.textures.normal {
            Some(t) => normal_map::texel_normal(t.rgb(uv)),
            None => self.normal,
        };
        normal_map::perturb(n_t, ns, ng, dpduv)
    }
}

/// The scalar Fresnel bound the base coat's albedo is computed with.
fn albedo_fresnel(specular: Option<&Spectrum>, ior: f32) -> CoatFresnel {
    match specular {
        Some(s) => CoatFresnel::Schlick {
            f0: SampledSpectrum::splat(s.to_dense().max_value().clamp(0.0, 1.0)),
        },
        None => CoatFresnel::Dielectric { eta: ior },
    }
}

/// Roughness levels of [`RoughnessCoats`]: r = k / (N − 1).
pub const ROUGHNESS_LEVELS: usize = 33;

/// The base coat's albedo and average transmittance at [`ROUGHNESS_LEVELS`] roughnesses, for
/// a textured `roughness`.
#[derive(Debug)]
pub struct RoughnessCoats {
    pub albedo: [CoatAlbedo; ROUGHNESS_LEVELS],
    pub t_avg: [f32; ROUGHNESS_LEVELS],
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
    use crate::bxdf::TransportMode;
    use crate::scene::desc::{TextureChannel, Wrap};
    use crate::spectral::uplift;
    use crate::texture::ImageTexture;

    /// A 1×1 texture of `rgba`, used through `channel`.
    fn constant_texture(rgba: [f32; 4], channel: TextureChannel) -> TextureInput {
        TextureInput {
            image: Arc::new(ImageTexture::from_texels(1, 1, vec![rgba]).unwrap()),
            wrap: [Wrap::Repeat; 2],
            scale: [1.0; 4],
            bias: [0.0; 4],
            fallback: [0.0; 4],
            channel,
        }
    }

    /// A textured material whose textures hold the constants of another gives its BSDF
    /// (roughness 0.5 lies on the precomputed grid, so even the energy compensation agrees).
    #[test]
    fn constant_textures_reproduce_constant_inputs() {
        let d = PreviewSurfaceDesc {
            diffuse_color: [0.6, 0.3, 0.2],
            metallic: 0.25,
            roughness: 0.5,
            clearcoat: 0.5,
            ..PreviewSurfaceDesc::default()
        };
        let lookup = Spectrum::Sigmoid(uplift::reflectance_lookup(d.diffuse_color));
        let spec = Spectrum::Constant(0.0);
        let plain = PreviewMaterial::new(&d, lookup, spec.clone());
        let mut textured = PreviewMaterial::new(
            &PreviewSurfaceDesc {
                roughness: 0.9,
                metallic: 0.0,
                clearcoat: 0.0,
                ..d.clone()
            },
            Spectrum::Constant(0.0),
            spec,
        );
        let rgb = d.diffuse_color;
        textured.textures.diffuse = Some(constant_texture(
            [rgb[0], rgb[1], rgb[2], 1.0],
            TextureChannel::Rgb,
        ));
        let scalars = [0.25, 0.5, 0.5, 1.0];
        textured.textures.metallic = Some(constant_texture(scalars, TextureChannel::R));
        textured.textures.clearcoat = Some(constant_texture(scalars, TextureChannel::G));
        textured.set_roughness_texture(constant_texture(scalars, TextureChannel::B));
        let lambda = SampledWavelengths {
            lambda: [450.0, 520.0, 600.0, 680.0],
            pdf: [1.0; 4],
        };
        let uv = Vec2::new(0.3, 0.7);
        let (a, b) = (
            plain.bsdf(uv, Vec3::Z, &lambda),
            textured.bsdf(uv, Vec3::Z, &lambda),
        );
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        for wi in [
            Vec3::new(-0.2, 0.4, 0.8),
            Vec3::new(0.5, -0.5, 0.3),
            Vec3::Z,
        ] {
            let wi = wi.normalize();
            let (fa, fb) = (
                a.f(wo, wi, TransportMode::Radiance),
                b.f(wo, wi, TransportMode::Radiance),
            );
            for i in 0..4 {
                assert!(
                    (fa.0[i] - fb.0[i]).abs() <= 1e-6 * fa.0[i].max(1.0),
                    "{fa:?} {fb:?}"
                );
            }
        }
    }

    #[test]
    fn textured_opacity_applies_the_threshold_per_lookup() {
        let d = PreviewSurfaceDesc {
            opacity_threshold: 0.5,
            ..PreviewSurfaceDesc::default()
        };
        let s = Spectrum::Constant(0.5);
        let mut m = PreviewMaterial::new(&d, s.clone(), s);
        assert!(m.is_opaque());
        let texels = vec![[0.0, 0.0, 0.0, 0.2], [0.0, 0.0, 0.0, 0.8]];
        m.textures.opacity = Some(TextureInput {
            image: Arc::new(ImageTexture::from_texels(2, 1, texels).unwrap()),
            ..constant_texture([0.0; 4], TextureChannel::A)
        });
        assert!(!m.is_opaque());
        assert_eq!(m.opacity(Vec2::new(0.25, 0.5)), 0.0);
        assert_eq!(m.opacity(Vec2::new(0.75, 0.5)), 1.0);
    }

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
