//! UsdLux SphereLight: a sphere emitting outwards. Seen from outside it is sampled uniformly
//! in the cone it subtends (PBR 4ed §6.2.4); from inside, uniformly by area. Under a
//! non-uniform scale or a shear it is the ellipsoid of `ellipsoid.rs`, sampled through the
//! map from the unit sphere (`radius` is then the ellipsoid's bounding radius).
//!
//! The cone is handled through 1 − cos θmax = sin²θmax / (1 + cos θmax), sin²θmax = r²/d²,
//! never as the f32 difference 1 − cos θmax: for a 2 mm sphere seen from 2 m that difference
//! is 5e-7, below the f32 spacing near 1, and the pdf would be off by percents (PBR 4ed
//! §6.2.4 handles small cones with a Taylor expansion for the same reason).

use super::ellipsoid::Ellipsoid;
use super::shaping::{self, Shaping};
use super::{area_to_solid_angle, LightHit, LightLiSample, LightSampleContext};
use crate::math::{safe_sqrt, Frame, INV_2PI};
use crate::sampling::warp::{uniform_cone_gap, uniform_sphere};
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct SphereLight {
    pub prim_path: String,
    pub center: Vec3,
    pub radius: f32,
    pub radiance: Spectrum,
    /// UsdLux ShapingAPI, if any (relative to the light's local −Z axis).
    pub shaping: Option<Shaping>,
    /// The shape under a non-uniform transform (None: the round sphere of `radius`).
    pub ellipsoid: Option<Box<Ellipsoid>>,
}

impl SphereLight {
    pub fn area(&self) -> f32 {
        match &self.ellipsoid {
            Some(e) => e.area,
            None => 4.0 * PI * self.radius * self.radius,
        }
    }

    /// Area projected along unit `w` (πr² for the round sphere).
    pub fn projected_area(&self, w: Vec3) -> f32 {
        match &self.ellipsoid {
            Some(e) => e.projected_area(w),
            None => PI * self.radius * self.radius,
        }
    }

    /// A point by area: (point, outward normal, density per unit area); uniform for the
    /// round sphere, `Ellipsoid::sample_area`'s density for an ellipsoid.
    pub fn sample_area(&self, u: [f32; 2]) -> (Vec3, Vec3, f32) {
        match &self.ellipsoid {
            Some(e) => {
                let (off, n, pdf) = e.sample_area(u);
                (self.center + off, n, pdf)
            }
            None => {
                let n = uniform_sphere(u);
                (self.center + self.radius * n, n, 1.0 / self.area())
            }
        }
    }

    /// Density per unit area of [`SphereLight::sample_area`] at the surface point `p`.
    pub fn pdf_area(&self, p: Vec3) -> f32 {
        match &self.ellipsoid {
            Some(e) => e.pdf_area(p - self.center),
            None => 1.0 / self.area(),
        }
    }

