//! Random walks for both subpaths: the loop-carried state ([`Walk`], SmallVCM's
//! `SubPathState`), the step from one vertex to the next with its MIS bookkeeping, and the
//! whole light subpath ([`trace_light_subpath`]), stored in a reused per-thread buffer.
//!
//! Depth: a light vertex y_i and a camera vertex z_i have depth i (segments from the light or
//! the camera). A full path of s light and t camera vertices has s + t − 2 scattering events,
//! at most `max_depth` (pbrt's maxdepth, as the path tracer), so light subpaths stop at
//! y_{max_depth} and camera subpaths at z_{max_depth+1}.

use super::merge_rule::near_specular;
use super::mis::{Mis, SubpathMis};
use super::vertex::{cached_bsdf_at, shading_correction, LightOrigin, PathVertex};
use crate::bxdf::{Bsdf, BsdfSample, TransportMode};
use crate::geometry::offset::spawn_ray;
use crate::geometry::Ray;
use crate::light::emit::{LightLeSample, SceneSphere};
use crate::light::{LightHit, LightSampleContext};
use crate::material::SpectraCache;
use crate::sampling::dimensions::{self, BSDF, ROULETTE};
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene, SurfaceHit};
use crate::sensor::{Sensor, SensorRay};
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;
use glam::Vec3;

/// What every bidirectional technique needs to know about the render.
#[derive(Clone, Copy)]
pub struct BidirContext<'a> {
    pub scene: &'a Scene,
    pub sensor: Sensor<'a>,
    pub sphere: SceneSphere,
    pub mis: Mis,
    pub max_depth: u32,
    /// Texture footprints: the camera's for images (`render.rs`), none for meters.
    pub filter: TextureFilter,
    /// An irradiance meter's point also merges light vertices (VCM): its subpath's MIS
    /// start accounts for that technique.
    pub sensor_merges: bool,
    /// Which lights' points the sensor may see (`origin_view.rs`; every bit for a meter).
    pub origins_in_view: u64,
}

impl<'a> BidirContext<'a> {
    /// The camera as sensor, the scene's emission sphere, textures at the finest level.
    pub fn new(scene: &'a Scene, mis: Mis, max_depth: u32) -> BidirContext<'a> {
        BidirContext {
            scene,
            sensor: Sensor::Camera(&scene.camera),
            sphere: scene.emission_sphere(),
            mis,
            max_depth,
            filter: TextureFilter::Finest,
            sensor_merges: false,
            origins_in_view: super::origin_view::lights_in_view(&scene.camera, &scene.lights),
        }
    }

    /// The same render with texture footprints from `filter`.
    pub fn with_filter(&self, filter: TextureFilter) -> BidirContext<'a> {
        BidirContext { filter, ..*self }
    }

