//! Unidirectional path tracing with next-event estimation, multiple importance sampling
//! (power heuristic, Veach 1997 §9.2) between light and BSDF sampling, and Russian roulette
//! (PBR 4ed §13.4, the PathIntegrator) from bounce `rr_depth` on (`roulette.rs`).
//!
//! Depth counts scattering events as pbrt's `maxdepth`: depth 0 sees emitters directly,
//! `max_depth` = 7 allows up to seven bounces (Mitsuba's max_depth 8). Without a cap from the
//! user, Russian roulette ends paths and the safety cap `cut::SAFETY_DEPTH` stands behind it;
//! a path that reaches a cap is continued past it with probability q into a separate
//! accumulator, so the run can say what the cap cut (`cut.rs`).
//!
//! Two material hooks (`material/mod.rs`):
//! - **Opacity.** A surface is present with probability `Material::opacity()`; otherwise the
//!   ray continues unchanged from the hit and no vertex is counted (pbrt-v4's stochastic
//!   alpha). Shadow rays are attenuated by (1 − opacity) of every translucent surface they
//!   cross instead, the expected value of the same test.
//! - **Dispersion.** At a material whose refraction depends on λ the secondary wavelengths
//!   are terminated before the BSDF is built (docs/design.md §5). `li` works on its own copy of the
//!   wavelengths and re-expresses its estimate against the caller's pdfs on return, so the
//!   caller's `sampled_to_xyz(l, lambda)` stays unbiased without seeing the termination.

use super::bidir::Contribution;
use super::cut::{continuation, continuation_limit, continuation_of, CutSample};
use super::gathered::Gathered;
use super::meter::MeterIntegrator;
use super::radiance_memo::RadianceMemo;
use super::roulette;
use super::roulette_pilot::PilotGroup;
use super::{Estimator, Settings, Workspace};
use crate::bxdf::{Bsdf, BsdfAt, TransportMode};
use crate::geometry::offset::{spawn_ray, SpawnPoint};
use crate::geometry::Ray;
use crate::light::emission_layers::LayerSource;
use crate::light::{Light, LightHit, LightLiSample, LightSampleContext};
use crate::material::{Material, SpectraCache};
use crate::sampling::dimensions::{self, BSDF, LIGHT, ROULETTE};
use crate::sampling::{power_heuristic, Sampler};
use crate::scene::{ray_count, Hit, Scene, SurfaceHit};
use crate::sensor::meter::{MeterKind, MeterSensor};
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct PathIntegrator {
    pub max_depth: u32,
    /// The first scattering event after which Russian roulette may end a path
    /// (`roulette.rs`, `--rr-depth`).
    pub rr_depth: u32,
    /// Texture footprints: the camera's for images, none for meters.
    pub filter: TextureFilter,
    /// The continuations an image's path splits into at its first vertex (a power of two,
    /// `--split`: [`li_split`](Self::li_split)); 1 for meters and the bidirectional
    /// integrators' uses.
    pub split: u32,
}

/// What the previous vertex knew, for MIS when a BSDF-sampled ray finds an emitter.
#[derive(Clone, Copy)]
pub(crate) struct Previous {
    pub(crate) ctx: LightSampleContext,
    /// Solid-angle pdf with which the vertex sampled the ray's direction.
    pub(crate) pdf_bsdf_w: f32,
    pub(crate) specular: bool,
}

/// Where a path stands between vertices: what the loop carries from one to the next.
#[derive(Clone, Copy)]
struct PathState {
    ray: Ray,
    t_max: f32,
    prev: Option<Previous>,
    beta: SampledSpectrum,
    /// Product of η'² over the refractions so far: radiance is scaled by 1/η'² across an
    /// interface, which Russian roulette must not mistake for absorption (pbrt-v4
    /// `etaScale`, PBR 4ed §14.1.3).
    eta_scale: f32,
    /// Scattering events so far.
    depth: u32,
    /// Surfaces passed through (opacity) so far.
    pass_throughs: u32,
    /// The radiance at the path's wavelengths of the light class next event estimation
    /// sampled last (`radiance_memo.rs`).
    le: RadianceMemo,
}

/// A scattering vertex's BSDF, the point its rays leave from and its bounce's block of
/// dimensions (`dimensions::bounce`). The BSDF is the caller's local ([`PathIntegrator::prepare`]
/// builds it in place): held by value here (before session 40), it was built aside and copied
/// in, 284 bytes a vertex (design.md §8, "Samples/s against the build issue 18 was measured
/// on").
struct Vertex<'b> {
    bsdf: &'b Bsdf,
    from: SpawnPoint,
    block: u32,
}

