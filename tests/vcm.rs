//! VCM against a closed form on a path class no other estimator can sample: a caustic seen
//! only in a mirror (E–S–D–S–L).
//!
//! A tiny sphere light (r = 0.1 mm, a point for every purpose but its finite luminance) hangs
//! 10 cm above a Lambertian floor (ρ = 0.5) beside a vertical aluminium mirror A, which
//! throws a caustic onto the floor; a black card just below the light shades the floor patch
//! from the light itself. The camera sees that patch only through a second mirror B tilted
//! 45° above it: every pixel's ray reflects off B down to the floor. The patch is lit only
//! through A (E–S–D–S–L): no connection can end on a specular vertex and no camera path can
//! hit a 0.1 mm light after two specular bounces (it would with probability ~10⁻⁸ per
//! path), so path tracing and BDPT estimate 0, while merging at the floor finds the caustic.
//!
//! Closed form, per pixel: the camera ray (the renderer's own camera model) reflects off B to
//! the floor point x; the luminance there is ρ/π · (E_direct + E_A), with the irradiance of a
//! sphere of luminance L and radius r, E = π r² L cos θ / d² (exact for a sphere above the
//! horizon), from the light and from its image in A (the image-source method: the segment
//! from the image to x must cross A's rectangle), times A's Fresnel reflectance R(θ_A, λ);
//! the pixel sees that times B's R(θ_B, λ). R is the unpolarised Fresnel reflectance of a
//! conductor with complex index n + ik (Born and Wolf, Principles of Optics §14.2), computed
//! here in f64 from the aluminium table of `spectra/metal/Al.csv`, and the luminance
//! Y = K_m ∫ L(λ) ȳ(λ) dλ over the light's D65 spectrum on the 1 nm grid. With max depth 3
//! nothing else reaches the pixels (floor → mirror → floor interreflection needs 4 events).

mod common;
use common::*;
use glam::DVec3;
use spectral_render::integrator::bidir::MergeRule;
use spectral_render::integrator::vcm::{VcmMode, VcmParams, IMAGE_RADIUS_FOOTPRINTS};
use spectral_render::scene::Scene;
use spectral_render::session::{self, RenderOptions};
use spectral_render::spectral::data;
use spectral_render::{Integrator, MisHeuristic};

const LIGHT: DVec3 = DVec3::new(0.0, 0.1, 0.0);
const LIGHT_RADIUS: f64 = 1.0e-4;
const LIGHT_NITS: f64 = 8.0e7;
const RHO: f64 = 0.5;
const MAX_DEPTH: u32 = 3;
const RES: u32 = 32;

/// A mirror rectangle: centre, unit normal, and half-extent vectors.
#[derive(Clone, Copy)]
struct Mirror {
    c: DVec3,
    n: DVec3,
    u: DVec3,
    v: DVec3,
}

