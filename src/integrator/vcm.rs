//! Spectral vertex connection and merging (Georgiev, Křivánek, Davidovič, Slusallek 2012,
//! "Light transport simulation with vertex connection and merging"; the tech. rep.
//! "Implementing Vertex Connection and Merging"; SmallVCM), on the machinery BDPT uses.
//!
//! **Iterations.** Each iteration k (k = 0, 1, … ; one sample per pixel, or one block of
//! samples per meter reading):
//! 1. picks the iteration's radius r_k = r_0 (k + 1)^((α−1)/2) (eq. 25; Knaus and Zwicker
//!    2011), η_VCM = π r_k² N_L and the MIS factors ([`Mis::vcm`]), and its wavelengths;
//! 2. traces N_L light subpaths (one per pixel for images, [`VcmParams::meter_light_paths`]
//!    for meters) and keeps them in the store (`bidir/store.rs`): their non-specular vertices
//!    with a hash grid for merging, and each subpath whole for connections;
//! 3. the camera samples trace their camera subpath, connecting to the stored light subpath
//!    of their pixel (splats t = 1 included, n_VC = 1) and merging with every stored vertex
//!    within the radius at every non-specular camera vertex: one light subpath per camera
//!    sample serves both, as in SmallVCM. Meter samples (64 per reading and iteration against
//!    4096 stored subpaths) trace a light subpath of their own for connections, as BDPT.
//!
//! **Wavelengths.** A merge may only combine vertices that carry the same wavelengths, so an
//! iteration shares one hero tuple, and the tuples of successive iterations are stratified:
//! the hero of iteration k is drawn from a base-4 radical-inverse sequence of k
//! (`stratified_u`, one tuple per value), shifted by a hash of the seed — over all of [0, 1),
//! since a path that terminates its secondary wavelengths (dispersion) keeps the hero alone. A
//! light subpath that terminates its secondary wavelengths at a dispersive vertex stores its
//! vertices as hero-only; a merge with one counts on the hero lane alone
//! (`SampleRecord::hero_only`).
//!
//! **Where it merges** (`--vcm-merge`, `bidir/merge_rule.rs`): by default only at vertices
//! that follow a specular or near-specular one in light order (caustics, Jensen 1996), or at
//! every non-specular vertex as in the paper (`all`).
//!
//! **Modes.** `vcm` connects and merges; `vm` merges only, plus emitters at the end of purely
//! specular camera paths (bidirectional photon mapping); `vc` is BDPT, estimator and all
//! (`Integrator::estimator` builds a `BdptEstimator` for it).
//!
//! VCM is consistent, not unbiased: merging blurs the light arriving at a camera vertex over
//! a disk of radius r_k, a bias that vanishes as r_k → 0 over the iterations while the
//! variance of the merges grows as 1/r_k² (α < 1 trades them, eq. 25).

use super::bdpt::{BdptIntegrator, Techniques};
use super::bidir::store::Traced;
use super::bidir::vertex::bsdf_at;
use super::bidir::{
    trace_light_subpath, BidirContext, LightVertexStore, MergeParams, MergeRule, Mis, MisHeuristic,
    Workspace,
};
use super::{Estimator, Iteration, Settings};
use crate::bxdf::TransportMode;
use crate::geometry::offset::spawn_ray;
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene};
use crate::sensor::meter::MeterSensor;
use crate::sensor::Sensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;
use std::f32::consts::PI;

/// What VCM does at a camera vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VcmMode {
    /// Connections and merges.
    #[default]
    Vcm,
    /// Connections only: BDPT.
    Vc,
    /// Merges only: bidirectional photon mapping.
    Vm,
}

impl VcmMode {
    pub const ALL: [VcmMode; 3] = [VcmMode::Vcm, VcmMode::Vc, VcmMode::Vm];

    pub fn name(&self) -> &'static str {
        match self {
            VcmMode::Vcm => "vcm",
            VcmMode::Vc => "vc",
            VcmMode::Vm => "vm",
        }
    }
}

/// The settings of VCM.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmParams {
    pub mis: MisHeuristic,
    pub mode: VcmMode,
    /// r_0 in metres; None derives it (images: from the pixel footprint, meters: from the
    /// scene's extent).
    pub radius: Option<f32>,
    /// α of the radius schedule, in (0, 1]: 1 keeps the radius.
    pub alpha: f32,
    /// Light subpaths an iteration stores for meters.
    pub meter_light_paths: u64,
    /// How camera samples and light subpaths choose their wavelengths (a test option: the
    /// measured alternative to the default, docs/design.md "### VCM").
    pub wavelengths: VcmWavelengths,
    /// Where mode `vcm` merges (`bidir/merge_rule.rs`, `--vcm-merge`); `vm` merges everywhere.
    pub merges: MergeRule,
}