impl<'b> Vertex<'b> {
    /// The vertex at `si` with the BSDF `bsdf` and the dimensions' `block`.
    #[inline(always)]
    fn new(si: &SurfaceHit, bsdf: &'b Bsdf, block: u32) -> Vertex<'b> {
        Vertex {
            bsdf,
            // The offset off the surface, shared by the shadow ray and the next ray.
            from: SpawnPoint::new(si.p, si.p_error, si.ng),
            block,
        }
    }
}

impl PathState {
    fn new(ray: Ray, t_max: f32, prev: Option<Previous>) -> PathState {
        PathState {
            ray,
            t_max,
            prev,
            beta: SampledSpectrum::ONE,
            eta_scale: 1.0,
            depth: 0,
            pass_throughs: 0,
            le: RadianceMemo::EMPTY,
        }
    }
}

impl PathIntegrator {
    /// Radiance arriving along `ray` (limited to t < t_max for the camera ray), at the path's
    /// wavelengths. Not yet divided by the wavelength pdfs. If the path terminated the
    /// secondary wavelengths (dispersion), the estimate is scaled by p(λ)/p'(λ) per lane, so
    /// that it is relative to `lambda`'s pdfs (the hero lane ×N, the others 0). A path that
    /// reaches the depth cap ends there (nothing is estimated beyond it).
    #[cfg(any(test, feature = "testing"))]
    pub fn li(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
    ) -> SampledSpectrum {
        let mut spectra = SpectraCache::default();
        self.li_from(scene, ray, t_max, None, lambda, sampler, None, &mut spectra)
    }

    /// [`li`](Self::li) that also continues a capped path past the cap into `cut`.
    #[cfg(any(test, feature = "testing"))]
    pub fn li_cut(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        cut: &mut CutSample,
    ) -> SampledSpectrum {
        let mut spectra = SpectraCache::default();
        self.li_from(
            scene,
            ray,
            t_max,
            None,
            lambda,
            sampler,
            Some(cut),
            &mut spectra,
        )
    }

    /// [`li`](Self::li) for a ray whose direction was sampled at vertex `prev` (None: a camera
    /// ray), so that emitters it finds are MIS-weighted against light sampling at that vertex.
    /// The light meters (`integrator::meter`) start paths here from their sensor point. With
    /// `cut`, a path that reaches the cap is counted there and continued past it with
    /// probability q (`cut.rs`), its light added to `cut` (relative to `lambda_in`, as the
    /// returned estimate). `spectra` is the thread's cache of the materials' spectra
    /// (`material::spectra`), begun here at `lambda_in`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn li_from(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        prev: Option<Previous>,
        lambda_in: &SampledWavelengths,
        sampler: &mut Sampler,
        cut: Option<&mut CutSample>,
        spectra: &mut SpectraCache,
    ) -> SampledSpectrum {
        let mut g = Gathered::plain();
        self.li_gather(
            scene, ray, t_max, prev, lambda_in, sampler, cut, &mut g, spectra,
        );
        g.l
    }

