//! One emissive triangle of a mesh light (MeshLightAPI or an emissive material), sampled
//! for next-event estimation uniformly by solid angle (the spherical triangle it subtends,
//! Arvo 1995) warped by the receiver's cos θ when it is near the receiver and its solid angle
//! lies within pbrt-v4's thresholds (`solid_angle.rs`), else uniformly by area (PBR 4ed
//! §6.5.4).
//!
//! A textured UsdPreviewSurface `emissiveColor` ([`EmissiveTexture`]) makes the radiance vary
//! over the triangle: it is looked up at the st of the emitting point and uplifted per lookup
//! as an RGB illuminant (D65 × sigmoid, pbrt-v4 `RGBIlluminantSpectrum`), so the colour
//! (1, 1, 1) emits D65 of 1 cd/m², as a constant `emissiveColor` does. The sampling ignores
//! the texture (its pdfs are the untextured triangle's), the radiance is looked up at the
//! sampled point; `radiance` then holds the triangle's mean colour, which weights the light
//! sampler and the `lights` report.

use super::solid_angle::{self, cos_weights};
use super::{
    area_to_solid_angle, emits_towards, sample_by_area, LightHit, LightLiSample, LightSampleContext,
};
use crate::sampling::bilinear::bilinear_pdf;
use crate::sampling::spherical_triangle::SphericalTriangle;
use crate::sampling::warp::uniform_triangle;
use crate::spectral::uplift::RgbIlluminantSpectrum;
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::TextureInput;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// A texture on the emitted radiance: the shared `emissiveColor` texture and the triangle's
/// st at its corners.
#[derive(Clone, Debug)]
pub struct EmissiveTexture {
    pub texture: Arc<TextureInput>,
    pub uv: [Vec2; 3],
}

impl EmissiveTexture {
    /// Spectral radiance at barycentrics `b` for the path's wavelengths.
    #[inline]
    fn radiance(&self, b: [f32; 3], lambda: &SampledWavelengths) -> SampledSpectrum {
        let uv = b[0] * self.uv[0] + b[1] * self.uv[1] + b[2] * self.uv[2];
        let s = RgbIlluminantSpectrum::new_lookup(self.texture.rgb(uv.into()));
        SampledSpectrum::from_fn(|i| s.eval(lambda.lambda[i]))
    }

    /// The mean linear RGB over the triangle, from a 4 × 4 stratified set of points.
    fn mean_rgb(&self) -> [f32; 3] {
        const N: usize = 4;
        let mut sum = [0.0f32; 3];
        for k in 0..N * N {
            let u = [(k % N) as f32 + 0.5, (k / N) as f32 + 0.5].map(|x| x / N as f32);
            let b = uniform_triangle(u);
            let uv = b[0] * self.uv[0] + b[1] * self.uv[1] + b[2] * self.uv[2];
            let rgb = self.texture.rgb(uv.into());
            for c in 0..3 {
                sum[c] += rgb[c].max(0.0) / (N * N) as f32;
            }
        }
        sum
    }
}