impl Default for VcmParams {
    fn default() -> Self {
        VcmParams {
            mis: MisHeuristic::Power,
            mode: VcmMode::Vcm,
            radius: None,
            alpha: DEFAULT_ALPHA,
            meter_light_paths: DEFAULT_METER_LIGHT_PATHS,
            wavelengths: VcmWavelengths::PerIteration,
            merges: DEFAULT_MERGE_RULE,
        }
    }
}

/// The wavelength tuples of VCM's samples. A merge may only combine vertices carrying the
/// same wavelengths; the two ways to arrange that:
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VcmWavelengths {
    /// One tuple per iteration, shared by all its samples and light subpaths, the heroes of
    /// successive iterations stratified ([`iteration_u`]). Every stored vertex can merge.
    #[default]
    PerIteration,
    /// A tuple per light subpath, shared by the camera sample connected to it; a merge counts
    /// only when the camera's hero and the light vertex's hero fall in the same of B_k
    /// equal-probability bins of the hero's primary sample u, B_k = ⌈B · (k + 1)^((1−α)/2)⌉
    /// in iteration k (bins narrowing as r_k shrinks, so the spectral blur vanishes with the
    /// spatial one), with η_VCM = π r_k² N_L / B_k and the kernel normalised by it. Images
    /// only: meters keep one tuple per iteration.
    PerSample { bins: u32 },
}

/// α of Georgiev et al. 2012 (their eq. 25 and §6).
pub const DEFAULT_ALPHA: f32 = 0.75;
/// Light subpaths per iteration of a meter reading.
pub const DEFAULT_METER_LIGHT_PATHS: u64 = 1 << 12;
/// Samples per reading in one iteration of meters (one block of the meter driver).
pub const METER_ITERATION_SAMPLES: u64 = 64;
/// r_0 of meters relative to the scene's bounding radius (SmallVCM's default factor).
pub const METER_RADIUS_FACTOR: f32 = 0.003;
/// r_0 of images in pixel footprints at the first hit (median over the image). Chosen by an
/// equal-CPU-time sweep (docs/design.md "### VCM", "Radius"): the smaller r_0, the less the
/// merges blur and cost and the closer VCM comes to BDPT on diffuse scenes (the Cornell box),
/// while the variance of merged caustics grows as 1/r_0² (Georgiev et al. 2012 §5; SmallVCM
/// sets r_0 = 0.003 × the scene's radius). 0.75 keeps a mirror-seen caustic 34× below the path
/// tracer's MSE, with a 3× margin over issue 10's 10×; 1.5 before.
pub const IMAGE_RADIUS_FOOTPRINTS: f32 = 0.75;
/// Where mode `vcm` merges by default (`--vcm-merge`): only after near-specular vertices,
/// chosen by an equal-CPU comparison (docs/design.md "### VCM", "Merges only after
/// near-specular vertices"): it ties merging everywhere on the caustic scenes, where the
/// merges that count follow specular vertices, and costs 20–30 % less CPU time on the
/// diffuse ones (the Cornell box, `gap.usda`, `room.usda`) for the same error.
pub const DEFAULT_MERGE_RULE: MergeRule = MergeRule::Caustic;
/// Light subpaths traced per parallel task when filling the store (one batch of the store).
const STORE_CHUNK: u64 = 1024;
/// Offsets the store's sampler streams from the samples' own.
const STORE_STREAM: u64 = 0x5643_4d5f_4c49_4748;

/// The radius of iteration `k` (0-based) for r_0 and α: r_0 (k + 1)^((α−1)/2) (Georgiev et
/// al. 2012 eq. 25), never below r_0 · 2⁻²⁰ so that π r² N_L stays a normal f32 for any
/// iteration count.
pub fn radius(r0: f32, alpha: f32, k: u64) -> f32 {
    let shrink = ((k as f64 + 1.0).powf((f64::from(alpha) - 1.0) * 0.5)) as f32;
    (r0 * shrink).max(r0 * (1.0 / 1_048_576.0))
}