    /// [`li_from`](Self::li_from) gathering into `g`: the image's radiance in `g.l` and
    /// each emission layer's in `g.sums` (`integrator::gathered`), all relative to
    /// `lambda_in`. Inlined into its two callers (`image_sample`, `li_from`): −41
    /// instructions a sample as a call of its own (design.md §8, eighth pass).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn li_gather(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        prev: Option<Previous>,
        lambda_in: &SampledWavelengths,
        sampler: &mut Sampler,
        cut: Option<&mut CutSample>,
        g: &mut Gathered,
        spectra: &mut SpectraCache,
    ) {
        let mut lambda = *lambda_in;
        let mut st = PathState::new(ray, t_max, prev);
        spectra.begin(&scene.materials, lambda_in);
        let (depth, s) = (self.max_depth, &mut *spectra);
        let capped = if scene.dispersive {
            self.walk::<true>(scene, &mut st, depth, &mut lambda, sampler, g, s)
        } else {
            self.walk::<false>(scene, &mut st, depth, &mut lambda, sampler, g, s)
        };
        if let (Some(si), Some(cut)) = (capped, cut) {
            cut.capped += 1;
            if let Some(mut ext) = continuation(sampler) {
                let (c, limited) =
                    self.continue_past_cap(scene, &si, &st, &lambda, &mut ext, spectra);
                cut.add(lambda_in.rebase(c, &lambda), 1.0, limited);
            }
        }
        g.l = lambda_in.rebase(g.l, &lambda);
        for s in g.sums.iter_mut() {
            *s = lambda_in.rebase(*s, &lambda);
        }
    }

    /// [`li_gather`](Self::li_gather) with the path split at its first vertex into
    /// `self.split` (2^k) continuations: the camera ray, the first vertex's BSDF and next
    /// event estimation there are taken once, then each continuation samples its own
    /// direction from the vertex and walks on (its own roulette, its own wavelengths), on the
    /// sampler's continuation stream (`Sampler::enter_continuation`). The estimate is the mean
    /// of the continuations' full-path estimates, (1/n) Σ_c (shared + continuation c), each
    /// re-expressed against `lambda_in` with its own wavelengths: unbiased for any n chosen
    /// before the continuations are drawn (splitting, Rath et al. 2022, "EARS:
    /// Efficiency-Aware Russian Roulette and Splitting", §3; Arvo and Kirk 1990). A specular
    /// first vertex is not split (its continuations would share their direction), and a
    /// cap of 0 ends every path there: both are `li_gather`'s estimate itself. A call of its
    /// own: inlined into `image_sample` beside `li_gather` it slowed the unsplit samples.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn li_split<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        lambda_in: &SampledWavelengths,
        sampler: &mut Sampler,
        mut cut: Option<&mut CutSample>,
        g: &mut Gathered,
        (spectra, scratch): (&mut SpectraCache, &mut Vec<SampledSpectrum>),
    ) {
        let mut lambda = *lambda_in;
        let mut st = PathState::new(ray, t_max, None);
        spectra.begin(&scene.materials, lambda_in);
        let hit = self.next_vertex(scene, &mut st, &lambda, sampler, g);
        let Some(Hit::Surface(si)) = &hit else {
            return;
        };
        let wo = -st.ray.d;
        // Each decision draws from its own dimensions of this bounce (`dimensions.rs`).
        let block = dimensions::bounce(st.depth, 0);
        let bsdf = self.prepare::<DISPERSION>(scene, si, &mut st, &mut lambda, spectra);
        let v = Vertex::new(si, &bsdf, block);
        let at = v.bsdf.at(wo);
        self.nee(scene, si, &v, &at, &mut st, &lambda, sampler, g);
        let n = if v.bsdf.is_specular() { 1 } else { self.split };
        let bits = n.trailing_zeros();
        // The layers' shared sums, then their total over the continuations.
        let layers = g.sums.len();
        scratch.clear();
        scratch.extend_from_slice(g.sums);
        scratch.resize(2 * layers, SampledSpectrum::ZERO);
        let (shared_layers, sums) = scratch.split_at_mut(layers);
        let (shared, mut l, w) = (g.l, SampledSpectrum::ZERO, 1.0 / n as f32);
        for c in 0..n {
            if n > 1 {
                sampler.enter_continuation(c, bits);
            }
            let (mut sc, mut lc) = (st, lambda);
            g.l = shared;
            g.sums.copy_from_slice(shared_layers);
            let capped = if self.bounce(si, &v, &at, &mut sc, sampler) {
                self.walk::<DISPERSION>(
                    scene,
                    &mut sc,
                    self.max_depth,
                    &mut lc,
                    sampler,
                    g,
                    spectra,
                )
            } else {
                None
            };
            if let (Some(end), Some(cut)) = (capped, cut.as_deref_mut()) {
                cut.capped += 1;
                if let Some(mut ext) = continuation_of(sampler, c) {
                    let (x, limited) =
                        self.continue_past_cap(scene, &end, &sc, &lc, &mut ext, spectra);
                    cut.add(lambda_in.rebase(x, &lc), w, limited);
                }
            }
            l += lambda_in.rebase(g.l, &lc);
            for (sum, s) in sums.iter_mut().zip(g.sums.iter()) {
                *sum += lambda_in.rebase(*s, &lc);
            }
        }
        g.l = l * w;
        for (s, sum) in g.sums.iter_mut().zip(sums.iter()) {
            *s = *sum * w;
        }
    }

    /// One camera sample of the roulette pilot (`roulette_pilot.rs`): `li_split`'s walk
    /// without roulette, to this integrator's depth cap, split at the first vertex into two
    /// continuations (none at a specular vertex or a cap of 0), recording each group of
    /// contributions that one roulette test decides (the emission found on arriving at a
    /// vertex and next event estimation there), relative to `lambda_in`, with the ray queries
    /// it took and the max β·η² of the test before it (1 before the first). `shared` gets
    /// the first group (the camera ray, the first vertex's next event estimation: the
    /// emission the camera ray finds is not recorded, roulette and splitting do not touch
    /// it), `split[c]` continuation c's groups after it; `split[1]` stays empty when the
    /// path is not split. Returns how many continuations were taken (0 when the camera ray
    /// found no vertex to scatter at). No cut: the cap ends the path.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn pilot_walk(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        lambda_in: &SampledWavelengths,
        sampler: &mut Sampler,
        spectra: &mut SpectraCache,
        (shared, split): (&mut PilotGroup, &mut [Vec<PilotGroup>; 2]),
    ) -> u32 {
        let pt = PathIntegrator {
            rr_depth: u32::MAX,
            ..*self
        };
        if scene.dispersive {
            pt.pilot_split::<true>(
                scene, ray, t_max, lambda_in, sampler, spectra, shared, split,
            )
        } else {
            pt.pilot_split::<false>(
                scene, ray, t_max, lambda_in, sampler, spectra, shared, split,
            )
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn pilot_split<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        lambda_in: &SampledWavelengths,
        sampler: &mut Sampler,
        spectra: &mut SpectraCache,
        shared: &mut PilotGroup,
        split: &mut [Vec<PilotGroup>; 2],
    ) -> u32 {
        split.iter_mut().for_each(Vec::clear);
        let mut lambda = *lambda_in;
        let mut st = PathState::new(ray, t_max, None);
        spectra.begin(&scene.materials, lambda_in);
        let mut g = Gathered::plain();
        let rays0 = ray_count::on_this_thread();
        let hit = self.next_vertex(scene, &mut st, &lambda, sampler, &mut g);
        // Emitters the camera sees directly are left out.
        g.l = SampledSpectrum::ZERO;
        let first = match &hit {
            Some(Hit::Surface(si)) if self.max_depth > 0 => Some(*si),
            _ => None,
        };
        let Some(si) = first else {
            let rays = ray_count::on_this_thread().wrapping_sub(rays0) as u32;
            *shared = PilotGroup {
                l: g.l,
                b: 1.0,
                rays,
            };
            return 0;
        };
        let wo = -st.ray.d;
        let block = dimensions::bounce(st.depth, 0);
        let bsdf = self.prepare::<DISPERSION>(scene, &si, &mut st, &mut lambda, spectra);
        let v = Vertex::new(&si, &bsdf, block);
        let at = v.bsdf.at(wo);
        self.nee(scene, &si, &v, &at, &mut st, &lambda, sampler, &mut g);
        *shared = PilotGroup {
            l: lambda_in.rebase(g.l, &lambda),
            b: 1.0,
            rays: ray_count::on_this_thread().wrapping_sub(rays0) as u32,
        };
        let n = if v.bsdf.is_specular() { 1 } else { 2 };
        for (c, out) in split.iter_mut().enumerate().take(n) {
            if n > 1 {
                sampler.enter_continuation(c as u32, 1);
            }
            let (mut sc, mut lc) = (st, lambda);
            let rays0 = ray_count::on_this_thread();
            if !self.bounce(&si, &v, &at, &mut sc, sampler) {
                continue;
            }
            let b = sc.beta.max_value() * sc.eta_scale;
            let rays = ray_count::on_this_thread().wrapping_sub(rays0) as u32;
            self.pilot_groups::<DISPERSION>(
                scene, &mut sc, &mut lc, lambda_in, b, rays, sampler, spectra, out,
            );
        }
        n as u32
    }

    /// The groups of a pilot's continuation from the state `st` (its ray leaving a vertex),
    /// `b` the max β·η² of the test before the first, `rays` those already taken.
    #[allow(clippy::too_many_arguments)]
    fn pilot_groups<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        st: &mut PathState,
        lambda: &mut SampledWavelengths,
        lambda_in: &SampledWavelengths,
        mut b: f32,
        mut rays: u32,
        sampler: &mut Sampler,
        spectra: &mut SpectraCache,
        out: &mut Vec<PilotGroup>,
    ) {
        let mut g = Gathered::plain();
        loop {
            let (l0, rays0) = (g.l, ray_count::on_this_thread());
            let hit = self.next_vertex(scene, st, lambda, sampler, &mut g);
            let more = match &hit {
                Some(Hit::Surface(si)) if st.depth < self.max_depth => {
                    self.scatter::<DISPERSION>(scene, si, st, lambda, sampler, &mut g, spectra)
                }
                _ => false,
            };
            rays += ray_count::on_this_thread().wrapping_sub(rays0) as u32;
            out.push(PilotGroup {
                l: lambda_in.rebase(g.l - l0, lambda),
                b,
                rays,
            });
            if !more {
                return;
            }
            (b, rays) = (st.beta.max_value() * st.eta_scale, 0);
        }
    }

    /// The light a path capped at vertex `si` (its state `st`, its wavelengths `lambda`) would
    /// have found beyond the cap, on the continuation's sampler `ext`, relative to `lambda`'s
    /// pdfs; true when the continuation reached its own limit (`cut::continuation_limit`).
    /// `spectra` holds the materials' spectra at `lambda` (the path's).
    fn continue_past_cap(
        &self,
        scene: &Scene,
        si: &SurfaceHit,
        st: &PathState,
        lambda: &SampledWavelengths,
        ext: &mut Sampler,
        spectra: &mut SpectraCache,
    ) -> (SampledSpectrum, bool) {
        let mut st = *st;
        let mut g = Gathered::plain();
        let mut lambda_ext = *lambda;
        let (limit, s) = (continuation_limit(self.max_depth), spectra);
        let limited = if scene.dispersive {
            self.scatter::<true>(scene, si, &mut st, &mut lambda_ext, ext, &mut g, s)
                && self
                    .walk::<true>(scene, &mut st, limit, &mut lambda_ext, ext, &mut g, s)
                    .is_some()
        } else {
            self.scatter::<false>(scene, si, &mut st, &mut lambda_ext, ext, &mut g, s)
                && self
                    .walk::<false>(scene, &mut st, limit, &mut lambda_ext, ext, &mut g, s)
                    .is_some()
        };
        (lambda.rebase(g.l, &lambda_ext), limited)
    }

    /// The light beyond the cap of a path capped at vertex `si`, reached along `-wo` with
    /// `depth` scattering events before it, per unit throughput: the path tracer continued
    /// from there on `ext` (BDPT's and VCM's camera subpaths, `cut.rs`). Relative to
    /// `lambda`'s pdfs; true when it reached its own limit. `spectra`: the thread's cache of
    /// the materials' spectra, begun here at `lambda`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn continue_from_vertex(
        &self,
        scene: &Scene,
        si: &SurfaceHit,
        wo: Vec3,
        depth: u32,
        lambda: &SampledWavelengths,
        ext: &mut Sampler,
        spectra: &mut SpectraCache,
    ) -> (SampledSpectrum, bool) {
        // Only the arriving ray's direction is read at `si` (wo = −d).
        let mut st = PathState::new(Ray::new(si.p + wo, -wo), f32::INFINITY, None);
        st.depth = depth;
        spectra.begin(&scene.materials, lambda);
        self.continue_past_cap(scene, si, &st, lambda, ext, spectra)
    }

    /// The path-tracing loop from `st` until the path ends (None) or reaches a vertex at
    /// depth `limit` (that vertex, its emission counted, `st` as it arrived there). With
    /// `DISPERSION` (the scene has a dispersive material) each vertex checks whether to
    /// terminate the secondary wavelengths of `lambda`; without, no check runs. Inlined
    /// into its callers (once a sample from `li_gather`): −17 instructions a sample.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn walk<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        st: &mut PathState,
        limit: u32,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        g: &mut Gathered,
        spectra: &mut SpectraCache,
    ) -> Option<SurfaceHit> {
        loop {
            // The hit is read in place: `?` on the Option copied its 80 bytes out at every
            // vertex (design.md §8, "The per-sample cost, seventh pass").
            let hit = self.next_vertex(scene, st, lambda, sampler, g);
            let Some(Hit::Surface(si)) = &hit else {
                return None;
            };
            if st.depth == limit {
                return Some(*si);
            }
            if !self.scatter::<DISPERSION>(scene, si, st, lambda, sampler, g, spectra) {
                return None;
            }
        }
    }

    /// Follows `st.ray` to the next surface the path scatters at (passing through surfaces
    /// that are absent for this path), adding the emission it finds to `l`: always a
    /// `Hit::Surface`, or None when the path ends (escaped, an analytic light, too many
    /// pass-throughs).
    /// Inlined into the walk, its only caller: LLVM left it a call of its own, whose frame and
    /// `Option<Hit>` return cost about 100 instructions a sample (design.md §8, eighth pass).
    #[inline(always)]
    fn next_vertex(
        &self,
        scene: &Scene,
        st: &mut PathState,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        g: &mut Gathered,
    ) -> Option<Hit> {
        loop {
            let hit = scene.intersect(&st.ray, st.t_max);
            // The common answer, a non-emitting surface of an all-opaque scene, goes back as
            // it came, `Scene::intersect`'s answer itself, rather than taken apart and
            // rebuilt (two copies fewer).
            if let Some(Hit::Surface(si)) = &hit {
                if scene.all_opaque && si.light.is_none() {
                    return hit;
                }
            }
            let si = match hit {
                Some(Hit::Surface(si)) => si,
                Some(Hit::Light { light, hit }) => {
                    self.add_emitted(scene, light, &hit, st, lambda, g);
                    return None;
                }
                None => {
                    self.add_escaped(scene, st, lambda, g);
                    return None;
                }
            };
            // An all-opaque scene has every surface present (no draw either way).
            let material = || &scene.materials[si.material as usize];
            if !scene.all_opaque && !surface_present(material(), si.uv, sampler) {
                st.pass_throughs += 1;
                if st.pass_throughs > MAX_PASS_THROUGHS {
                    return None;
                }
                st.ray = spawn_ray(si.p, si.p_error, si.ng, st.ray.d);
                st.t_max -= si.t;
                continue;
            }
            if let Some(light) = si.light {
                let lh = LightHit {
                    p: si.p,
                    n: si.ng,
                    t: si.t,
                };
                self.add_emitted(scene, light, &lh, st, lambda, g);
            }
            return Some(Hit::Surface(si));
        }
    }

    /// One scattering event at `si`: next-event estimation into `l`, a BSDF-sampled
    /// direction and Russian roulette; false when the path ends. Inlined into the walk (and
    /// the cut's continuation): as a call it cost about 19 instructions a vertex in frame and
    /// arguments (design.md §8, eighth pass). Its three steps are also those of a path split
    /// at its first vertex (`li_split`), which takes the first two once and the third once a
    /// continuation.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn scatter<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        si: &SurfaceHit,
        st: &mut PathState,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        g: &mut Gathered,
        spectra: &mut SpectraCache,
    ) -> bool {
        let wo = -st.ray.d;
        let block = dimensions::bounce(st.depth, 0);
        let bsdf = self.prepare::<DISPERSION>(scene, si, st, lambda, spectra);
        let v = Vertex::new(si, &bsdf, block);
        // The BSDF's terms of ωo, shared by next event estimation and the BSDF sample.
        let at = v.bsdf.at(wo);
        self.nee(scene, si, &v, &at, st, lambda, sampler, g);
        self.bounce(si, &v, &at, st, sampler)
    }

    /// The vertex's BSDF; counts the scattering event and terminates the secondary
    /// wavelengths at a dispersive material. The caller takes the bounce's block of
    /// dimensions before (`dimensions::bounce` of the depth before the count) and makes the
    /// [`Vertex`] after.
    #[inline(always)]
    fn prepare<const DISPERSION: bool>(
        &self,
        scene: &Scene,
        si: &SurfaceHit,
        st: &mut PathState,
        lambda: &mut SampledWavelengths,
        spectra: &mut SpectraCache,
    ) -> Bsdf {
        st.depth += 1;
        let index = si.material as usize;
        let material = &scene.materials[index];
        if DISPERSION && material.is_dispersive() {
            lambda.terminate_secondary();
        }
        let tc = scene.tex_coord(si, self.filter);
        spectra.bsdf(material, index, tc, si.ns, lambda)
    }

    /// Next-event estimation at the vertex `v` (none at a specular one), into `g`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn nee(
        &self,
        scene: &Scene,
        si: &SurfaceHit,
        v: &Vertex,
        at: &BsdfAt,
        st: &mut PathState,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        g: &mut Gathered,
    ) {
        if !v.bsdf.is_specular() {
            sampler.set_dimension(dimensions::in_block(v.block, LIGHT));
            let l = (st.beta, &mut st.le);
            self.sample_ld(scene, (si, &v.from), at, lambda, sampler, l, g);
        }
    }

    /// The BSDF-sampled direction from the vertex `v` into `st` and Russian roulette; false
    /// when the path ends.
    #[inline(always)]
    fn bounce(
        &self,
        si: &SurfaceHit,
        v: &Vertex,
        at: &BsdfAt,
        st: &mut PathState,
        sampler: &mut Sampler,
    ) -> bool {
        sampler.set_dimension(dimensions::in_block(v.block, BSDF));
        let (uc, u) = (sampler.get_1d(), sampler.get_2d());
        let Some(bs) = at.sample_f(uc, u, TransportMode::Radiance) else {
            return false;
        };
        st.beta *= bs.f * (bs.wi.dot(si.ns).abs() / bs.pdf_w);
        if bs.transmission {
            st.eta_scale *= bs.eta * bs.eta;
        }
        st.prev = Some(Previous {
            ctx: LightSampleContext { p: si.p, n: si.ng },
            pdf_bsdf_w: bs.pdf_w,
            specular: bs.specular,
        });
        st.ray = v.from.ray(bs.wi);
        st.t_max = f32::INFINITY;
        sampler.set_dimension(dimensions::in_block(v.block, ROULETTE));
        roulette::survives(&mut st.beta, st.eta_scale, st.depth, self.rr_depth, sampler)
    }

    /// The emission of area light `light` met at `hit` by the path in state `st`, into the
    /// image and every layer (a replacing layer evaluates its own light there).
    #[inline]
    fn add_emitted(
        &self,
        scene: &Scene,
        light: u32,
        hit: &LightHit,
        st: &PathState,
        lambda: &SampledWavelengths,
        g: &mut Gathered,
    ) {
        let (w, prev) = (-st.ray.d, st.prev);
        let le = self.emitted(scene, &scene.lights, light, hit, w, prev, lambda);
        g.l += st.beta * le;
        for (layer, sum) in g.layers.iter().zip(g.sums.iter_mut()) {
            match &layer.source {
                LayerSource::Group(mask) if mask[light as usize] => *sum += st.beta * le,
                LayerSource::Group(_) => {}
                LayerSource::Replaced(lights) => {
                    let le = self.emitted(scene, lights, light, hit, w, prev, lambda);
                    *sum += st.beta * le;
                }
            }
        }
    }

    /// The infinite lights' radiance along the escaped ray of the path in state `st`, into
    /// the image and every layer.
    #[inline]
    fn add_escaped(
        &self,
        scene: &Scene,
        st: &PathState,
        lambda: &SampledWavelengths,
        g: &mut Gathered,
    ) {
        let (d, prev) = (st.ray.d, st.prev);
        g.l += st.beta * self.escaped(scene, &scene.lights, |_| true, d, prev, lambda);
        for (layer, sum) in g.layers.iter().zip(g.sums.iter_mut()) {
            let le = match &layer.source {
                LayerSource::Group(mask) => {
                    self.escaped(scene, &scene.lights, |i| mask[i], d, prev, lambda)
                }
                LayerSource::Replaced(lights) => {
                    self.escaped(scene, lights, |_| true, d, prev, lambda)
                }
            };
            *sum += st.beta * le;
        }
    }

    /// Emission from area light `light` of `lights` (the scene's, or a layer's replacement
    /// of them) met by the path, MIS-weighted against light sampling.
    #[allow(clippy::too_many_arguments)]
    fn emitted(
        &self,
        scene: &Scene,
        lights: &[Light],
        light: u32,
        hit: &LightHit,
        w: Vec3,
        prev: Option<Previous>,
        lambda: &SampledWavelengths,
    ) -> SampledSpectrum {
        let lgt = &lights[light as usize];
        let le = lgt.l(hit, w, lambda);
        match prev {
            // Next event estimation took all of a shadowless light's direct light.
            Some(p) if !p.specular && !scene.casts_shadows(light) => SampledSpectrum::ZERO,
            Some(p) if !p.specular && !le.is_black() => {
                let pdf_light = scene.light_sampler.pmf_at(&p.ctx, light as usize)
                    * lgt.pdf_li(&p.ctx, -w, hit);
                le * power_heuristic(p.pdf_bsdf_w, pdf_light)
            }
            _ => le,
        }
    }

    /// Radiance from the infinite lights of `lights` (the scene's or a layer's) with index
    /// in `include` along an escaped ray.
    fn escaped(
        &self,
        scene: &Scene,
        lights: &[Light],
        include: impl Fn(usize) -> bool,
        d: Vec3,
        prev: Option<Previous>,
        lambda: &SampledWavelengths,
    ) -> SampledSpectrum {
        // No infinite light: the sum below is zero; answered before its loop is set up.
        if scene.infinite_lights.is_empty() {
            return SampledSpectrum::ZERO;
        }
        let far = LightHit {
            p: Vec3::ZERO,
            n: Vec3::ZERO,
            t: f32::INFINITY,
        };
        let mut l = SampledSpectrum::ZERO;
        for &i in &scene.infinite_lights {
            if !include(i as usize) {
                continue;
            }
            let lgt = &lights[i as usize];
            let le = lgt.le(d, lambda);
            if le.is_black() {
                continue;
            }
            l += match prev {
                Some(p) if !p.specular && !scene.casts_shadows(i) => SampledSpectrum::ZERO,
                Some(p) if !p.specular => {
                    let pdf_light = scene.light_sampler.pmf_at(&p.ctx, i as usize)
                        * lgt.pdf_li(&p.ctx, d, &far);
                    le * power_heuristic(p.pdf_bsdf_w, pdf_light)
                }
                _ => le,
            };
        }
        l
    }

    /// Next-event estimation: one light chosen by the scene's light sampler (by power, or by its
    /// importance at this vertex: `light::spatial`), one point on it, MIS-weighted
    /// against BSDF sampling (Veach 1997 eq. 9.13 with β = 2), × `beta` into the image and
    /// every layer. A replacing layer samples its own light with the same numbers (the same
    /// point: only the spectrum differs) and shares the BSDF value, the shadow ray and the
    /// MIS weight, computed once. `from` is the vertex's [`SpawnPoint`], `bsdf` the BSDF at
    /// the path's ωo, `le` the path's memo of the light's radiance.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn sample_ld(
        &self,
        scene: &Scene,
        (si, from): (&SurfaceHit, &SpawnPoint),
        bsdf: &BsdfAt,
        lambda: &SampledWavelengths,
        sampler: &mut Sampler,
        (beta, le): (SampledSpectrum, &mut RadianceMemo),
        g: &mut Gathered,
    ) {
        let (ul, u) = (sampler.get_1d(), sampler.get_2d());
        let ctx = LightSampleContext { p: si.p, n: si.ng };
        let Some((light, pmf)) = scene.light_sampler.sample_at(&ctx, ul) else {
            return;
        };
        let nee = Nee {
            scene,
            si,
            from,
            bsdf,
            light,
            pmf,
        };
        let mut shared = None;
        let le = le.get((&scene.lights, &scene.radiance_class), light, lambda);
        let main = scene.lights[light]
            .sample_li_given(&ctx, u, lambda, le)
            .map_or(SampledSpectrum::ZERO, |ls| nee.term(&ls, &mut shared));
        g.l += beta * main;
        for (layer, sum) in g.layers.iter().zip(g.sums.iter_mut()) {
            match &layer.source {
                LayerSource::Group(mask) if mask[light] => *sum += beta * main,
                LayerSource::Group(_) => {}
                LayerSource::Replaced(lights) => {
                    if let Some(ls) = lights[light].sample_li(&ctx, u, lambda) {
                        *sum += beta * nee.term(&ls, &mut shared);
                    }
                }
            }
        }
    }
}

