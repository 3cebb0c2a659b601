//! UsdLux RectLight: a one-sided rectangle emitting along its local −Z. Next-event estimation
//! samples the spherical rectangle it subtends uniformly (Ureña et al. 2013) warped by the
//! receiver's cos θ when it is near the receiver, its solid angle passes pbrt-v4's threshold
//! (`solid_angle.rs`) and its edges are orthogonal (a sheared transform makes a
//! parallelogram), else uniformly by area (PBR 4ed §12.5 for area lights; the pdf conversion is
//! eq. 4.9).
//!
//! `inputs:texture:file` multiplies the emission by the texture, looked up at st = the
//! point's coordinates along the rectangle's local +X and +Y edges (UsdLux: "the U axis along
//! +X and V along +Y"). The texel's linear RGB is uplifted per lookup as an unbounded
//! reflectance (scale · sigmoid, pbrt-v4 `RGBUnboundedSpectrum`; Jakob and Hanika 2019), so a
//! grey texel v multiplies the spectrum by exactly v. As for textured mesh lights
//! (`triangle.rs`), the sampling ignores the texture: the radiance is looked up at the sampled
//! point; the light sampler and the report use the texture's mean luminance.

use super::shaping::{self, Shaping};
use super::solid_angle::{self, floor_weights};
use super::{area_to_solid_angle, sample_by_area, LightHit, LightLiSample, LightSampleContext};
use crate::sampling::bilinear::bilinear_pdf;
use crate::sampling::spherical_rect::SphericalRect;
use crate::spectral::uplift::reflectance_lookup;
use crate::spectral::{xyz, SampledSpectrum, SampledWavelengths, Spectrum};
use crate::texture::TextureInput;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// The texture of a RectLight and its mean luminance factor.
#[derive(Clone, Debug)]
pub struct RectTexture {
    pub texture: Arc<TextureInput>,
    /// The mean over the rectangle of the texel's luminance (Rec.709 Y of the RGB).
    pub mean: f32,
    /// The largest channel of any texel.
    pub peak: f32,
}

/// Relative luminance Y of a linear Rec.709 RGB (ITU-R BT.709-6, item 3.2).
fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

impl RectTexture {
    /// The texture with its mean and peak from a 64 × 64 grid of lookups.
    pub fn new(texture: Arc<TextureInput>) -> RectTexture {
        const N: usize = 64;
        let (mut sum, mut peak) = (0.0f64, 0.0f32);
        for k in 0..N * N {
            let st = Vec2::new((k % N) as f32 + 0.5, (k / N) as f32 + 0.5) / N as f32;
            let rgb = texture.rgb(st.into()).map(|c| c.max(0.0));
            sum += f64::from(luminance(rgb));
            peak = peak.max(rgb[0].max(rgb[1]).max(rgb[2]));
        }
        RectTexture {
            texture,
            mean: (sum / (N * N) as f64) as f32,
            peak,
        }
    }

