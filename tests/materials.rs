//! Issue 3: the material library's energy, reciprocity, consistency, limit and stability
//! checks, on every model of `spectral_render::testing::examples()` and on rendered scenes.
//!
//! Monte Carlo tolerances come from the estimators' own standard errors (fixed seeds, so the
//! tests are deterministic); run with `-- --nocapture` to see the measured numbers.

mod common;

use common::*;
use glam::Vec3;
use spectral_render::bxdf::{Bxdf, DielectricBxdf, TransportMode};
use spectral_render::bxdf::{PlasticBxdf, TrowbridgeReitz};
use spectral_render::material::Material;
use spectral_render::sampling::warp::uniform_sphere;
use spectral_render::sampling::Sampler;
use spectral_render::session::RenderOutput;
use spectral_render::spectral::sellmeier::Sellmeier;
use spectral_render::spectral::{data, SampledSpectrum, SampledWavelengths, Spectrum};
use spectral_render::testing::{examples, Example};
use std::f32::consts::PI;
use std::sync::Arc;

const RADIANCE: TransportMode = TransportMode::Radiance;
const IMPORTANCE: TransportMode = TransportMode::Importance;

/// A unit direction at polar angle `theta_deg` from +Z (or −Z when `below`), azimuth 0.7 rad.
fn dir(theta_deg: f32, below: bool) -> Vec3 {
    let t = theta_deg.to_radians();
    let z = if below { -t.cos() } else { t.cos() };
    Vec3::new(t.sin() * 0.7f32.cos(), t.sin() * 0.7f32.sin(), z).normalize()
}

/// Per-lane mean and standard error of f |cos θi| / pdf over `n` samples (failed samples count
/// as 0): the directional albedo when `mode` transports importance (energy).
fn albedo(b: &Bxdf, wo: Vec3, n: usize, mode: TransportMode, seed: u64) -> ([f64; 4], [f64; 4]) {
    let mut s = Sampler::new(seed, 0, 0);
    let (mut sum, mut sum2) = ([0.0f64; 4], [0.0f64; 4]);
    for _ in 0..n {
        let (uc, u) = (s.get_1d(), s.get_2d());
        if let Some(x) = b.sample_f(wo, uc, u, mode) {
            if x.pdf_w > 0.0 {
                let w = x.f * (x.wi.z.abs() / x.pdf_w);
                for i in 0..4 {
                    sum[i] += w[i] as f64;
                    sum2[i] += (w[i] as f64).powi(2);
                }
            }
        }
    }
    let nf = n as f64;
    let mean = sum.map(|v| v / nf);
    let sem = std::array::from_fn(|i| ((sum2[i] / nf - mean[i].powi(2)).max(0.0) / nf).sqrt());
    (mean, sem)
}

fn example(name: &str) -> Example {
    examples()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("no example {name}"))
}

#[test]
fn furnace_every_model_reflects_at_most_what_it_receives() {
    // ∫ f |cos θi| dωi ≤ 1 for every ωo, down to θo = 89°, on both sides. Importance transport
    // is the energy balance (radiance across a refraction is scaled by 1/η², PBR 4ed §9.5.2).
    // Lossless models conserve it exactly.
    let lossless = [
        "glass-smooth",
        "glass-1e-4",
        "ior-1",
        "ior-1.0001",
        "ior-1.0001-smooth",
        "thin-bk7",
        "thin-constant-1.5",
    ];
    let n = 40_000;
    println!("model                      max albedo (θo, side)         ± s.e.");
    for ex in examples() {
        let mut worst = (f64::MIN, 0.0, 0.0, false);
        for theta in [0.0, 30.0, 60.0, 80.0, 89.0] {
            for below in [false, true] {
                let (mean, sem) = albedo(&ex.bxdf, dir(theta, below), n, IMPORTANCE, 1);
                for i in 0..4 {
                    assert!(
                        mean[i] <= 1.0 + 4.0 * sem[i] + 1e-3,
                        "{}: albedo {} ± {} at θo = {theta}° (below: {below}), lane {i}",
                        ex.name,
                        mean[i],
                        sem[i]
                    );
                    if lossless.contains(&ex.name) {
                        let tol = 4.0 * sem[i] + 1e-5;
                        assert!((mean[i] - 1.0).abs() < tol, "{}: {}", ex.name, mean[i]);
                    }
                    if mean[i] > worst.0 {
                        worst = (mean[i], sem[i], theta, below);
                    }
                }
            }
        }
        let side = if worst.3 { "below" } else { "above" };
        println!(
            "{:26} {:.5} ({:>2}°, {side})             ±{:.5}",
            ex.name, worst.0, worst.2, worst.1
        );
    }
}