/// A next-event estimate's vertex and chosen light.
struct Nee<'a> {
    scene: &'a Scene,
    si: &'a SurfaceHit,
    /// Where the shadow ray leaves `si` from.
    from: &'a SpawnPoint,
    /// The BSDF at the path's ωo.
    bsdf: &'a BsdfAt<'a>,
    light: usize,
    pmf: f32,
}

/// What a light sample's estimate shares with the other layers' samples of the same point:
/// the BSDF value × cos, the transmittance, the light pdf and the MIS weight.
type Shared = (SampledSpectrum, f32, f32, f32);

impl Nee<'_> {
    /// The estimate f · L · tr · w / p of light sample `ls` (0 where it carries nothing).
    #[inline]
    fn term(&self, ls: &LightLiSample, shared: &mut Option<Shared>) -> SampledSpectrum {
        if ls.l.is_black() || ls.pdf_w == 0.0 {
            return SampledSpectrum::ZERO;
        }
        let (f, tr, pdf_light, w) = *shared.get_or_insert_with(|| self.shared(ls));
        if f.is_black() || tr == 0.0 {
            return SampledSpectrum::ZERO;
        }
        if ls.delta || !self.scene.casts_shadows(self.light as u32) {
            return f * ls.l * (tr / pdf_light);
        }
        f * ls.l * (tr * w / pdf_light)
    }

    fn shared(&self, ls: &LightLiSample) -> Shared {
        let si = self.si;
        // f and the BSDF's pdf of ωi together: one frame change, shared microfacet terms.
        let (f, pdf_bsdf) = self.bsdf.f_pdf(ls.wi, TransportMode::Radiance);
        let f = f * ls.wi.dot(si.ns).abs();
        if f.is_black() {
            return (f, 0.0, 0.0, 0.0);
        }
        let tr = transmittance(self.scene, self.from, ls, self.light as u32);
        let pdf_light = self.pmf * ls.pdf_w;
        // A shadowless light's direct light is all next event estimation's (its BSDF-sampled
        // hits count nothing, `emitted`), so its weight is 1 as a delta light's.
        let w = if ls.delta || tr == 0.0 || !self.scene.casts_shadows(self.light as u32) {
            1.0
        } else {
            power_heuristic(pdf_light, pdf_bsdf)
        };
        (f, tr, pdf_light, w)
    }
}

