//! UsdLux CylinderLight: a tube of `radius` along the light's local X axis, `length` long,
//! centred on the origin, emitting outwards from its side only ("The cylinder does not emit
//! light from the flat end-caps", UsdLux `CylinderLight`). The end caps are opaque and dark,
//! so the light is a closed solid that blocks rays like the other analytic shapes.
//!
//! Sampled uniformly by area on the lateral surface, A = 2π r ℓ (as hdEmbree's
//! `_SampleCylinder`), converted to solid angle with PBR 4ed eq. 4.9. A Lambertian side of
//! luminance L emits Φ = π A L; seen broadside its projected area is 2 r ℓ, so the peak
//! intensity is 2 r ℓ L, and towards a direction at angle β from the axis it is 2 r ℓ L sin β.
//!
//! ```text
//! def CylinderLight "Tube" {
//!     float inputs:radius = 0.0125
//!     float inputs:length = 1.2
//!     float spectral:luminousFlux = 2500
//!     token spectral:emission = "CIE-F11"
//! }
//! ```

use super::shaping::{self, Shaping};
use super::{area_to_solid_angle, sample_by_area, LightHit, LightLiSample, LightSampleContext};
use crate::math::Frame;
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct CylinderLight {
    pub prim_path: String,
    pub center: Vec3,
    /// `n` is the unit axis (world-space local X); `s`, `t` span the cross-section.
    pub frame: Frame,
    pub radius: f32,
    pub length: f32,
    pub radiance: Spectrum,
    pub shaping: Option<Shaping>,
}

impl CylinderLight {
    /// Emitting (lateral) area 2π r ℓ.
    pub fn area(&self) -> f32 {
        2.0 * PI * self.radius * self.length
    }

    /// Projected area of the lateral surface towards unit direction `w`: 2 r ℓ sin β.
    pub fn projected_area(&self, w: Vec3) -> f32 {
        let cos_b = w.dot(self.frame.n).clamp(-1.0, 1.0);
        2.0 * self.radius * self.length * (1.0 - cos_b * cos_b).sqrt()
    }

    /// `true` when `n` is a cap's normal rather than the side's.
    #[inline]
    fn is_cap(&self, n: Vec3) -> bool {
        n.dot(self.frame.n).abs() > 0.5
    }

