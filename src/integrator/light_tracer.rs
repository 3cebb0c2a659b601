//! Light tracing (particle tracing): paths start on the lights and every vertex is connected
//! to the camera, splatting to the pixel it lands in (the t = 1 techniques alone, without MIS;
//! Veach 1997 §10.2; PBR 3ed §16.3.1; SmallVCM `kLightTrace`).
//!
//! The light's own point (s = 1) is connected too, so emitters seen by the camera appear.
//! Infinite lights seen directly are not rendered (no point of theirs can be connected to the
//! lens); everything they light is. Samples are indexed like the path tracer's: one light path
//! per (pixel, sample), with the pixel's sampler stream.
//!
//! The sensor may also be an irradiance meter (`integrator::meter_bidir`), which does see
//! infinite lights directly (`bidir::connect::infinite_to_sensor`); a luminance meter, a delta
//! in position and direction, cannot be estimated by light tracing at all.

use super::bidir::{splat_light_subpath, trace_light_subpath, BidirContext, Workspace};
use crate::sampling::Sampler;
use crate::spectral::SampledWavelengths;

#[derive(Clone, Copy, Debug)]
pub struct LightTracer {
    pub max_depth: u32,
}

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
