//! UsdPreviewSurface (the UsdPreviewSurface specification, OpenUSD 24) mapped onto
//! [`PreviewBxdf`]: a clearcoat over a metallic blend of a metal and a plastic.
//!
//! | input | mapping |
//! |---|---|
//! | `diffuseColor` | the Lambertian base ρ of the plastic, and the metal's Schlick F0 |
//! | `emissiveColor` | an emitter of that RGB radiance in nits (the scene builder makes the mesh's triangles lights) |
//! | `useSpecularWorkflow` = 0 | metallic workflow: plastic coat = dielectric Fresnel with `ior`; metal weight = `metallic` |
//! | `useSpecularWorkflow` = 1 | plastic coat = Schlick with F0 = `specularColor`, F90 = 1; no metal lobe (`metallic` ignored, as the spec says) |
//! | `roughness` | GGX α = roughness² for metal and plastic coat |
//! | `clearcoat`, `clearcoatRoughness` | weight c of a GGX coat of IOR 1.5 (the spec's fixed clearcoat IOR), α = clearcoatRoughness² |
//! | `opacity`, `opacityThreshold` | threshold > 0: present where opacity ≥ threshold, a cutout elsewhere; threshold 0: present with probability `opacity` |
//! | `normal` | a tangent-space normal (constant or a normal map), applied to the shading normal in the tangent frame of st by the scene (`normal_map.rs`) |
//!
//! **Pruning.** Lobes whose weight is exactly zero at every hit are left out when the material
//! is built ([`PreviewLobes`]): `clearcoat` 0 has no coat, `metallic` 0 (or the specular
//! workflow) no metal, and then the material is the plastic alone — or, in the metallic
//! workflow with `ior` 1, whose coat reflects nothing, a Lambertian. `specularColor` 0 keeps
//! its coat: the specification's edge colour is white, F90 = 1.
//!
//! **Textures.** Every input but `useSpecularWorkflow`, `ior` and `opacityThreshold` may be
//! connected to a `UsdUVTexture` ([`PreviewTextures`]): the BSDF's inputs are looked up at the
//! hit's st per BSDF, filtered over the pixel footprint, colours uplifted per lookup
//! (`crate::texture`); `normal` is applied by the scene to the hit's shading normal;
//! `emissiveColor` by the mesh's triangle lights (`light::triangle`); those two and `opacity`
//! are looked up at the finest level (pbrt-v4 does the same). A textured `roughness` or `clearcoatRoughness` sets the GGX α exactly;
//! the coats' energy compensation (albedo E(μ), T̄) comes from the nearest of 33 roughness
//! levels precomputed at build time, and a textured `specularColor` interpolates it exactly
//! between F0 = 0 and 1 (`coat_levels`).
//!
//! Roughness is squared (α = r²) as in the specification's reference implementation and in
//! Burley 2012 (§5.4), where `roughness` is perceptually linear; `spectral:` materials take α
//! directly (docs/design.md §3). The plastic coat uses the exact dielectric Fresnel of `ior`
//! rather than the reference shader's Schlick fit of it; the spec's F0 of `specularColor`
//! is Schlick by definition. Colours are uplifted with Jakob–Hanika 2019 and clamped to
//! [0, 1]. The tangent frame of `normal` is ∂p/∂u (Gram–Schmidt against the shading normal)
//! and ±n × t on the side of ∂p/∂v; on a mesh without st (or where st is degenerate) it is the
//! arbitrary basis of Duff et al. 2017 around the shading normal, so there only the default
//! (0, 0, 1) and normals symmetric about +Z are portable between renderers.

