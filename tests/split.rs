//! Splitting at the first vertex (`--split`, `PathIntegrator::li_split`): unbiased against the
//! unsplit path tracer (plain, dispersive, with the depth cap's report), the same bits on any
//! number of threads, and `--split 1` the unsplit estimator itself.

mod common;

use common::*;
use spectral_render::integrator::roulette::RrStart;
use spectral_render::integrator::split::Split;
use spectral_render::integrator::Integrator;
use spectral_render::sampling::SamplerKind;
use spectral_render::scene;
use spectral_render::session::layers::LayerOptions;
use spectral_render::session::RenderOptions;
use std::path::Path;

fn options(spp: u32, seed: u64, sampler: SamplerKind, split: u32) -> RenderOptions {
    RenderOptions {
        spp: Some(spp),
        seed,
        threads: Some(2),
        max_depth: Some(7),
        rr_depth: RrStart::At(3),
        split: Split::At(split),
        integrator: Integrator::Path,
        sampler,
        layers: LayerOptions {
            variance: true,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Split renders agree with unsplit ones: mean luminance over each quarter and the whole
/// within |z| < 3.5 (two-sided p = 4.7e-4 each), on the box with both samplers (split 4) and
/// on the prism, whose dispersive glass terminates a continuation's secondary wavelengths on
/// its own (split 2). The seeds differ, so the renders are independent; the test sees a bias
/// of 2 % in the box's mean.
#[test]
fn split_images_agree_with_unsplit_ones() {
    let cbox = scene::load(&cbox_path(), Some((96, 72))).unwrap();
    let prism_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/prism.usda");
    let prism = scene::load(&prism_path, Some((64, 48))).unwrap();
    assert!(prism.dispersive);
    let cases = [
        ("box zsobol", &cbox, SamplerKind::ZSobol, 4, 32),
        ("box independent", &cbox, SamplerKind::Independent, 4, 32),
        ("prism zsobol", &prism, SamplerKind::ZSobol, 2, 64),
    ];
    for (name, scene, sampler, n, spp) in cases {
        let split = render_checked(scene, &options(spp, 11, sampler, n));
        let unsplit = render_checked(scene, &options(spp * n, 12, sampler, 1));
        let z = z_scores(&split, &unsplit, 1.0);
        eprintln!("{name}: z {z:.2?}");
        assert!(z.iter().all(|z| z.abs() < 3.5), "{name}: biased: {z:?}");
        if name == "box zsobol" {
            let biased = z_scores(&split, &unsplit, 1.02);
            assert!(biased[4].abs() > 3.5, "{name}: 2 % unseen: {biased:?}");
        }
    }
}

/// The depth cap's report counts a split path's continuations: what the cap cut agrees with
/// the unsplit render's within 3.5 of their combined 95 % half-widths / 1.96.
#[test]
fn the_depth_cut_of_a_split_render_agrees() {
    let scene = scene::load(&cbox_path(), Some((48, 36))).unwrap();
    let split = render_checked(&scene, &options(64, 3, SamplerKind::ZSobol, 4));
    let unsplit = render_checked(&scene, &options(256, 4, SamplerKind::ZSobol, 1));
    let (a, b) = (split.depth_cut.unwrap(), unsplit.depth_cut.unwrap());
    let se = ((a.ci95 / 1.96).powi(2) + (b.ci95 / 1.96).powi(2)).sqrt();
    eprintln!(
        "cut {} ± {} against {} ± {}",
        a.fraction, a.ci95, b.fraction, b.ci95
    );
    assert!(a.fraction > 0.0 && (a.fraction - b.fraction).abs() < 3.5 * se);
    // Four continuations a sample reach the cap where one path did.
    assert!(
        a.capped > 2 * b.capped / 4,
        "{} against {}",
        a.capped,
        b.capped
    );
}

#[test]
fn split_images_are_bit_identical_for_one_and_two_threads() {
    let scene = scene::load(&cbox_path(), Some((40, 30))).unwrap();
    for sampler in [SamplerKind::ZSobol, SamplerKind::Independent] {
        let run = |threads| {
            let opts = RenderOptions {
                threads: Some(threads),
                ..options(8, 5, sampler, 4)
            };
            render_checked(&scene, &opts)
        };
        assert_eq!(run(1).xyz, run(2).xyz, "{sampler:?}");
    }
}

/// The split is an estimator of its own: its image differs from the unsplit one at the same
/// seed, and `auto` reports the split it took.
#[test]
fn auto_reports_its_split() {
    let scene = scene::load(&cbox_path(), Some((40, 30))).unwrap();
    let opts = options(4, 5, SamplerKind::ZSobol, 1);
    let one = render_checked(&scene, &opts);
    let two = render_checked(
        &scene,
        &RenderOptions {
            split: Split::At(2),
            ..opts.clone()
        },
    );
    assert_ne!(one.xyz, two.xyz);
    assert_eq!((one.split, two.split), (Some(1), Some(2)));
    let auto = render_checked(
        &scene,
        &RenderOptions {
            split: Split::Auto,
            ..opts
        },
    );
    assert!(
        matches!(auto.split, Some(1 | 2 | 4 | 8)),
        "{:?}",
        auto.split
    );
}

/// A split path gathers the emission layers as it gathers the image: each illuminant layer of
/// a split render is, bit for bit, the split render of the stage with that illuminant.
#[test]
fn split_emission_layers_are_the_replaced_scenes_renders() {
    let stage = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/metamers.usda");
    let load = || scene::load(&stage, Some((40, 20))).unwrap();
    let opts = RenderOptions {
        layers: LayerOptions::default(),
        ..options(4, 11, SamplerKind::ZSobol, 4)
    };
    let names = ["D65", "A"];
    let mut scene = load();
    scene
        .add_illuminant_layers(&names.map(String::from))
        .unwrap();
    let one_pass = render_checked(&scene, &opts);
    assert_eq!(one_pass.split, Some(4));
    for (layer, name) in one_pass.layers.emission.iter().zip(names) {
        let mut replaced = load();
        replaced.replace_emission(name).unwrap();
        let separate = render_checked(&replaced, &opts);
        assert!(layer.xyz == separate.xyz, "layer {name} differs");
    }
}
