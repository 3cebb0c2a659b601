//! Light tracing (particle tracing): paths start on the lights and every vertex is connected
//! to the camera, splatting to the pixel it lands in (the t = 1 techniques alone, without MIS;
//! Veach 1997 §10.2; PBR 3ed §16.3.1; SmallVCM `kLightTrace`).
//!
//! The light's own point (s = 1) is connected too, so emitters seen by the camera appear.
//! Infinite lights seen directly are not rendered (no point of theirs can be connected to the
//! lens); everything they light is. Samples are indexed like the path tracer's: one light path
//! per (pixel, sample), with the pixel's sampler stream.
//!
//! A light subpath stopped by the depth cap is counted, and a fraction q of them continued
//! past it on a stream of their own, each further vertex connected to the sensor, into the
//! sample's cut (`cut.rs`).
//!
//! The sensor may also be an irradiance meter ([`LightEstimator`]'s `meter_sample`: its
//! origin and every vertex connected to the meter point, E = Σ β f |cos θ_y| cos θ / d²,
//! Veach 1997 §10.2 with a point sensor), which does see infinite lights directly
//! (`bidir::connect::infinite_to_sensor`); a luminance meter, a delta in position and
//! direction, cannot be estimated by light tracing at all (`Capabilities::luminance_meters`).

use super::bidir::connect::vertex_to_sensor;
use super::bidir::vertex::cached_bsdf_at;
use super::bidir::{
    splat_light_subpath, trace_light_subpath, BidirContext, CappedSubpath, Mis, PathVertex, Walk,
    Workspace,
};
use super::cut::{continuation, continuation_limit};
use super::{Estimator, MisHeuristic, Settings};
use crate::bxdf::TransportMode;
use crate::material::SpectraCache;
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene, SurfaceHit};
use crate::sensor::meter::MeterSensor;
use crate::sensor::Sensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

/// The integrator itself: its depth limit and MIS are the context's ([`BidirContext`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct LightTracer;

impl LightTracer {
    /// Traces one light path with the wavelengths `lambda` and records its contributions to
    /// the sensor of `ctx` (camera or meter) in `ws.record` (which the caller has cleared).
    pub fn sample(
        &self,
        ctx: &BidirContext,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        trace_light_subpath(ctx, lambda, sampler, &mut ws.light);
        splat_light_subpath(ctx, lambda, sampler, ws, false);
        if let Some(capped) = ws.light.capped {
            ws.record.cut.capped += 1;
            if let Some(mut ext) = continuation(sampler) {
                let spectra = &mut ws.light.spectra;
                let (l, limited) = continue_past_cap(ctx, &capped, lambda, &mut ext, spectra);
                ws.record.cut.add(l, 1.0, limited);
            }
        }
    }
}

/// The light a light subpath stopped by the depth cap at `capped` would have brought to the
/// sensor beyond it: the walk continued on `ext`, each vertex beyond the cap connected to the
/// sensor (`cut.rs`). Relative to `lambda`'s pdfs; true when the continuation reached its own
/// limit. `spectra` holds the materials' spectra at `lambda` (the subpath's).
fn continue_past_cap(
    ctx: &BidirContext,
    capped: &CappedSubpath,
    lambda: &SampledWavelengths,
    ext: &mut Sampler,
    spectra: &mut SpectraCache,
) -> (SampledSpectrum, bool) {
    let mut lambda_ext = *lambda;
    let mut walk = capped.walk;
    let mut sum = SampledSpectrum::ZERO;
    let limit = continuation_limit(ctx.max_depth);
    let connect = !capped.within_cap;
    let mut v = vertex_at(
        ctx,
        &capped.si,
        &walk,
        &mut lambda_ext,
        ext,
        connect,
        &mut sum,
        spectra,
    );
    let limited = loop {
        if walk.depth >= limit {
            break true;
        }
        if !walk.scatter(&ctx.mis, &v, TransportMode::Importance, ext) {
            break false;
        }
        let Some(Hit::Surface(si)) = ctx.scene.intersect(&walk.ray, walk.t_max) else {
            break false;
        };
        walk.arrive(&ctx.mis, si.p, si.ng);
        v = vertex_at(
            ctx,
            &si,
            &walk,
            &mut lambda_ext,
            ext,
            true,
            &mut sum,
            spectra,
        );
    };
    (lambda.rebase(sum, &lambda_ext), limited)
}

/// The light subpath's vertex at `si` (the walk arrived there); with `connect`, its
/// connection to the sensor is added to `sum` unless it is specular.
#[allow(clippy::too_many_arguments)]
fn vertex_at(
    ctx: &BidirContext,
    si: &SurfaceHit,
    walk: &Walk,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    connect: bool,
    sum: &mut SampledSpectrum,
    spectra: &mut SpectraCache,
) -> PathVertex {
    let bsdf = cached_bsdf_at(ctx.scene, si, ctx.filter, lambda, spectra);
    let v = PathVertex::new(si, -walk.ray.d, bsdf, walk.beta, walk.mis, walk.depth);
    if connect && !bsdf.is_specular() {
        if let Some(sc) = vertex_to_sensor(ctx, &v, sampler.get_2d(), false) {
            *sum += sc.c.weighted;
        }
    }
    v
}

/// Light tracing as an [`Estimator`]: the render's context (camera as sensor) and the tracer.
pub struct LightEstimator<'a> {
    ctx: BidirContext<'a>,
    tracer: LightTracer,
}

impl<'a> LightEstimator<'a> {
    pub fn new(scene: &'a Scene, settings: Settings) -> LightEstimator<'a> {
        // Light tracing uses no MIS; the context's heuristic is never asked.
        let ctx = BidirContext::new(scene, Mis::bdpt(MisHeuristic::Power), settings.max_depth)
            .with_filter(settings.filter);
        LightEstimator {
            ctx,
            tracer: LightTracer,
        }
    }
}

impl Estimator for LightEstimator<'_> {
    fn image_sample(
        &self,
        _film: [f32; 2],
        _u_lens: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        self.tracer.sample(&self.ctx, lambda, sampler, ws);
    }

    fn meter_sample(
        &self,
        meter: &MeterSensor,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        let ctx = self.ctx.with_sensor(Sensor::Meter(*meter));
        ws.record.clear();
        self.tracer.sample(&ctx, lambda, sampler, ws);
        ws.record.total(lambda)
    }
}
