//! The closed set of spectrum representations the scene stores. Evaluated per sample into
//! a [`SampledSpectrum`]; never copied on the hot path (materials and lights hold them).

use super::blackbody::planck;
use super::dense::DenseSpectrum;
use super::uplift::{RgbIlluminantSpectrum, Sigmoid};
use super::{SampledSpectrum, SampledWavelengths};
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    Constant(f32),
    /// A bounded reflectance from RGB (Jakob–Hanika sigmoid polynomial).
    Sigmoid(Sigmoid),
    /// An illuminant from RGB: scale · sigmoid(λ) · D65(λ) (pbrt-v4 RGBIlluminantSpectrum).
    RgbIlluminant(RgbIlluminantSpectrum),
    /// Tabulated data times a scale.
    Dense {
        data: Arc<DenseSpectrum>,
        scale: f32,
    },
    /// Planck's law at `kelvin` times a scale (W·m⁻²·sr⁻¹·nm⁻¹ before scaling).
    Blackbody {
        kelvin: f32,
        scale: f32,
    },
}

impl Spectrum {
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        match self {
            Spectrum::Constant(c) => *c,
            Spectrum::Sigmoid(s) => s.eval(lambda),
            Spectrum::RgbIlluminant(s) => s.eval(lambda),
            Spectrum::Dense { data, scale } => data.eval(lambda) * scale,
            Spectrum::Blackbody { kelvin, scale } => planck(lambda, *kelvin) * scale,
        }
    }

    #[inline]
    pub fn sample(&self, w: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum::from_fn(|i| self.eval(w.lambda[i]))
    }

    /// The spectrum on the 1 nm grid (for integrals such as luminance and power).
    pub fn to_dense(&self) -> DenseSpectrum {
        DenseSpectrum::from_fn(|l| self.eval(l))
    }

    /// This spectrum times a constant.
    pub fn scaled(&self, s: f32) -> Spectrum {
        match self {
            Spectrum::Constant(c) => Spectrum::Constant(c * s),
            Spectrum::Dense { data, scale } => Spectrum::Dense {
                data: data.clone(),
                scale: scale * s,
            },
            Spectrum::Blackbody { kelvin, scale } => Spectrum::Blackbody {
                kelvin: *kelvin,
                scale: scale * s,
            },
            Spectrum::RgbIlluminant(r) => Spectrum::RgbIlluminant(r.scaled(s)),
            Spectrum::Sigmoid(_) => Spectrum::Dense {
                data: Arc::new(self.to_dense()),
                scale: s,
            },
        }
    }
}