    /// The same render with another sensor (a meter).
    pub fn with_sensor(&self, sensor: Sensor<'a>) -> BidirContext<'a> {
        let origins_in_view = match sensor {
            Sensor::Camera(c) => super::origin_view::lights_in_view(c, &self.scene.lights),
            _ => !0,
        };
        BidirContext {
            sensor,
            origins_in_view,
            ..*self
        }
    }
}

/// A light subpath: its origin y_0 and its non-specular scattering vertices y_1, y_2, …
/// (specular ones cannot be connected to and are not stored), with the surface hit of each
/// (what VCM's store keeps to rebuild them, `store.rs`), and where the depth cap stopped it,
/// if it did.
#[derive(Clone, Debug, Default)]
pub struct LightSubpath {
    pub origin: Option<LightOrigin>,
    pub vertices: Vec<PathVertex>,
    pub hits: Vec<SurfaceHit>,
    pub capped: Option<CappedSubpath>,
    /// The materials' constant spectra at the wavelengths of the sample it belongs to
    /// (`material::spectra`): a per-thread cache that outlives [`Self::clear`], which the
    /// sample's camera subpath (through the [`super::Workspace`]) shares.
    pub spectra: SpectraCache,
}

impl LightSubpath {
    pub fn clear(&mut self) {
        self.origin = None;
        self.vertices.clear();
        self.hits.clear();
        self.capped = None;
    }
}

/// Where the depth cap stopped a light subpath: the walk as it arrived at the surface `si`
/// (light tracing continues it past the cap, `cut.rs`).
#[derive(Clone, Copy, Debug)]
pub struct CappedSubpath {
    pub walk: Walk,
    pub si: SurfaceHit,
    /// The vertex at `si` is y_{max_depth}, part of the subpath; false with a cap of 0, where
    /// the first hit already lies beyond it.
    pub within_cap: bool,
}

/// The state carried from one vertex of a subpath to the next.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    pub ray: Ray,
    pub t_max: f32,
    /// Throughput including emission (light) or importance (camera).
    pub beta: SampledSpectrum,
    /// Product of the scattering factors f |cos| / pdf alone: what Russian roulette looks at
    /// (a light subpath's `beta` is in units of power). For radiance (camera subpaths) each
    /// refraction's 1/η'² is undone here, as the path tracer's `eta_scale` does (pbrt-v4
    /// `etaScale`, PBR 4ed §14.1.3): a ray inside glass is not absorbed. Roulette that took
    /// the factor for absorption let a camera path inside a ball of IOR 1.5 survive with
    /// 1/1.5² of the path tracer's probability, about doubling the variance of the caustics
    /// it carries (issue 17).
    pub rr_beta: SampledSpectrum,
    pub mis: SubpathMis,
    /// Depth of the vertex the ray left from.
    pub depth: u32,
    /// Position and geometric normal of the vertex the ray left from.
    pub prev: LightSampleContext,
    /// The ray left an infinite light (no distance factor in the MIS update, §5.1).
    pub from_infinite: bool,
    /// Merging is available at the vertex the walk arrives at next (`merge_rule.rs`): the
    /// vertex it left is near-specular, or every vertex merges. Light walks only.
    pub arrival_merges: bool,
    /// The merge terms of the vertex left, m(|cos| / p_fwd) / m(|cos θ|) since arrival, not
    /// yet in dVC and dVM: a camera walk under the caustic rule adds them once the vertex
    /// found decides (`merge_rule.rs`, [`Walk::vertex`]); 0 otherwise.
    pub pending: f32,
}

impl Walk {
    /// A camera subpath starting with the sensor's own ray `sr`: throughput
    /// W |cos θ| / (p_pos p_dir) (1 for the camera, π for an irradiance meter) and the MIS
    /// start [tech. rep. (31)–(33)] for its direction density, or the delta-direction start of
    /// a luminance meter ([`SubpathMis::delta_sensor_start`]).
    pub fn sensor(ctx: &BidirContext, sr: &SensorRay) -> Option<Walk> {
        let d = sr.ray.d;
        let mut pending = 0.0;
        let mis = if ctx.sensor.delta_direction() {
            SubpathMis::delta_sensor_start()
        } else {
            let pdf_dir_w = ctx.sensor.ray_pdf_dir_w(d);
            if pdf_dir_w.is_nan() || pdf_dir_w <= 0.0 {
                return None;
            }
            match ctx.sensor.infinite_light_meter() {
                Some(m) if ctx.sensor_merges => {
                    let start = SubpathMis::meter_start_with_sensor_merges(
                        &ctx.mis,
                        pdf_dir_w,
                        d.dot(m.dir),
                    );
                    if ctx.mis.caustic() {
                        // Merging at the meter's point: decided by z_1 (`merge_rule.rs`).
                        pending = start.dvm;
                        SubpathMis::camera_start(&ctx.mis, pdf_dir_w)
                    } else {
                        start
                    }
                }
                _ => SubpathMis::camera_start(&ctx.mis, pdf_dir_w),
            }
        };
        let weight = ctx.sensor.ray_weight(d);
        if !(weight > 0.0 && weight.is_finite()) {
            return None;
        }
        Some(Walk {
            ray: sr.ray,
            t_max: sr.t_max,
            beta: SampledSpectrum::splat(weight),
            rr_beta: SampledSpectrum::ONE,
            mis,
            depth: 0,
            prev: LightSampleContext {
                p: sr.p,
                n: Vec3::ZERO,
            },
            from_infinite: false,
            arrival_merges: true,
            pending,
        })
    }