#[test]
fn white_plastic_conserves_energy() {
    // A white base under a lossless coat reflects everything (the plastic's T̄ normalisation
    // and internal-reflection series): exactly for the smooth coat; within the single-scattering
    // loss of GGX for a rough one.
    let white = SampledSpectrum::ONE;
    for (alpha, floor) in [(0.0, 0.999), (0.1, 0.985), (0.5, 0.95)] {
        let b = Bxdf::Plastic(PlasticBxdf::new(white, 1.5, alpha));
        for theta in [0.0, 45.0, 80.0, 89.0] {
            let (mean, sem) = albedo(&b, dir(theta, false), 100_000, IMPORTANCE, 2);
            println!(
                "white plastic α = {alpha}, θo = {theta}°: albedo {:.5} ± {:.5}",
                mean[0], sem[0]
            );
            assert!(mean[0] <= 1.0 + 4.0 * sem[0] + 1e-3);
            assert!(
                mean[0] >= floor - 4.0 * sem[0],
                "α {alpha} θ {theta}: {}",
                mean[0]
            );
        }
    }
}

/// The smooth dielectric's reflected and transmitted energy fractions at ωo: R from the
/// reflection branch (uc = 0), T from the transmission branch (uc → 1), in importance mode.
fn smooth_r_t(b: &DielectricBxdf, wo: Vec3) -> (f32, f32) {
    let r = b.sample_f(wo, 0.0, [0.5; 2], IMPORTANCE).unwrap();
    assert!(r.specular);
    let r = if r.transmission {
        0.0
    } else {
        r.f[0] * r.wi.z.abs()
    };
    let t = b
        .sample_f(wo, 1.0 - f32::EPSILON, [0.5; 2], IMPORTANCE)
        .filter(|t| t.transmission)
        .map_or(0.0, |t| t.f[0] * t.wi.z.abs());
    (r, t)
}

#[test]
fn smooth_dielectric_r_plus_t_is_one_per_wavelength() {
    // Per wavelength of the BK7 Sellmeier fit (360–830 nm every 5 nm), from outside and from
    // inside (where TIR sets T = 0), down to grazing incidence; and the radiance-mode
    // transmission is T/η'² (PBR 4ed eq. 9.20).
    let bk7 = data::glass("BK7").unwrap();
    let mut worst = 0.0f32;
    let mut lambda = 360.0;
    while lambda <= 830.0 {
        let eta = bk7.ior(lambda);
        let b = DielectricBxdf::new(TrowbridgeReitz::isotropic(0.0), eta);
        for theta in [0.0, 20.0, 40.0, 41.0, 42.0, 60.0, 80.0, 89.0, 89.99] {
            for below in [false, true] {
                let wo = dir(theta, below);
                let (r, t) = smooth_r_t(&b, wo);
                worst = worst.max((r + t - 1.0).abs());
                assert!((r + t - 1.0).abs() < 2e-6, "λ {lambda}: R {r} + T {t}");
                let critical = (1.0 / eta).asin().to_degrees();
                if below && theta > critical {
                    assert_eq!(t, 0.0, "TIR at {theta}° > {critical}°");
                }
                let rad = b.sample_f(wo, 1.0 - f32::EPSILON, [0.5; 2], RADIANCE);
                if let Some(s) = rad.filter(|s| s.transmission) {
                    let expected = t / (s.eta * s.eta);
                    assert!((s.f[0] * s.wi.z.abs() - expected).abs() < 1e-6);
                }
            }
        }
        lambda += 5.0;
    }
    println!("max |R + T − 1| over 95 wavelengths × 18 directions: {worst:e}");
}

