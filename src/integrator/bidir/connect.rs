//! The techniques of bidirectional path tracing, each returning its unweighted estimate and
//! MIS weight (Veach 1997 §10.2; PBR 3ed §16.3.3 `ConnectBDPT`; weights per [`super::mis`]):
//!
//! | s, t | function | how the path is closed |
//! |---|---|---|
//! | 0, ≥2 | [`emitter_hit`], [`escaped`] | the camera subpath finds an emitter |
//! | 1, 1 | [`origin_to_sensor`] | the light's own point y_0 seen by the sensor |
//! | 1, 1 | [`infinite_to_sensor`] | an infinite light's direction y_0 seen by a meter |
//! | ≥2, 1 | [`vertex_to_sensor`] | a light vertex connected to the sensor (light tracing) |
//! | 1, ≥2 | [`next_event`] | a camera vertex samples a light (NEE) |
//! | ≥2, ≥2 | [`connect`] | a light vertex connected to a camera vertex |
//!
//! Throughputs use shading cosines; area densities use geometric ones.

use super::mis::{ConnectionPdfs, DirectPdfs};
use super::subpath::{direct_pdf_w, BidirContext, Walk};
use super::vertex::{LightOrigin, PathVertex};
use crate::bxdf::TransportMode;
use crate::geometry::offset::{spawn_ray, spawn_ray_to, spawn_ray_to_point};
use crate::light::{Light, LightHit, LightLiSample, LightSampleContext};
use crate::sampling::Sampler;
use crate::sensor::SensorSample;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;

/// One technique's estimate, with and without its MIS weight.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Contribution {
    pub weighted: SampledSpectrum,
    pub unweighted: SampledSpectrum,
}

impl Contribution {
    #[inline]
    pub fn new(value: SampledSpectrum, weight: f32) -> Contribution {
        Contribution {
            weighted: value * weight,
            unweighted: value,
        }
    }
}

impl std::ops::AddAssign for Contribution {
    #[inline]
    fn add_assign(&mut self, o: Contribution) {
        self.weighted += o.weighted;
        self.unweighted += o.unweighted;
    }
}

/// A contribution that lands on a sensor bin other than the camera sample's own pixel.
#[derive(Clone, Copy, Debug)]
pub struct SensorContribution {
    pub bin: u32,
    pub c: Contribution,
}

/// s ≥ 2, t = 1: light vertex `y` connected to a point sampled on the sensor
/// (PBR 4ed §5.4.1 importance; weight [tech. rep. (46)]; `use_mis` false for light tracing).
pub fn vertex_to_sensor(
    ctx: &BidirContext,
    y: &PathVertex,
    u: [f32; 2],
    use_mis: bool,
) -> Option<SensorContribution> {
    let ss = ctx.sensor.sample_wi(y.p, u)?;
    let f = y.f_importance(ss.wi);
    if f.is_black() {
        return None;
    }
    let value = y.beta * f * (y.cos_shading(ss.wi) * ss.we_over_pdf);
    if value.is_black() || sensor_occluded(ctx, y.p, y.p_error, y.ng, &ss, None) {
        return None;
    }
    let weight = if use_mis {
        sensor_weight(ctx, y, ss.p, ss.pdf_dir_w)
    } else {
        1.0
    };
    Some(SensorContribution {
        bin: ss.bin,
        c: Contribution::new(value, weight),
    })
}

/// MIS weight of light vertex `y` connected to sensor point `p_sensor`, whose rays leave
/// towards `y` with direction density `pdf_dir_w` [tech. rep. (46), (47)].
pub fn sensor_weight(ctx: &BidirContext, y: &PathVertex, p_sensor: Vec3, pdf_dir_w: f32) -> f32 {
    let d = p_sensor - y.p;
    let dist2 = d.length_squared();
    let wi = d / dist2.sqrt();
    let cam_a = pdf_dir_w * y.cos_geo(wi) / dist2;
    let land = || y.bsdf.pdf(y.wo, wi, TransportMode::Importance);
    let merge = sensor_merge(ctx, wi, dist2, land, y.near_specular);
    ctx.mis.light_to_camera(
        &y.mis,
        cam_a,
        y.reverse_pdf(wi, TransportMode::Importance),
        merge,
        y.merges,
    )
}