/// How many surfaces with opacity < 1 a ray may pass through before it is given up.
const MAX_PASS_THROUGHS: u32 = 256;

/// The stochastic opacity test: true when the surface is there for this path. A path may
/// take it any number of times between two bounces, so it draws outside the dimension
/// layout (`Sampler::get_1d_free`).
#[inline]
fn surface_present(material: &Material, uv: Vec2, sampler: &mut Sampler) -> bool {
    let a = material.opacity(uv);
    a >= 1.0 || (a > 0.0 && sampler.get_1d_free() < a)
}

/// The shadow ray from a surface point to a light sample, and its t_max: towards an infinite
/// light's direction, else to the sample's point, which has no error to offset (a light's
/// sampled point is exact: `spawn_ray_to` with error 0 there, `geometry::offset`).
#[inline]
fn shadow_ray(from: &SpawnPoint, ls: &LightLiSample) -> (Ray, f32) {
    if ls.infinite {
        (from.ray(ls.wi), f32::INFINITY)
    } else {
        from.ray_to_exact(ls.p_light)
    }
}

/// The fraction of the light sample's radiance that reaches the surface point `from`: 0
/// behind an opaque surface, the product of (1 − opacity) over the translucent surfaces in
/// between, else 1.
/// Inlined into next event estimation (`Nee::shared`, the meters): a call of its own cost a
/// frame per shadow ray (design.md §8, eighth pass).
#[inline(always)]
pub(crate) fn transmittance(
    scene: &Scene,
    from: &SpawnPoint,
    ls: &LightLiSample,
    light: u32,
) -> f32 {
    if !scene.casts_shadows(light) {
        return 1.0;
    }
    let (ray, t) = shadow_ray(from, ls);
    if !scene.occluded(&ray, t, Some(light)) {
        return 1.0;
    }
    if scene.all_opaque {
        return 0.0;
    }
    translucent_transmittance(scene, ray, t, ls, light)
}