#[test]
fn reflection_is_reciprocal_and_transmission_obeys_the_eta_squared_rule() {
    // Reflection: f(ωo, ωi) = f(ωi, ωo). Rough transmission (Veach 1997 eq. 5.14):
    // f(ωo, ωi) / η_o² = f(ωi, ωo) / η_i², η on the side of each direction.
    let mut s = Sampler::new(3, 0, 0);
    let mut checked = 0;
    for ex in examples() {
        if ex.bxdf.is_specular() {
            continue;
        }
        for _ in 0..2000 {
            let (a, b) = (uniform_sphere(s.get_2d()), uniform_sphere(s.get_2d()));
            let (fab, fba) = (ex.bxdf.f(a, b, RADIANCE), ex.bxdf.f(b, a, RADIANCE));
            let (sa, sb) = if a.z * b.z > 0.0 {
                (1.0, 1.0)
            } else if let Bxdf::Dielectric(d) = ex.bxdf {
                let eta_of = |w: Vec3| if w.z > 0.0 { 1.0 } else { d.eta };
                (eta_of(a).powi(2), eta_of(b).powi(2))
            } else {
                (1.0, 1.0)
            };
            for i in 0..4 {
                let (x, y) = (fab[i] / sa, fba[i] / sb);
                assert!(
                    (x - y).abs() <= 2e-4 * x.abs().max(y.abs()) + 1e-6,
                    "{}: f(a,b) = {x}, f(b,a) = {y} (a = {a}, b = {b})",
                    ex.name
                );
            }
            checked += 1;
        }
    }
    println!("reciprocity checked on {checked} direction pairs");
}

#[test]
fn samples_agree_with_eval_and_pdf() {
    // For every non-delta sample: the returned f and pdf equal f(ωo, ωi) and pdf(ωo, ωi).
    let mut checked = 0;
    let mut worst = 0.0f32;
    for ex in examples() {
        let mut s = Sampler::new(4, 0, 0);
        for theta in [0.0, 35.0, 70.0, 88.0] {
            for below in [false, true] {
                let wo = dir(theta, below);
                for _ in 0..2000 {
                    let (uc, u) = (s.get_1d(), s.get_2d());
                    let Some(x) = ex.bxdf.sample_f(wo, uc, u, RADIANCE) else {
                        continue;
                    };
                    assert!(
                        (x.wi.length() - 1.0).abs() < 1e-3,
                        "{}: |wi| = {}",
                        ex.name,
                        x.wi.length()
                    );
                    assert_eq!(x.transmission, wo.z * x.wi.z < 0.0, "{}", ex.name);
                    if x.specular {
                        continue;
                    }
                    let f = ex.bxdf.f(wo, x.wi, RADIANCE);
                    let pdf = ex.bxdf.pdf(wo, x.wi, RADIANCE);
                    let rel = |a: f32, b: f32| (a - b).abs() / a.abs().max(b.abs()).max(1e-3);
                    worst = worst.max(rel(pdf, x.pdf_w));
                    assert!(
                        rel(pdf, x.pdf_w) < 2e-3,
                        "{}: pdf {pdf} vs sampled {}",
                        ex.name,
                        x.pdf_w
                    );
                    for i in 0..4 {
                        worst = worst.max(rel(f[i], x.f[i]));
                        assert!(
                            rel(f[i], x.f[i]) < 2e-3,
                            "{}: f {} vs sampled {}",
                            ex.name,
                            f[i],
                            x.f[i]
                        );
                    }
                    checked += 1;
                }
            }
        }
    }
    println!("{checked} non-delta samples: max relative difference {worst:e}");
}

/// ∫ pdf(ωo, ωi) dωi over the sphere by the midpoint rule on a (cos θ, φ) grid.
fn pdf_integral(b: &Bxdf, wo: Vec3, nz: usize) -> f64 {
    let nphi = 2 * nz;
    let mut sum = 0.0f64;
    for i in 0..nz {
        let z = -1.0 + 2.0 * (i as f32 + 0.5) / nz as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f32 + 0.5) / nphi as f32;
            sum += b.pdf(wo, Vec3::new(r * phi.cos(), r * phi.sin(), z), RADIANCE) as f64;
        }
    }
    sum * (2.0 / nz as f64) * (2.0 * PI as f64 / nphi as f64)
}