/// The hero-wavelength sample of image iteration `k`, in [0, 1): the even iterations
/// k = 2m take u = g(m) + s₀ and the odd ones g(m) + s₁ (mod 1), with s₀, s₁ two independent
/// shifts drawn from the seed (Cranley–Patterson rotations) and g the stratified sequence of
/// [`stratified_u`]. The film's even and odd halves (`sensor::film`) are then two independent,
/// identically distributed randomised-QMC estimates, each stratified over the spectrum on its
/// own, so their difference gives an honest variance (Owen's independent replicates) — with
/// one shift for all iterations, the halves would interleave one stratified set (the base-2
/// radical inverse put even iterations' heroes in [0, ½) and odd ones' in [½, 1)), their
/// errors would be anticorrelated and the even/odd variance overstated.
pub fn iteration_u(seed: u64, k: u64) -> f32 {
    let shift = (splitmix(seed ^ splitmix(k & 1)) >> 40) as f64 / (1u64 << 24) as f64;
    ((stratified_u(k >> 1) + shift).fract() as f32).min(1.0 - f32::EPSILON)
}

/// The hero-wavelength sample of meter iteration `k`: independent uniform in [0, 1) from the
/// seed and k. A reading's interval is over its iteration means (`session::meter`), which
/// must be independent for its ci95 to hold; stratifying the iterations' wavelengths would
/// make them anticorrelated and the interval too wide.
pub fn meter_iteration_u(seed: u64, k: u64) -> f32 {
    let u = (splitmix(seed ^ splitmix(k ^ STORE_STREAM)) >> 40) as f32 / (1u32 << 24) as f32;
    u.min(1.0 - f32::EPSILON)
}

/// g(m) = (q_m + ρ₄(m)) / 4 in [0, 1); ρ₄ is the base-4 radical inverse and q_m the sum of
/// m's base-4 digits mod 4. A tuple's N = 4 lanes sit a quarter apart
/// (`SampledWavelengths::sample_visible`), so the tuple is fixed by u mod 1/4 = ρ₄(m)/4:
/// distinct for every m and stratified over them (the base-2 radical inverse of m alone
/// repeats each tuple 4 times in succession, as a rotation of its lanes, leaving a pixel a
/// quarter as many wavelength samples as iterations). The hero's quarter q_m makes the
/// heroes alone stratified too — the first 4^j values put one hero in each of 4^j strata of
/// [0, 1) (for m < 4^j, fixing m's first j − 1 digits fixes u's digits after the first, and
/// the last digit then runs q_m over all quarters) — for paths through dispersive glass,
/// which keep their hero alone.
fn stratified_u(m: u64) -> f64 {
    let (mut rest, mut digits, mut inverse, mut scale) = (m, 0u64, 0.0f64, 0.25f64);
    while rest > 0 {
        digits += rest & 3;
        inverse += (rest & 3) as f64 * scale;
        rest >>= 2;
        scale *= 0.25;
    }
    ((digits & 3) as f64 + inverse) * 0.25
}

fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// VCM (modes `vcm` and `vm`) as an [`Estimator`].
pub struct VcmEstimator<'a> {
    params: VcmParams,
    settings: Settings,
    r0: f32,
    /// N_L: light subpaths per iteration.
    light_paths: u64,
    /// Image width in pixels (camera sample j = y · width + x connects to light subpath j).
    width: u64,
    meters: bool,
    // The current iteration:
    ctx: BidirContext<'a>,
    lambda: SampledWavelengths,
    /// B_k of [`VcmWavelengths::PerSample`] (1 for one tuple per iteration).
    bins: u32,
    store: LightVertexStore,
    merge: MergeParams,
}

impl<'a> VcmEstimator<'a> {
    /// `settings.meters` selects the meter form (the store's size, the radius from the
    /// scene's extent, iterations of [`METER_ITERATION_SAMPLES`]).
    pub fn new(scene: &'a Scene, settings: Settings, mut params: VcmParams) -> Self {
        let meters = settings.meters;
        if meters {
            params.wavelengths = VcmWavelengths::PerIteration;
        }
        let light_paths = if meters {
            params.meter_light_paths.max(1)
        } else {
            u64::from(scene.camera.width) * u64::from(scene.camera.height)
        };
        let r0 = params
            .radius
            .filter(|r| r.is_finite() && *r > 0.0)
            .unwrap_or_else(|| default_radius(scene, meters));
        let ctx = BidirContext::new(scene, Mis::bdpt(params.mis), settings.max_depth)
            .with_filter(settings.filter);
        let mut est = VcmEstimator {
            params,
            settings,
            r0,
            light_paths,
            width: u64::from(scene.camera.width),
            meters,
            ctx,
            lambda: SampledWavelengths::sample_visible(0.0),
            bins: 1,
            store: LightVertexStore::default(),
            merge: MergeParams {
                mis: ctx.mis,
                normalization: 0.0,
                max_depth: settings.max_depth,
                key: 0,
            },
        };
        est.set_radius(0);
        est
    }

