//! UsdLux DistantLight: light from a distant disk of angular diameter `angle`, shining along
//! the light's local −Z. With θmax = angle/2 > 0 it is a cone of directions of constant
//! radiance L (sampled uniformly in the cone, PBR 4ed §A.5.4), giving an illuminance of
//! E = L π sin²θmax on a facing plane; with angle 0 it is a delta light of illuminance L
//! (the UsdLux sizeFactor rule, USDLUX.md).

use super::{LightLiSample, LightSampleContext};
use crate::math::Frame;
use crate::sampling::warp::uniform_cone_gap;
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
    /// 1 − cos θmax = 2 sin²(θmax/2), computed from θmax: for the sun's 0.27° the f32
    /// difference 1 − cos θmax would be off by up to 0.3%, and so would the pdf and the
    /// illuminance.
    pub one_minus_cos: f32,
    /// Radiance inside the cone, or irradiance (per unit area) for a delta light.
    pub radiance: Spectrum,
}

impl DistantLight {
    pub fn is_delta(&self) -> bool {
        self.one_minus_cos <= 0.0
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
        let sin2_max = self.one_minus_cos * (2.0 - self.one_minus_cos);
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
        let wi =
            Frame::from_normal(self.to_light).to_world(uniform_cone_gap(u, self.one_minus_cos));
        let pdf_w = self.cone_pdf();
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
        self.cone_pdf()
    }

    /// Uniform pdf over the cone, 1 / (2π (1 − cos θmax)).
    fn cone_pdf(&self) -> f32 {
        1.0 / (2.0 * PI * self.one_minus_cos)
    }

    /// sin²θmax, from the accurate 1 − cos θmax.
    pub fn sin2_theta_max(&self) -> f32 {
        self.one_minus_cos * (2.0 - self.one_minus_cos)
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
            lv * PI * self.sin2_theta_max()
        };
        e * PI * scene_radius * scene_radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sun (0.53°) with normalize: L = E / (π sin²θmax), and light sampling gives back E.
    #[test]
    fn sun_disk_irradiance_is_exact() {
        let theta = (0.5f32 * 0.53).to_radians();
        let e_lux = 1000.0;
        let l = e_lux / (PI * theta.sin().powi(2));
        let sun = DistantLight {
            prim_path: "/Sun".into(),
            to_light: Vec3::Y,
            cos_theta_max: theta.cos(),
            one_minus_cos: 2.0 * (0.5 * theta).sin().powi(2),
            radiance: Spectrum::Constant(l),
        };
        let ctx = LightSampleContext {
            p: Vec3::ZERO,
            n: Vec3::Y,
        };
        let lambda = SampledWavelengths::sample_visible(0.5);
        let n = 32;
        let mut e = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                let ls = sun.sample_li(&ctx, u, &lambda).unwrap();
                e += (ls.l[0] * ls.wi.dot(ctx.n) / ls.pdf_w) as f64;
            }
        }
        e /= (n * n) as f64;
        assert!((e / e_lux as f64 - 1.0).abs() < 1e-4, "{e}");
        assert!((sun.sin2_theta_max() / theta.sin().powi(2) - 1.0).abs() < 1e-5);
    }
}