#[test]
fn pdf_integrates_to_the_probability_of_a_non_delta_sample() {
    // ∫ pdf dω over the sphere must equal the probability that sample_f returns a non-delta
    // sample (1 for glossy/diffuse models, less where the sampler can fail below the horizon
    // or picks a delta lobe). The narrowest lobe (η = 1.01, α = 0.3: 3 mrad) is below the
    // grid's resolution and skipped.
    println!("model                     θo   ∫pdf dω     P(non-delta sample)");
    for ex in examples() {
        if ex.bxdf.is_specular() || ex.name == "ior-1.01-0.3" {
            continue;
        }
        for theta in [30.0, 75.0] {
            let wo = dir(theta, false);
            let integral = pdf_integral(&ex.bxdf, wo, 1000);
            let n = 200_000;
            let mut s = Sampler::new(6, 0, 0);
            let hits = (0..n)
                .filter(|_| {
                    let (uc, u) = (s.get_1d(), s.get_2d());
                    ex.bxdf
                        .sample_f(wo, uc, u, RADIANCE)
                        .is_some_and(|x| !x.specular && x.pdf_w > 0.0)
                })
                .count();
            let p = hits as f64 / n as f64;
            let sem = (p * (1.0 - p) / n as f64).sqrt();
            println!(
                "{:24} {theta:>4}°  {integral:.5}     {p:.5} ± {sem:.5}",
                ex.name
            );
            assert!(integral <= 1.0 + 3e-3, "{}: ∫pdf = {integral}", ex.name);
            assert!(
                (integral - p).abs() < 4.0 * sem + 3e-3,
                "{}: ∫pdf = {integral}, sampled {p}",
                ex.name
            );
        }
    }
}

#[test]
fn rough_models_converge_to_their_smooth_counterparts() {
    // Directional albedo per lane (and for the dielectric the reflected and transmitted parts
    // separately) as α → 0, against the smooth model, at θo = 50°.
    let wo = dir(50.0, false);
    let lambda = SampledWavelengths {
        lambda: [450.0, 520.0, 590.0, 660.0],
        pdf: [1.0; 4],
    };
    let (n, k) = data::metal("Au").unwrap();
    let dense = |d: &spectral_render::spectral::DenseSpectrum| Spectrum::Dense {
        data: Arc::new(d.clone()),
        scale: 1.0,
    };
    let gold = |alpha: f32| {
        Material::Conductor {
            eta: dense(n),
            k: dense(k),
            distrib: TrowbridgeReitz::isotropic(alpha),
            roughness: None,
        }
        .bsdf(glam::Vec2::ZERO.into(), Vec3::Z, &lambda)
        .bxdf
    };
    let plastic = |alpha: f32| {
        Bxdf::Plastic(PlasticBxdf::new(
            SampledSpectrum([0.8, 0.5, 0.2, 0.1]),
            1.5,
            alpha,
        ))
    };
    let glass =
        |alpha: f32| Bxdf::Dielectric(DielectricBxdf::new(TrowbridgeReitz::isotropic(alpha), 1.5));
    let split = |b: &Bxdf, n: usize| {
        let mut s = Sampler::new(8, 0, 0);
        let (mut r, mut t) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (uc, u) = (s.get_1d(), s.get_2d());
            if let Some(x) = b.sample_f(wo, uc, u, IMPORTANCE) {
                let w = (x.f[0] * x.wi.z.abs() / x.pdf_w) as f64;
                if x.transmission {
                    t += w;
                } else {
                    r += w;
                }
            }
        }
        (r / n as f64, t / n as f64)
    };
    let alphas = [0.3, 0.1, 0.03, 0.01, 0.003];
    for (name, model) in [
        ("gold", &gold as &dyn Fn(f32) -> Bxdf),
        ("plastic", &plastic),
    ] {
        let (smooth, _) = albedo(&model(0.0), wo, 100_000, IMPORTANCE, 9);
        let mut last = f64::MAX;
        for alpha in alphas {
            let (rough, sem) = albedo(&model(alpha), wo, 100_000, IMPORTANCE, 9);
            let diff = (0..4)
                .map(|i| (rough[i] - smooth[i]).abs())
                .fold(0.0, f64::max);
            let se = sem.iter().copied().fold(0.0, f64::max);
            println!("{name}: α = {alpha:<6} max |E_rough − E_smooth| = {diff:.5} (± {se:.5})");
            assert!(
                diff <= last + 4.0 * se,
                "{name}: not converging at α {alpha}"
            );
            last = diff;
        }
        assert!(last < 0.005, "{name}: {last}");
    }
    let (r0, t0) = split(&glass(0.0), 100_000);
    let mut last = f64::MAX;
    for alpha in alphas {
        let (r, t) = split(&glass(alpha), 100_000);
        let diff = (r - r0).abs().max((t - t0).abs());
        println!("glass: α = {alpha:<6} R = {r:.5} (smooth {r0:.5}), T = {t:.5} (smooth {t0:.5})");
        assert!(diff <= last + 0.005);
        last = diff;
    }
    assert!(last < 0.005);
}