/// The ratio of merging at an irradiance meter's point (VCM) for a light subpath reaching it
/// along unit `wi` over `dist2` from a scattering vertex, its direction density `pdf_w()`
/// there: m(p_a η) with p_a on the meter's normal [`Mis::sensor_merge_ratio`]; 0 without such
/// merges. The meter merges light vertices of depth ≥ 2 only: at depth 1 the competing
/// connection of the light's own point would need its emission density in place of the
/// next-event one the vertex carries, and direct light is the connections' anyway. Under the
/// caustic rule the merge exists only when the light vertex, its predecessor, is
/// near-specular (`near_specular`, `merge_rule.rs`).
fn sensor_merge(
    ctx: &BidirContext,
    wi: Vec3,
    dist2: f32,
    pdf_w: impl FnOnce() -> f32,
    near_specular: bool,
) -> f32 {
    match ctx.sensor.infinite_light_meter() {
        Some(m) if ctx.sensor_merges => {
            let cos = m.dir.dot(wi).abs();
            ctx.mis
                .sensor_merge_ratio(pdf_w() * cos / dist2, near_specular)
        }
        _ => 0.0,
    }
}

/// s = 1, t = 1: the light subpath's own origin y_0 seen by the sensor. Its estimate is
/// L(y_0 → sensor) |cos θ| We / (pdf_w · pmf · p_pos); weight against the camera ray finding
/// y_0 (eq. (37) with n = 2). An infinite light has no such point: see [`infinite_to_sensor`].
pub fn origin_to_sensor(
    ctx: &BidirContext,
    o: &LightOrigin,
    lambda: &SampledWavelengths,
    u: [f32; 2],
    use_mis: bool,
) -> Option<SensorContribution> {
    if o.infinite {
        return infinite_to_sensor(ctx, o, use_mis);
    }
    let ss = ctx.sensor.sample_wi(o.p, u)?;
    let light = &ctx.scene.lights[o.light as usize];
    // A sphere's far side is hidden by the sphere itself (which does not shadow its own samples).
    if matches!(light, Light::Sphere(_)) && o.n.dot(ss.wi) <= 0.0 {
        return None;
    }
    let le = light.l(&o.hit(0.0), ss.wi, lambda);
    let pos_a = o.pmf * o.pdf_pos_a;
    // A point or line light carries an intensity: no cosine at y_0.
    let cos = if o.delta_pos {
        1.0
    } else {
        o.n.dot(ss.wi).abs()
    };
    let value = le * (cos * ss.we_over_pdf / pos_a);
    let skip = Some(o.light);
    if value.is_black() || sensor_occluded(ctx, o.p, o.p_error, o.n, &ss, skip) {
        return None;
    }
    let weight = if use_mis {
        origin_weight(ctx, o, ss.p, ss.pdf_dir_w)
    } else {
        1.0
    };
    Some(SensorContribution {
        bin: ss.bin,
        c: Contribution::new(value, weight),
    })
}

/// MIS weight of the light's point y_0 seen from sensor point `p_sensor` (eq. (37), n = 2).
pub fn origin_weight(ctx: &BidirContext, o: &LightOrigin, p_sensor: Vec3, pdf_dir_w: f32) -> f32 {
    if o.delta_pos {
        return 1.0; // no camera ray finds a point or line light
    }
    let d = p_sensor - o.p;
    let dist2 = d.length_squared();
    let cam_a = pdf_dir_w * o.n.dot(d).abs() / (dist2 * dist2.sqrt());
    // No merge at the meter competes: it merges light vertices of depth 2 or more only.
    ctx.mis.origin_to_camera(cam_a, o.pmf * o.pdf_pos_a, 0.0)
}