use super::coat_levels::{CoatLevels, SchlickLevels};
use super::normal_map;
use super::MaterialSpectra;
use crate::bxdf::coat::ScalarFresnel;
use crate::bxdf::fresnel::diffuse_fresnel;
use crate::bxdf::{
    Bsdf, Bxdf, CoatAlbedo, CoatFresnel, DiffuseBxdf, PlasticBase, PlasticBxdf, PreviewBxdf,
    SpecularCoat, TrowbridgeReitz,
};
use crate::desc::PreviewSurfaceDesc;
use crate::spectral::uplift::reflectance_lookup;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::{TexCoord, TextureInput};
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
    /// `roughness` clamped to [0, 1]; α = roughness².
    pub roughness: f32,
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
    /// The lobes that can carry weight, decided when the material is built.
    pub lobes: PreviewLobes,
    /// True when the BSDF reads a texture ([`Self::bsdf_is_textured`]), decided when the
    /// material is built (and by [`Self::prepare_textures`]) rather than tested per hit.
    bsdf_textured: bool,
}

/// Which BSDF a UsdPreviewSurface becomes: its lobes whose weight is exactly zero for every
/// hit (from constant inputs) are pruned when the material is built, so no hit evaluates
/// them. The pruned model is the same function up to float round-off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreviewLobes {
    /// No clearcoat, no metal and a plastic coat that reflects nothing (the metallic
    /// workflow with `ior` 1, where the dielectric Fresnel is 0, its albedo 0 and the
    /// diffuse term ρ/π exactly): Lambertian reflection of `diffuseColor`.
    Lambert,
    /// No clearcoat (`clearcoat` 0) and no metal (`metallic` 0, or the specular workflow):
    /// the plastic alone (its coat and diffuse base).
    Plastic,
    /// Clearcoat, metal and plastic as inputs and textures may weigh them.
    Full,
}

/// The textured inputs of a UsdPreviewSurface; `None` where the input is a constant. After
/// setting them, [`PreviewMaterial::prepare_textures`] precomputes the coat albedos they need.
#[derive(Clone, Debug, Default)]
pub struct PreviewTextures {
    pub diffuse: Option<TextureInput>,
    pub specular: Option<TextureInput>,
    pub metallic: Option<TextureInput>,
    pub roughness: Option<TextureInput>,
    pub clearcoat: Option<TextureInput>,
    pub clearcoat_roughness: Option<TextureInput>,
    pub opacity: Option<TextureInput>,
    /// A tangent-space normal map (`normal`, usually raw with scale 2 and bias −1).
    pub normal: Option<TextureInput>,
    /// The base coat's albedos when `roughness` or `specularColor` is textured.
    pub base_coats: Option<Arc<BaseCoats>>,
    /// The clearcoat's albedos when `clearcoatRoughness` is textured.
    pub clearcoat_coats: Option<Arc<CoatLevels>>,
    /// `opacityThreshold`, applied to a textured opacity per lookup.
    pub opacity_threshold: f32,
}

/// The plastic base coat's E(μ) and T̄ for textured inputs (`coat_levels`).
#[derive(Debug)]
pub enum BaseCoats {
    /// One Fresnel (dielectric `ior`, or the constant `specularColor`'s bound), at every
    /// roughness level.
    Fixed(CoatLevels),
    /// A textured `specularColor`: Schlick at F0 = 0 and 1, at every roughness level or at
    /// the constant roughness.
    Schlick(SchlickLevels),
}

impl BaseCoats {
    /// E and T̄ at perceptual roughness `r`, for the Schlick bound `f0` (textured specular).
    #[inline]
    fn get(&self, r: f32, f0: f32) -> (CoatAlbedo, f32) {
        match self {
            BaseCoats::Fixed(l) => l.get(l.level(r)),
            BaseCoats::Schlick(s) => s.get(s.f0_zero.level(r), f0),
        }
    }
}

impl PreviewTextures {
    /// True when a texture feeds the BSDF (the opacity and the normal map do not).
    fn read_by_bsdf(&self) -> bool {
        [
            &self.diffuse,
            &self.specular,
            &self.metallic,
            &self.roughness,
            &self.clearcoat,
            &self.clearcoat_roughness,
        ]
        .iter()
        .any(|t| t.is_some())
    }

    /// True when no input is textured.
    pub fn is_empty(&self) -> bool {
        !self.read_by_bsdf() && self.opacity.is_none() && self.normal.is_none()
    }
}