#[test]
fn normal_incidence_metal_reflectance_matches_the_tables() {
    // R(0) = ((n − 1)² + k²) / ((n + 1)² + k²) from spectra/metal/*.csv, every nm.
    for metal in ["Au", "Ag", "Cu", "Al"] {
        let (n, k) = data::metal(metal).unwrap();
        let dense = |d: &spectral_render::spectral::DenseSpectrum| Spectrum::Dense {
            data: Arc::new(d.clone()),
            scale: 1.0,
        };
        let m = Material::Conductor {
            eta: dense(n),
            k: dense(k),
            distrib: TrowbridgeReitz::isotropic(0.0),
            roughness: None,
        };
        let mut worst = 0.0f32;
        for l in 360..=830 {
            let lambda = SampledWavelengths {
                lambda: [l as f32; 4],
                pdf: [1.0; 4],
            };
            let bsdf = m.bsdf(glam::Vec2::ZERO.into(), Vec3::Z, &lambda);
            let s = bsdf
                .bxdf
                .sample_f(Vec3::Z, 0.5, [0.5; 2], RADIANCE)
                .unwrap();
            let (nv, kv) = (n.eval(l as f32), k.eval(l as f32));
            let expected = ((nv - 1.0).powi(2) + kv * kv) / ((nv + 1.0).powi(2) + kv * kv);
            let got = s.f[0] * s.wi.z;
            worst = worst.max((got - expected).abs() / expected);
            assert!((got - expected).abs() <= 1e-5 * expected, "{metal} {l} nm");
        }
        println!("{metal}: max relative error of R(0) over 360–830 nm: {worst:e}");
    }
}

#[test]
fn no_nan_or_inf_at_grazing_tir_tiny_roughness_and_unit_ior() {
    // Every model at cos θo down to 1e-7 and exactly 0, from both sides (TIR inside glass),
    // with random and extreme random numbers: all of f, pdf and the samples are finite.
    let cosines = [1.0f32, 0.5, 1e-2, 1e-4, 1e-6, 1e-7, 0.0];
    let extremes = [0.0f32, 0.5, 1.0 - f32::EPSILON];
    let mut s = Sampler::new(10, 0, 0);
    let mut evaluated = 0;
    for ex in examples() {
        for &c in &cosines {
            for below in [false, true] {
                let sin = (1.0 - c * c).sqrt();
                let wo = Vec3::new(sin, 0.0, if below { -c } else { c });
                let mut us: Vec<(f32, [f32; 2])> =
                    (0..500).map(|_| (s.get_1d(), s.get_2d())).collect();
                for &a in &extremes {
                    for &b in &extremes {
                        for &d in &extremes {
                            us.push((a, [b, d]));
                        }
                    }
                }
                for (uc, u) in us {
                    for mode in [RADIANCE, IMPORTANCE] {
                        if let Some(x) = ex.bxdf.sample_f(wo, uc, u, mode) {
                            assert!(
                                x.f.is_finite() && x.pdf_w.is_finite() && x.wi.is_finite(),
                                "{}: {x:?} at wo = {wo}",
                                ex.name
                            );
                            assert!(x.pdf_w >= 0.0 && x.f.0.iter().all(|&v| v >= 0.0));
                        }
                        let wi = uniform_sphere(s.get_2d());
                        let f = ex.bxdf.f(wo, wi, mode);
                        let pdf = ex.bxdf.pdf(wo, wi, mode);
                        assert!(
                            f.is_finite() && pdf.is_finite() && pdf >= 0.0,
                            "{}",
                            ex.name
                        );
                        evaluated += 1;
                    }
                }
            }
        }
    }
    println!("{evaluated} evaluations, all finite");
}

// ---------------------------------------------------------------------------------------------
// Rendered checks.

/// A uniform white dome of 1 nit, a camera at z = 2 looking down −Z with a ±0.25 field, a
/// grey Lambertian backdrop at z = −1 and `extra` prims.
fn backdrop_stage(extra: &str, looks: &str) -> String {
    format!(
        "{}{}def Scope \"Looks\" {{\n{}{looks}}}\n{}def DomeLight \"Sky\" {{\n    float inputs:intensity = 1\n}}\n{}",
        header(),
        camera(2.0, 0.25, 0.0),
        material("Grey", "spectral:diffuse", "        color3f inputs:reflectance = (0.6, 0.3, 0.1)\n"),
        quad("Backdrop", -1.0, 3.0, &binding("Grey"), ""),
        extra
    )
}