/// s = 1, t = 1 for an infinite light and an irradiance meter. The emitted point on the disk
/// through which the light enters the scene cannot be connected: the meter's point lies on
/// the sampled ray with probability 0, and moving the disk point changes the direction (and
/// so the disk). But an infinite light's radiance depends on direction only, so y_0 is a
/// direction at infinity with densities per solid angle (tech. rep. §5.1; PBR 3ed §16.3.1,
/// `Vertex::ConvertDensity`), and the meter's delta position fixes the ray through it: the
/// estimate is L(ω) W cos θ / (pmf · p_dir(ω)), ω the emitted direction, visibility along
/// the ray from the meter towards the light. None for sensors that do not connect so (the
/// camera; pbrt-v4 and SmallVCM light tracing neither).
pub fn infinite_to_sensor(
    ctx: &BidirContext,
    o: &LightOrigin,
    use_mis: bool,
) -> Option<SensorContribution> {
    let m = ctx.sensor.infinite_light_meter()?;
    let w = -o.n; // from the meter towards the light
    let we_cos = m.we_cos(w);
    let emit_dir = o.pmf * o.pdf_dir_w;
    if !(we_cos > 0.0 && emit_dir > 0.0) {
        return None;
    }
    let value = o.le * (we_cos / emit_dir);
    let shadow = m.ray_towards(w);
    if value.is_black() || ctx.scene.occluded(&shadow, f32::INFINITY, None) {
        return None;
    }
    let weight = if use_mis {
        infinite_origin_weight(ctx, o, m.pdf_dir_w(w))
    } else {
        1.0
    };
    Some(SensorContribution {
        bin: 0,
        c: Contribution::new(value, weight),
    })
}

/// MIS weight of an infinite light's direction connected to a meter whose own rays take that
/// direction with density `pdf_dir_w` (eq. (37), n = 2, both densities per solid angle at the
/// meter); 1 for a delta direction, which the meter's rays cannot find.
pub fn infinite_origin_weight(ctx: &BidirContext, o: &LightOrigin, pdf_dir_w: f32) -> f32 {
    if o.delta_dir {
        return 1.0;
    }
    ctx.mis
        .origin_to_camera(pdf_dir_w, o.pmf * o.pdf_dir_w, 0.0)
}

/// s = 1, t ≥ 2: next-event estimation at camera vertex `z`, one light chosen by power
/// (as the path tracer), weighted by [tech. rep. (44), (45)].
pub fn next_event(
    ctx: &BidirContext,
    z: &PathVertex,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
) -> Option<Contribution> {
    let (ul, u) = (sampler.get_1d(), sampler.get_2d());
    let scene = ctx.scene;
    let (index, pmf) = scene.light_sampler.sample(ul)?;
    let light = &scene.lights[index];
    let lctx = LightSampleContext { p: z.p, n: z.ng };
    let ls = light.sample_li(&lctx, u, lambda)?;
    if ls.l.is_black() || ls.pdf_w.is_nan() || ls.pdf_w <= 0.0 {
        return None;
    }
    let f = z.f_radiance(ls.wi);
    if f.is_black() {
        return None;
    }
    let direct_w = pmf * ls.pdf_w;
    let value = z.beta * f * ls.l * (z.cos_shading(ls.wi) / direct_w);
    let (shadow, t) = if ls.infinite {
        (spawn_ray(z.p, z.p_error, z.ng, ls.wi), f32::INFINITY)
    } else if matches!(light, Light::Triangle(_)) {
        spawn_ray_to(z.p, z.p_error, z.ng, ls.p_light, Vec3::ZERO, ls.n_light)
    } else {
        spawn_ray_to_point(z.p, z.p_error, z.ng, ls.p_light)
    };
    if value.is_black() || scene.occluded(&shadow, t, Some(index as u32)) {
        return None;
    }
    let weight = direct_weight(ctx, z, index as u32, &ls);
    Some(Contribution::new(value, weight))
}

