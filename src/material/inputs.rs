//! Inputs of the `spectral:*` materials that are a constant or a `UsdUVTexture` (colour
//! reflectances and roughnesses), evaluated at the hit's st.
//!
//! A textured reflectance is uplifted per lookup like a UsdPreviewSurface colour
//! (`crate::texture`); a textured roughness is read from the texture's float output as the
//! shader's own unit (GGX α, Oren–Nayar σ in radians), clamped to ≥ 0.

use super::coat_levels::CoatLevels;
use crate::bxdf::TrowbridgeReitz;
use crate::spectral::uplift::reflectance_lookup;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::{TexCoord, TextureInput};
use std::sync::Arc;

/// A reflectance: a spectrum, or an RGB texture uplifted per lookup.
#[derive(Clone, Debug)]
pub enum ColorInput {
    Constant(Spectrum),
    Texture(TextureInput),
}

impl ColorInput {
    pub fn is_textured(&self) -> bool {
        matches!(self, ColorInput::Texture(_))
    }

    /// The constant's reflectance at the path's wavelengths, clamped to [0, 1]; zero for a
    /// texture (`material::spectra`).
    #[inline]
    pub fn constant(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            ColorInput::Constant(s) => s.sample(lambda).map(|v| v.clamp(0.0, 1.0)),
            ColorInput::Texture(_) => SampledSpectrum::ZERO,
        }
    }

    /// The reflectance at `tc` for the path's wavelengths, clamped to [0, 1], given the
    /// constant's, [`Self::constant`] at `lambda`.
    #[inline]
    pub fn reflectance_with(
        &self,
        tc: TexCoord,
        lambda: &SampledWavelengths,
        constant: SampledSpectrum,
    ) -> SampledSpectrum {
        match self {
            ColorInput::Constant(_) => constant,
            ColorInput::Texture(t) => {
                let sigmoid = reflectance_lookup(t.rgb(tc));
                SampledSpectrum::from_fn(|i| sigmoid.eval(lambda.lambda[i]))
                    .map(|v| v.clamp(0.0, 1.0))
            }
        }
    }
}

/// A non-negative scalar (a roughness): a constant, or a texture's float output.
#[derive(Clone, Debug)]
pub enum FloatInput {
    Constant(f32),
    Texture(TextureInput),
}

impl FloatInput {
    pub fn is_textured(&self) -> bool {
        matches!(self, FloatInput::Texture(_))
    }

    #[inline]
    pub fn eval(&self, tc: TexCoord) -> f32 {
        match self {
            FloatInput::Constant(v) => *v,
            FloatInput::Texture(t) => non_negative(t.float(tc)),
        }
    }
}

/// A textured GGX α, and for a coated model the coat's albedo at roughness levels.
#[derive(Clone, Debug)]
pub struct AlphaTexture {
    pub texture: TextureInput,
    /// The coat's E(μ) and T̄ at levels of √α (plastic only).
    pub coats: Option<Arc<CoatLevels>>,
}

impl AlphaTexture {
    /// α at `tc`.
    #[inline]
    pub fn alpha(&self, tc: TexCoord) -> f32 {
        non_negative(self.texture.float(tc))
    }

    /// The GGX distribution at `tc`, or `constant` without a texture.
    #[inline]
    pub fn distrib(
        t: Option<&AlphaTexture>,
        constant: TrowbridgeReitz,
        tc: TexCoord,
    ) -> TrowbridgeReitz {
        match t {
            Some(t) => TrowbridgeReitz::isotropic(t.alpha(tc)),
            None => constant,
        }
    }
}

/// `v` if finite and positive, else 0.
#[inline]
fn non_negative(v: f32) -> f32 {
    if v.is_finite() {
        v.max(0.0)
    } else {
        0.0
    }
}
