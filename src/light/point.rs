//! A SphereLight with `treatAsPoint`: a true point light (a delta in position) at the
//! sphere's centre, emitting the sphere's far field. UsdLux defines the hint as "effectively,
//! a zero-radius sphere"; a sphere of luminance L seen from afar has the intensity
//! I(ω) = L(ω) · A⊥(ω), A⊥ its projected area (πr² for a round one), which is what the point
//! emits: the same flux (∫ I dω = π A L) and the same illuminance far away, whatever the
//! authored radius — and with `normalize` (L = intensity / 4πr²) I = intensity / 4,
//! independent of the radius, the limit the hint describes.
//!
//! Sampling (PBR 4ed §12.1, PointLight): next event estimation returns I(ω)/d² with density 1
//! relative to the delta; emission picks the point (density 1) and a uniform direction
//! (1/(4π)). No ray can hit it.

use super::sphere::SphereLight;
use super::{LightLiSample, LightSampleContext};
use crate::math::INV_4PI;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;

#[derive(Clone, Debug)]
pub struct PointLight {
    /// The sphere (or ellipsoid) it stands for; its centre is the point.
    pub sphere: SphereLight,
}

impl PointLight {
    pub fn p(&self) -> Vec3 {
        self.sphere.center
    }

    /// Intensity towards unit `w` (pointing away from the light), W·sr⁻¹·nm⁻¹.
    pub fn intensity(&self, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.sphere.l(w, lambda) * self.sphere.projected_area(w)
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let d = self.p() - ctx.p;
        let dist2 = d.length_squared();
        if dist2 == 0.0 || !dist2.is_finite() {
            return None;
        }
        let wi = d / dist2.sqrt();
        Some(LightLiSample {
            l: self.intensity(-wi, lambda) * (1.0 / dist2),
            wi,
            pdf_w: 1.0,
            p_light: self.p(),
            n_light: -wi,
            delta: true,
            infinite: false,
        })
    }

    /// Density of the emitted direction (uniform over the sphere of directions).
    pub const DIR_PDF: f32 = INV_4PI;

    /// Φv, the sphere's flux.
    pub fn luminous_power(&self) -> f32 {
        self.sphere.luminous_power()
    }
}