fn render_stage(name: &str, text: &str, res: u32, spp: u32) -> RenderOutput {
    let dir = temp_dir(name);
    let path = write(&dir, "stage.usda", text);
    render_file(&path, (res, res), spp, Some(5), None)
}

/// Per-pixel z-scores of two renders' luminance, from a 4×4-pixel block average and its
/// spread: (max |z|, mean a, mean b).
fn compare(a: &RenderOutput, b: &RenderOutput) -> (f64, f64, f64) {
    let (w, h) = (a.width, a.height);
    let block = 4;
    let mut max_z = 0.0f64;
    for by in 0..h / block {
        for bx in 0..w / block {
            let pix = |o: &RenderOutput| -> Vec<f32> {
                (0..block * block)
                    .map(|k| {
                        let (x, y) = (bx * block + k % block, by * block + k / block);
                        o.xyz[y * w + x][1]
                    })
                    .collect()
            };
            let (ma, sa) = mean_and_sem(pix(a));
            let (mb, sb) = mean_and_sem(pix(b));
            let z = (ma - mb) / (sa * sa + sb * sb).sqrt().max(1e-3 * ma.max(mb)).max(1e-9);
            max_z = max_z.max(z.abs());
        }
    }
    let mean =
        |o: &RenderOutput| o.xyz.iter().map(|p| p[1] as f64).sum::<f64>() / o.xyz.len() as f64;
    (max_z, mean(a), mean(b))
}

#[test]
fn unit_ior_glass_sphere_is_invisible() {
    let sphere = |ior: &str| {
        format!(
            "def Sphere \"Ball\" {{\n    double radius = 0.3\n{}}}\n",
            binding(ior)
        )
    };
    let looks = material(
        "Air",
        "spectral:dielectric",
        "        float inputs:ior = 1\n",
    ) + &material(
        "AirRough",
        "spectral:dielectric",
        "        float inputs:ior = 1\n        float inputs:roughness = 0.3\n",
    );
    let without = render_stage("ior1-none", &backdrop_stage("", &looks), 32, 64);
    for name in ["Air", "AirRough"] {
        let with = render_stage("ior1", &backdrop_stage(&sphere(name), &looks), 32, 64);
        let (z, ma, mb) = compare(&with, &without);
        println!(
            "IOR-1 sphere ({name}): mean Y {ma:.5} vs {mb:.5} without, max block |z| = {z:.2}"
        );
        assert!(z < 4.5, "{name}: max |z| {z}");
        assert!((ma / mb - 1.0).abs() < 0.01);
    }
}

#[test]
fn opacity_cutouts_and_partial_opacity() {
    // A non-reflecting UsdPreviewSurface (black, IOR 1) pane in front of the backdrop: with
    // opacity 0.2 under a threshold of 0.5 it is cut out (same image as without it); with
    // opacity 0.5 and no threshold it stops half of the light, in camera and shadow rays alike.
    let looks = material(
        "Cutout",
        "UsdPreviewSurface",
        "        color3f inputs:diffuseColor = (0, 0, 0)\n        float inputs:ior = 1\n        float inputs:opacity = 0.2\n        float inputs:opacityThreshold = 0.5\n",
    ) + &material(
        "Half",
        "UsdPreviewSurface",
        "        color3f inputs:diffuseColor = (0, 0, 0)\n        float inputs:ior = 1\n        float inputs:opacity = 0.5\n",
    );
    let pane = |m: &str| quad("Pane", 1.0, 1000.0, &binding(m), "");
    let without = render_stage("cut-none", &backdrop_stage("", &looks), 32, 64);
    let cut = render_stage("cut", &backdrop_stage(&pane("Cutout"), &looks), 32, 64);
    let (z, ma, mb) = compare(&cut, &without);
    println!("cutout pane: mean Y {ma:.5} vs {mb:.5} without, max block |z| = {z:.2}");
    assert!(z < 4.5 && (ma / mb - 1.0).abs() < 0.01);
    // Opacity 0.5: the camera sees the backdrop half the time, and all the dome light the
    // backdrop receives crosses the (practically infinite) pane: 0.5 × 0.5 of the open image.
    let half = render_stage("half", &backdrop_stage(&pane("Half"), &looks), 32, 256);
    let ratio = half.xyz.iter().map(|p| p[1] as f64).sum::<f64>()
        / without.xyz.iter().map(|p| p[1] as f64).sum::<f64>();
    println!("half-opaque pane: image / unblocked image = {ratio:.4} (expected 0.25)");
    assert!((ratio - 0.25).abs() < 0.01, "{ratio}");
}