/// [`transmittance`] past the first surface the shadow ray `(ray, t)` met, in a scene that
/// is not all opaque: its own function, so that the common answers above (unshadowed, or
/// opaque scenes' blocked rays) take no frame for this loop.
#[cold]
#[inline(never)]
fn translucent_transmittance(
    scene: &Scene,
    mut ray: Ray,
    mut t: f32,
    ls: &LightLiSample,
    light: u32,
) -> f32 {
    let mut tr = 1.0;
    for _ in 0..MAX_PASS_THROUGHS {
        let si = match scene.intersect(&ray, t) {
            None => return tr,
            Some(Hit::Light { light: l, .. }) => return if l == light { tr } else { 0.0 },
            Some(Hit::Surface(si)) => si,
        };
        let opacity = scene.materials[si.material as usize].opacity(si.uv);
        tr *= 1.0 - opacity.clamp(0.0, 1.0);
        if tr == 0.0 {
            return 0.0;
        }
        (ray, t) = shadow_ray(&SpawnPoint::new(si.p, si.p_error, si.ng), ls);
        if !scene.occluded(&ray, t, Some(light)) {
            return tr;
        }
    }
    0.0
}

/// The path tracer as an [`Estimator`]: camera rays for images, the meter estimators of
/// `meter.rs` for light meters.
pub struct PathEstimator<'a> {
    scene: &'a Scene,
    pt: PathIntegrator,
}

