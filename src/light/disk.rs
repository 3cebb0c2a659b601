//! UsdLux DiskLight: a one-sided disk emitting along its local −Z, sampled uniformly by area
//! with the concentric map (PBR 4ed §6.2.3 / §A.5.1).
//!
//! Under a non-uniform scale or a shear in its plane the disk is an ellipse: the image
//! c + a·x + b·y of the unit disk x² + y² ≤ 1 under the in-plane semi-axes `axes` = [a, b]
//! (r·s and r·t for a round disk). A linear map has a constant Jacobian |a × b|, so the
//! concentric map's uniform points stay uniform over the ellipse, of area π|a × b|.

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
    /// The largest semi-axis (the radius of a round disk).
    pub radius: f32,
    /// The images a, b of the local unit X and Y semi-axes: points c + x·a + y·b, x² + y² ≤ 1.
    pub axes: [Vec3; 2],
    pub radiance: Spectrum,
    /// UsdLux ShapingAPI, if any.
    pub shaping: Option<Shaping>,
}

impl DiskLight {
    /// A round disk of `radius` in the plane of `frame.s`, `frame.t`.
    pub fn round(
        prim_path: String,
        center: Vec3,
        frame: Frame,
        radius: f32,
        radiance: Spectrum,
    ) -> DiskLight {
        DiskLight {
            prim_path,
            center,
            frame,
            radius,
            axes: [radius * frame.s, radius * frame.t],
            radiance,
            shaping: None,
        }
    }

    pub fn area(&self) -> f32 {
        PI * self.axes[0].cross(self.axes[1]).length()
    }

    /// The point of the ellipse at `q` in the unit disk.
    pub fn point(&self, q: glam::Vec2) -> Vec3 {
        self.center + q.x * self.axes[0] + q.y * self.axes[1]
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let p = self.point(concentric_disk(u));
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
        // The coordinates (x, y) of p − c = x·a + y·b by the dual basis: x = ((p − c) × b)·N/|N|²,
        // y = (a × (p − c))·N/|N|², N = a × b.
        let (q, [a, b]) = (p - self.center, self.axes);
        let n = a.cross(b);
        let (x, y) = (q.cross(b).dot(n), a.cross(q).dot(n));
        let n2 = n.length_squared();
        if x * x + y * y > n2 * n2 {
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
