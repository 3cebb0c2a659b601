//! Light tracing (particle tracing): paths start on the lights and every vertex is connected
//! to the camera, splatting to the pixel it lands in (the t = 1 techniques alone, without MIS;
//! Veach 1997 §10.2; PBR 3ed §16.3.1; SmallVCM `kLightTrace`).
//!
//! The light's own point (s = 1) is connected too, so emitters seen by the camera appear.
//! Infinite lights seen directly are not rendered (no point of theirs can be connected to the
//! lens); everything they light is. Samples are indexed like the path tracer's: one light path
//! per (pixel, sample), with the pixel's sampler stream.

use super::bidir::connect::{origin_to_sensor, vertex_to_sensor};
use super::bidir::{trace_light_subpath, BidirContext, Workspace};
use crate::sampling::Sampler;
use crate::spectral::SampledWavelengths;

#[derive(Clone, Copy, Debug)]
pub struct LightTracer {
    pub max_depth: u32,
}

impl LightTracer {
    /// Traces one light path with the wavelengths `lambda` and records its splats in
    /// `ws.record` (which the caller has cleared).
    pub fn sample(
        &self,
        ctx: &BidirContext,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        trace_light_subpath(ctx, lambda, sampler, &mut ws.light);
        if let Some(o) = ws.light.origin {
            let u = sampler.get_2d();
            if let Some(sc) = origin_to_sensor(ctx, &o, lambda, u, false) {
                ws.record.add_splat(sc.bin, 1, sc.c);
            }
        }
        for y in &ws.light.vertices {
            let u = sampler.get_2d();
            if let Some(sc) = vertex_to_sensor(ctx, y, u, false) {
                ws.record.add_splat(sc.bin, y.depth + 1, sc.c);
            }
        }
    }
}
