//! Adaptive sampling (`--adaptive`, `session::adaptive`): unbiased against uniform sampling,
//! the same bits on any number of threads, counts that follow the noise, and the options it
//! refuses.

mod common;

use common::*;
use spectral_render::integrator::Integrator;
use spectral_render::output::exr;
use spectral_render::sampling::SamplerKind;
use spectral_render::scene;
use spectral_render::session::layers::LayerOptions;
use spectral_render::session::{self, RenderOptions};

fn options(spp: u32, seed: u64, sampler: SamplerKind, adaptive: bool) -> RenderOptions {
    RenderOptions {
        spp: Some(spp),
        seed,
        threads: Some(2),
        max_depth: Some(7),
        integrator: Integrator::Path,
        sampler,
        adaptive,
        layers: LayerOptions {
            variance: true,
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn adaptive_images_agree_with_uniform_ones() {
    // The image is unbiased whatever the allocation (session::adaptive): its mean luminance
    // over each quarter and the whole agrees with a uniform render's within |z| < 3.5
    // (two-sided p = 4.7e-4 each, five per sampler), the variances from the films' even and
    // odd halves. Seeds differ, so the two renders are independent.
    let scene = scene::load(&cbox_path(), Some((96, 72))).unwrap();
    for sampler in [SamplerKind::ZSobol, SamplerKind::Independent] {
        let adaptive = render_checked(&scene, &options(64, 11, sampler, true));
        let uniform = render_checked(&scene, &options(64, 12, sampler, false));
        let z = z_scores(&adaptive, &uniform, 1.0);
        eprintln!("{sampler:?}: z {z:.2?}");
        assert!(
            z.iter().all(|z| z.abs() < 3.5),
            "{sampler:?}: biased: {z:?}"
        );
        // The test sees a bias of 2 % in the image's mean luminance.
        let biased = z_scores(&adaptive, &uniform, 1.02);
        assert!(biased[4].abs() > 3.5, "{sampler:?}: 2 % unseen: {biased:?}");
    }
}

#[test]
fn adaptive_images_are_bit_identical_for_one_and_two_threads() {
    let scene = scene::load(&cbox_path(), Some((40, 30))).unwrap();
    for sampler in [SamplerKind::ZSobol, SamplerKind::Independent] {
        let run = |threads| {
            let opts = RenderOptions {
                threads: Some(threads),
                ..options(24, 5, sampler, true)
            };
            render_checked(&scene, &opts)
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one.xyz, two.xyz, "{sampler:?}");
        assert_eq!(one.layers.adaptive, two.layers.adaptive, "{sampler:?}");
    }
}

#[test]
fn counts_keep_the_mean_and_follow_the_noise() {
    let scene = scene::load(&cbox_path(), Some((64, 48))).unwrap();
    let out = render_checked(&scene, &options(64, 3, SamplerKind::ZSobol, true));
    let a = out.layers.adaptive.as_ref().unwrap();
    let n = a.samples.len() as f64;
    let mean = a.samples.iter().map(|&c| f64::from(c)).sum::<f64>() / n;
    assert!((mean - 64.0).abs() < 0.5, "mean {mean}");
    assert_eq!(out.spp, 64);
    let pilot = 2 * session::adaptive::Plan::new(64).unwrap().pilot;
    assert!(a.samples.iter().all(|&c| c >= pilot as f32));
    // The noisier half of the pixels (by a uniform render's variance estimates, summed over
    // 5 × 5 boxes as the allocation does) takes more samples than the quieter half.
    let uniform = render_checked(&scene, &options(64, 4, SamplerKind::ZSobol, false));
    let v = uniform.layers.variance.as_ref().unwrap();
    let mask = vec![true; v.len()];
    let v: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
    let smooth = session::adaptive::box_average(&v, &mask, out.width, 2);
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&i, &j| smooth[i].total_cmp(&smooth[j]));
    let half = |px: &[usize]| px.iter().map(|&i| f64::from(a.samples[i])).sum::<f64>();
    let (quiet, noisy) = order.split_at(order.len() / 2);
    assert!(
        half(noisy) > 1.5 * half(quiet),
        "noisy {} quiet {}",
        half(noisy),
        half(quiet)
    );
}

#[test]
fn the_cli_writes_the_counts_and_refuses_what_it_cannot_do() {
    let dir = temp_dir("adaptive");
    let stage = cbox_path();
    let stage = stage.to_str().unwrap();
    let out = dir.join("a.exr");
    let base = [stage, "--resolution", "32x24", "--adaptive"];
    let spp = ["--spp", "16"];
    let o = spectral_render(
        &[&base[..], &spp, &["-o", out.to_str().unwrap()]].concat(),
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("adaptive sampling: pilot 6 spp"),
        "{}",
        stderr(&o)
    );
    let img = exr::read(&out).unwrap();
    let counts = &img.channels["samples"];
    assert_eq!(counts.len(), 32 * 24);
    assert!(counts.iter().all(|&c| c >= 6.0));
    assert!(img.attributes["spectralRender:adaptive"].contains("samples per pixel"));
    assert_eq!(img.attributes["spectralRender:spp"], "16");
    for (extra, why) in [
        (
            &["--spp", "16", "--integrator", "bdpt"][..],
            "integrator bdpt",
        ),
        (&["--time", "1"][..], "not a time budget"),
        (&["--spp", "16", "--part", "0/2"][..], "--part and --crop"),
        (
            &["--spp", "16", "--checkpoint", "c.state"][..],
            "--checkpoint and --resume",
        ),
        (
            &["--spp", "16", "--aov", "albedo"][..],
            "--aov variance is supported",
        ),
        (&["--spp", "5"][..], "--spp 6 or more"),
    ] {
        let o = spectral_render(&[&base[..], extra, &["-o", "x.exr"]].concat(), &dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains(why), "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
        assert!(!dir.join("x.exr").exists());
    }
}