    /// Arrival at point `p` with geometric normal `ng`: the MIS quantities completed for the
    /// new vertex [tech. rep. (31)–(36)] and the depth advanced.
    #[inline]
    pub fn arrive(&mut self, mis: &Mis, p: Vec3, ng: Vec3) {
        let dist2 = (p - self.prev.p).length_squared();
        let cos = ng.dot(self.ray.d);
        let c = self.mis.at_hit(mis, dist2, cos, self.from_infinite);
        if self.pending != 0.0 {
            self.pending /= c;
        }
        self.depth += 1;
    }

    /// The vertex at `si` (BSDF `bsdf`) the walk has just arrived at ([`Walk::arrive`]), with
    /// its merge flags (`merge_rule.rs`): whether merging is available at it (light walks) and
    /// whether it is near-specular. A camera walk's pending merge term of the vertex it left
    /// enters dVC and dVM here when this vertex is near-specular, and is dropped otherwise.
    #[inline]
    pub fn vertex(&mut self, ctx: &BidirContext, si: &SurfaceHit, bsdf: Bsdf) -> PathVertex {
        let near = ctx.mis.caustic() && near_specular(ctx.scene, si, &bsdf);
        if self.pending != 0.0 {
            if near {
                self.mis.add_merge(&ctx.mis, self.pending);
            }
            self.pending = 0.0;
        }
        let mut v = PathVertex::new(si, -self.ray.d, bsdf, self.beta, self.mis, self.depth);
        v.merges = self.arrival_merges;
        v.near_specular = near;
        v
    }

    /// Samples the next direction at vertex `v` and moves on ([`Walk::advance`]), then
    /// Russian roulette. False when the walk ends. A camera walk draws both at the
    /// dimensions of bounce depth − 1 (`sampling::dimensions`, the path tracer's: the camera
    /// ray's first hit z_1 is bounce 0); light walks run detached from the sequence
    /// ([`trace_light_subpath`]), where setting a dimension does nothing.
    pub fn scatter(
        &mut self,
        mis: &Mis,
        v: &PathVertex,
        mode: TransportMode,
        sampler: &mut Sampler,
    ) -> bool {
        let bounce = self.depth.saturating_sub(1);
        sampler.set_dimension(dimensions::bounce(bounce, BSDF));
        let (uc, u) = (sampler.get_1d(), sampler.get_2d());
        let Some(bs) = v.bsdf.sample_f(v.wo, uc, u, mode) else {
            return false;
        };
        self.advance(mis, v, bs, mode);
        sampler.set_dimension(dimensions::bounce(bounce, ROULETTE));
        self.roulette(sampler)
    }

    /// Leaves vertex `v` along the sampled `bs`: throughput f |cos θ| / pdf (with the adjoint
    /// shading correction for importance), MIS [tech. rep. (34)–(36), (53)–(55)], new ray.
    /// The merge terms of `v` (`merge_rule.rs`): a light walk knows their availability
    /// (`v.merges`); a camera walk under the caustic rule leaves them pending.
    pub fn advance(&mut self, mis: &Mis, v: &PathVertex, bs: BsdfSample, mode: TransportMode) {
        let mut factor = v.cos_shading(bs.wi) / bs.pdf_w;
        if mode == TransportMode::Importance {
            factor *= shading_correction(v.ns, v.ng, v.wo, bs.wi);
        }
        let pdf_rev_w = if bs.specular {
            bs.pdf_w
        } else {
            v.reverse_pdf(bs.wi, mode)
        };
        let f = bs.f * factor;
        self.beta *= f;
        self.rr_beta *= f;
        if mode == TransportMode::Radiance && bs.transmission {
            self.rr_beta *= bs.eta * bs.eta;
        }
        let caustic = mis.caustic();
        let camera_defers = caustic && mode == TransportMode::Radiance;
        let merge = if v.merges && !camera_defers { 1.0 } else { 0.0 };
        let g = self.mis.scatter(
            mis,
            v.cos_geo(bs.wi),
            bs.pdf_w,
            pdf_rev_w,
            bs.specular,
            merge,
        );
        if camera_defers {
            self.pending = g;
        }
        self.arrival_merges = !caustic || v.near_specular;
        self.ray = spawn_ray(v.p, v.p_error, v.ng, bs.wi);
        self.t_max = f32::INFINITY;
        self.prev = LightSampleContext { p: v.p, n: v.ng };
        self.from_infinite = false;
    }