impl PreviewMaterial {
    /// Precomputes the material; `diffuse` and `specular` are the uplifted colours.
    pub fn new(d: &PreviewSurfaceDesc, diffuse: Spectrum, specular: Spectrum) -> PreviewMaterial {
        let roughness = d.roughness.clamp(0.0, 1.0);
        let distrib = TrowbridgeReitz::isotropic(roughness * roughness);
        let specular = d.use_specular_workflow.then_some(specular);
        let base_albedo = CoatAlbedo::new(distrib, albedo_fresnel(specular.as_ref(), d.ior));
        let fdr = match &specular {
            Some(_) => 0.0,
            None => diffuse_fresnel(1.0 / d.ior),
        };
        let clearcoat_distrib =
            TrowbridgeReitz::isotropic(d.clearcoat_roughness.clamp(0.0, 1.0).powi(2));
        let clearcoat_albedo = CoatAlbedo::new(
            clearcoat_distrib,
            ScalarFresnel::Dielectric { eta: CLEARCOAT_IOR },
        );
        let mut m = PreviewMaterial {
            diffuse,
            metallic: if specular.is_some() {
                0.0
            } else {
                d.metallic.clamp(0.0, 1.0)
            },
            specular,
            ior: d.ior,
            roughness,
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
            lobes: PreviewLobes::Full,
            bsdf_textured: false,
        };
        m.lobes = m.lobes_with_weight();
        m
    }

    /// The [`PreviewLobes`] of the inputs: a lobe is pruned only when its weight is exactly
    /// zero at every hit (a constant 0, untextured). `specularColor` 0 in
    /// the specular workflow does not prune the coat: the specification's edge colour is
    /// white (F90 = 1), so Schlick's F = (1 − cos θ)⁵ still reflects at grazing angles.
    fn lobes_with_weight(&self) -> PreviewLobes {
        let t = &self.textures;
        let no_clearcoat = self.clearcoat == 0.0 && t.clearcoat.is_none();
        let no_metal = self.specular.is_some() || (self.metallic == 0.0 && t.metallic.is_none());
        let dark_coat = self.specular.is_none() && self.ior == 1.0;
        match (no_clearcoat && no_metal, dark_coat) {
            (true, true) => PreviewLobes::Lambert,
            (true, false) => PreviewLobes::Plastic,
            (false, _) => PreviewLobes::Full,
        }
    }

    /// Precomputes the coat albedos the textured inputs need (`coat_levels`): a textured
    /// `roughness` takes the base coat's E and T̄ from the nearest of 33 levels, a textured
    /// `specularColor` interpolates them exactly in F0, a textured `clearcoatRoughness` takes
    /// the clearcoat's E from the nearest level. The GGX α is exact per lookup.
    pub fn prepare_textures(&mut self) {
        let t = &mut self.textures;
        let rough = t.roughness.is_some();
        let base = match (&self.specular, &t.specular) {
            (Some(_), Some(_)) => Some(BaseCoats::Schlick(SchlickLevels::new(
                rough,
                self.roughness,
            ))),
            (specular, _) if rough => Some(BaseCoats::Fixed(CoatLevels::levels(albedo_fresnel(
                specular.as_ref(),
                self.ior,
            )))),
            _ => None,
        };
        t.base_coats = base.map(Arc::new);
        t.clearcoat_coats = t.clearcoat_roughness.as_ref().map(|_| {
            Arc::new(CoatLevels::levels(ScalarFresnel::Dielectric {
                eta: CLEARCOAT_IOR,
            }))
        });
        self.lobes = self.lobes_with_weight();
        self.bsdf_textured = self.textures.read_by_bsdf();
    }

    /// The base GGX distribution, its coat albedo and average transmittance at `tc`;
    /// `f0` is the Schlick bound of a textured `specularColor` there.
    #[inline]
    fn base_coat(&self, tc: TexCoord, f0: f32) -> (TrowbridgeReitz, CoatAlbedo, f32) {
        let Some(coats) = &self.textures.base_coats else {
            return (self.distrib, self.base_albedo, self.base_t_avg);
        };
        let (r, distrib) = match &self.textures.roughness {
            Some(t) => {
                let r = Self::scalar(Some(t), 0.0, tc);
                (r, TrowbridgeReitz::isotropic(r * r))
            }
            None => (self.roughness, self.distrib),
        };
        let (albedo, t_avg) = coats.get(r, f0);
        (distrib, albedo, t_avg)
    }

