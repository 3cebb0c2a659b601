//! Light-meter estimators: one Monte Carlo sample of the irradiance on a virtual surface, or of
//! the radiance along a ray, for the path's wavelengths (not yet divided by their pdfs, like
//! [`PathIntegrator::li`]). `sensor::meter` turns these samples into readings with confidence
//! intervals.
//!
//! **Irradiance** E(p, n) = ∫_{H²(n)} Lᵢ(p, ω) cos θ dω is estimated as Mitsuba 3's
//! `irradiancemeter` sensor and pbrt-v4's path tracer would estimate the light reflected by a
//! white one-sided Lambertian surface at p, times π (E = π·L_o when f = 1/π):
//! - *direct light*, two strategies combined by multiple importance sampling with the power
//!   heuristic (Veach 1997, §9.2, eq. 9.13, β = 2): a light chosen by power and a point on it
//!   (next-event estimation, PBR 4ed §13.3.2's `SampleLd` with `f·cos` replaced by `cos`), and a
//!   cosine-weighted direction (pdf cos θ/π, PBR 4ed §A.5.3), whose emitted radiance is weighted
//!   where the ray meets an emitter;
//! - *indirect light*: the cosine-sampled ray continues as a path of the path tracer
//!   ([`PathIntegrator::li_from`], with the meter point as its first vertex so that the MIS
//!   weights above are applied there). Its estimate L·cos θ / pdf is π·L.
//!
//! The meter is a sensor, not geometry: it sees the scene, the scene does not see it, and it
//! has no BSDF. Depth counts as for a camera: `max_depth` = 0 measures direct light only.
//! Paths that reach the depth cap are counted, and a fraction of them continued past it, in
//! the caller's [`CutSample`] (`cut.rs`).
//!
//! **Radiance** along a ray (Mitsuba's `radiancemeter`) is [`PathIntegrator::li`] of that ray.
//!
//! Ray origins: a meter point carries no error bound of its own (it is typed in, not computed
//! by a ray hit), so it is given the bound `p_error` chosen by the caller (see
//! `sensor::meter::origin_error`) and rays leave it through the same robust offset as surface
//! hits ([`spawn_ray`], PBR 4ed §6.8.6). That makes a meter lying on a floor or a wall safe.

use super::cut::CutSample;
use super::path::{transmittance, PathIntegrator, Previous};
use super::Workspace;
use crate::geometry::offset::{spawn_ray, SpawnPoint};
use crate::light::LightSampleContext;
use crate::math::{Frame, INV_PI};
use crate::sampling::warp::cosine_hemisphere;
use crate::sampling::{power_heuristic, Sampler};
use crate::scene::Scene;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;
use std::f32::consts::PI;

/// The estimators of both meter kinds, sharing the path tracer's settings.
#[derive(Clone, Copy, Debug)]
pub struct MeterIntegrator {
    pub path: PathIntegrator,
}

impl MeterIntegrator {
    /// One sample of the irradiance (W·m⁻²·nm⁻¹ per lane) at `p` on a surface facing the unit
    /// normal `n`; `p_error` bounds the error of `p` per axis. The light beyond the depth cap
    /// goes to `ws.record.cut`; the materials' spectra come from `ws.light.spectra`.
    #[allow(clippy::too_many_arguments)]
    pub fn irradiance(
        &self,
        scene: &Scene,
        p: Vec3,
        p_error: Vec3,
        n: Vec3,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        let ctx = LightSampleContext { p, n };
        let direct = light_sample(scene, &ctx, p_error, lambda, sampler);
        let wi = Frame::from_normal(n).to_world(cosine_hemisphere(sampler.get_2d()));
        let pdf_w = wi.dot(n) * INV_PI;
        if pdf_w <= 0.0 {
            return direct;
        }
        let prev = Previous {
            ctx,
            pdf_bsdf_w: pdf_w,
            specular: false,
        };
        let ray = spawn_ray(p, p_error, n, wi);
        let mut beyond = CutSample::default();
        let li = self.path.li_from(
            scene,
            ray,
            f32::INFINITY,
            Some(prev),
            lambda,
            sampler,
            Some(&mut beyond),
            &mut ws.light.spectra,
        );
        let cut = &mut ws.record.cut;
        // L cos θ / (cos θ / π) = π L.
        cut.light += beyond.light * PI;
        cut.capped += beyond.capped;
        cut.limited += beyond.limited;
        direct + li * PI
    }

    /// One sample of the radiance arriving at `p` from the direction the unit vector `dir`
    /// points to (the ray p + t·dir), as a radiancemeter looking along `dir`.
    #[allow(clippy::too_many_arguments)]
    pub fn radiance(
        &self,
        scene: &Scene,
        p: Vec3,
        p_error: Vec3,
        dir: Vec3,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        let ray = spawn_ray(p, p_error, dir, dir);
        let (cut, spectra) = (&mut ws.record.cut, &mut ws.light.spectra);
        self.path.li_from(
            scene,
            ray,
            f32::INFINITY,
            None,
            lambda,
            sampler,
            Some(cut),
            spectra,
        )
    }
}

/// Next-event estimation at the meter: Lᵢ cos θ / p, MIS-weighted against the cosine-weighted
/// direction (pdf cos θ / π) unless the light is a delta light.
fn light_sample(
    scene: &Scene,
    ctx: &LightSampleContext,
    p_error: Vec3,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
) -> SampledSpectrum {
    let (ul, u) = (sampler.get_1d(), sampler.get_2d());
    let Some((light, pmf)) = scene.light_sampler.sample_at(ctx, ul) else {
        return SampledSpectrum::ZERO;
    };
    let Some(ls) = scene.lights[light].sample_li(ctx, u, lambda) else {
        return SampledSpectrum::ZERO;
    };
    let cos = ls.wi.dot(ctx.n);
    if cos <= 0.0 || ls.l.is_black() || ls.pdf_w == 0.0 {
        return SampledSpectrum::ZERO;
    }
    let from = SpawnPoint::new(ctx.p, p_error, ctx.n);
    let tr = transmittance(scene, &from, &ls, light as u32);
    if tr == 0.0 {
        return SampledSpectrum::ZERO;
    }
    let pdf_light = pmf * ls.pdf_w;
    if ls.delta || !scene.casts_shadows(light as u32) {
        return ls.l * (tr * cos / pdf_light);
    }
    let w = power_heuristic(pdf_light, cos * INV_PI);
    ls.l * (tr * cos * w / pdf_light)
}