    /// Russian roulette after the second bounce when the scattering throughput has dropped
    /// below 1 (PBR 4ed §13.4.1, q = max(0, 1 − max β), the path tracer's rule).
    #[inline]
    fn roulette(&mut self, sampler: &mut Sampler) -> bool {
        let m = self.rr_beta.max_value();
        if m < 1.0 && self.depth > 1 {
            let q = (1.0 - m).max(0.0);
            if sampler.get_1d() < q {
                return false;
            }
            let k = 1.0 / (1.0 - q);
            self.beta *= k;
            self.rr_beta *= k;
        }
        self.beta.is_finite() && !self.beta.is_black()
    }
}

/// pmf · the light-sampling (next-event) density per solid angle at `ctx` of the point `hit` on
/// light `light` seen along `wi`; for a delta light pmf · its density relative to the delta
/// (`Light::delta_pdf`: 1, or 1/ℓ along a line light).
#[inline]
pub fn direct_pdf_w(
    scene: &Scene,
    light: u32,
    ctx: &LightSampleContext,
    wi: Vec3,
    hit: &LightHit,
) -> f32 {
    let pmf = scene.light_sampler.pmf(light as usize);
    let l = &scene.lights[light as usize];
    if l.is_delta() {
        pmf * l.delta_pdf()
    } else {
        pmf * l.pdf_li(ctx, wi, hit)
    }
}

/// Traces a light subpath into `path` (cleared first): a light chosen by power, an emitted
/// ray, then BSDF sampling in importance mode up to y_{max_depth}. Analytic light shapes
/// absorb light paths; escaping paths end. Its numbers come from the sampler's independent
/// stream ([`Sampler::detached`]): their count depends on the subpath's length, so drawing
/// them from the low-discrepancy sequence would shift the camera subpath's dimensions.
pub fn trace_light_subpath(
    ctx: &BidirContext,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    path: &mut LightSubpath,
) {
    sampler.detached(|s| trace_detached(ctx, lambda, s, path));
}

/// [`trace_light_subpath`] on a sampler without a low-discrepancy stream.
fn trace_detached(
    ctx: &BidirContext,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    path: &mut LightSubpath,
) {
    path.clear();
    path.spectra.begin(&ctx.scene.materials, lambda);
    let (u_light, u_pos, u_dir) = (sampler.get_1d(), sampler.get_2d(), sampler.get_2d());
    let Some((index, pmf)) = ctx.scene.light_sampler.sample(u_light) else {
        return;
    };
    let light = &ctx.scene.lights[index];
    let Some(le) = light.sample_le(u_pos, u_dir, &ctx.sphere, lambda) else {
        return;
    };
    let Some(origin) = LightOrigin::new(index as u32, pmf, &le) else {
        return;
    };
    // y_0 is kept even when no radiance leaves along the sampled direction (a shaped light
    // emitting nothing there): its t = 1 and s ≥ 1 connections do not use that direction.
    path.origin = Some(origin);
    let Some(mut walk) = Walk::light(ctx, &origin, &le) else {
        return;
    };
    loop {
        let Some(Hit::Surface(si)) = ctx.scene.intersect(&walk.ray, walk.t_max) else {
            return;
        };
        if walk.depth == 0 {
            let direct = first_hit_direct(ctx, &origin, si.p, si.ng, walk.ray.d);
            walk.mis.light_direct(&ctx.mis, direct);
        }
        walk.arrive(&ctx.mis, si.p, si.ng);
        if walk.depth > ctx.max_depth {
            let within_cap = false;
            path.capped = Some(CappedSubpath {
                walk,
                si,
                within_cap,
            });
            return;
        }
        let bsdf = cached_bsdf_at(ctx.scene, &si, ctx.filter, lambda, &mut path.spectra);
        let v = walk.vertex(ctx, &si, bsdf);
        if !bsdf.is_specular() {
            path.vertices.push(v);
            path.hits.push(si);
        }
        if walk.depth >= ctx.max_depth {
            let within_cap = true;
            path.capped = Some(CappedSubpath {
                walk,
                si,
                within_cap,
            });
            return;
        }
        if !walk.scatter(&ctx.mis, &v, TransportMode::Importance, sampler) {
            return;
        }
    }
}

