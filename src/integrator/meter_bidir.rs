//! Light meters estimated by light tracing or BDPT: the meter is the sensor of the
//! bidirectional machinery (`bidir::Sensor::Meter`, importance and densities in
//! `sensor::meter::point`), and one meter sample is one sample of the image integrators with
//! that sensor — the same loops, techniques and MIS weights:
//!
//! - **light tracing**: one light subpath, its origin and every vertex connected to the meter
//!   point (t = 1), E = Σ β f |cos θ_y| cos θ / d² (Veach 1997 §10.2 with a point sensor);
//!   infinite lights through their sampled direction (`bidir::connect::infinite_to_sensor`).
//!   A luminance meter is a delta in position and direction, which no t = 1 connection can
//!   reach: `sensor::meter::check_integrator` refuses it.
//! - **BDPT**: that light subpath and one sensor subpath from the meter (cosine-distributed
//!   for irradiance, the viewing ray for luminance), every (s, t) combined by MIS.
//!
//! Both subpaths use the sample's wavelengths; the contributions stay spectral until the
//! sample ends, so a secondary-wavelength termination on either subpath (dispersion) applies
//! to the whole estimate, which is returned relative to the *final* wavelengths (the caller
//! converts it with them). Buffers come from the caller's per-thread [`Workspace`].

use super::bidir::{BidirContext, Mis, MisHeuristic, Sensor, Workspace};
use super::{BdptIntegrator, IntegratorKind, LightTracer};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::sensor::meter::MeterSensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

/// The bidirectional estimators of a meter reading.
#[derive(Clone, Copy)]
pub struct BidirMeter<'a> {
    /// The render's context; its sensor is replaced by the meter per sample.
    ctx: BidirContext<'a>,
    bdpt: bool,
}

impl<'a> BidirMeter<'a> {
    /// Light tracing (`IntegratorKind::Light`) or BDPT (`IntegratorKind::Bdpt`); None for
    /// the path tracer, which `integrator::meter` serves.
    pub fn new(
        scene: &'a Scene,
        kind: IntegratorKind,
        mis: MisHeuristic,
        max_depth: u32,
    ) -> Option<BidirMeter<'a>> {
        let bdpt = match kind {
            IntegratorKind::Path => return None,
            IntegratorKind::Light => false,
            IntegratorKind::Bdpt => true,
        };
        Some(BidirMeter {
            ctx: BidirContext::new(scene, Mis::bdpt(mis), max_depth),
            bdpt,
        })
    }

    /// One sample of `meter`'s quantity (irradiance or radiance per lane), not yet divided by
    /// the wavelength pdfs; `lambda` may have its secondary wavelengths terminated.
    pub fn sample(
        &self,
        meter: &MeterSensor,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        let ctx = self.ctx.with_sensor(Sensor::Meter(*meter));
        let max_depth = ctx.max_depth;
        ws.record.clear();
        if self.bdpt {
            let u = sampler.get_2d();
            BdptIntegrator { max_depth }.sample(&ctx, [0.0; 2], u, lambda, sampler, ws);
        } else {
            LightTracer { max_depth }.sample(&ctx, lambda, sampler, ws);
        }
        ws.record.total()
    }
}