/// MIS weight of next-event estimation at `z` that chose light `light` and sampled `ls`
/// [tech. rep. (44), (45)].
pub fn direct_weight(ctx: &BidirContext, z: &PathVertex, light: u32, ls: &LightLiSample) -> f32 {
    let pmf = ctx.scene.light_sampler.pmf(light as usize);
    let lgt = &ctx.scene.lights[light as usize];
    let le = lgt.pdf_le(ls.p_light, ls.n_light, -ls.wi, &ctx.sphere);
    ctx.mis.direct(
        &z.mis,
        DirectPdfs {
            direct_w: pmf * ls.pdf_w,
            emit: pmf * le.pos_a * le.dir_w,
            cos_cam: z.cos_geo(ls.wi),
            cos_light: if ls.infinite {
                1.0
            } else if lgt.is_delta_position() {
                // A point or line light's next-event density is relative to its delta at y_0,
                // which the emission density shares; the d² that turns it into a density per
                // solid angle at z goes here (SmallVCM's point light returns d² as its
                // `directPdfW` and 1 as `cosAtLight`).
                (ls.p_light - z.p).length_squared()
            } else {
                ls.n_light.dot(ls.wi).abs()
            },
            bsdf_fwd_w: z.bsdf.pdf(z.wo, ls.wi, TransportMode::Radiance),
            bsdf_rev_w: z.reverse_pdf(ls.wi, TransportMode::Radiance),
            delta: ls.delta,
        },
    )
}

/// s ≥ 2, t ≥ 2: light vertex `y` joined to camera vertex `z` by a shadow ray
/// (Veach 1997 eq. 10.8; weight [tech. rep. (40), (41)]).
pub fn connect(ctx: &BidirContext, y: &PathVertex, z: &PathVertex) -> Option<Contribution> {
    let d = y.p - z.p;
    let dist2 = d.length_squared();
    if dist2 == 0.0 {
        return None;
    }
    let w = d / dist2.sqrt();
    let f_cam = z.f_radiance(w);
    if f_cam.is_black() {
        return None;
    }
    let f_light = y.f_importance(-w);
    let g = z.cos_shading(w) * y.cos_shading(w) / dist2;
    let value = z.beta * f_cam * y.beta * f_light * g;
    if value.is_black() {
        return None;
    }
    let (ray, t) = spawn_ray_to(z.p, z.p_error, z.ng, y.p, y.p_error, y.ng);
    if ctx.scene.occluded(&ray, t, None) {
        return None;
    }
    Some(Contribution::new(value, connect_weight(ctx, y, z)))
}

/// MIS weight of joining light vertex `y` to camera vertex `z` [tech. rep. (40), (41)].
pub fn connect_weight(ctx: &BidirContext, y: &PathVertex, z: &PathVertex) -> f32 {
    let d = y.p - z.p;
    let dist2 = d.length_squared();
    let w = d / dist2.sqrt();
    let pdfs = ConnectionPdfs {
        cam_fwd_a: z.bsdf.pdf(z.wo, w, TransportMode::Radiance) * y.cos_geo(w) / dist2,
        cam_rev_w: z.reverse_pdf(w, TransportMode::Radiance),
        light_fwd_a: y.bsdf.pdf(y.wo, -w, TransportMode::Importance) * z.cos_geo(w) / dist2,
        light_rev_w: y.reverse_pdf(-w, TransportMode::Importance),
    };
    ctx.mis
        .connect(&y.mis, &z.mis, pdfs, y.merges, y.near_specular)
}

/// s = 0: the camera walk, just arrived at light `light` (point `hit`), sees its emission
/// towards `w` (back along the ray) [tech. rep. (42), (43)]. For t = 2 the competing
/// technique is (1, 1), which samples the point by emission, not by next-event estimation.
pub fn emitter_hit(
    ctx: &BidirContext,
    walk: &Walk,
    light: u32,
    hit: &LightHit,
    w: Vec3,
    lambda: &SampledWavelengths,
) -> Option<Contribution> {
    let lgt = &ctx.scene.lights[light as usize];
    let le = lgt.l(hit, w, lambda);
    if le.is_black() {
        return None;
    }
    let weight = emitter_weight(ctx, walk, light, hit, w);
    Some(Contribution::new(walk.beta * le, weight))
}