    /// The clearcoat's GGX distribution and albedo at `tc`.
    #[inline]
    fn clearcoat_coat(&self, tc: TexCoord) -> (TrowbridgeReitz, CoatAlbedo) {
        match (
            &self.textures.clearcoat_roughness,
            &self.textures.clearcoat_coats,
        ) {
            (Some(t), Some(levels)) => {
                let r = Self::scalar(Some(t), 0.0, tc);
                let (albedo, _) = levels.get(levels.level(r));
                (TrowbridgeReitz::isotropic(r * r), albedo)
            }
            _ => (self.clearcoat_distrib, self.clearcoat_albedo),
        }
    }

    /// The plastic coat's Fresnel at `tc` and, for a textured `specularColor`, the
    /// scalar bound of its F0 (the albedo's; 0 otherwise).
    #[inline]
    fn base_fresnel(
        &self,
        tc: TexCoord,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> (CoatFresnel, f32) {
        if self.specular.is_none() {
            return (CoatFresnel::Dielectric { eta: self.ior }, 0.0);
        }
        match &self.textures.specular {
            Some(t) => {
                let sigmoid = reflectance_lookup(t.rgb(tc));
                let f0 = SampledSpectrum::from_fn(|i| sigmoid.eval(lambda.lambda[i]));
                let f0 = f0.map(|v| v.clamp(0.0, 1.0));
                let bound = sigmoid.max_value().clamp(0.0, 1.0);
                (CoatFresnel::Schlick { f0 }, bound)
            }
            None => (CoatFresnel::Schlick { f0: c.s1 }, 0.0),
        }
    }

    /// The probability that the surface is present at st = `uv`.
    #[inline]
    pub fn opacity(&self, uv: Vec2) -> f32 {
        match &self.textures.opacity {
            Some(t) => presence(t.float(uv.into()), self.textures.opacity_threshold),
            None => self.opacity,
        }
    }

    /// True when the surface is present everywhere.
    pub fn is_opaque(&self) -> bool {
        self.textures.opacity.is_none() && self.opacity >= 1.0
    }

    /// The diffuse reflectance at `tc`, clamped to [0, 1] (`c.s0` when constant).
    #[inline]
    fn rho(
        &self,
        tc: TexCoord,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> SampledSpectrum {
        match &self.textures.diffuse {
            Some(t) => {
                let sigmoid = reflectance_lookup(t.rgb(tc));
                SampledSpectrum::from_fn(|i| sigmoid.eval(lambda.lambda[i]))
                    .map(|v| v.clamp(0.0, 1.0))
            }
            None => c.s0,
        }
    }

    /// The spectra of [`crate::material::Material::constant_spectra`]: `diffuseColor` and
    /// `specularColor` where constant, clamped to [0, 1], and the plastic base when ρ and the
    /// base coat are constant.
    #[inline]
    pub fn constant_spectra(&self, lambda: &SampledWavelengths) -> MaterialSpectra {
        let clamped = |s: &Spectrum| s.sample(lambda).map(|v| v.clamp(0.0, 1.0));
        let s0 = match &self.textures.diffuse {
            Some(_) => SampledSpectrum::ZERO,
            None => clamped(&self.diffuse),
        };
        let s1 = match (&self.specular, &self.textures.specular) {
            (Some(s), None) => clamped(s),
            _ => SampledSpectrum::ZERO,
        };
        let base = if self.has_constant_base() && self.lobes != PreviewLobes::Lambert {
            PlasticBase::new(s0, self.base_fdr_internal, self.base_t_avg)
        } else {
            PlasticBase::default()
        };
        MaterialSpectra { s0, s1, base }
    }

    /// True when the plastic base depends on no texture: a constant `diffuseColor` and a
    /// base coat of one roughness and Fresnel (no [`PreviewTextures::base_coats`]).
    #[inline]
    fn has_constant_base(&self) -> bool {
        self.textures.diffuse.is_none() && self.textures.base_coats.is_none()
    }

    /// A scalar input: the texture's float output at `tc` or the constant, clamped to [0, 1].
    #[inline]
    fn scalar(t: Option<&TextureInput>, constant: f32, tc: TexCoord) -> f32 {
        match t {
            Some(t) => {
                let v = t.float(tc);
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            }
            None => constant,
        }
    }

    /// The BSDF at a hit with texture coordinates `tc` and shading normal `ns`: the model of
    /// [`PreviewMaterial::lobes`].
    #[inline]
    pub fn bsdf(&self, tc: TexCoord, ns: Vec3, lambda: &SampledWavelengths) -> Bsdf {
        self.bsdf_with(tc, ns, lambda, &self.constant_spectra(lambda))
    }

    /// [`Self::bsdf`] given [`Self::constant_spectra`] at `lambda`.
    #[inline]
    pub fn bsdf_with(
        &self,
        tc: TexCoord,
        ns: Vec3,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> Bsdf {
        let rho = self.rho(tc, lambda, c);
        // Each arm builds its Bsdf in place: one match over a Bxdf then `Bsdf::new` copied
        // the plastic's 116 bytes twice more (design.md §8, session 34).
        match self.lobes {
            PreviewLobes::Lambert => Bsdf::new(Bxdf::Diffuse(DiffuseBxdf { r: rho }), ns),
            PreviewLobes::Plastic => Bsdf::new(Bxdf::Plastic(self.plastic(tc, rho, lambda, c)), ns),
            PreviewLobes::Full => Bsdf::new(Bxdf::Preview(self.composite(tc, rho, lambda, c)), ns),
        }
    }

    /// The plastic (coat over the diffuse base) at `tc` with diffuse reflectance `rho`.
    #[inline]
    fn plastic(
        &self,
        tc: TexCoord,
        rho: SampledSpectrum,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> PlasticBxdf {
        let (fresnel, f0_bound) = self.base_fresnel(tc, lambda, c);
        let (distrib, albedo, t_avg) = self.base_coat(tc, f0_bound);
        let base = if self.has_constant_base() {
            c.base
        } else {
            PlasticBase::new(rho, self.base_fdr_internal, t_avg)
        };
        PlasticBxdf::with_base(SpecularCoat::new(distrib, fresnel), albedo, base)
    }

    /// Every lobe: clearcoat over the metallic blend of metal and plastic.
    #[inline]
    fn composite(
        &self,
        tc: TexCoord,
        rho: SampledSpectrum,
        lambda: &SampledWavelengths,
        c: &MaterialSpectra,
    ) -> PreviewBxdf {
        let metallic = if self.specular.is_some() {
            0.0
        } else {
            Self::scalar(self.textures.metallic.as_ref(), self.metallic, tc)
        };
        let clearcoat = Self::scalar(self.textures.clearcoat.as_ref(), self.clearcoat, tc);
        let base = self.plastic(tc, rho, lambda, c);
        let (cc_distrib, cc_albedo) = self.clearcoat_coat(tc);
        PreviewBxdf {
            base,
            metal: SpecularCoat::new(base.coat.distrib, CoatFresnel::Schlick { f0: rho }),
            metallic,
            clearcoat: SpecularCoat::new(
                cc_distrib,
                CoatFresnel::Dielectric { eta: CLEARCOAT_IOR },
            ),
            clearcoat_albedo: cc_albedo,
            clearcoat_weight: clearcoat,
        }
    }

    /// True when an input of the BSDF is textured (not `normal`, `opacity` or
    /// `emissiveColor`, which are looked up at the finest level).
    #[inline]
    pub fn bsdf_is_textured(&self) -> bool {
        self.bsdf_textured
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
            Some(t) => normal_map::texel_normal(t.rgb(uv.into())),
            None => self.normal,
        };
        normal_map::perturb(n_t, ns, ng, dpduv)
    }
}

/// The scalar Fresnel bound the base coat's albedo is computed with.
fn albedo_fresnel(specular: Option<&Spectrum>, ior: f32) -> ScalarFresnel {
    match specular {
        Some(s) => ScalarFresnel::Schlick {
            f0: s.to_dense().max_value().clamp(0.0, 1.0),
        },
        None => ScalarFresnel::Dielectric { eta: ior },
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
    use crate::bxdf::TransportMode;
    use crate::desc::{TextureChannel, Wrap};
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
            transform: None,
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
        textured.textures.roughness = Some(constant_texture(scalars, TextureChannel::B));
        textured.prepare_textures();
        assert!(textured.bsdf_is_textured() && !plain.bsdf_is_textured());
        assert_same_f(&plain, &textured, Vec2::new(0.3, 0.7), 1e-6);
    }

    /// f of two materials at st = `uv` agree within `tol` (relative) for a few directions.
    fn assert_same_f(a: &PreviewMaterial, b: &PreviewMaterial, uv: Vec2, tol: f32) {
        let lambda = SampledWavelengths {
            lambda: [450.0, 520.0, 600.0, 680.0],
            pdf: [1.0; 4],
        };
        let (a, b) = (
            a.bsdf(uv.into(), Vec3::Z, &lambda),
            b.bsdf(uv.into(), Vec3::Z, &lambda),
        );
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        for wi in [
            Vec3::new(-0.2, 0.4, 0.8),
            Vec3::new(0.5, -0.5, 0.3),
            Vec3::new(-0.3, -0.1, 0.9),
            Vec3::Z,
        ] {
            let wi = wi.normalize();
            let (fa, fb) = (
                a.f(wo, wi, TransportMode::Radiance),
                b.f(wo, wi, TransportMode::Radiance),
            );
            for i in 0..4 {
                assert!(
                    (fa.0[i] - fb.0[i]).abs() <= tol * fa.0[i].max(1.0),
                    "{fa:?} {fb:?}"
                );
            }
        }
    }

    /// A 2×1 texture (left texel `l`, right `r`) read through `channel`.
    fn two_texels(l: [f32; 4], r: [f32; 4], channel: TextureChannel) -> TextureInput {
        TextureInput {
            image: Arc::new(ImageTexture::from_texels(2, 1, vec![l, r]).unwrap()),
            ..constant_texture([0.0; 4], channel)
        }
    }

    /// Textured `specularColor` (specular workflow) and `clearcoatRoughness` give, at each
    /// texel, the BSDF of the material with those constants: the base albedo is exactly
    /// linear in F0, the clearcoat roughnesses 0.25 and 0.75 lie on the level grid.
    #[test]
    fn textured_specular_and_clearcoat_roughness_match_constants_per_texel() {
        let specs = [[0.3, 0.2, 0.1], [0.05, 0.4, 0.9]];
        let cc_rough = [0.25, 0.75];
        let base = PreviewSurfaceDesc {
            diffuse_color: [0.4, 0.5, 0.6],
            use_specular_workflow: true,
            roughness: 0.37,
            clearcoat: 0.8,
            ..PreviewSurfaceDesc::default()
        };
        let diffuse = Spectrum::Sigmoid(uplift::reflectance_lookup(base.diffuse_color));
        let mut textured = PreviewMaterial::new(&base, diffuse.clone(), Spectrum::Constant(0.5));
        let [a, b] = specs;
        textured.textures.specular = Some(two_texels(
            [a[0], a[1], a[2], 1.0],
            [b[0], b[1], b[2], 1.0],
            TextureChannel::Rgb,
        ));
        textured.textures.clearcoat_roughness = Some(two_texels(
            [cc_rough[0]; 4],
            [cc_rough[1]; 4],
            TextureChannel::R,
        ));
        textured.prepare_textures();
        for (k, u) in [0.25f32, 0.75].into_iter().enumerate() {
            let d = PreviewSurfaceDesc {
                clearcoat_roughness: cc_rough[k],
                ..base.clone()
            };
            let spec = Spectrum::Sigmoid(uplift::reflectance_lookup(specs[k]));
            let plain = PreviewMaterial::new(&d, diffuse.clone(), spec);
            assert_same_f(&plain, &textured, Vec2::new(u, 0.5), 1e-4);
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