    /// The spectral factor at st for the path's wavelengths.
    #[inline]
    fn factor(&self, st: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let rgb = self.texture.rgb(st.into()).map(|c| c.max(0.0));
        let m = rgb[0].max(rgb[1]).max(rgb[2]);
        if m.is_nan() || m <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let scale = 2.0 * m;
        let sigmoid = reflectance_lookup(rgb.map(|c| c / scale));
        SampledSpectrum::from_fn(|i| scale * sigmoid.eval(lambda.lambda[i]))
    }
}

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
    /// `inputs:texture:file`, if any.
    pub texture: Option<RectTexture>,
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
            texture: None,
        }
    }

    /// The light with `inputs:texture:file` `texture`.
    pub fn with_texture(self, texture: Option<RectTexture>) -> RectLight {
        RectLight { texture, ..self }
    }

    /// The unshaped radiance at the point of edge coordinates `st` ∈ [0, 1]².
    #[inline]
    fn radiance_at(&self, st: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let base = self.radiance.sample(lambda);
        match &self.texture {
            Some(t) => base * t.factor(st, lambda),
            None => base,
        }
    }

    /// The edge coordinates (a, b) of the point corner + a·edge_u + b·edge_v nearest `p`.
    fn edge_coords(&self, p: Vec3) -> Vec2 {
        let q = p - self.corner;
        let (uu, uv, vv) = (
            self.edge_u.dot(self.edge_u),
            self.edge_u.dot(self.edge_v),
            self.edge_v.dot(self.edge_v),
        );
        let (qu, qv) = (q.dot(self.edge_u), q.dot(self.edge_v));
        let det = uu * vv - uv * uv;
        Vec2::new((qu * vv - qv * uv) / det, (qv * uu - qu * uv) / det)
    }

    /// The light with ShapingAPI `shaping`.
    pub fn with_shaping(self, shaping: Option<Shaping>) -> RectLight {
        RectLight { shaping, ..self }
    }

    /// The spherical rectangle seen from `ctx` when a near rectangle with the receiver in front
    /// ([`Self::near`]) is to be sampled by solid angle: orthogonal edges (relative |cos| ≤
    /// 10⁻⁴; pbrt-v4's `BilinearPatch::IsRectangle` allows the same 10⁻⁴ of relative difference
    /// between the corners' squared distances from the centre), Ω above the threshold.
    #[inline(never)]
    fn spherical(&self, ctx: &LightSampleContext) -> Option<SphericalRect> {
        let skew = self.edge_u.dot(self.edge_v).abs();
        if skew.is_nan() || skew > 1e-4 * self.edge_u.length() * self.edge_v.length() {
            return None;
        }
        let r = SphericalRect::new(ctx.p, self.corner, self.edge_u, self.edge_v)?;
        (r.area >= solid_angle::RECT_MIN_SOLID_ANGLE).then_some(r)
    }

    /// The receiver's cos θ weights at the primary-sample square's corners, which
    /// `SphericalRect::sample` maps to corner + (0 | edge_u) + (0 | edge_v): the cosines from
    /// the spherical rectangle's local coordinates (`SphericalRect::corner_cosines`).
    fn weights(ctx: &LightSampleContext, r: &SphericalRect) -> Option<[f32; 4]> {
        (ctx.n != Vec3::ZERO).then(|| floor_weights(r.corner_cosines(ctx.n)))
    }

    /// The first, cheap half of [`Self::solid_angle`]: the switch, `solid_angle::is_near` and
    /// a receiver in front (so that receivers behind a near light, a ceiling beside its panel,
    /// do not call out for the rest).
    #[inline]
    fn near(&self, ctx: &LightSampleContext) -> bool {
        let centre = self.corner + 0.5 * (self.edge_u + self.edge_v);
        solid_angle::SOLID_ANGLE_SAMPLING
            && solid_angle::is_near(self.area, centre, ctx.p)
            && self.n.dot(ctx.p - self.corner) > 0.0
    }

    /// The spherical rectangle to sample by solid angle from `ctx`, if any: the cheap test
    /// first ([`Self::near`], so that far receivers' area sampling pays only for it), then
    /// [`Self::spherical`]. Both `sample_li` and `pdf_li` decide by it.
    #[inline]
    fn solid_angle(&self, ctx: &LightSampleContext) -> Option<SphericalRect> {
        self.near(ctx).then(|| self.spherical(ctx)).flatten()
    }

    #[inline]
    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        if self.near(ctx) {
            if let Some(ls) = self.sample_near(ctx, u, lambda) {
                return ls;
            }
        }
        self.sample_area(ctx, u, lambda)
    }

    /// The solid-angle sample when [`Self::solid_angle`] gives a spherical rectangle, None when
    /// the light is to be area sampled: out of line, so that the far receivers' path (area
    /// sampling, inlined into `Light::sample_li`) stays small.
    #[inline(never)]
    fn sample_near(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<Option<LightLiSample>> {
        let r = self.solid_angle(ctx)?;
        Some(self.sample_solid_angle(ctx, &r, u, lambda))
    }

    /// Uniform by area: p_w = d² / (A cos θ_light) (eq. 4.9).
    #[inline]
    pub(crate) fn sample_area(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let p = self.corner + u[0] * self.edge_u + u[1] * self.edge_v;
        sample_by_area(ctx, p, self.n, self.area, false, |w| {
            let radiance = self.radiance_at(Vec2::from(u), lambda);
            shaping::shape(&self.shaping, w, radiance, lambda)
        })
    }

    /// Uniform by solid angle, warped by the bilinear cos θ weights: p_w = p_bilinear(u′)/Ω.
    #[inline]
    fn sample_solid_angle(
        &self,
        ctx: &LightSampleContext,
        r: &SphericalRect,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let (u, warp) = solid_angle::warp(u, Self::weights(ctx, r));
        let p = r.sample(u);
        let wi = (p - ctx.p.as_dvec3()).normalize_or_zero().as_vec3();
        let pdf_w = (f64::from(warp) / r.area) as f32;
        if wi == Vec3::ZERO || self.n.dot(wi) >= 0.0 || !(pdf_w > 0.0 && pdf_w.is_finite()) {
            return None;
        }
        let p = p.as_vec3();
        Some(LightLiSample {
            l: self.l(p, -wi, lambda),
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
        let Some(r) = self.solid_angle(ctx) else {
            return area_to_solid_angle(1.0 / self.area, ctx.p, hit.p, self.n);
        };
        let warp = Self::weights(ctx, &r).map_or(1.0, |w| bilinear_pdf(r.invert(hit.p), w));
        (f64::from(warp) / r.area) as f32
    }

    /// Radiance leaving the point `p` of the rectangle towards `w`.
    pub fn l(&self, p: Vec3, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.n.dot(w) <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let st = match self.texture {
            Some(_) => self.edge_coords(p).clamp(Vec2::ZERO, Vec2::ONE),
            None => Vec2::ZERO,
        };
        shaping::shape(&self.shaping, w, self.radiance_at(st, lambda), lambda)
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
        let Vec2 { x: a, y: b } = self.edge_coords(o + t * d);
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
            return None;
        }
        Some(LightHit {
            p: o + t * d,
            n: self.n,
            t,
        })
    }

    /// The texture's mean luminance factor (1 without a texture).
    pub fn texture_mean(&self) -> f32 {
        self.texture.as_ref().map_or(1.0, |t| t.mean)
    }

    /// Φv = π A Lv, or the shaped integral; Lv with the texture's mean.
    pub fn luminous_power(&self) -> f32 {
        let lv = xyz::luminance(&self.radiance.to_dense()) as f32 * self.texture_mean();
        shaping::luminous_power(&self.shaping, PI * self.area, lv)
    }
}