#[derive(Clone, Debug)]
pub struct TriangleLight {
    pub prim_path: String,
    pub p: [Vec3; 3],
    /// Unit geometric normal of the front face.
    pub n: Vec3,
    pub area: f32,
    /// Emitted radiance (with a texture: its mean over the triangle).
    pub radiance: Spectrum,
    pub two_sided: bool,
    pub texture: Option<EmissiveTexture>,
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
            texture: None,
        }
    }

    /// This triangle emitting `texture` (an RGB radiance in nits per unit) instead.
    pub fn with_texture(self, texture: EmissiveTexture) -> TriangleLight {
        let mean = RgbIlluminantSpectrum::new(texture.mean_rgb());
        TriangleLight {
            radiance: Spectrum::RgbIlluminant(mean),
            texture: Some(texture),
            ..self
        }
    }

    /// The radiance at barycentrics `b` (all of them for an untextured triangle).
    #[inline]
    fn radiance_at(&self, b: [f32; 3], lambda: &SampledWavelengths) -> SampledSpectrum {
        match &self.texture {
            Some(t) => t.radiance(b, lambda),
            None => self.radiance.sample(lambda),
        }
    }

    /// The barycentrics of a point `p` on the triangle (least squares in its plane).
    fn barycentrics(&self, p: Vec3) -> [f32; 3] {
        let (e1, e2, d) = (self.p[1] - self.p[0], self.p[2] - self.p[0], p - self.p[0]);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d20, d21) = (d.dot(e1), d.dot(e2));
        let denom = d00 * d11 - d01 * d01;
        if denom.is_nan() || denom <= 0.0 {
            return [1.0 / 3.0; 3];
        }
        let b1 = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
        let b2 = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0 - b1);
        [1.0 - b1 - b2, b1, b2]
    }

    /// The spherical triangle seen from `ctx` when a near triangle with the receiver in front
    /// ([`Self::near`]) is to be sampled by solid angle: Ω within the thresholds.
    #[inline(never)]
    fn spherical(&self, ctx: &LightSampleContext) -> Option<SphericalTriangle> {
        let t = SphericalTriangle::new(ctx.p, self.p)?;
        let range = solid_angle::TRIANGLE_MIN_SOLID_ANGLE..=solid_angle::TRIANGLE_MAX_SOLID_ANGLE;
        range.contains(&t.area).then_some(t)
    }

    /// The receiver's cos θ weights at the corners of the primary-sample square of `t`:
    /// (·, 0) → b, (0, 1) → a, (1, 1) → c (`SphericalTriangle::sample`).
    fn weights(ctx: &LightSampleContext, t: &SphericalTriangle) -> Option<[f32; 4]> {
        let [a, b, c] = t.vertices();
        cos_weights(ctx.n, [b, b, a, c])
    }

    /// The first, cheap half of [`Self::solid_angle`]: the switch, `solid_angle::is_near` and
    /// a receiver the triangle emits towards (so that receivers behind a near one-sided light,
    /// a ceiling beside its lamp, do not call out for the rest).
    #[inline]
    fn near(&self, ctx: &LightSampleContext) -> bool {
        let centre = (self.p[0] + self.p[1] + self.p[2]) * (1.0 / 3.0);
        solid_angle::SOLID_ANGLE_SAMPLING
            && solid_angle::is_near(self.area, centre, ctx.p)
            && emits_towards(self.n, ctx.p - self.p[0], self.two_sided)
    }

    /// The spherical triangle to sample by solid angle from `ctx`, if any: the cheap test
    /// first ([`Self::near`], so that far receivers' area sampling pays only for it), then
    /// [`Self::spherical`]. Both `sample_li` and `pdf_li` decide by it.
    #[inline]
    fn solid_angle(&self, ctx: &LightSampleContext) -> Option<SphericalTriangle> {
        self.near(ctx).then(|| self.spherical(ctx)).flatten()
    }

    #[inline]
    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        self.sample_li_given(ctx, u, lambda, None)
    }

    /// The radiance an untextured triangle emits everywhere, at `lambda` (None when textured:
    /// it varies over the triangle).
    #[inline]
    pub fn uniform_radiance(&self, lambda: &SampledWavelengths) -> Option<SampledSpectrum> {
        match self.texture {
            Some(_) => None,
            None => Some(self.radiance.sample(lambda)),
        }
    }

    /// [`Self::sample_li`] with `le`, when given, as the radiance at the sampled point: it must
    /// be [`Self::uniform_radiance`] at `lambda` (a caller that keeps it for the wavelength
    /// tuple spares the evaluation per sample; the same bits).
    #[inline]
    pub fn sample_li_given(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
        le: Option<SampledSpectrum>,
    ) -> Option<LightLiSample> {
        if self.area == 0.0 {
            return None;
        }
        if self.near(ctx) {
            if let Some(ls) = self.sample_near(ctx, u, lambda, le) {
                return ls;
            }
        }
        self.sample_area(ctx, u, lambda, le)
    }

    /// The solid-angle sample when [`Self::solid_angle`] gives a spherical triangle, None when
    /// the light is to be area sampled: out of line, so that the far receivers' path (area
    /// sampling, inlined into `Light::sample_li`) stays small.
    #[inline(never)]
    fn sample_near(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
        le: Option<SampledSpectrum>,
    ) -> Option<Option<LightLiSample>> {
        let t = self.solid_angle(ctx)?;
        Some(self.sample_solid_angle(ctx, &t, u, lambda, le))
    }

    /// Uniform by area: p_w = d² / (A |cos θ_light|) (eq. 4.9); `le` as in
    /// [`Self::sample_li_given`].
    #[inline]
    pub(crate) fn sample_area(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
        le: Option<SampledSpectrum>,
    ) -> Option<LightLiSample> {
        let b = uniform_triangle(u);
        let p = b[0] * self.p[0] + b[1] * self.p[1] + b[2] * self.p[2];
        sample_by_area(ctx, p, self.n, self.area, self.two_sided, |_| {
            le.unwrap_or_else(|| self.radiance_at(b, lambda))
        })
    }

    /// Uniform by solid angle, warped by the bilinear cos θ weights: p_w = p_bilinear(u′)/Ω.
    #[inline]
    fn sample_solid_angle(
        &self,
        ctx: &LightSampleContext,
        t: &SphericalTriangle,
        u: [f32; 2],
        lambda: &SampledWavelengths,
        le: Option<SampledSpectrum>,
    ) -> Option<LightLiSample> {
        let (u, warp) = solid_angle::warp(u, Self::weights(ctx, t));
        let wi = t.sample(u);
        // The point: the ray's hit on the triangle's plane.
        let (o, n) = (ctx.p.as_dvec3(), self.n.as_dvec3());
        let cos = n.dot(wi);
        let dist = n.dot(self.p[0].as_dvec3() - o) / cos;
        let pdf_w = (f64::from(warp) / t.area) as f32;
        if !(dist > 0.0 && dist.is_finite() && pdf_w > 0.0 && pdf_w.is_finite()) {
            return None;
        }
        let (p, wi) = ((o + dist * wi).as_vec3(), wi.as_vec3());
        if !emits_towards(self.n, -wi, self.two_sided) {
            return None;
        }
        Some(LightLiSample {
            l: le.unwrap_or_else(|| self.radiance_from(p, lambda)),
            wi,
            pdf_w,
            p_light: p,
            n_light: self.n,
            delta: false,
            infinite: false,
        })
    }

    pub fn pdf_li(&self, ctx: &LightSampleContext, _wi: Vec3, hit: &LightHit) -> f32 {
        if self.area == 0.0 {
            return 0.0;
        }
        let Some(t) = self.solid_angle(ctx) else {
            return area_to_solid_angle(1.0 / self.area, ctx.p, hit.p, self.n);
        };
        let u = || t.invert((hit.p - ctx.p).normalize_or_zero());
        let warp = Self::weights(ctx, &t).map_or(1.0, |w| bilinear_pdf(u(), w));
        (f64::from(warp) / t.area) as f32
    }

    /// Radiance leaving the point `hit` of the triangle towards `w`.
    pub fn l(&self, hit: &LightHit, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if !emits_towards(self.n, w, self.two_sided) {
            return SampledSpectrum::ZERO;
        }
        self.radiance_from(hit.p, lambda)
    }

    /// The radiance at the point `p` of the triangle (its barycentrics only when textured).
    #[inline]
    fn radiance_from(&self, p: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match &self.texture {
            Some(t) => t.radiance(self.barycentrics(p), lambda),
            None => self.radiance.sample(lambda),
        }
    }

    /// Φv = π A Lv per emitting side (Lambertian emitter, PBR 4ed §4.1.2); with a texture, Lv
    /// of its mean colour.
    pub fn luminous_power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        sides * PI * self.area * xyz::luminance(&self.radiance.to_dense()) as f32
    }
}