#[test]
fn materials_scene_renders_without_nan() {
    let out = render_file(
        std::path::Path::new("scenes/materials.usda"),
        (96, 40),
        8,
        Some(7),
        None,
    );
    assert_finite(&out);
    let y: f64 = out.xyz.iter().map(|p| p[1] as f64).sum::<f64>() / out.xyz.len() as f64;
    println!("materials.usda at 96×40, 8 spp: mean Y = {y:.4} cd/m², no NaN/Inf, 0 dropped");
    assert!(y > 0.0);
}

#[test]
fn dispersion_terminates_secondary_wavelengths_only_when_the_ior_varies() {
    let bk7 = Material::Dielectric {
        ior: data::glass("BK7").unwrap(),
        distrib: TrowbridgeReitz::isotropic(0.0),
        roughness: None,
    };
    let constant = Material::Dielectric {
        ior: Sellmeier::constant(1.5),
        distrib: TrowbridgeReitz::isotropic(0.0),
        roughness: None,
    };
    let thin = Material::ThinDielectric {
        ior: data::glass("BK7").unwrap(),
    };
    assert!(bk7.is_dispersive());
    assert!(!constant.is_dispersive() && !thin.is_dispersive());
    // The dispersive BSDF is built for the hero wavelength.
    let lambda = SampledWavelengths {
        lambda: [450.0, 550.0, 650.0, 750.0],
        pdf: [1.0; 4],
    };
    match bk7.bsdf(glam::Vec2::ZERO.into(), Vec3::Z, &lambda).bxdf {
        Bxdf::Dielectric(d) => assert_eq!(d.eta, data::glass("BK7").unwrap().ior(450.0)),
        _ => panic!(),
    }
}

#[test]
fn dispersive_and_constant_glass_render_the_same_mean_when_the_ior_matches() {
    // A constant-IOR glass ball keeps all four wavelengths; a "dispersive" one whose Sellmeier
    // terms give the same constant index (B₁ = n² − 1 with a tiny C₁) terminates them. Both
    // estimate the same image; the terminated one is noisier.
    let looks = material("Const", "spectral:dielectric", "        float inputs:ior = 1.5\n")
        + &material(
            "Disp",
            "spectral:dielectric",
            "        float3 inputs:sellmeierB = (1.25, 0, 0)\n        float3 inputs:sellmeierC = (1e-9, 0, 0)\n",
        );
    let ball = |m: &str| {
        format!(
            "def Sphere \"Ball\" {{\n    double radius = 0.3\n{}}}\n",
            binding(m)
        )
    };
    let a = render_stage("const", &backdrop_stage(&ball("Const"), &looks), 24, 128);
    let b = render_stage("disp", &backdrop_stage(&ball("Disp"), &looks), 24, 128);
    let (z, ma, mb) = compare(&a, &b);
    println!("constant vs dispersive-terminated glass: mean Y {ma:.5} vs {mb:.5}, max |z| {z:.2}");
    assert!(z < 4.5 && (ma / mb - 1.0).abs() < 0.02);
}

#[test]
fn bxdf_examples_cover_every_model() {
    let names: Vec<&str> = examples().iter().map(|e| e.bxdf.name()).collect();
    for model in [
        "diffuse",
        "oren-nayar",
        "conductor",
        "dielectric",
        "thin-dielectric",
        "plastic",
        "preview-surface",
    ] {
        assert!(names.contains(&model), "{model}");
    }
    let _: Example = example("lambert");
}

/// Loads a stage made of `looks` (materials) and one quad bound to `bound`.
fn load_looks(
    name: &str,
    looks: &str,
    bound: &str,
) -> spectral_render::Result<spectral_render::scene::Scene> {
    let text = format!(
        "{}{}def Scope \"Looks\" {{\n{looks}}}\n{}",
        header(),
        camera(2.0, 0.25, 0.0),
        quad("Q", 0.0, 1.0, &binding(bound), "")
    );
    let dir = temp_dir(name);
    spectral_render::scene::load(&write(&dir, "stage.usda", &text), Some((8, 8)))
}