    /// The iteration's techniques for a camera sample of merge key `key`; `light_given` when
    /// the sample's light subpath for connections is the stored one already in its
    /// workspace.
    fn techniques(&self, light_given: bool, key: u32) -> Techniques<'_> {
        Techniques {
            connect: self.params.mode != VcmMode::Vm,
            light_given,
            merge: Some((&self.store, MergeParams { key, ..self.merge })),
        }
    }

    /// The stored light subpath of the image sample at raster position `film`: j = y · width
    /// + x of its pixel.
    fn pixel_subpath(&self, film: [f32; 2]) -> u64 {
        let (w, n) = (self.width.max(1), self.light_paths);
        let x = (film[0].max(0.0) as u64).min(w - 1);
        ((film[1].max(0.0) as u64) * w + x).min(n.saturating_sub(1))
    }

    /// The MIS factors and kernel normalisation of iteration `k`: η_VCM = π r_k² N_L / B_k
    /// [tech. rep. (20)] (B_k = 1 with one tuple per iteration).
    fn set_radius(&mut self, k: u64) {
        self.bins = match self.params.wavelengths {
            VcmWavelengths::PerIteration => 1,
            VcmWavelengths::PerSample { bins } => hero_bins(bins, self.params.alpha, k),
        };
        let r = radius(self.r0, self.params.alpha, k);
        let area = PI * r * r * self.light_paths as f32 / self.bins as f32;
        let connect = self.params.mode != VcmMode::Vm;
        // Photon mapping keeps every merge: for most paths it is its only technique.
        let rule = if connect {
            self.params.merges
        } else {
            MergeRule::All
        };
        self.ctx.mis = Mis::vcm(self.params.mis, area, connect, true).with_merge_rule(rule);
        self.merge = MergeParams {
            mis: self.ctx.mis,
            normalization: 1.0 / area,
            max_depth: self.settings.max_depth,
            key: 0,
        };
    }

    /// Traces the iteration's light subpaths into the store, in parallel, in a fixed order:
    /// all with the iteration's wavelengths, or subpath j with its own (per-sample tuples:
    /// the iteration's stratified hero sequence shifted by a hash of j, so that every pixel's
    /// heroes are stratified over the iterations and neighbouring pixels' are independent),
    /// its merge key the bin of its hero.
    fn fill_store(&mut self, seed: u64, k: u64, radius: f32) {
        let (ctx, lambda, bins) = (self.ctx, self.lambda, self.bins);
        let per_sample = self.params.wavelengths != VcmWavelengths::PerIteration;
        self.store
            .fill(self.light_paths, STORE_CHUNK, radius, |j, path| {
                let mut sampler = Sampler::new(seed ^ STORE_STREAM, j, k);
                let (lambda, key) = if per_sample {
                    let u = iteration_u(seed ^ splitmix(j ^ STORE_STREAM), k);
                    let bin = ((u * bins as f32) as u32).min(bins - 1);
                    (SampledWavelengths::sample_visible(u), bin)
                } else {
                    (lambda, 0)
                };
                let mut l = lambda;
                trace_light_subpath(&ctx, &mut l, &mut sampler, path);
                Traced {
                    lambda,
                    hero_only: l.secondary_terminated(),
                    key,
                }
            });
    }
}

/// B_k of [`VcmWavelengths::PerSample`]: ⌈B (k + 1)^((1−α)/2)⌉, growing as r_0 / r_k, at most
/// 2^16.
pub fn hero_bins(bins: u32, alpha: f32, k: u64) -> u32 {
    let grow = (k as f64 + 1.0).powf((1.0 - f64::from(alpha)) * 0.5);
    (f64::from(bins.max(1)) * grow).ceil().min(65_536.0) as u32
}