    /// A uniformly distributed point on the lateral surface and its outward normal.
    pub fn point_on_side(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        let x = (u[0] - 0.5) * self.length;
        let (sin_phi, cos_phi) = (2.0 * PI * u[1]).sin_cos();
        let n = cos_phi * self.frame.s + sin_phi * self.frame.t;
        (self.center + x * self.frame.n + self.radius * n, n)
    }

    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let (p, n) = self.point_on_side(u);
        sample_by_area(ctx, p, n, self.area(), false, |w| {
            shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, _wi: Vec3, hit: &LightHit) -> f32 {
        if self.is_cap(hit.n) || self.area() == 0.0 {
            return 0.0;
        }
        area_to_solid_angle(1.0 / self.area(), ctx.p, hit.p, hit.n)
    }

    pub fn l(&self, n: Vec3, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.is_cap(n) || n.dot(w) <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        shaping::shape(&self.shaping, w, self.radiance.sample(lambda), lambda)
    }

    /// Nearest hit on the side or a cap with t in (0, t_max). The side is the quadric
    /// |f⊥ + t d⊥|² = r² (f = o − centre, ⊥ = the part perpendicular to the axis), solved in
    /// the stable form of the sphere light; the caps are the disks at ±ℓ/2 on the axis.
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<LightHit> {
        let a = self.frame.n;
        let f = o - self.center;
        let (fa, da) = (f.dot(a), d.dot(a));
        let (f_perp, d_perp) = (f - fa * a, d - da * a);
        let half = 0.5 * self.length;
        let r2 = self.radius * self.radius;
        let mut best: Option<LightHit> = None;
        let mut consider = |t: f32, p: Vec3, n: Vec3| {
            if t > 0.0 && t < best.as_ref().map_or(t_max, |b| b.t) {
                best = Some(LightHit { p, n, t });
            }
        };
        let qa = d_perp.length_squared();
        if qa > 0.0 {
            let b_half = f_perp.dot(d_perp);
            let perp = f_perp - (b_half / qa) * d_perp;
            let disc = qa * (r2 - perp.length_squared());
            if disc >= 0.0 {
                let q = -(b_half + b_half.signum() * disc.sqrt());
                let c = f_perp.length_squared() - r2;
                for t in [c / q, q / qa] {
                    let x = fa + t * da;
                    if t.is_finite() && x.abs() <= half {
                        let n = (f_perp + t * d_perp).normalize_or_zero();
                        consider(t, self.center + x * a + self.radius * n, n);
                    }
                }
            }
        }
        if da != 0.0 {
            for side in [-1.0f32, 1.0] {
                let t = (side * half - fa) / da;
                if (f_perp + t * d_perp).length_squared() <= r2 {
                    consider(t, o + t * d, side * a);
                }
            }
        }
        best
    }

    /// Φv = π · 2π r ℓ · Lv, or the shaped integral.
    pub fn luminous_power(&self) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32;
        shaping::luminous_power(&self.shaping, PI * self.area(), lv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tube() -> CylinderLight {
        CylinderLight {
            prim_path: "/Tube".into(),
            center: Vec3::new(1.0, 2.0, 3.0),
            frame: Frame::from_normal(Vec3::X),
            radius: 0.1,
            length: 2.0,
            radiance: Spectrum::Constant(1.0),
            shaping: None,
        }
    }

    #[test]
    fn rays_hit_the_side_and_the_caps() {
        let c = tube();
        let side = c
            .intersect(Vec3::new(1.5, 2.0, 5.0), Vec3::NEG_Z, 10.0)
            .unwrap();
        assert!((side.t - 1.9).abs() < 1e-5 && (side.n - Vec3::Z).length() < 1e-5);
        let cap = c
            .intersect(Vec3::new(5.0, 2.05, 3.0), Vec3::NEG_X, 10.0)
            .unwrap();
        assert!((cap.t - 3.0).abs() < 1e-5 && (cap.n - Vec3::X).length() < 1e-5);
        assert!(c.is_cap(cap.n));
        // Past the end: misses.
        assert!(c
            .intersect(Vec3::new(2.5, 2.0, 5.0), Vec3::NEG_Z, 10.0)
            .is_none());
        // From inside the tube: the far wall, seen from its back.
        let inside = c.intersect(c.center, Vec3::Y, 10.0).unwrap();
        assert!((inside.t - 0.1).abs() < 1e-5);
        let lambda = SampledWavelengths::sample_visible(0.5);
        assert!(c.l(inside.n, -Vec3::Y, &lambda).is_black());
    }

    #[test]
    fn light_sampling_estimates_the_irradiance_of_a_long_tube() {
        // A point at distance D from the axis of an (effectively) infinite Lambertian tube of
        // radiance L, facing the axis: the view factor is r / D (2D strip-to-cylinder, tangent
        // lines at ±asin(r/D)), so E = π L r / D.
        let c = CylinderLight {
            length: 200.0,
            ..tube()
        };
        let p = c.center + Vec3::new(0.0, 0.0, 1.0);
        let ctx = LightSampleContext { p, n: Vec3::NEG_Z };
        let lambda = SampledWavelengths::sample_visible(0.5);
        let (nx, nphi) = (8000, 64);
        let mut e = 0.0f64;
        for i in 0..nx {
            for j in 0..nphi {
                let u = [(i as f32 + 0.5) / nx as f32, (j as f32 + 0.5) / nphi as f32];
                if let Some(s) = c.sample_li(&ctx, u, &lambda) {
                    e += (s.l[0] * s.wi.dot(ctx.n).max(0.0) / s.pdf_w) as f64;
                }
            }
        }
        e /= (nx * nphi) as f64;
        let expected = std::f64::consts::PI * 0.1 / 1.0;
        assert!((e / expected - 1.0).abs() < 2e-3, "{e} vs {expected}");
    }

    #[test]
    fn projected_area_and_power() {
        let c = tube();
        assert!((c.projected_area(Vec3::Y) - 0.4).abs() < 1e-6);
        assert!(c.projected_area(Vec3::X).abs() < 1e-6);
        let lv = xyz::luminance(&c.radiance.to_dense()) as f32;
        assert!((c.luminous_power() / (PI * 2.0 * PI * 0.1 * 2.0 * lv) - 1.0).abs() < 1e-6);
    }
}