impl Mirror {
    fn corners(&self) -> [DVec3; 4] {
        let (c, u, v) = (self.c, self.u, self.v);
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// The point where segment a → b crosses the mirror's rectangle, if it does.
    fn crossing(&self, a: DVec3, b: DVec3) -> Option<DVec3> {
        let (da, db) = ((a - self.c).dot(self.n), (b - self.c).dot(self.n));
        if da * db >= 0.0 {
            return None;
        }
        let p = a + (b - a) * (da / (da - db));
        let q = p - self.c;
        let inside = |e: DVec3| q.dot(e).abs() <= e.length_squared();
        (inside(self.u) && inside(self.v)).then_some(p)
    }

    fn image(&self, p: DVec3) -> DVec3 {
        p - 2.0 * (p - self.c).dot(self.n) * self.n
    }
}

/// Mirror A: x = 0.1, facing −x, 30 cm tall from the floor, 60 cm wide.
const MIRROR_A: Mirror = Mirror {
    c: DVec3::new(0.1, 0.15, 0.0),
    n: DVec3::new(-1.0, 0.0, 0.0),
    u: DVec3::new(0.0, 0.15, 0.0),
    v: DVec3::new(0.0, 0.0, 0.3),
};

/// The black card shading the patch from the light: vertical, 1 cm to its left, from 6 to
/// 20 cm above the floor — above the caustic's rays from A to the patch (at most 5.3 cm high
/// there), below the light's own rays to it (at least 8 cm).
const CARD: Mirror = Mirror {
    c: DVec3::new(-0.01, 0.13, 0.0),
    n: DVec3::new(1.0, 0.0, 0.0),
    u: DVec3::new(0.0, 0.07, 0.0),
    v: DVec3::new(0.0, 0.0, 0.3),
};

/// Mirror B: above the floor patch around (−0.15, 0, 0), tilted 45° to send the camera's
/// +x view down.
fn mirror_b() -> Mirror {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    Mirror {
        c: DVec3::new(-0.15, 0.25, 0.0),
        n: DVec3::new(-s, -s, 0.0),
        u: DVec3::new(s, -s, 0.0) * 0.1,
        v: DVec3::new(0.0, 0.0, 0.08),
    }
}

fn stage() -> String {
    let p = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
    let aluminium = "        uniform token inputs:metal = \"Al\"\n";
    let mut s = header();
    s += &looks_scope(
        &(material("Floor", "spectral:diffuse", &flat_reflectance(RHO))
            + &material("Mirror", "spectral:conductor", aluminium)
            + &material("Black", "spectral:diffuse", &flat_reflectance(0.0))),
    );
    s += &polygon("Card", &CARD.corners().map(p), None, &binding("Black"));
    let floor = [
        [-1.0f32, 0.0, -1.0],
        [1.0, 0.0, -1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, 1.0],
    ];
    s += &polygon("Floor", &floor, None, &binding("Floor"));
    for (name, m) in [("MirrorA", MIRROR_A), ("MirrorB", mirror_b())] {
        s += &polygon(name, &m.corners().map(p), None, &binding("Mirror"));
    }
    s += &prim(
        "SphereLight",
        "Bulb",
        &(format!(
            "    float inputs:radius = {LIGHT_RADIUS}\n    float inputs:intensity = {LIGHT_NITS}\n"
        ) + &xform(&[(
            "translate",
            format!("({}, {}, {})", LIGHT.x, LIGHT.y, LIGHT.z),
        )])),
    );
    // At (−0.65, 0.25, 0) looking along +x (rotateY −90 turns −Z to +X), B filling the view.
    s += &prim(
        "Camera",
        "Cam",
        &("    float focalLength = 100\n    float horizontalAperture = 20\n    float verticalAperture = 20\n    float2 clippingRange = (0.01, 100)\n".to_string()
            + &xform(&[
                ("translate", "(-0.65, 0.25, 0)".into()),
                ("rotateY", "-90".into()),
            ])),
    );
    s
}

/// Unpolarised Fresnel reflectance of a conductor n + ik at incidence cos θ (Born & Wolf
/// §14.2, the exact form with a² and b²).
fn conductor_reflectance(cos: f64, n: f64, k: f64) -> f64 {
    let (c2, s2) = (cos * cos, 1.0 - cos * cos);
    let t = n * n - k * k - s2;
    let a2b2 = (t * t + 4.0 * n * n * k * k).sqrt();
    let a = (0.5 * (a2b2 + t)).max(0.0).sqrt();
    let rs = (a2b2 + c2 - 2.0 * a * cos) / (a2b2 + c2 + 2.0 * a * cos);
    let rp = rs * (a2b2 * c2 + s2 * s2 - 2.0 * a * cos * s2)
        / (a2b2 * c2 + s2 * s2 + 2.0 * a * cos * s2);
    0.5 * (rs + rp)
}

/// The expected luminance of every pixel, and of the same pixels without the caustic.
fn expected(scene: &Scene) -> (Vec<f64>, Vec<f64>) {
    let b = mirror_b();
    let (eta, k) = data::metal("Al").unwrap();
    let d65 = data::illuminant("CIE-D65").unwrap();
    let ybar = &data::cie_xyz()[1];
    let lambdas: Vec<f32> = (360..=830).map(|l| l as f32).collect();
    let weight: Vec<f64> = lambdas
        .iter()
        .map(|&l| d65.eval(l) as f64 * ybar.eval(l) as f64)
        .collect();
    let norm: f64 = weight.iter().sum();
    // The light's D65 luminance-weighted mean of a spectral factor.
    let mean = |f: &dyn Fn(f64, f64) -> f64| -> f64 {
        lambdas
            .iter()
            .zip(&weight)
            .map(|(&l, w)| w * f(eta.eval(l) as f64, k.eval(l) as f64))
            .sum::<f64>()
            / norm
    };
    let intensity = std::f64::consts::PI * LIGHT_RADIUS * LIGHT_RADIUS * LIGHT_NITS;
    let cam = &scene.camera;
    let (mut full, mut direct_only) = (Vec::new(), Vec::new());
    for j in 0..RES {
        for i in 0..RES {
            let (ray, _) = cam.generate_ray([i as f32 + 0.5, j as f32 + 0.5], [0.5; 2]);
            let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
            let hit = b
                .crossing(o, o + 10.0 * d)
                .unwrap_or_else(|| panic!("pixel ({i}, {j}) misses mirror B"));
            let cos_b = d.dot(b.n).abs();
            let r = d - 2.0 * d.dot(b.n) * b.n;
            let x = hit + r * (-hit.y / r.y);
            // Irradiance factors cos θ / d² at x from the light and from its images in the
            // mirrors, with the reflectance's incidence cosine, where the path is clear.
            let g = |src: DVec3| {
                let v = src - x;
                v.y / v.length() / v.length_squared()
            };
            let occluders = [MIRROR_A, b, CARD];
            let clear = |a: DVec3, z: DVec3, skip: Option<usize>| {
                occluders
                    .iter()
                    .enumerate()
                    .all(|(k, o)| Some(k) == skip || o.crossing(a, z).is_none())
            };
            let g_direct = if clear(LIGHT, x, None) { g(LIGHT) } else { 0.0 };
            // Through mirror k (A = 0, B = 1): the segment from the light's image to x crosses
            // the mirror at m, and both real segments are clear.
            let via = |k: usize| -> Option<(f64, f64)> {
                let m_k = occluders[k];
                let image = m_k.image(LIGHT);
                let m = m_k.crossing(image, x)?;
                (clear(LIGHT, m, Some(k)) && clear(m, x, Some(k)))
                    .then(|| (g(image), (LIGHT - m).normalize().dot(m_k.n).abs()))
            };
            let (g_a, cos_a) = via(0).unwrap_or((0.0, 1.0));
            assert!(via(1).is_none(), "B must not light the patch");
            let scale = intensity * RHO / std::f64::consts::PI;
            full.push(
                scale
                    * mean(&|n, k| {
                        conductor_reflectance(cos_b, n, k)
                            * (g_direct + g_a * conductor_reflectance(cos_a, n, k))
                    }),
            );
            direct_only.push(scale * g_direct * mean(&|n, k| conductor_reflectance(cos_b, n, k)));
        }
    }
    (full, direct_only)
}

/// Mean luminance of the image over `runs` renders with `integrator` (and its standard error).
fn image_mean(scene: &Scene, integrator: Integrator, spp: u32, runs: u64) -> (f64, f64) {
    let means: Vec<f64> = (0..runs)
        .map(|seed| {
            let opts = RenderOptions {
                spp: Some(spp),
                seed: 100 + seed,
                max_depth: Some(MAX_DEPTH),
                integrator,
                ..Default::default()
            };
            let out = session::render(scene, &opts).unwrap();
            assert_finite(&out);
            out.xyz.iter().map(|p| p[1] as f64).sum::<f64>() / out.xyz.len() as f64
        })
        .collect();
    mean_and_sem(means)
}

/// The relative bias of merging at radius `r`: the disk average of the caustic's irradiance
/// (cos θ / d² from A's image of the light; R(θ) varies far slower) around a floor point
/// against its centre value, the largest over the patch's corners and centre (numerically,
/// 2000 points on the disk).
fn merge_bias_bound(r: f64) -> f64 {
    let e = |x: DVec3| {
        let g = |src: DVec3| {
            let v = src - x;
            v.y / v.length() / v.length_squared()
        };
        g(MIRROR_A.image(LIGHT))
    };
    let mut worst = 0.0f64;
    for (px, pz) in [
        (-0.25, -0.1),
        (-0.15, 0.0),
        (-0.05, 0.1),
        (-0.25, 0.1),
        (-0.05, -0.1),
    ] {
        let c = DVec3::new(px, 0.0, pz);
        let n = 2000;
        let avg: f64 = (0..n)
            .map(|s| {
                // Fibonacci points on the disk (uniform by area).
                let a = (s as f64 + 0.5) / n as f64;
                let phi = s as f64 * 2.399_963_229_728_653;
                e(c + DVec3::new(phi.cos(), 0.0, phi.sin()) * (r * a.sqrt()))
            })
            .sum::<f64>()
            / n as f64;
        worst = worst.max((avg / e(c) - 1.0).abs());
    }
    worst
}

#[test]
fn vcm_renders_a_caustic_seen_in_a_mirror_that_pt_and_bdpt_miss() {
    let scene = load_text("sds", &stage(), (RES, RES));
    let (full, direct) = expected(&scene);
    let n = full.len() as f64;
    let (exact, exact_direct) = (full.iter().sum::<f64>() / n, direct.iter().sum::<f64>() / n);
    assert!(
        exact > 0.0 && exact_direct == 0.0,
        "the patch must be lit through A only: {exact} vs {exact_direct}"
    );
    // r_0 = 1.5 pixel footprints of the floor seen through B (0.75 m × the pixel's angle,
    // 0.2 / 32 rad; twice the default, IMAGE_RADIUS_FOOTPRINTS): the merges' variance goes as
    // 1/r², and at this radius 8 × 128 spp judge the closed form to within 2 % while the
    // blur's bias stays below 10⁻³ of it.
    let r0 = 1.5 * 0.75 * 0.2 / RES as f64;
    // The largest radius VCM used is its base radius.
    let bias = merge_bias_bound(r0) * exact;
    // Both merge rules: the caustic's merges at the floor follow the mirror (specular), so
    // merging only after near-specular vertices keeps them (`bidir/merge_rule.rs`).
    for merges in MergeRule::ALL {
        let vcm = Integrator::Vcm(VcmParams {
            radius: Some(r0 as f32),
            merges,
            ..VcmParams::default()
        });
        let (v, v_sem) = image_mean(&scene, vcm, 128, 8);
        let rule = merges.name();
        eprintln!(
            "E-S-D-S-L: exact {exact:.5} cd/m² (direct alone {exact_direct:.5}); VCM (merges {rule}) {v:.5} ± {v_sem:.5} (bias bound {bias:.2e})"
        );
        assert!(
            (v - exact).abs() < 3.3 * v_sem + bias,
            "VCM (merges {rule}) {v} ± {v_sem} vs the closed form {exact} (bias bound {bias})"
        );
        assert!(v_sem < 0.02 * exact, "VCM too noisy to judge: {v_sem}");
    }
    let bdpt = Integrator::Bdpt {
        mis: MisHeuristic::Power,
    };
    let (b, b_sem) = image_mean(&scene, bdpt, 48, 4);
    let (p, p_sem) = image_mean(&scene, Integrator::Path, 96, 4);
    eprintln!("E-S-D-S-L: BDPT {b:.5} ± {b_sem:.5}, PT {p:.5} ± {p_sem:.5}");
    // PT and BDPT cannot sample the caustic in practice: nothing of it at these counts.
    for (name, m, sem) in [("BDPT", b, b_sem), ("PT", p, p_sem)] {
        assert!(
            m + 3.3 * sem < 0.01 * exact,
            "{name} {m} ± {sem}: no strategy of it samples E-S-D-S-L ({exact})"
        );
    }
}

#[test]
fn photon_mapping_alone_converges_to_the_same_caustic() {
    let scene = load_text("sds-vm", &stage(), (RES, RES));
    let (full, _) = expected(&scene);
    let exact = full.iter().sum::<f64>() / full.len() as f64;
    let vm = Integrator::Vcm(VcmParams {
        mode: VcmMode::Vm,
        ..VcmParams::default()
    });
    let (v, sem) = image_mean(&scene, vm, 128, 8);
    // The default base radius, at most IMAGE_RADIUS_FOOTPRINTS footprints of the floor seen
    // through B (0.75 m × the pixel's angle, 0.2 / 32 rad).
    let r0 = f64::from(IMAGE_RADIUS_FOOTPRINTS) * 0.75 * 0.2 / RES as f64;
    let bias = merge_bias_bound(r0) * exact;
    eprintln!("photon mapping: {v:.5} ± {sem:.5} vs {exact:.5} (bias bound {bias:.2e})");
    assert!(
        (v - exact).abs() < 3.3 * sem + bias,
        "{v} ± {sem} vs {exact}"
    );
}

/// The test's Fresnel formula against two known values: normal incidence
/// ((n−1)² + k²)/((n+1)² + k²), and grazing incidence 1.
#[test]
fn conductor_reflectance_limits() {
    let (n, k) = (1.2, 7.0);
    let r0 = ((n - 1.0f64).powi(2) + k * k) / ((n + 1.0f64).powi(2) + k * k);
    assert!((conductor_reflectance(1.0, n, k) - r0).abs() < 1e-12);
    assert!((conductor_reflectance(1e-9, n, k) - 1.0).abs() < 1e-6);
}

/// A point-like light above a smooth glass slab (IOR 1.5, 10 cm thick) over a black floor,
/// and an irradiance meter on the floor straight below: every path to the meter refracts
/// twice (L–S–S–meter), which no connection and no meter ray can complete, so only merging
/// at the meter's point reads it.
///
/// Closed form, on the axis: a ray leaving the source at a small angle θ crosses the air
/// gaps a (above) and b (below) at θ and the slab at θ/n, landing at ρ ≈ θ (a + b + t/n); the
/// irradiance I T dΩ/dA is then I T / D² with D = a + b + t/n (exact as ρ → 0), the source
/// seen through the slab at its apparent depth. Each pair of internal reflections adds a
/// path through the slab twice more: E = I (1 − R)² Σ_k R^{2k} / (a + b + (2k + 1) t/n)², with
/// R = ((n − 1)/(n + 1))² at normal incidence (Fresnel). A second computation checks it: the
/// same sum with D² from the exact landing radius of a ray at θ = 10⁻⁴ rad traced through the
/// slab by Snell's law.
///
/// Bias bound: the meter averages the floor's irradiance over a disk of radius r; near the
/// axis E falls off as the cos³θ of a source at distance D, so the disk average is low by
/// 3 r² / (4 D²) (1.5 × that as the bound, for the slab's steeper off-axis falloff).
#[test]
fn vcm_meter_reads_the_lux_under_a_glass_slab() {
    let (a, t, b, n, r_light, nits) = (0.1f64, 0.1f64, 0.1f64, 1.5f64, 1.0e-4f64, 2.0e9f64);
    let slab_top = b + t;
    let mut s = header();
    s += &looks_scope(
        &(material(
            "Glass",
            "spectral:dielectric",
            "        float inputs:ior = 1.5\n",
        ) + &material("Black", "spectral:diffuse", &flat_reflectance(0.0))),
    );
    let floor = [
        [-3.0f32, 0.0, -3.0],
        [3.0, 0.0, -3.0],
        [3.0, 0.0, 3.0],
        [-3.0, 0.0, 3.0],
    ];
    s += &polygon("Floor", &floor, None, &binding("Black"));
    // `cube`'s faces look inwards; a solid of glass needs them outwards.
    let (pts, inward) = cube(1.0);
    let faces: Vec<Vec<usize>> = inward
        .iter()
        .map(|f| f.iter().rev().copied().collect())
        .collect();
    let slab: Vec<DVec3> = pts
        .iter()
        .map(|p| DVec3::new(2.0 * p.x, b + t * 0.5 * (p.y + 1.0), 2.0 * p.z))
        .collect();
    s += &mesh("Slab", BINDING_API, &slab, &faces, &binding("Glass"));
    s += &prim(
        "SphereLight",
        "Bulb",
        &(format!("    float inputs:radius = {r_light}\n    float inputs:intensity = {nits}\n")
            + &xform(&[("translate", format!("(0, {}, 0)", slab_top + a))])),
    );
    let scene = load_text("slab", &s, (1, 1));
    let intensity = std::f64::consts::PI * r_light * r_light * nits;
    let big_r = ((n - 1.0) / (n + 1.0)).powi(2);
    let paraxial: f64 = (0..6)
        .map(|k| big_r.powi(2 * k) / (a + b + (2 * k + 1) as f64 * t / n).powi(2))
        .sum::<f64>()
        * intensity
        * (1.0 - big_r).powi(2);
    // Second computation: D² = ρ/θ · ρ'/… from Snell's law at a small angle.
    let theta = 1e-4f64;
    let traced: f64 = (0..6)
        .map(|k| {
            let inside = (theta.sin() / n).asin();
            let rho = (a + b) * theta.tan() + (2 * k + 1) as f64 * t * inside.tan();
            // dΩ/dA = sinθ dθ / (ρ dρ) ≈ θ² / ρ² for a ray bundle ∝ θ near the axis.
            big_r.powi(2 * k) * (theta / rho).powi(2)
        })
        .sum::<f64>()
        * intensity
        * (1.0 - big_r).powi(2);
    assert!(
        (traced / paraxial - 1.0).abs() < 1e-6,
        "{traced} vs {paraxial}"
    );
    let radius = 0.015f64;
    let d0 = a + b + t / n;
    let bias = 1.5 * 0.75 * (radius / d0).powi(2);
    let meter = spectral_render::Meter::illuminance(glam::Vec3::ZERO, glam::Vec3::Y).unwrap();
    let options = |merges| spectral_render::session::MeterOptions {
        stop: spectral_render::session::Stop::RelError(0.03),
        max_depth: Some(10),
        seed: 5,
        integrator: Integrator::Vcm(VcmParams {
            radius: Some(radius as f32),
            alpha: 1.0,
            merges,
            ..VcmParams::default()
        }),
        ..Default::default()
    };
    // Both merge rules: the merges at the meter's point follow the slab's lower interface
    // (specular), so the caustic rule keeps them (`bidir/merge_rule.rs`).
    for merges in MergeRule::ALL {
        let run = spectral_render::session::measure(&scene, &[meter], &options(merges)).unwrap();
        assert_eq!(run.dropped, 0);
        let r = run.readings[0];
        let sigma = r.ci95 / 1.96;
        eprintln!(
            "lux under the slab: VCM (merges {}) {:.3} ± {:.3} ({} samples) vs closed form {paraxial:.3} (bias bound {:.2} %)",
            merges.name(),
            r.value,
            r.ci95,
            r.samples,
            100.0 * bias
        );
        assert!(
            (r.value - paraxial).abs() < 3.3 * sigma + bias * paraxial,
            "merges {}: {} ± {} vs {paraxial}",
            merges.name(),
            r.value,
            r.ci95
        );
    }
    let opts = options(MergeRule::All);
    // Path tracing cannot: its meter rays never find the 0.1 mm bulb through the slab.
    let pt = spectral_render::session::measure(
        &scene,
        &[meter],
        &spectral_render::session::MeterOptions {
            integrator: Integrator::Path,
            ..opts
        },
    )
    .unwrap()
    .readings[0];
    assert!(pt.value < 0.01 * paraxial, "path tracing read {}", pt.value);
}

/// Two floors (separate meshes) meet under a zero-thickness wall 2 m tall; a sphere light
/// 30 cm above the right floor lights it, and the camera, on the left, sees the left floor
/// and the wall's back near its foot. No light path reaches the left side: light crossing
/// x = 0 below the wall's top is blocked, and light crossing above it travels upwards, away
/// from the left floor. The left side is exactly black.
fn walled_stage() -> String {
    let mut s = header();
    s += &looks_scope(&material(
        "White",
        "spectral:diffuse",
        &flat_reflectance(0.8),
    ));
    let floors = [
        (
            "FloorLeft",
            [
                [-1.0f32, 0.0, -1.0],
                [0.0, 0.0, -1.0],
                [0.0, 0.0, 1.0],
                [-1.0, 0.0, 1.0],
            ],
        ),
        (
            "FloorRight",
            [
                [0.0f32, 0.0, -1.0],
                [1.0, 0.0, -1.0],
                [1.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
            ],
        ),
        (
            "Wall",
            [
                [0.0f32, 0.0, -1.0],
                [0.0, 0.0, 1.0],
                [0.0, 2.0, 1.0],
                [0.0, 2.0, -1.0],
            ],
        ),
    ];
    for (name, corners) in floors {
        s += &polygon(name, &corners, None, &binding("White"));
    }
    s += &prim(
        "SphereLight",
        "Bulb",
        &("    float inputs:radius = 0.05\n    float inputs:intensity = 1000\n".to_string()
            + &xform(&[("translate", "(0.5, 0.3, 0)".into())])),
    );
    // At (−0.4, 0.25, 0) looking along +x and 30° down: the wall's foot at the image centre.
    s += &prim(
        "Camera",
        "Cam",
        &("    float focalLength = 18\n    float horizontalAperture = 24\n    float verticalAperture = 24\n    float2 clippingRange = (0.01, 100)\n".to_string()
            + &xform(&[
                ("translate", "(-0.4, 0.25, 0)".into()),
                ("rotateY", "-90".into()),
                ("rotateX", "-30".into()),
            ])),
    );
    s
}

#[test]
fn vcm_does_not_merge_light_through_a_wall() {
    // The default radius (0.75 pixel footprints, here about 2.5 cm) reaches across the wall's
    // foot; merges with vertices the camera vertex cannot see must not count.
    let scene = load_text("vcm_walled", &walled_stage(), (16, 16));
    for integrator in [
        // Every vertex merges (the default rule merges nothing on these diffuse floors).
        Integrator::Vcm(VcmParams {
            merges: MergeRule::All,
            ..VcmParams::default()
        }),
        Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
    ] {
        let opts = RenderOptions {
            spp: Some(16),
            max_depth: Some(5),
            integrator,
            ..Default::default()
        };
        let out = session::render(&scene, &opts).unwrap();
        let lit = out.xyz.iter().filter(|p| p[1] != 0.0).count();
        assert_eq!(lit, 0, "{}: {lit} pixels lit", integrator.name());
    }
}
