//! A CylinderLight with `treatAsLine`: a true line light (zero radius, a delta across its
//! axis) along the cylinder's axis, emitting the cylinder's far field. A thin Lambertian side
//! of luminance L seen at angle β from the axis has the projected width 2r sin β per unit
//! length, so the line emits the intensity per unit length dI/dℓ(ω) = L(ω) · 2r sin β: the
//! cylinder's flux π · 2πrℓ · L (∫ 2r sin β dω = 2πr · π) and its illuminance from afar, and
//! with `normalize` (L = intensity / 2πrℓ) dI/dℓ = intensity · sin β / (πℓ), independent of
//! the radius.
//!
//! Next event estimation picks a point x uniformly along the segment (density 1/ℓ per unit
//! length, "relative to the delta" across the axis) and returns dI/dℓ(ω)/d²: the estimator
//! of E = ∫ dI/dℓ cos θ / d² dℓ. Emission picks the point the same way and a uniform
//! direction (1/(4π)). No ray can hit it.

use super::cylinder::CylinderLight;
use super::shaping;
use super::{LightLiSample, LightSampleContext};
use crate::math::INV_4PI;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;

#[derive(Clone, Debug)]
pub struct LineLight {
    /// The cylinder it stands for: its axis is the line.
    pub cylinder: CylinderLight,
}

impl LineLight {
    pub fn length(&self) -> f32 {
        self.cylinder.length
    }

    /// The point at fraction `u` of the segment.
    pub fn point(&self, u: f32) -> Vec3 {
        let c = &self.cylinder;
        c.center + (u - 0.5) * c.length * c.frame.n
    }

    /// Intensity per unit length towards unit `w` (pointing away from the line).
    pub fn intensity(&self, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        let c = &self.cylinder;
        let width = c.projected_area(w) / c.length;
        shaping::shape(&c.shaping, w, c.radiance.sample(lambda), lambda) * width
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let x = self.point(u[0]);
        let d = x - ctx.p;
        let dist2 = d.length_squared();
        if dist2 == 0.0 || !dist2.is_finite() || self.length() <= 0.0 {
            return None;
        }
        let wi = d / dist2.sqrt();
        Some(LightLiSample {
            l: self.intensity(-wi, lambda) * (1.0 / dist2),
            wi,
            pdf_w: 1.0 / self.length(),
            p_light: x,
            n_light: -wi,
            delta: true,
            infinite: false,
        })
    }

    /// Density of the emitted direction (uniform over the sphere of directions).
    pub const DIR_PDF: f32 = INV_4PI;

    /// Φv, the cylinder's flux.
    pub fn luminous_power(&self) -> f32 {
        self.cylinder.luminous_power()
    }
}
