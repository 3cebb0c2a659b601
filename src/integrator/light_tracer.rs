//! Light tracing (particle tracing): paths start on the lights and every vertex is connected
//! to the camera, splatting to the pixel it lands in (the t = 1 techniques alone, without MIS;
//! Veach 1997 §10.2; PBR 3ed §16.3.1; SmallVCM `kLightTrace`).
//!
//! The light's own point (s = 1) is connected too, so emitters seen by the camera appear.
//! Infinite lights seen directly are not rendered (no point of theirs can be connected to the
//! lens); everything they light is. Samples are indexed like the path tracer's: one light path
//! per (pixel, sample), with the pixel's sampler stream.
//!
//! The sensor may also be an irradiance meter ([`LightEstimator`]'s `meter_sample`: its
//! origin and every vertex connected to the meter point, E = Σ β f |cos θ_y| cos θ / d²,
//! Veach 1997 §10.2 with a point sensor), which does see infinite lights directly
//! (`bidir::connect::infinite_to_sensor`); a luminance meter, a delta in position and
//! direction, cannot be estimated by light tracing at all (`Capabilities::luminance_meters`).

use super::bidir::{splat_light_subpath, trace_light_subpath, BidirContext, Mis, Workspace};
use super::{Estimator, MisHeuristic, Settings};
use crate::sampling::Sampler;
use crate::scene::Scene;
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
    }
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