/// MIS weight of the camera walk finding light `light` at `hit`, `w` pointing back
/// [tech. rep. (42), (43)].
pub fn emitter_weight(ctx: &BidirContext, walk: &Walk, light: u32, hit: &LightHit, w: Vec3) -> f32 {
    let lgt = &ctx.scene.lights[light as usize];
    let pmf = ctx.scene.light_sampler.pmf(light as usize);
    let pdf = lgt.pdf_le(hit.p, hit.n, w, &ctx.sphere);
    if walk.depth == 1 {
        // Two-vertex paths: no merge at the sensor competes (see `sensor_merge`).
        return ctx.mis.emitter_hit(&walk.mis, pmf * pdf.pos_a, 0.0);
    }
    let dist2 = (hit.p - walk.prev.p).length_squared();
    let direct_w = direct_pdf_w(ctx.scene, light, &walk.prev, -w, hit);
    let direct_a = direct_w * hit.n.dot(w).abs() / dist2;
    ctx.mis
        .emitter_hit(&walk.mis, direct_a, pmf * pdf.pos_a * pdf.dir_w)
}

/// s = 0 for infinite lights: the camera walk escaped along `d`. The walk's MIS quantities
/// are those left by the last scattering, not divided by any distance (§5.1); a camera ray
/// that escapes directly (t = 2) has no competing technique.
pub fn escaped(
    ctx: &BidirContext,
    walk: &Walk,
    d: Vec3,
    lambda: &SampledWavelengths,
) -> Contribution {
    let mut total = Contribution::default();
    for &i in &ctx.scene.infinite_lights {
        let lgt = &ctx.scene.lights[i as usize];
        let le = lgt.le(d, lambda);
        if le.is_black() {
            continue;
        }
        total += Contribution::new(walk.beta * le, escaped_weight(ctx, walk, i, d));
    }
    total
}

/// MIS weight of the camera walk escaping along `d` to infinite light `light`
/// [tech. rep. (43), §5.1]. The sensor's own ray escaping (t = 2) competes with nothing for
/// the camera, and with the light's direction connected to the meter ([`infinite_to_sensor`],
/// density pmf · p_dir per solid angle) for an irradiance meter.
pub fn escaped_weight(ctx: &BidirContext, walk: &Walk, light: u32, d: Vec3) -> f32 {
    let lgt = &ctx.scene.lights[light as usize];
    if lgt.is_delta() {
        return 0.0; // no ray finds a delta light
    }
    let pmf = ctx.scene.light_sampler.pmf(light as usize);
    let pdf = lgt.pdf_le(Vec3::ZERO, Vec3::ZERO, -d, &ctx.sphere);
    if walk.depth == 0 {
        return match ctx.sensor.infinite_light_meter() {
            Some(_) => ctx.mis.emitter_hit(&walk.mis, pmf * pdf.dir_w, 0.0),
            None => 1.0,
        };
    }
    let far = LightHit {
        p: Vec3::ZERO,
        n: Vec3::ZERO,
        t: f32::INFINITY,
    };
    let direct_w = direct_pdf_w(ctx.scene, light, &walk.prev, d, &far);
    ctx.mis
        .emitter_hit(&walk.mis, direct_w, pmf * pdf.pos_a * pdf.dir_w)
}

/// True when something blocks the segment from `p` (error `p_error`, geometric normal `n`) to
/// the sensor sample `ss`; `skip` names a light shape that does not count (the one `p` lies on).
fn sensor_occluded(
    ctx: &BidirContext,
    p: Vec3,
    p_error: Vec3,
    n: Vec3,
    ss: &SensorSample,
    skip: Option<u32>,
) -> bool {
    let (ray, t) = ctx.sensor.shadow_ray(p, p_error, n, ss);
    ctx.scene.occluded(&ray, t, skip)
}
