//! Spectral bidirectional path tracing (Veach & Guibas 1995; Veach 1997 ch. 10; Lafortune &
//! Willems 1993) with all (s, t) techniques combined by multiple importance sampling, the
//! weights computed by SmallVCM's recurrences (`bidir::mis`, Georgiev 2012):
//! s = 0 (the camera path finds an emitter), t = 1 (light vertices splat to the camera),
//! s = 1 (next-event estimation) and s, t ≥ 2 (connections). BDPT is VCM without merging.
//!
//! One light subpath per camera sample, both with the camera sample's wavelengths; the light
//! subpath is traced first, stored in the per-thread workspace, splatted (t = 1), then the
//! camera subpath is traced and each of its vertices connected to the light and to every
//! stored light vertex within the depth limit. The sensor is whatever the context names: the
//! camera, or a light meter ([`BdptEstimator`]'s `meter_sample`: a sensor subpath from the
//! meter, cosine-distributed for irradiance, the viewing ray for luminance), through the same
//! loop.

use super::bidir::connect::{connect, emitter_hit, escaped, next_event};
use super::bidir::vertex::bsdf_at;
use super::bidir::{
    splat_light_subpath, trace_light_subpath, BidirContext, Mis, MisHeuristic, PathVertex, Walk,
    Workspace,
};
use super::{Estimator, Settings};
use crate::bxdf::TransportMode;
use crate::light::LightHit;
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene};
use crate::sensor::meter::MeterSensor;
use crate::sensor::Sensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

/// The integrator itself: its depth limit and MIS are the context's ([`BidirContext`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct BdptIntegrator;

impl BdptIntegrator {
    /// One BDPT sample for the sensor of `ctx`: the camera ray through raster point `film`
    /// with lens sample `u_sensor`, or a meter's ray from `u_sensor` (`film` unused);
    /// contributions go to `ws.record` (cleared by the caller).
    pub fn sample(
        &self,
        ctx: &BidirContext,
        film: [f32; 2],
        u_sensor: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        trace_light_subpath(ctx, lambda, sampler, &mut ws.light);
        splat_light_subpath(ctx, lambda, sampler, ws, true);
        let Some(sr) = ctx.sensor.generate_ray(film, u_sensor) else {
            return;
        };
        if let Some(walk) = Walk::sensor(ctx, &sr) {
            self.camera_subpath(ctx, walk, lambda, sampler, ws);
        }
    }

    /// The camera walk z_1, z_2, … with s = 0 at emitters and s ≥ 1 at every non-specular
    /// vertex; z_{max_depth+1} only collects emission.
    fn camera_subpath(
        &self,
        ctx: &BidirContext,
        mut walk: Walk,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        loop {
            // s = 0: escaped rays and analytic emitters end the walk.
            let si = match ctx.scene.intersect(&walk.ray, walk.t_max) {
                None => {
                    let c = escaped(ctx, &walk, walk.ray.d, lambda);
                    ws.record.add_camera(0, walk.depth + 2, c);
                    return;
                }
                Some(Hit::Light { light, hit }) => {
                    walk.arrive(&ctx.mis, hit.p, hit.n);
                    if let Some(c) = emitter_hit(ctx, &walk, light, &hit, -walk.ray.d, lambda) {
                        ws.record.add_camera(0, walk.depth + 1, c);
                    }
                    return;
                }
                Some(Hit::Surface(si)) => si,
            };
            walk.arrive(&ctx.mis, si.p, si.ng);
            if let Some(light) = si.light {
                let hit = LightHit {
                    p: si.p,
                    n: si.ng,
                    t: si.t,
                };
                if let Some(c) = emitter_hit(ctx, &walk, light, &hit, -walk.ray.d, lambda) {
                    ws.record.add_camera(0, walk.depth + 1, c);
                }
            }
            if walk.depth > ctx.max_depth {
                return;
            }
            let bsdf = bsdf_at(ctx.scene, &si, ctx.filter, lambda);
            let z = PathVertex::new(&si, -walk.ray.d, bsdf, walk.beta, walk.mis, walk.depth);
            if !bsdf.is_specular() {
                self.connect_vertex(ctx, &z, lambda, sampler, ws);
            }
            if !walk.scatter(&ctx.mis, &z, TransportMode::Radiance, sampler) {
                return;
            }
        }
    }

    /// s = 1 (next-event estimation) and s ≥ 2 (every light vertex within the depth limit).
    fn connect_vertex(
        &self,
        ctx: &BidirContext,
        z: &PathVertex,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        let t = z.depth + 1;
        if let Some(c) = next_event(ctx, z, lambda, sampler) {
            ws.record.add_camera(1, t, c);
        }
        for y in &ws.light.vertices {
            if y.depth + z.depth > ctx.max_depth {
                break;
            }
            if let Some(c) = connect(ctx, y, z) {
                ws.record.add_camera(y.depth + 1, t, c);
            }
        }
    }
}

/// BDPT as an [`Estimator`]: the render's context (camera as sensor) and the integrator.
pub struct BdptEstimator<'a> {
    ctx: BidirContext<'a>,
    bdpt: BdptIntegrator,
}

impl<'a> BdptEstimator<'a> {
    pub fn new(scene: &'a Scene, settings: Settings, mis: MisHeuristic) -> BdptEstimator<'a> {
        let ctx = BidirContext::new(scene, Mis::bdpt(mis), settings.max_depth)
            .with_filter(settings.filter);
        BdptEstimator {
            ctx,
            bdpt: BdptIntegrator,
        }
    }
}

impl Estimator for BdptEstimator<'_> {
    fn image_sample(
        &self,
        film: [f32; 2],
        u_lens: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        self.bdpt
            .sample(&self.ctx, film, u_lens, lambda, sampler, ws);
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
        let u = sampler.get_2d();
        self.bdpt.sample(&ctx, [0.0; 2], u, lambda, sampler, ws);
        ws.record.total()
    }
}
