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
use super::bidir::merge::MergeParams;
use super::bidir::vertex::cached_bsdf_at;
use super::bidir::{
    splat_light_subpath, trace_light_subpath, BidirContext, LightVertexStore, Mis, MisHeuristic,
    PathVertex, Walk, Workspace,
};
use super::cut::continuation;
use super::path::PathIntegrator;
use super::{Estimator, Settings};
use crate::bxdf::TransportMode;
use crate::light::LightHit;
use crate::sampling::dimensions::{self, LIGHT};
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene, SurfaceHit};
use crate::sensor::meter::MeterSensor;
use crate::sensor::Sensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

/// The integrator itself: its depth limit and MIS are the context's ([`BidirContext`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct BdptIntegrator;

/// Which techniques a bidirectional sample uses (Georgiev et al. 2012 §5): connections
/// (s ≥ 1, and t = 1 through the sample's light subpath), merges with the iteration's
/// light vertices, or both. BDPT connects; bidirectional photon mapping merges; VCM does both.
#[derive(Clone, Copy, Debug)]
pub struct Techniques<'s> {
    pub connect: bool,
    /// The light subpath for connections is already in the workspace (VCM's stored subpath
    /// of the sample's pixel); false traces the sample's own.
    pub light_given: bool,
    pub merge: Option<(&'s LightVertexStore, MergeParams)>,
}

impl Techniques<'_> {
    pub const BDPT: Techniques<'static> = Techniques {
        connect: true,
        light_given: false,
        merge: None,
    };
}

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
        self.sample_with(&Techniques::BDPT, ctx, film, u_sensor, lambda, sampler, ws);
    }

    /// One sample with the techniques `tech`: with connections, the sample's light subpath
    /// (traced here, or given in `ws.light`) is splatted first (t = 1), then the camera
    /// subpath.
    #[allow(clippy::too_many_arguments)]
    pub fn sample_with(
        &self,
        tech: &Techniques,
        ctx: &BidirContext,
        film: [f32; 2],
        u_sensor: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        if tech.connect {
            if !tech.light_given {
                trace_light_subpath(ctx, lambda, sampler, &mut ws.light);
            }
            splat_light_subpath(ctx, lambda, sampler, ws, true);
        }
        let Some(sr) = ctx.sensor.generate_ray(film, u_sensor) else {
            return;
        };
        if let Some(walk) = Walk::sensor(ctx, &sr) {
            self.camera_subpath(tech, ctx, walk, lambda, sampler, ws);
        }
    }

    /// The camera walk z_1, z_2, … with s = 0 at emitters, and at every non-specular vertex
    /// s ≥ 1 (connections) and merges; z_{max_depth+1} only collects emission. Without
    /// connections (photon mapping) emitters count only at the end of a purely specular camera
    /// path, which no merge can produce (SmallVCM's rule), with weight 1.
    fn camera_subpath(
        &self,
        tech: &Techniques,
        ctx: &BidirContext,
        mut walk: Walk,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        let mut specular_only = true;
        ws.light.spectra.begin(&ctx.scene.materials, lambda);
        loop {
            // s = 0: escaped rays and analytic emitters end the walk.
            let si = match ctx.scene.intersect(&walk.ray, walk.t_max) {
                None => {
                    let c = escaped(ctx, &walk, walk.ray.d, lambda);
                    record_emission(tech, ws, walk.depth + 2, c, specular_only);
                    return;
                }
                Some(Hit::Light { light, hit }) => {
                    walk.arrive(&ctx.mis, hit.p, hit.n);
                    if let Some(c) = emitter_hit(ctx, &walk, light, &hit, -walk.ray.d, lambda) {
                        record_emission(tech, ws, walk.depth + 1, c, specular_only);
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
                    record_emission(tech, ws, walk.depth + 1, c, specular_only);
                }
            }
            if walk.depth > ctx.max_depth {
                continue_past_cap(ctx, &walk, &si, lambda, sampler, ws);
                return;
            }
            let bsdf = cached_bsdf_at(ctx.scene, &si, ctx.filter, lambda, &mut ws.light.spectra);
            let z = walk.vertex(ctx, &si, bsdf);
            if !bsdf.is_specular() {
                specular_only = false;
                if tech.connect {
                    self.connect_vertex(ctx, &z, lambda, sampler, ws);
                }
                if let Some((store, params)) = &tech.merge {
                    let hero = lambda.secondary_terminated();
                    let m = store.merge(ctx.scene, &z, si.tri.mesh, &z.mis, hero, params);
                    ws.record.camera.weighted += m.all;
                    ws.record.camera.unweighted += m.all;
                    ws.record.hero_only += m.hero_only;
                }
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
        // The path tracer's next-event dimensions of this bounce (`sampling::dimensions`).
        sampler.set_dimension(dimensions::bounce(z.depth - 1, LIGHT));
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

/// A camera subpath stopped by the depth cap at `si` (z_{max_depth+1}, its emission counted):
/// counted, and with probability q continued past the cap by the path tracer on a stream of
/// its own, into the sample's cut (`cut.rs`). Every path longer than the cap has such a
/// camera prefix, so this estimates all the light the cap cut (what the path tracer can
/// sample of it).
fn continue_past_cap(
    ctx: &BidirContext,
    walk: &Walk,
    si: &SurfaceHit,
    lambda: &SampledWavelengths,
    sampler: &Sampler,
    ws: &mut Workspace,
) {
    ws.record.cut.capped += 1;
    let Some(mut ext) = continuation(sampler) else {
        return;
    };
    let pt = PathIntegrator {
        max_depth: ctx.max_depth,
        rr_depth: super::roulette::PBRT_RR_DEPTH,
        filter: ctx.filter,
        split: 1,
    };
    let depth = walk.depth - 1;
    let spectra = &mut ws.light.spectra;
    let wo = -walk.ray.d;
    let (l, limited) = pt.continue_from_vertex(ctx.scene, si, wo, depth, lambda, &mut ext, spectra);
    ws.record.cut.add(walk.beta * l, 1.0, limited);
}

/// An emitter found by the camera walk (s = 0, strategy (0, t)): weighted by MIS with
/// connections; without them (photon mapping) only at the end of a purely specular camera
/// path, unweighted.
fn record_emission(
    tech: &Techniques,
    ws: &mut Workspace,
    t: u32,
    c: super::bidir::Contribution,
    specular_only: bool,
) {
    if tech.connect {
        ws.record.add_camera(0, t, c);
    } else if specular_only {
        let whole = super::bidir::Contribution::new(c.unweighted, 1.0);
        ws.record.add_camera(0, t, whole);
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
        ws.record.total(lambda)
    }
}