impl LightOrigin {
    /// The light's point y_0 of an emitted ray `le` from light `index` (chosen with
    /// probability `pmf`); None when the ray's densities are unusable.
    pub fn new(index: u32, pmf: f32, le: &LightLeSample) -> Option<LightOrigin> {
        let emit = pmf * le.pdf_pos_a * le.pdf_dir_w;
        if !emit.is_finite() || emit <= 0.0 {
            return None;
        }
        Some(LightOrigin {
            light: index,
            p: le.p,
            p_error: le.p_error,
            n: le.n,
            pmf,
            pdf_pos_a: le.pdf_pos_a,
            pdf_dir_w: le.pdf_dir_w,
            le: le.l,
            infinite: le.infinite,
            delta_dir: le.delta_dir,
            delta_pos: le.delta_pos,
        })
    }
}

impl Walk {
    /// The walk of a light subpath leaving `origin` along the emitted ray `le`, with
    /// β = L |cos θ| / (pmf p_pos p_dir) (PBR 3ed §16.3.1, GenerateLightSubpath; Veach 1997
    /// §10.2) and the MIS start [tech. rep. (31)–(33), (48)–(50)]; None when the ray carries
    /// no radiance.
    pub fn light(ctx: &BidirContext, origin: &LightOrigin, le: &LightLeSample) -> Option<Walk> {
        if le.l.is_black() {
            return None;
        }
        let emit = origin.pmf * le.pdf_pos_a * le.pdf_dir_w;
        let ray = if le.infinite {
            Ray::new(le.p, le.w)
        } else {
            spawn_ray(le.p, le.p_error, le.n, le.w)
        };
        Some(Walk {
            ray,
            t_max: f32::INFINITY,
            beta: le.l * (le.cos_light() / emit),
            rr_beta: SampledSpectrum::ONE,
            // No camera ray finds a point or line light either: dVC = 0 as for a delta
            // direction (SmallVCM's `IsDelta()` covers both).
            mis: SubpathMis::light_start(
                &ctx.mis,
                emit,
                le.cos_light(),
                le.delta_dir || le.delta_pos,
            ),
            depth: 0,
            prev: LightSampleContext { p: le.p, n: le.n },
            from_infinite: le.infinite,
            // The light source is never near-specular: y_1 does not merge under the caustic
            // rule (`merge_rule.rs`).
            arrival_merges: !ctx.mis.caustic(),
            pending: 0.0,
        })
    }
}

/// The next-event density with which the first light vertex y_1 (at `p`, normal `ng`) would
/// have chosen y_0, in the form [`SubpathMis::light_direct`] takes: per area at y_0,
/// pmf · p_li_w · |cos θ_y0| / d², for finite lights; per solid angle, pmf · p_li_w, for
/// infinite ones (`d` is the direction of travel y_0 → y_1).
pub fn first_hit_direct(ctx: &BidirContext, o: &LightOrigin, p: Vec3, ng: Vec3, d: Vec3) -> f32 {
    let rctx = LightSampleContext { p, n: ng };
    let dist2 = (o.p - p).length_squared();
    let direct = direct_pdf_w(ctx.scene, o.light, &rctx, -d, &o.hit(dist2.sqrt()));
    // A point or line light's density is already relative to its delta at y_0: no conversion
    // (SmallVCM's point light: `directPdfA` = 1).
    if o.infinite || o.delta_pos {
        direct
    } else {
        direct * o.n.dot(d).abs() / dist2
    }
}