impl Estimator for VcmEstimator<'_> {
    fn iteration_samples(&self) -> Option<u64> {
        Some(if self.meters {
            METER_ITERATION_SAMPLES
        } else {
            1
        })
    }

    fn report(&self) -> Option<String> {
        let mb = |b: usize| b as f64 / 1e6;
        Some(format!(
            "{} (merges: {}): r0 = {:.4} mm, alpha = {}, {} light subpaths per iteration; light \
             vertex store peak {:.1} MB ({} B per merging vertex); consistent, not unbiased: \
             merges blur over the radius, which shrinks with the iterations",
            self.params.mode.name(),
            self.ctx.mis.merge_rule.name(),
            self.r0 * 1e3,
            self.params.alpha,
            self.light_paths,
            mb(self.store.peak_bytes),
            LightVertexStore::BYTES_PER_VERTEX
        ))
    }

    fn begin_iteration(&mut self, it: Iteration) {
        self.set_radius(it.index);
        let u = if self.meters {
            meter_iteration_u(it.seed, it.index)
        } else {
            iteration_u(it.seed, it.index)
        };
        self.lambda = SampledWavelengths::sample_visible(u);
        let r = radius(self.r0, self.params.alpha, it.index);
        self.fill_store(it.seed, it.index, r);
    }

    fn own_image_wavelengths(&self) -> bool {
        true
    }

    fn image_sample(
        &self,
        film: [f32; 2],
        u_lens: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        // The camera sample takes the wavelengths of its pixel's light subpath, terminated as
        // its trace left them when it connects to it (whatever `lambda` held: the driver
        // leaves it unset, `own_image_wavelengths`).
        let j = self.pixel_subpath(film);
        let traced = self.store.traced(j).unwrap_or(Traced {
            lambda: self.lambda,
            hero_only: false,
            key: 0,
        });
        *lambda = traced.lambda;
        let connect = self.params.mode != VcmMode::Vm;
        if connect {
            if traced.hero_only {
                lambda.terminate_secondary();
            }
            let (scene, filter) = (self.ctx.scene, self.ctx.filter);
            self.store.subpath(j, scene, filter, lambda, &mut ws.light);
        }
        let tech = self.techniques(connect, traced.key);
        BdptIntegrator.sample_with(&tech, &self.ctx, film, u_lens, lambda, sampler, ws);
    }

    fn meter_sample(
        &self,
        meter: &MeterSensor,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        *lambda = self.lambda;
        let mut ctx = self.ctx.with_sensor(Sensor::Meter(*meter));
        // An irradiance meter merges at its own point too (a luminance meter's direction is a
        // delta no light vertex arrives along).
        ctx.sensor_merges = !meter.delta_direction();
        ws.record.clear();
        let u = sampler.get_2d();
        let tech = self.techniques(false, 0);
        BdptIntegrator.sample_with(&tech, &ctx, [0.0; 2], u, lambda, sampler, ws);
        if ctx.sensor_merges {
            let m = self
                .store
                .merge_at_sensor(meter, lambda.secondary_terminated(), &self.merge);
            ws.record.camera.weighted += m.all;
            ws.record.camera.unweighted += m.all;
            ws.record.hero_only += m.hero_only;
        }
        ws.record.total(lambda)
    }
}

/// r_0: for images [`IMAGE_RADIUS_FOOTPRINTS`] × the median pixel footprint where camera rays
/// through a grid of pixel centres first meet a non-specular surface — where merges happen —
/// (the distance travelled times the angle between neighbouring pixels' rays, following
/// specular reflections and refractions: a floor seen in a planar mirror has the footprint of
/// its distance through the mirror); for meters, or when no ray meets one,
/// [`METER_RADIUS_FACTOR`] × the scene's bounding radius.
fn default_radius(scene: &Scene, meters: bool) -> f32 {
    let extent = (METER_RADIUS_FACTOR * scene.radius).max(1e-6);
    if meters {
        return extent;
    }
    let cam = &scene.camera;
    let (w, h) = (cam.width as f32, cam.height as f32);
    let mut footprints: Vec<f32> = Vec::new();
    for j in 0..32 {
        for i in 0..32 {
            let film = [(i as f32 + 0.5) / 32.0 * w, (j as f32 + 0.5) / 32.0 * h];
            let (ray, t_max) = cam.generate_ray(film, [0.5, 0.5]);
            let (next, _) = cam.generate_ray([film[0] + 1.0, film[1]], [0.5, 0.5]);
            let Some(t) = distance_to_non_specular(scene, ray, t_max) else {
                continue;
            };
            let angle = ray.d.angle_between(next.d);
            if (t * angle).is_finite() && t * angle > 0.0 {
                footprints.push(t * angle);
            }
        }
    }
    if footprints.is_empty() {
        return extent;
    }
    footprints.sort_by(f32::total_cmp);
    IMAGE_RADIUS_FOOTPRINTS * footprints[footprints.len() / 2]
}

