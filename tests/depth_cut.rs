//! Defaults never silently bias (issue 11): a depth cap that acts says how much light it cut,
//! for every integrator, images and meters, and the estimate leaves the capped answer alone.
//!
//! In the white furnace (walls of emission Le and reflectance ρ all round) every bounce adds
//! ρᵏ Le, so a cap of d scattering events keeps Le (1 − ρ^(d+1)) / (1 − ρ) of Le / (1 − ρ):
//! it cuts exactly ρ^(d+1) of the image and of every reading. The reported fraction must match
//! it within 4σ of its own interval (2.04 × ci95), and that interval must be narrow enough
//! for the check to mean something. Without a cap the safety cap stands behind Russian
//! roulette; at ρ = 1, where roulette never ends a path, it is reached and reported.

mod common;
use common::*;
use glam::Vec3;
use spectral_render::integrator::path::PathIntegrator;
use spectral_render::integrator::roulette::{RrStart, DEFAULT_RR_DEPTH};
use spectral_render::sampling::Sampler;
use spectral_render::scene::Scene;
use spectral_render::session::{self, measure, DepthCut, MeterOptions, RenderOptions, Stop};
use spectral_render::spectral::SampledWavelengths;
use spectral_render::texture::TextureFilter;
use spectral_render::{Integrator, Meter};

const RHO: f32 = 0.8;
const CAP: u32 = 2;

fn furnace(rho: f32) -> Scene {
    load_text(&format!("furnace-{rho}"), &furnace_stage(2.0, rho), (8, 8))
}

fn integrators() -> [Integrator; 4] {
    ["path", "light", "bdpt", "vcm"].map(|n| Integrator::from_name(n).unwrap())
}

/// The reported cut against ρ^(CAP+1).
fn check(label: &str, cut: Option<DepthCut>) {
    let cut = cut.unwrap_or_else(|| panic!("{label}: the cap acted but nothing was reported"));
    let exact = f64::from(RHO).powi(CAP as i32 + 1);
    eprintln!(
        "{label}: cut {:.4} ± {:.4} (exact {exact:.4}), {} capped",
        cut.fraction, cut.ci95, cut.capped
    );
    assert!(cut.user && cut.max_depth == CAP && !cut.lower_bound && cut.capped > 0);
    assert!(
        cut.ci95 < 0.03,
        "{label}: too noisy to judge: ±{}",
        cut.ci95
    );
    assert!(
        (cut.fraction - exact).abs() < 2.04 * cut.ci95,
        "{label}: {} ± {} vs {exact}",
        cut.fraction,
        cut.ci95
    );
}

#[test]
fn a_cap_reports_the_light_it_cut_from_images_with_every_integrator() {
    let scene = furnace(RHO);
    for integrator in integrators() {
        let opts = RenderOptions {
            spp: Some(512),
            seed: 4,
            max_depth: Some(CAP),
            integrator,
            ..Default::default()
        };
        let out = session::render(&scene, &opts).unwrap();
        assert_finite(&out);
        check(&format!("{} image", integrator.name()), out.depth_cut);
    }
}

#[test]
fn a_cap_reports_the_light_it_cut_from_readings_with_every_integrator() {
    let scene = furnace(RHO);
    let meter = Meter::illuminance(Vec3::new(0.2, -0.3, 0.1), Vec3::new(0.3, 1.0, -0.2)).unwrap();
    for integrator in integrators() {
        let opts = MeterOptions {
            stop: Stop::Samples(16_384),
            seed: 5,
            max_depth: Some(CAP),
            integrator,
            ..Default::default()
        };
        let run = measure(&scene, &[meter], &opts).unwrap();
        assert_eq!(run.dropped, 0);
        check(
            &format!("{} reading", integrator.name()),
            run.readings[0].depth_cut,
        );
    }
}

#[test]
fn without_a_cap_nothing_is_cut_unless_the_safety_cap_is_reached() {
    let scene = furnace(RHO);
    let opts = RenderOptions {
        spp: Some(4),
        ..Default::default()
    };
    assert_eq!(session::render(&scene, &opts).unwrap().depth_cut, None);
    // ρ = 1: no path ends before the safety cap, and a continuation not before its own
    // limit either: 1025 bounces' worth of Le kept, 1024 more found, a lower bound. Whatever
    // bounce roulette starts at: its survival probability is min(max β, 1) = 1 (`roulette.rs`).
    let white = furnace(1.0);
    for rr_depth in [
        RrStart::At(1),
        RrStart::At(2),
        RrStart::At(5),
        RrStart::Auto,
    ] {
        let opts = RenderOptions {
            spp: Some(16),
            rr_depth,
            ..Default::default()
        };
        let out = session::render(&white, &opts).unwrap();
        let cut = out.depth_cut.expect("the safety cap acted");
        let expected = 1024.0 / 2049.0;
        eprintln!(
            "safety cap, rr-depth {rr_depth}: {} paths, cut {:.3} ± {:.3} (expected {expected:.3})",
            cut.capped, cut.fraction, cut.ci95
        );
        assert!(!cut.user && cut.lower_bound && cut.max_depth == 1024);
        assert_eq!(cut.capped, 8 * 8 * 16);
        assert!((cut.fraction - expected).abs() < 2.04 * cut.ci95, "{cut:?}");
    }
}

/// The path tracer's estimate is the same number whether or not the capped path is
/// continued: the continuation draws from a stream of its own.
#[test]
fn the_continuation_leaves_the_capped_estimate_alone() {
    let scene = furnace(RHO);
    let pt = PathIntegrator {
        max_depth: CAP,
        rr_depth: DEFAULT_RR_DEPTH,
        filter: TextureFilter::Finest,
        split: 1,
    };
    let mut continued = 0;
    for k in 0..256 {
        let lambda = SampledWavelengths::sample_visible((k as f32 + 0.5) / 256.0);
        let (ray, t_max) = scene.camera.generate_ray([4.0, 4.0], [0.5, 0.5]);
        let mut cut = Default::default();
        let a = pt.li_cut(
            &scene,
            ray,
            t_max,
            &lambda,
            &mut Sampler::new(1, k, 0),
            &mut cut,
        );
        let b = pt.li(&scene, ray, t_max, &lambda, &mut Sampler::new(1, k, 0));
        assert_eq!(a, b);
        continued += usize::from(!cut.light.is_black());
    }
    assert!(continued > 0, "no path was continued");
}
