//! One emissive triangle of a mesh light (MeshLightAPI or an emissive material), sampled
//! uniformly by area (PBR 4ed §6.5.4).

use super::{
    area_to_solid_angle, emits_towards, sample_by_area, LightHit, LightLiSample, LightSampleContext,
};
use crate::sampling::warp::uniform_triangle;
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct TriangleLight {
    pub prim_path: String,
    pub p: [Vec3; 3],
    /// Unit geometric normal of the front face.
    pub n: Vec3,
    pub area: f32,
    /// Emitted radiance.
    pub radiance: Spectrum,
    pub two_sided: bool,
}

impl TriangleLight {
    pub fn new(
        prim_path: String,
        p: [Vec3; 3],
        radiance: Spectrum,
        two_sided: bool,
    ) -> TriangleLight {
        let c = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * c.length();
        let n = c.normalize_or_zero();
        TriangleLight {
            prim_path,
            p,
            n,
            area,
            radiance,
            two_sided,
        }
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        if self.area == 0.0 {
            return None;
        }
        let b = uniform_triangle(u);
        let p = b[0] * self.p[0] + b[1] * self.p[1] + b[2] * self.p[2];
        sample_by_area(ctx, p, self.n, self.area, self.two_sided, |_| {
            self.radiance.sample(lambda)
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, _wi: Vec3, hit: &LightHit) -> f32 {
        if self.area == 0.0 {
            return 0.0;
        }
        area_to_solid_angle(1.0 / self.area, ctx.p, hit.p, self.n)
    }

    pub fn l(&self, _n: Vec3, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if !emits_towards(self.n, w, self.two_sided) {
            return SampledSpectrum::ZERO;
        }
        self.radiance.sample(lambda)
    }

    /// Φv = π A Lv per emitting side (Lambertian emitter, PBR 4ed §4.1.2).
    pub fn luminous_power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        sides * PI * self.area * xyz::luminance(&self.radiance.to_dense()) as f32
    }
}
