//! UsdLux RectLight: a one-sided rectangle emitting along its local −Z, sampled uniformly by
//! area (PBR 4ed §12.5 for area lights; the pdf conversion is eq. 4.9).

use super::shaping::{self, Shaping};
use super::{area_to_solid_angle, sample_by_area, LightHit, LightLiSample, LightSampleContext};
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct RectLight {
    pub prim_path: String,
    /// Corner of the rectangle and its two world-space edge vectors.
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Unit emission normal (world-space local −Z).
    pub n: Vec3,
    pub area: f32,
    pub radiance: Spectrum,
    /// UsdLux ShapingAPI, if any.
    pub shaping: Option<Shaping>,
}

impl RectLight {
    pub fn new(
        prim_path: String,
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        n: Vec3,
        radiance: Spectrum,
    ) -> RectLight {
        let area = edge_u.cross(edge_v).length();
        RectLight {
            prim_path,
            corner,
            edge_u,
            edge_v,
            n: n.normalize_or_zero(),
            area,
            radiance,
            shaping: None,
        }
    }

    /// The light with ShapingAPI `shaping`.
    pub fn with_shaping(self, shaping: Option<Shaping>) -> RectLight {
        RectLight { shaping, ..self }
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let p = self.corner + u[0] * self.edge_u + u[1] * self.edge_v;
        sample_by_area(ctx, p, self.n, self.area, false, |w| {
            shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, _wi: Vec3, hit: &LightHit) -> f32 {
        if self.area == 0.0 {
            return 0.0;
        }
        area_to_solid_angle(1.0 / self.area, ctx.p, hit.p, self.n)
    }

    pub fn l(&self, _n: Vec3, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.n.dot(w) <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
    }

    /// Ray–parallelogram test (plane hit, then the two edge coordinates in [0,1]).
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<LightHit> {
        let n = self.edge_u.cross(self.edge_v);
        let denom = n.dot(d);
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(self.corner - o) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let q = o + t * d - self.corner;
        let (uu, uv, vv) = (
            self.edge_u.dot(self.edge_u),
            self.edge_u.dot(self.edge_v),
            self.edge_v.dot(self.edge_v),
        );
        let (qu, qv) = (q.dot(self.edge_u), q.dot(self.edge_v));
        let det = uu * vv - uv * uv;
        let a = (qu * vv - qv * uv) / det;
        let b = (qv * uu - qu * uv) / det;
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
            return None;
        }
        Some(LightHit {
            p: o + t * d,
            n: self.n,
            t,
        })
    }

    /// Φv = π A Lv, or the shaped integral.
    pub fn luminous_power(&self) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32;
        shaping::luminous_power(&self.shaping, PI * self.area, lv)
    }
}