#[test]
fn preview_surface_normal_input_tilts_the_shading_normal() {
    let looks = material(
        "Tilted",
        "UsdPreviewSurface",
        "        normal3f inputs:normal = (0.6, 0, 0.8)\n",
    ) + &material(
        "Down",
        "UsdPreviewSurface",
        "        normal3f inputs:normal = (0, 0, -1)\n",
    );
    let scene = load_looks("normal", &looks, "Tilted").unwrap();
    let Material::Preview(p) = &scene.materials[0] else {
        panic!("preview surface")
    };
    assert!((p.normal - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6);
    // The quad has no st: the tangent frame is the arbitrary one around +Z (x = +X). The
    // scene perturbs the hit's shading normal, which the BSDF frame then uses.
    let ray = spectral_render::geometry::Ray::new(Vec3::new(0.2, 0.1, 1.0), -Vec3::Z);
    let Some(spectral_render::scene::Hit::Surface(si)) = scene.intersect(&ray, f32::INFINITY)
    else {
        panic!("the ray hits the quad")
    };
    assert!(
        (si.ns - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-5,
        "{}",
        si.ns
    );
    assert_eq!(si.ng, Vec3::Z);
    let lambda = SampledWavelengths::sample_visible(0.3);
    let bsdf = scene.materials[0].bsdf(si.uv.into(), si.ns, &lambda);
    assert!((bsdf.frame.n.dot(Vec3::Z) - 0.8).abs() < 1e-5);
    // A normal pointing into the surface is replaced by (0, 0, 1), with a warning.
    let scene = load_looks("normal-down", &looks, "Down").unwrap();
    assert!(scene
        .summary
        .warnings
        .iter()
        .any(|w| w.contains("/Looks/Down") && w.contains("normal")));
}

#[test]
fn bad_material_inputs_are_errors_naming_the_prim() {
    let cases = [
        ("spectral:conductor", "        token inputs:metal = \"Pt\"\n", "unknown eta spectrum 'metal/Pt'"),
        ("spectral:dielectric", "        token inputs:glass = \"SF99\"\n", "unknown glass 'SF99'"),
        (
            "spectral:dielectric",
            "        float3 inputs:sellmeierB = (-3, 0, 0)\n        float3 inputs:sellmeierC = (0.01, 0, 0)\n",
            "no real index of refraction",
        ),
        ("spectral:conductor", "        float inputs:roughness = -0.1\n", "roughness"),
    ];
    for (i, (id, inputs, reason)) in cases.iter().enumerate() {
        let looks = material("Bad", id, inputs);
        let err = load_looks(&format!("bad{i}"), &looks, "Bad")
            .err()
            .expect("an error")
            .to_string();
        println!("{err}");
        assert!(err.contains("/Looks/Bad") && err.contains(reason), "{err}");
    }
}

#[test]
fn path_tracer_collapses_wavelengths_only_at_dispersive_glass() {
    // Camera rays through the centre of a glass ball: with a Sellmeier (dispersive) IOR only
    // the hero lane of li() is non-zero; with a constant IOR all four lanes carry radiance.
    use spectral_render::integrator::path::PathIntegrator;
    let looks = material(
        "Const",
        "spectral:dielectric",
        "        float inputs:ior = 1.5\n",
    ) + &material(
        "Disp",
        "spectral:dielectric",
        "        token inputs:glass = \"BK7\"\n",
    );
    for (name, dispersive) in [("Const", false), ("Disp", true)] {
        let ball = format!(
            "def Sphere \"Ball\" {{\n    double radius = 0.3\n{}}}\n",
            binding(name)
        );
        let dir = temp_dir("collapse");
        let path = write(&dir, "stage.usda", &backdrop_stage(&ball, &looks));
        let scene = spectral_render::scene::load(&path, Some((8, 8))).unwrap();
        let integrator = PathIntegrator {
            max_depth: 5,
            rr_depth: spectral_render::integrator::roulette::DEFAULT_RR_DEPTH,
            filter: spectral_render::texture::TextureFilter::Finest,
            split: 1,
        };
        let (mut hero, mut secondary) = (0.0f32, 0.0f32);
        for s in 0..64 {
            let mut sampler = Sampler::new(1, 0, s);
            let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
            let (ray, t_max) = scene.camera.generate_ray([4.0, 4.0], [0.5, 0.5]);
            let l = integrator.li(&scene, ray, t_max, &lambda, &mut sampler);
            hero += l[0];
            secondary += l[1] + l[2] + l[3];
        }
        println!("{name}: hero lane sums to {hero}, secondary lanes to {secondary}");
        assert!(hero > 0.0);
        assert_eq!(secondary == 0.0, dispersive, "{name}");
    }
}
