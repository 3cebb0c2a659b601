//! UsdLux DistantLight: light from a distant disk of angular diameter `angle`, shining along
//! the light's local −Z. With θmax = angle/2 > 0 it is a cone of directions of constant
//! radiance L (sampled uniformly in the cone, PBR 4ed §A.5.4), giving an illuminance of
//! E = L π sin²θmax on a facing plane; with angle 0 it is a delta light of illuminance L
//! (the UsdLux sizeFactor rule, USDLUX.md).

use super::{LightLiSample, LightSampleContext};
use crate::math::Frame;
use crate::sampling::warp::{uniform_cone, uniform_cone_pdf};
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct DistantLight {
    pub prim_path: String,
    /// Unit direction *towards* the light (world-space local +Z).
    pub to_light: Vec3,
    /// cos θmax; 1 for a delta light.
    pub cos_theta_max: f32,
    /// Radiance inside the cone, or irradiance (per unit area) for a delta light.
    pub radiance: Spectrum,
}

impl DistantLight {
    pub fn is_delta(&self) -> bool {
        self.cos_theta_max >= 1.0
    }

    /// True when direction `w` lies in the cone. For cones narrower than 60° the test compares
    /// sin² of the angle, |w × axis|², with sin²θmax = (1 − cos θmax)(1 + cos θmax): `w · axis`
    /// against cos θmax would decide a sun-sized cone (1 − cos θmax ≈ 10⁻⁵) at the f32 rounding
    /// of numbers near 1 and blur its edge by about 1 %.
    #[inline]
    fn in_cone(&self, w: Vec3) -> bool {
        let cos = w.dot(self.to_light);
        let c = self.cos_theta_max;
        if c < 0.5 {
            return cos >= c;
        }
        let sin2_max = (1.0 - c) * (1.0 + c);
        cos > 0.0 && w.cross(self.to_light).length_squared() <= sin2_max * w.length_squared()
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let far = 2.0e7;
        if self.is_delta() {
            let wi = self.to_light;
            return Some(LightLiSample {
                l: self.radiance.sample(lambda),
                wi,
                pdf_w: 1.0,
                p_light: ctx.p + far * wi,
                n_light: Vec3::ZERO,
                delta: true,
                infinite: true,
            });
        }
        let wi = Frame::from_normal(self.to_light).to_world(uniform_cone(u, self.cos_theta_max));
        let pdf_w = uniform_cone_pdf(self.cos_theta_max);
        Some(LightLiSample {
            l: self.radiance.sample(lambda),
            wi,
            pdf_w,
            p_light: ctx.p + far * wi,
            n_light: Vec3::ZERO,
            delta: false,
            infinite: true,
        })
    }

    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        if self.is_delta() || !self.in_cone(wi) {
            return 0.0;
        }
        uniform_cone_pdf(self.cos_theta_max)
    }

    pub fn le(&self, d: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.is_delta() || !self.in_cone(d) {
            return SampledSpectrum::ZERO;
        }
        self.radiance.sample(lambda)
    }

    /// Illuminance on a facing plane (lx) times the area of the scene's bounding disk.
    pub fn luminous_power(&self, scene_radius: f32) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32;
        let e = if self.is_delta() {
            lv
        } else {
            lv * PI * (1.0 - self.cos_theta_max * self.cos_theta_max)
        };
        e * PI * scene_radius * scene_radius
    }
}
