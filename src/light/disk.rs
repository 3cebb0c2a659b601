//! UsdLux DiskLight: a one-sided disk emitting along its local −Z, sampled uniformly by area
//! with the concentric map (PBR 4ed §6.2.3 / §A.5.1).

use super::shaping::{self, Shaping};
use super::{area_to_solid_angle, sample_by_area, LightHit, LightLiSample, LightSampleContext};
use crate::math::Frame;
use crate::sampling::warp::concentric_disk;
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct DiskLight {
    pub prim_path: String,
    pub center: Vec3,
    /// Frame whose `n` is the emission direction; `s`, `t` span the disk.
    pub frame: Frame,
    pub radius: f32,
    pub radiance: Spectrum,
    /// UsdLux ShapingAPI, if any.
    pub shaping: Option<Shaping>,
}

impl DiskLight {
    pub fn area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let d = concentric_disk(u) * self.radius;
        let p = self.center + d.x * self.frame.s + d.y * self.frame.t;
        sample_by_area(ctx, p, self.frame.n, self.area(), false, |w| {
            shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, _wi: Vec3, hit: &LightHit) -> f32 {
        area_to_solid_angle(1.0 / self.area(), ctx.p, hit.p, self.frame.n)
    }

    pub fn l(&self, _n: Vec3, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.frame.n.dot(w) <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
    }

    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<LightHit> {
        let denom = self.frame.n.dot(d);
        if denom == 0.0 {
            return None;
        }
        let t = self.frame.n.dot(self.center - o) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p = o + t * d;
        if (p - self.center).length_squared() > self.radius * self.radius {
            return None;
        }
        Some(LightHit {
            p,
            n: self.frame.n,
            t,
        })
    }

    /// Φv = π A Lv, or the shaped integral.
    pub fn luminous_power(&self) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32;
        shaping::luminous_power(&self.shaping, PI * self.area(), lv)
    }
}