/// Specular bounces [`distance_to_non_specular`] follows before giving up on a ray.
const MAX_SPECULAR_BOUNCES: u32 = 8;

/// The distance a camera ray travels to the first non-specular surface (or light) it meets,
/// through up to [`MAX_SPECULAR_BOUNCES`] specular vertices, each continued along the more
/// likely of its lobes at mid-spectrum wavelengths; None when the ray escapes or the chain
/// goes on.
fn distance_to_non_specular(
    scene: &Scene,
    mut ray: crate::geometry::Ray,
    t_max: f32,
) -> Option<f32> {
    let mut lambda = SampledWavelengths::sample_visible(0.5);
    let mut travelled = 0.0;
    let mut t_max = t_max;
    for _ in 0..=MAX_SPECULAR_BOUNCES {
        let si = match scene.intersect(&ray, t_max)? {
            Hit::Surface(si) => si,
            Hit::Light { hit, .. } => return Some(travelled + hit.t),
        };
        travelled += si.t;
        let bsdf = bsdf_at(scene, &si, TextureFilter::Finest, &mut lambda);
        if !bsdf.is_specular() {
            return Some(travelled);
        }
        let bs = bsdf.sample_f(-ray.d, 0.5, [0.5, 0.5], TransportMode::Radiance)?;
        ray = spawn_ray(si.p, si.p_error, si.ng, bs.wi);
        t_max = f32::INFINITY;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::*;
    use crate::integrator::bidir::LightSubpath;
    use glam::{Mat4, Vec3};

    /// A 1 m² floor under a small sphere light, seen by the default camera at 8 × 8.
    fn floor_scene() -> Scene {
        crate::scene::build(&floor_desc(), Some((8, 8))).unwrap()
    }

    fn floor_desc() -> SceneDescription {
        let mut desc = SceneDescription::default();
        desc.meshes.push(MeshDesc {
            prim_path: "/Floor".into(),
            positions: vec![
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
            ],
            indices: vec![[0, 2, 1], [0, 3, 2]],
            ..Default::default()
        });
        desc.lights.push(LightDesc {
            prim_path: "/Bulb".into(),
            kind: LightKind::Sphere {
                radius: 0.05,
                point: false,
            },
            to_world: Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            emission: EmissionDesc {
                intensity: 100.0,
                ..Default::default()
            },
            shaping: None,
            shadows: true,
        });
        desc
    }

    /// The tests' integrator settings: depth 5, finest textures, an image.
    fn test_settings() -> Settings {
        Settings {
            max_depth: 5,
            rr_depth: crate::integrator::roulette::DEFAULT_RR_DEPTH,
            split: 1,
            filter: TextureFilter::Finest,
            meters: false,
        }
    }

    #[test]
    fn stored_subpaths_rebuild_as_traced_bit_for_bit() {
        // The floor of rough BK7 (non-specular and dispersive): stored vertices on it have
        // terminated their subpath's secondary wavelengths.
        let mut desc = floor_desc();
        desc.materials.push(MaterialDesc {
            prim_path: "/Glass".into(),
            kind: MaterialKind::Dielectric {
                ior: IorDesc::Glass("BK7".into()),
                roughness: 0.3,
                thin: false,
            },
            emission: None,
            textures: Vec::new(),
            texcoord: "st".into(),
        });
        desc.meshes[0].material = Some(0);
        let scene = crate::scene::build(&desc, Some((8, 8))).unwrap();
        let settings = test_settings();
        // Both merge rules: every vertex is stored and rebuilt, merge flags included, and the
        // grid holds exactly those merging is available at.
        for merges in MergeRule::ALL {
            let params = VcmParams {
                merges,
                ..VcmParams::default()
            };
            store_rebuilds_as_traced(&scene, settings, params);
        }
    }

    #[test]
    fn image_samples_ignore_the_wavelengths_they_are_handed() {
        // The image driver hands VCM unset wavelengths (`own_image_wavelengths`): a sample's
        // contributions and final wavelengths must not depend on them, with one tuple per
        // iteration or one per light subpath.
        let scene = floor_scene();
        let handed = [0.1, 0.6].map(SampledWavelengths::sample_visible);
        let mut terminated = handed[1];
        terminated.terminate_secondary();
        for wavelengths in [
            VcmWavelengths::PerIteration,
            VcmWavelengths::PerSample { bins: 4 },
        ] {
            let params = VcmParams {
                wavelengths,
                ..VcmParams::default()
            };
            let mut est = VcmEstimator::new(&scene, test_settings(), params);
            assert!(est.own_image_wavelengths());
            est.begin_iteration(Iteration { seed: 3, index: 1 });
            let mut lit = 0;
            for j in 0..64u64 {
                let film = [(j % 8) as f32 + 0.5, (j / 8) as f32 + 0.5];
                let runs: Vec<String> = [handed[0], handed[1], terminated]
                    .into_iter()
                    .map(|mut lambda| {
                        let mut ws = Workspace::new(5, 0);
                        let mut sampler = Sampler::new(3, j, 1);
                        est.image_sample(film, [0.5; 2], &mut lambda, &mut sampler, &mut ws);
                        lit += usize::from(!ws.record.total(&lambda).is_black());
                        format!("{lambda:?} {:?}", ws.record)
                    })
                    .collect();
                assert!(runs.iter().all(|r| *r == runs[0]), "pixel {j}");
            }
            assert!(lit >= 3 * 32, "{lit}");
        }
    }

    fn store_rebuilds_as_traced(scene: &Scene, settings: Settings, params: VcmParams) {
        let mut est = VcmEstimator::new(scene, settings, params);
        est.begin_iteration(Iteration { seed: 5, index: 3 });
        let mut traced = LightSubpath::default();
        let mut rebuilt = LightSubpath::default();
        let (mut stored_vertices, mut dispersed, mut merging) = (0, 0, 0);
        for j in 0..64 {
            let mut sampler = Sampler::new(5 ^ STORE_STREAM, j, 3);
            let mut l = est.lambda;
            trace_light_subpath(&est.ctx, &mut l, &mut sampler, &mut traced);
            let report = est.store.traced(j).unwrap();
            let hero_only = report.hero_only;
            let mut l2 = report.lambda;
            if hero_only {
                l2.terminate_secondary();
            }
            est.store
                .subpath(j, scene, TextureFilter::Finest, &mut l2, &mut rebuilt);
            assert_eq!(hero_only, l.secondary_terminated());
            dispersed += u32::from(hero_only);
            assert_eq!(format!("{l:?}"), format!("{l2:?}"));
            assert_eq!(
                format!("{:?}", traced.origin),
                format!("{:?}", rebuilt.origin)
            );
            assert_eq!(
                format!("{:?}", traced.vertices),
                format!("{:?}", rebuilt.vertices)
            );
            stored_vertices += rebuilt.vertices.len();
            merging += rebuilt.vertices.iter().filter(|v| v.merges).count();
        }
        assert!(
            stored_vertices >= 5 && dispersed >= 5,
            "{stored_vertices} {dispersed}"
        );
        // The 64 subpaths are the iteration's all (8 × 8 pixels).
        assert_eq!(est.store.subpaths(), 64);
        assert_eq!(est.store.vertices.len(), merging);
        if params.merges == MergeRule::All {
            assert_eq!(merging, stored_vertices);
        }
    }

    #[test]
    fn the_caustic_rule_grids_only_vertices_after_near_specular_ones() {
        // A near-specular floor (conductor, GGX α 0.05) under the bulb and a diffuse ceiling
        // above it: light reaches the ceiling by the floor (L S D) and directly (L D).
        let mut desc = floor_desc();
        desc.materials.push(MaterialDesc {
            prim_path: "/Satin".into(),
            kind: MaterialKind::Conductor {
                eta: SpectrumDesc::Samples(vec![(360.0, 0.2), (830.0, 0.2)]),
                k: SpectrumDesc::Samples(vec![(360.0, 3.0), (830.0, 3.0)]),
                roughness: 0.05,
            },
            emission: None,
            textures: Vec::new(),
            texcoord: "st".into(),
        });
        desc.meshes[0].material = Some(0);
        let mut ceiling = desc.meshes[0].clone();
        ceiling.prim_path = "/Ceiling".into();
        ceiling.material = None;
        for p in &mut ceiling.positions {
            p.y = 2.0;
        }
        ceiling.indices = vec![[0, 1, 2], [0, 2, 3]];
        desc.meshes.push(ceiling);
        let scene = crate::scene::build(&desc, Some((8, 8))).unwrap();
        let settings = test_settings();
        let gridded = |merges| {
            let params = VcmParams {
                merges,
                ..VcmParams::default()
            };
            let mut est = VcmEstimator::new(&scene, settings, params);
            let mut all = Vec::new();
            for k in 0..16 {
                est.begin_iteration(Iteration { seed: 2, index: k });
                all.extend_from_slice(&est.store.vertices);
            }
            all
        };
        let (every, caustic) = (gridded(MergeRule::All), gridded(MergeRule::Caustic));
        // The caustic rule grids the ceiling's vertices lit by the floor, none lit directly
        // and none on the floor itself (its predecessor is the light or the ceiling).
        assert!(caustic.len() >= 20, "{}", caustic.len()); // 16 × 64 light subpaths
        assert!(
            every.len() >= 2 * caustic.len(),
            "{} {}",
            every.len(),
            caustic.len()
        );
        for v in &caustic {
            assert!(v.depth >= 2 && v.p.y > 1.9, "{v:?}");
        }
        assert!(every.iter().any(|v| v.depth == 1));
    }

    #[test]
    fn the_store_is_reused_and_memory_stays_flat_over_a_thousand_iterations() {
        let scene = floor_scene();
        let settings = test_settings();
        // Every vertex merges (the default rule merges nothing on this diffuse floor).
        let params = VcmParams {
            merges: MergeRule::All,
            ..VcmParams::default()
        };
        let mut est = VcmEstimator::new(&scene, settings, params);
        let mut peak_after_warmup = 0;
        for k in 0..1000 {
            est.begin_iteration(Iteration { seed: 1, index: k });
            assert!(est.merge.normalization.is_finite() && est.merge.normalization > 0.0);
            if k == 99 {
                peak_after_warmup = est.store.peak_bytes;
            }
        }
        // Light vertices per iteration vary (Russian roulette, misses); the buffers grow to
        // the largest iteration's and are then reused.
        assert!(peak_after_warmup > 0);
        assert!(
            est.store.peak_bytes <= peak_after_warmup * 3 / 2,
            "{} after 1000 iterations vs {peak_after_warmup} after 100",
            est.store.peak_bytes
        );
        assert!(!est.store.vertices.is_empty());
    }

    #[test]
    fn the_radius_follows_the_schedule_and_never_underflows() {
        let r0 = 0.01;
        assert_eq!(radius(r0, 0.75, 0), r0);
        let r = radius(r0, 0.75, 15);
        assert!((r / r0 - 16f32.powf(-0.125)).abs() < 1e-6, "{r}");
        assert_eq!(radius(r0, 1.0, 999_999), r0);
        let mut last = r0;
        for k in [10u64, 1000, 1_000_000, u64::MAX / 2] {
            let r = radius(r0, 0.05, k);
            assert!(
                r > 0.0 && r <= last && (PI * r * r * 1e6).is_normal(),
                "{k}: {r}"
            );
            last = r;
        }
    }

    #[test]
    fn iteration_wavelengths_are_stratified() {
        for m in 1..=4u32 {
            let n = 4u64.pow(m);
            // The first 4^m iterations put one hero in each of 4^m strata of [0, 1), and their
            // tuples (fixed by u mod 1/4, the lanes being a quarter apart) one in each of 4^m
            // strata of [0, 1/4): no tuple repeats.
            let mut heroes = vec![0u32; n as usize];
            let mut tuples = vec![0u32; n as usize];
            for k in 0..n {
                let u = stratified_u(k);
                heroes[(u * n as f64) as usize] += 1;
                tuples[((u % 0.25) * 4.0 * n as f64) as usize] += 1;
            }
            assert!(heroes.iter().all(|&c| c == 1), "{m}: {heroes:?}");
            assert!(tuples.iter().all(|&c| c == 1), "{m}: {tuples:?}");
        }
        for k in [0, 1, 17, 1 << 40, u64::MAX] {
            let u = iteration_u(3, k);
            assert!((0.0..1.0).contains(&u), "{k}: {u}");
            assert!((0.0..1.0).contains(&meter_iteration_u(3, k)));
        }
        // Even and odd iterations each run the whole stratified sequence, under shifts of
        // their own.
        for seed in [0, 3, 99] {
            let (s0, s1) = (iteration_u(seed, 0), iteration_u(seed, 1));
            assert_ne!(s0, s1);
            for m in 0..64u64 {
                for (k, s) in [(2 * m, s0), (2 * m + 1, s1)] {
                    let g = (f64::from(iteration_u(seed, k)) - f64::from(s)).rem_euclid(1.0);
                    let d = (g - stratified_u(m)).abs();
                    assert!(d.min(1.0 - d) < 1e-6, "seed {seed}, k {k}: {g}");
                }
            }
        }
    }
}