    /// 1 − cos θmax of the cone subtended at `p`, or None when `p` is inside the sphere.
    /// Computed as sin²θmax / (1 + cos θmax) so that it keeps its relative precision for a
    /// small or distant sphere (1 − √(1 − r²/d²) loses it all when r ≪ d).
    fn cone_gap(&self, p: Vec3) -> Option<f32> {
        let dist2 = (p - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if dist2 <= r2 * 1.0001 {
            return None;
        }
        let sin2_max = r2 / dist2;
        Some(sin2_max / (1.0 + safe_sqrt(1.0 - sin2_max)))
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        if let Some(e) = &self.ellipsoid {
            return self.sample_li_ellipsoid(e, ctx, u, lambda);
        }
        let Some(gap) = self.cone_gap(ctx.p) else {
            return self.sample_li_inside(ctx, u, lambda);
        };
        let axis = (self.center - ctx.p).normalize();
        let wi = Frame::from_normal(axis).to_world(uniform_cone_gap(u, gap));
        // The point where wi meets the sphere (nearest root); tangent rays graze it.
        let hit = self
            .intersect(ctx.p, wi, f32::INFINITY)
            .unwrap_or(LightHit {
                p: self.center + self.radius * (ctx.p - self.center).normalize(),
                n: (ctx.p - self.center).normalize(),
                t: (self.center - ctx.p).length(),
            });
        let pdf_w = INV_2PI / gap;
        if !pdf_w.is_finite() {
            return None;
        }
        Some(LightLiSample {
            l: shaping::shape(&self.shaping, -wi, self.radiance.sample(lambda), lambda),
            wi,
            pdf_w,
            p_light: hit.p,
            n_light: hit.n,
            delta: false,
            infinite: false,
        })
    }

    /// An ellipsoid: the cone through the map from outside, by area from inside.
    fn sample_li_ellipsoid(
        &self,
        e: &Ellipsoid,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let o = ctx.p - self.center;
        let Some(s) = e.sample_cone(o, u) else {
            return self.sample_li_inside(ctx, u, lambda);
        };
        // Tangent rays may graze past in f32: such a sample is dropped (measure zero).
        let (_, off, n) = e.intersect(o, s.wi, f32::INFINITY)?;
        Some(LightLiSample {
            l: shaping::shape(&self.shaping, -s.wi, self.radiance.sample(lambda), lambda),
            wi: s.wi,
            pdf_w: s.pdf_w,
            p_light: self.center + off,
            n_light: n,
            delta: false,
            infinite: false,
        })
    }

    fn sample_li_inside(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let (p, n, pdf_a) = self.sample_area(u);
        let wi = (p - ctx.p).normalize_or_zero();
        let pdf_w = area_to_solid_angle(pdf_a, ctx.p, p, n);
        // Seen from inside, every point faces away from the receiver, and `l` emits on both
        // sides, so no facing test here (one would reject every sample).
        if wi == Vec3::ZERO || pdf_w == 0.0 || !pdf_w.is_finite() {
            return None;
        }
        Some(LightLiSample {
            l: shaping::shape(&self.shaping, -wi, self.radiance.sample(lambda), lambda),
            wi,
            pdf_w,
            p_light: p,
            n_light: n,
            delta: false,
            infinite: false,
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, wi: Vec3, hit: &LightHit) -> f32 {
        if let Some(e) = &self.ellipsoid {
            return e.pdf_li(ctx.p - self.center, ctx.p, wi, hit, self.center);
        }
        match self.cone_gap(ctx.p) {
            Some(gap) => INV_2PI / gap,
            None => area_to_solid_angle(1.0 / self.area(), ctx.p, hit.p, hit.n),
        }
    }

    /// Radiance towards `w` (pointing away from the sphere).
    pub fn l(&self, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
    }

    /// Nearest ray–sphere hit with t in (0, t_max), on the side facing the ray origin
    /// (the quadratic in the numerically stable form of PBR 4ed §6.8.4 / Haines et al. 2019).
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<LightHit> {
        if let Some(e) = &self.ellipsoid {
            let (t, off, n) = e.intersect(o - self.center, d, t_max)?;
            return Some(LightHit {
                p: self.center + off,
                n,
                t,
            });
        }
        let f = o - self.center;
        let a = d.length_squared();
        let b_half = f.dot(d);
        // Discriminant as r² − |f − (f·d̂)d̂|² (Haines et al., Ray Tracing Gems ch. 7, eq. 10).
        let perp = f - (b_half / a) * d;
        let disc = a * (self.radius * self.radius - perp.length_squared());
        if disc < 0.0 {
            return None;
        }
        let q = -(b_half + b_half.signum() * disc.sqrt());
        let c = f.length_squared() - self.radius * self.radius;
        let (mut t0, mut t1) = (c / q, q / a);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let t = if t0 > 0.0 { t0 } else { t1 };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p_raw = o + t * d;
        let n = (p_raw - self.center).normalize();
        Some(LightHit {
            p: self.center + self.radius * n,
            n,
            t,
        })
    }

    /// Φv = π A Lv (A = 4πr² for the round sphere), or the shaped integral.
    pub fn luminous_power(&self) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32;
        shaping::luminous_power(&self.shaping, PI * self.area(), lv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E at a point facing a sphere of radiance L: π L sin²α = π L r²/d², estimated with
    /// stratified light samples (the integrand is constant over the cone, so the estimate is
    /// exact up to the pdf's rounding).
    #[test]
    fn small_distant_sphere_gives_the_exact_irradiance() {
        for (r, d) in [(0.002f32, 2.0f32), (0.5, 0.7), (1e-4, 30.0)] {
            let s = SphereLight {
                prim_path: "/S".into(),
                center: Vec3::ZERO,
                radius: r,
                radiance: Spectrum::Constant(1.0),
                shaping: None,
                ellipsoid: None,
            };
            let ctx = LightSampleContext {
                p: Vec3::new(0.0, 0.0, d),
                n: Vec3::NEG_Z,
            };
            let lambda = SampledWavelengths::sample_visible(0.5);
            let n = 64;
            let mut e = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                    let ls = s.sample_li(&ctx, u, &lambda).unwrap();
                    e += (ls.l[0] * ls.wi.dot(ctx.n) / ls.pdf_w) as f64;
                }
            }
            e /= (n * n) as f64;
            let expected = std::f64::consts::PI * (r as f64 / d as f64).powi(2);
            assert!(
                (e / expected - 1.0).abs() < 1e-4,
                "r {r} d {d}: {e} vs {expected}"
            );
        }
    }
}