impl<'a> PathEstimator<'a> {
    pub fn new(scene: &'a Scene, settings: Settings) -> PathEstimator<'a> {
        PathEstimator {
            scene,
            pt: PathIntegrator {
                max_depth: settings.max_depth,
                rr_depth: settings.rr_depth,
                filter: settings.filter,
                split: if settings.meters { 1 } else { settings.split },
            },
        }
    }
}

impl Estimator for PathEstimator<'_> {
    /// `Camera::generate_ray` reads the lens sample only for a thin lens.
    fn reads_lens(&self) -> bool {
        self.scene.camera.lens_radius > 0.0
    }

    fn image_sample(
        &self,
        film: [f32; 2],
        u_lens: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) {
        let (ray, t_max) = self.scene.camera.generate_ray(film, u_lens);
        let rec = &mut ws.record;
        let scratch = &mut rec.split_layers;
        let layers = &self.scene.emission_layers.layers;
        rec.layers.resize(layers.len(), SampledSpectrum::ZERO);
        let mut g = Gathered {
            l: SampledSpectrum::ZERO,
            layers,
            sums: &mut rec.layers,
        };
        let cut = Some(&mut rec.cut);
        let spectra = &mut ws.light.spectra;
        let (pt, scene) = (&self.pt, self.scene);
        match (pt.split > 1 && pt.max_depth > 0, scene.dispersive) {
            (false, _) => pt.li_gather(
                scene, ray, t_max, None, lambda, sampler, cut, &mut g, spectra,
            ),
            (true, false) => {
                let work = (spectra, scratch);
                pt.li_split::<false>(scene, ray, t_max, lambda, sampler, cut, &mut g, work)
            }
            (true, true) => {
                let work = (spectra, scratch);
                pt.li_split::<true>(scene, ray, t_max, lambda, sampler, cut, &mut g, work)
            }
        }
        rec.camera = Contribution::new(g.l, 1.0);
    }

    fn meter_sample(
        &self,
        m: &MeterSensor,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum {
        let meter = MeterIntegrator { path: self.pt };
        match m.kind {
            MeterKind::Illuminance => {
                meter.irradiance(self.scene, m.p, m.p_error, m.dir, lambda, sampler, ws)
            }
            MeterKind::Luminance => {
                meter.radiance(self.scene, m.p, m.p_error, m.dir, lambda, sampler, ws)
            }
        }
    }
}
